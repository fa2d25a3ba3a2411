#!/usr/bin/env bash
# The sanitizer build: configures build-asan/ (clang, RelWithDebInfo, LCMLOC_SANITIZE:
# -fsanitize=address,undefined, see CMakePresets.json "asan"), builds everything and runs every
# test through ctest with halt_on_error (the first report fails the test), leak detection on and
# the leaks inside Debian's liblcm suppressed (tests/sanitizers/lsan.supp). Installs what is
# missing (tools/setup.sh). Exits with ctest's status. Extra arguments go to ctest.
set -euo pipefail
if [[ ${1:-} == -h || ${1:-} == --help ]]; then
  sed -n '2,6p' "$0" | sed 's/^# \{0,1\}//'
  echo "Environment: LCMLOC_ASAN_BUILD_DIR (default build-asan/), CTEST_PARALLEL_LEVEL (default 1)."
  exit 0
fi
# shellcheck source=tools/setup.sh
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
build_dir="${LCMLOC_ASAN_BUILD_DIR:-$LCMLOC_ROOT/build-asan}"

lcmloc_install_packages
lcmloc_install_packages "${LCMLOC_SANITIZER_PACKAGES[@]}"
lcmloc_multicast_route
cmake -S "$LCMLOC_ROOT" -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DLCMLOC_SANITIZE=ON
cmake --build "$build_dir" -j "$(nproc)"

export ASAN_OPTIONS=halt_on_error=1:detect_leaks=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
export LSAN_OPTIONS="suppressions=$LCMLOC_ROOT/tests/sanitizers/lsan.supp:print_suppressions=0"
symbolizer=/usr/lib/llvm-14/bin/llvm-symbolizer
[[ -x $symbolizer ]] && export ASAN_SYMBOLIZER_PATH=$symbolizer
cd "$build_dir"
status=0
ctest --output-on-failure "$@" || status=$?
exit "$status"

#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz: LCMLOC_FUZZ, clang, ASan + UBSan) into build-fuzz/
# and runs each for a given time, starting from its seed corpus (tests/fuzz/corpus/<target>,
# read only: what it finds new goes to build-fuzz/fuzz-corpus/<target>), with its dictionary.
# Prints per target the executions, the new inputs and the findings (crash, leak, timeout and
# out-of-memory inputs, kept in build-fuzz/fuzz-findings/<target>/). Exit status 1 when any
# target found something. Installs what is missing (tools/setup.sh).
set -euo pipefail
usage() {
  sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'
  cat << 'USAGE'

Usage: tools/fuzz.sh [--time SECONDS] [--seed N] [--regression] [--no-build] [TARGET...]
  --time S       fuzz each target for S seconds (default 60)
  --seed N       libFuzzer's random seed (default: a new one each run). With a seed and an empty
                 build-fuzz/fuzz-corpus, runs try the same inputs in the same order (the targets
                 are deterministic), so a long run covers the start of a shorter one (CI: 1)
  --regression   run each target once over its committed corpus only (seconds), no fuzzing
  --no-build     use the targets already built
  TARGET         lcm_input, log, config, import, udpm (default: all)
Environment: LCMLOC_FUZZ_BUILD_DIR (default build-fuzz/).
USAGE
}
seconds=60 seed= regression=0 build=1 targets=()
while (($#)); do
  case $1 in
    -h | --help) usage; exit 0 ;;
    --time) seconds=${2:?--time needs a number of seconds}; shift ;;
    --seed) seed=${2:?--seed needs a number}; shift ;;
    --regression) regression=1 ;;
    --no-build) build=0 ;;
    -*) echo "unknown option $1" >&2; usage >&2; exit 2 ;;
    *) targets+=("$1") ;;
  esac
  shift
done
[[ $seconds =~ ^[0-9]+$ && $seconds -gt 0 ]] || { echo "--time: a whole number of seconds > 0" >&2; exit 2; }
[[ -z $seed || $seed =~ ^[0-9]+$ ]] || { echo "--seed: a whole number" >&2; exit 2; }
# shellcheck source=tools/setup.sh
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
build_dir="${LCMLOC_FUZZ_BUILD_DIR:-$LCMLOC_ROOT/build-fuzz}"
fuzz_dir="$LCMLOC_ROOT/tests/fuzz"
((${#targets[@]})) || targets=(lcm_input log config import udpm)
for t in "${targets[@]}"; do
  [[ -f $fuzz_dir/fuzz_$t.cpp ]] || { echo "unknown target '$t' (lcm_input, log, config, import, udpm)" >&2; exit 2; }
done

if ((build)); then
  lcmloc_install_packages
  lcmloc_install_packages "${LCMLOC_SANITIZER_PACKAGES[@]}"
  cmake -S "$LCMLOC_ROOT" -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DLCMLOC_FUZZ=ON > /dev/null
  cmake --build "$build_dir" -j "$(nproc)" --target lcmloc_fuzz
fi
export ASAN_OPTIONS=halt_on_error=1:detect_leaks=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
export LSAN_OPTIONS="suppressions=$LCMLOC_ROOT/tests/sanitizers/lsan.supp:print_suppressions=0"
symbolizer=/usr/lib/llvm-14/bin/llvm-symbolizer
[[ -x $symbolizer ]] && export ASAN_SYMBOLIZER_PATH=$symbolizer

# The value of libFuzzer's final statistic `name` in log, or 0.
stat() { sed -n "s/^stat::$1: *\([0-9]*\).*/\1/p" "$2" | tail -1 | grep . || echo 0; }

status=0
printf '%-10s %12s %10s %8s %s\n' target executions exec/s new findings
for t in "${targets[@]}"; do
  exe="$build_dir/fuzz-bin/fuzz_$t"
  [[ -x $exe ]] || { echo "$exe not built" >&2; exit 2; }
  found="$build_dir/fuzz-findings/$t"
  work="$build_dir/fuzz-corpus/$t"
  log="$build_dir/fuzz-logs/$t.log"
  mkdir -p "$found" "$work" "$(dirname "$log")"
  before=$(ls "$found")
  args=(-print_final_stats=1 -timeout=30 -rss_limit_mb=4096 "-artifact_prefix=$found/")
  [[ -f $fuzz_dir/$t.dict ]] && args+=("-dict=$fuzz_dir/$t.dict")
  [[ -n $seed ]] && args+=("-seed=$seed")
  rc=0
  if ((regression)); then
    "$exe" "${args[@]}" -runs=0 "$fuzz_dir/corpus/$t" > "$log" 2>&1 || rc=$?
  else
    "$exe" "${args[@]}" "-max_total_time=$seconds" "$work" "$fuzz_dir/corpus/$t" > "$log" 2>&1 || rc=$?
  fi
  new=$(comm -13 <(echo "$before") <(ls "$found") | grep . || true)
  n=$(grep -c . <<< "$new" || true)
  ((rc == 0 && n == 0)) || status=1
  what="$n"
  ((rc != 0 && n == 0)) && what="exit $rc (see $log)"
  ((n > 0)) && what="$n: $(echo $new) in $found (see $log)"
  printf '%-10s %12s %10s %8s %s\n' "$t" "$(stat number_of_executed_units "$log")" \
    "$(stat average_exec_per_sec "$log")" "$(stat new_units_added "$log")" "$what"
done
exit "$status"

#!/usr/bin/env bash
# Installs what is missing (Debian bookworm, as root), adds the loopback multicast route if
# there is none, configures build/ (Release), builds with all cores and runs every test through
# ctest. Exits with ctest's status. Extra arguments go to ctest (e.g. tools/test.sh -R eval).
set -euo pipefail
if [[ ${1:-} == -h || ${1:-} == --help ]]; then
  sed -n '2,4p' "$0" | sed 's/^# \{0,1\}//'
  echo "Environment: LCMLOC_BUILD_DIR (default build/), CTEST_PARALLEL_LEVEL (default 1)."
  exit 0
fi
# shellcheck source=tools/setup.sh
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"

lcmloc_install_packages
lcmloc_multicast_route
lcmloc_build
cd "$LCMLOC_BUILD_DIR"
status=0
ctest --output-on-failure "$@" || status=$?
exit "$status"

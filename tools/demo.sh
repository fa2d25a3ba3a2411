#!/usr/bin/env bash
# Runs the default scenario (the magnetic-ruler paper's experiment) live: every process is a
# real executable talking over udpm:// on loopback, started by lcmloc-launcher from
# config/system.yaml; the logger records out/demo/run.lcmlog. Then lcmloc-evaluate scores the
# recorded POSE and, replaying the log through the fusion daemon's code, dead reckoning, the UKF
# and the gated UKF into out/demo/evaluate/ (report.json, figures, a summary) and exports TUM
# files to out/demo/tum/. Same set-up as tools/test.sh (packages,
# multicast route, build).
set -euo pipefail

usage() {
  cat << 'USAGE'
usage: tools/demo.sh [--fast] [--factor X] [-o|--output DIR] [--no-build]
  --fast        run the simulation 10x faster than real time (default: 1.0, live pace)
  --factor X    real-time factor X (1.0 = live, 10 = ten times faster; X > 1 also
                scales fusion.reorder_window and fusion.max_time_jump by X, both
                spans of message time)
  -o, --output DIR  output directory (default: out/demo; its earlier results are replaced)
  --no-build    skip package installation and build (use what is in build/)
Environment: LCMLOC_BUILD_DIR (default build/), LCM_DEFAULT_URL (default
udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304).
USAGE
}

factor=1.0
out=""
build=1
while (($# > 0)); do
  case "$1" in
    --fast) factor=10 ;;
    --factor) factor="${2:?--factor needs a value}"; shift ;;
    -o | --output) out="${2:?--output needs a directory}"; shift ;;
    --no-build) build=0 ;;
    -h | --help) usage; exit 0 ;;
    *) echo "unknown argument: $1" >&2; usage >&2; exit 2 ;;
  esac
  shift
done

# shellcheck source=tools/setup.sh
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$LCMLOC_ROOT"
out="${out:-$LCMLOC_ROOT/out/demo}"
bin="$LCMLOC_BUILD_DIR/bin"
if ((build)); then
  lcmloc_install_packages
  lcmloc_multicast_route
  lcmloc_build
else
  lcmloc_multicast_route
fi
export LCM_DEFAULT_URL="${LCM_DEFAULT_URL:-udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304}"

mkdir -p "$out"
log="$out/run.lcmlog"
rm -f "$log"
# The run's scenario: config/paper.yaml with this run's real-time factor and log file. The
# fusion's reorder window is message time: at X times real time it is X times shorter in wall
# time, so it is scaled by X (X > 1) to keep the same margin for late UDP deliveries; so is the
# time-jump guard (an input later than it is taken for a new time base, whatever the window, and
# the window must stay below it). Offline replay of the log uses the same scenario, so both order
# the inputs alike.
scenario="$out/scenario.yaml"
scaled() {  # scaled KEY: config/paper.yaml's fusion.KEY, times the factor when it is above 1
  local base
  base=$(sed -n "s|^  $1: *\([0-9.eE+-]*\).*|\1|p" "$LCMLOC_ROOT/config/paper.yaml")
  awk -v w="$base" -v f="$factor" \
    'BEGIN { if (w !~ /^[0-9.eE+-]+$/ || f !~ /^[0-9.eE+-]+$/) exit 1; printf "%g", (f > 1 ? w * f : w) }'
}
if ! window=$(scaled reorder_window) || ! jump=$(scaled max_time_jump); then
  lcmloc_log "--factor must be a number (got '$factor'); config/paper.yaml needs fusion.reorder_window and fusion.max_time_jump"
  exit 2
fi
sed -e "s|^\(  realtime_factor:\)[^#]*|\1 $factor   |" -e "s|^\(  output:\)[^#]*|\1 $log   |" \
  -e "s|^\(  reorder_window:\)[^#]*|\1 $window   |" -e "s|^\(  max_time_jump:\)[^#]*|\1 $jump   |" \
  "$LCMLOC_ROOT/config/paper.yaml" > "$scenario"
if [[ $(grep -c -e "^  realtime_factor: $factor " -e "^  output: $log " -e "^  reorder_window: $window " \
  -e "^  max_time_jump: $jump " "$scenario") -ne 4 ]]; then
  lcmloc_log "could not set realtime_factor, reorder_window, max_time_jump and logger output in $scenario"
  exit 1
fi

lcmloc_log "running the paper scenario live (real-time factor $factor) on $LCM_DEFAULT_URL"
start=$SECONDS
"$bin/lcmloc-launcher" --system "$LCMLOC_ROOT/config/system.yaml" --config "$scenario"
lcmloc_log "live run done in $((SECONDS - start)) s: $log ($(stat -c %s "$log") bytes)"

lcmloc_log "scoring the recorded POSE and the replayed filters against GROUND_TRUTH (docs/evaluate.md)"
"$bin/lcmloc-evaluate" "$log" --config "$scenario" --filters dead_reckoning,ukf,ukf_gated -o "$out/evaluate" --overwrite \
  --tum-dir "$out/tum" --segment-lengths 5,10,20

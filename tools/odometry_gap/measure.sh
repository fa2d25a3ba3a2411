#!/bin/sh
# Error and sigma of the gated UKF after an odometry gap, with and without the gap handling:
# cuts ODOMETRY and MAGRULER* out of a recorded run over [START, START + G) s for each G, replays
# the cut log with fusion.max_odometry_gap 0 (off, the behaviour before) and with the default,
# and scores the POSE against GROUND_TRUTH (docs/odometry_gap.md).
#   tools/odometry_gap/measure.sh RUN.lcmlog OUTDIR [START_S] [GAPS...]   (defaults: 12, 2 5)
set -eu
log=$1; out=$2; start=${3:-12}; shift 2; [ $# -gt 0 ] && shift; gaps=${*:-2 5}
bin=${BUILD_DIR:-build}/bin
here=$(dirname "$0")
mkdir -p "$out"
printf 'fusion: {max_odometry_gap: 0}\n' > "$out/off.yaml"
printf 'fusion: {}\n' > "$out/on.yaml"
"$bin/lcmloc-log" to-csv "$log" -c GROUND_TRUTH -o "$out/truth.csv" --overwrite > /dev/null 2>&1
for g in $gaps; do
  python3 "$here/cut_gap.py" "$log" "$out/gap$g.lcmlog" "$start" "$g" > /dev/null
  for mode in off on; do
    r=$out/gap${g}_$mode
    "$bin/lcmloc-replay" "$out/gap$g.lcmlog" --config "$out/$mode.yaml" -o "$r.lcmlog" --overwrite --progress 0 > /dev/null 2>&1 || true
    "$bin/lcmloc-log" to-csv "$r.lcmlog" -c POSE -o "$r.pose.csv" --overwrite > /dev/null 2>&1
    "$bin/lcmloc-log" to-csv "$r.lcmlog" -c GATE -o "$r.gate.csv" --overwrite > /dev/null 2>&1
    printf 'gap %s s, gap handling %s: ' "$g" "$mode"
    python3 "$here/analyze.py" "$out/truth.csv" "$r.pose.csv" "$r.gate.csv" "$start" "$g"
  done
done

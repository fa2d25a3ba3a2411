#!/usr/bin/env bash
# Real recordings tried as a new user would, with the config the importer writes (its noise
# fitted against the recording's truth) and no hand edits: lcmloc-convert, lcmloc-import, then
# lcmloc-evaluate replaying the config's filter through the daemon's intake and engine. Prints
# each recording's scores (position error, NEES, gate decisions, observations without identity
# accepted) and writes every report under OUT. Victoria Park (no truth) is scored by
# lcmloc-vp-experiment at held-out GPS fixes.
#
# usage: tools/real_data_report.sh [BUILD_DIR=build] [DATA_DIR=../shared/data] [OUT_DIR=out/real_data]
set -euo pipefail
BUILD=${1:-build}
DATA=${2:-../shared/data}
OUT=${3:-out/real_data}
BIN=$BUILD/bin
for exe in lcmloc-convert lcmloc-import lcmloc-evaluate lcmloc-vp-experiment; do
  [[ -x $BIN/$exe ]] || { echo "missing $BIN/$exe: build first" >&2; exit 2; }
done
mkdir -p "$OUT"

# run NAME CONVERT-ARGS...: converts, imports and evaluates one recording.
run() {
  local name=$1
  shift
  local dir=$OUT/$name
  rm -rf "$dir"
  echo "== $name"
  "$BIN/lcmloc-convert" "$@" -o "$dir/csv" > "$dir.convert.txt"
  "$BIN/lcmloc-import" "$dir/csv" -o "$dir/import" > "$dir.import.txt" || [[ $? -eq 3 ]]  # 3: rows refused, the rest imported
  grep "noise fit:" "$dir.import.txt" || true
  local filter
  filter=$(sed -n 's/^    type: \([a-z_]*\).*/\1/p' "$dir/import/config.yaml" | head -1)
  "$BIN/lcmloc-evaluate" "$dir/import/run.lcmlog" --config "$dir/import/config.yaml" --filters "$filter" \
    --no-plots --log-level warn -o "$dir/eval" 2> /dev/null |
    grep -E -A1 "^channel|^gate filter|^identity filter|without identity" | grep -v -- "^--$" || true
  echo "report: $dir/eval/report.json"
}

found=0
if [[ -f $DATA/mrclam_ds6/Barcodes.dat ]]; then
  run mrclam_robot1 mrclam --dir "$DATA/mrclam_ds6" --robot 1
  run mrclam_robot2 mrclam --dir "$DATA/mrclam_ds6" --robot 2
  found=1
fi
if [[ -f $DATA/uwb_indoor/Indoor_UWB_Input.txt ]]; then
  run uwb_indoor uwb-labyrinth --dir "$DATA/uwb_indoor"
  found=1
fi
if [[ -f $DATA/victoria_park/vp_odometry.csv ]]; then
  # Every 5th fix held out and scored; each filter's noise fitted to the fixes it is given.
  echo "== victoria_park"
  "$BIN/lcmloc-vp-experiment" --dir "$DATA/victoria_park" --filters tvekf,ukf_gps -o "$OUT/victoria_park" --overwrite \
    --log-level warn | grep -E "^filter|^tvekf|^ukf_gps|^report"
  found=1
fi
((found)) || { echo "no recording found under $DATA (mrclam_ds6, uwb_indoor, victoria_park)" >&2; exit 2; }

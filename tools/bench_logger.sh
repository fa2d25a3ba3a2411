#!/usr/bin/env bash
# Benchmark: lcmloc-logger against lcm-logger (its defaults) on the same bursts, in one run.
# Both record channels BURST_.* on one udpm URL while lcmloc-burst (another process) publishes,
# as fast as it can, 100,000 messages of 100 B (BURST_SMALL) then 10,000 of 10 KB (BURST_LARGE).
# Reports messages recorded by each (read back with lcmloc-log info) and CPU used (user+sys from
# /usr/bin/time). Repeats RUNS times and prints medians; writes OUT_DIR/bench_logger.json.
#
# usage: tools/bench_logger.sh [BUILD_DIR=build] [RUNS=3] [OUT_DIR=out/bench_logger]
set -euo pipefail
BUILD=${1:-build}
RUNS=${2:-3}
OUT=${3:-out/bench_logger}
BIN=$BUILD/bin
PORT=$((30000 + $$ % 5000))
URL="udpm://239.255.76.67:$PORT?ttl=0&recv_buf_size=4194304"
SMALL_N=100000 SMALL_B=100 LARGE_N=10000 LARGE_B=10240
BURST=$BUILD/test-bin/lcmloc-burst  # (a benchmark program: not installed, not in bin/)
for exe in $BIN/lcmloc-logger $BURST $BIN/lcmloc-log; do
  [[ -x $exe ]] || { echo "missing $exe: build first" >&2; exit 2; }
done
command -v lcm-logger >/dev/null || { echo "lcm-logger not installed" >&2; exit 2; }
[[ -x /usr/bin/time ]] || { echo "/usr/bin/time not installed (apt-get install time)" >&2; exit 2; }
mkdir -p "$OUT"

# Waits until FILE stops growing for 1 s (max 60 s).
settle() {
  local last=-1 same=0 size
  for _ in $(seq 600); do
    size=$(stat -c %s "$1" 2>/dev/null || echo 0)
    if [[ $size == "$last" ]]; then same=$((same + 1)); [[ $same -ge 10 ]] && return 0; else same=0; fi
    last=$size
    sleep 0.1
  done
}
# Count of channel $2 in log $1.
# (exit 3: a damaged log, counted up to and past the damage)
count() { { "$BIN/lcmloc-log" --log-level error info "$1" || [ $? -eq 3 ]; } | awk -v ch="$2" '$1 == ch { print $3 }' | head -1; }
stop() {  # SIGINT the logger under /usr/bin/time (time itself does not forward signals)
  local child
  child=$(pgrep -P "$1" || true)
  [[ -n $child ]] && kill -INT "$child"
  wait "$1" || true
}

results=()
for run in $(seq "$RUNS"); do
  dir=$(mktemp -d)
  /usr/bin/time -f "%U %S" -o "$dir/lcm.time" lcm-logger -q --lcm-url="$URL" -c 'BURST_.*' "$dir/lcm.lcmlog" &
  lcm_pid=$!
  /usr/bin/time -f "%U %S" -o "$dir/ours.time" "$BIN/lcmloc-logger" --lcm-url "$URL" --channel 'BURST_.*' \
    --output "$dir/ours.lcmlog" 2>"$dir/ours.err" &
  ours_pid=$!
  sleep 1  # both subscribed
  "$BURST" --lcm-url "$URL" -n $SMALL_N -s $SMALL_B -c BURST_SMALL 2>"$dir/small.pub"
  "$BURST" --lcm-url "$URL" -n $LARGE_N -s $LARGE_B -c BURST_LARGE 2>"$dir/large.pub"
  small_rate=$(grep -o '([0-9]* msg/s)' "$dir/small.pub" | tr -dc 0-9)
  large_rate=$(grep -o '([0-9]* msg/s)' "$dir/large.pub" | tr -dc 0-9)
  settle "$dir/ours.lcmlog"; settle "$dir/lcm.lcmlog"
  stop $lcm_pid; stop $ours_pid
  read -r lu ls < "$dir/lcm.time"; read -r ou os < "$dir/ours.time"
  lcm_small=$(count "$dir/lcm.lcmlog" BURST_SMALL); lcm_large=$(count "$dir/lcm.lcmlog" BURST_LARGE)
  our_small=$(count "$dir/ours.lcmlog" BURST_SMALL); our_large=$(count "$dir/ours.lcmlog" BURST_LARGE)
  lcm_cpu=$(echo "$lu + $ls" | bc -l); our_cpu=$(echo "$ou + $os" | bc -l)
  echo "       published: 100 B at ${small_rate} msg/s, 10 KB at ${large_rate} msg/s"
  printf 'run %d: lcm-logger %s/%d small %s/%d large, %.2f s CPU | lcmloc-logger %s/%d small %s/%d large, %.2f s CPU\n' \
    "$run" "${lcm_small:-0}" $SMALL_N "${lcm_large:-0}" $LARGE_N "$lcm_cpu" "${our_small:-0}" $SMALL_N \
    "${our_large:-0}" $LARGE_N "$our_cpu"
  echo "       lcmloc-logger: $(grep -o 'recorded .*' "$dir/ours.err" | sed 's/ to [0-9]* file(s) ([^)]*)//')"
  results+=("${lcm_small:-0} ${lcm_large:-0} $lcm_cpu ${our_small:-0} ${our_large:-0} $our_cpu ${small_rate:-0} ${large_rate:-0}")
  rm -rf "$dir"
done

printf '%s\n' "${results[@]}" | python3 -c '
import json, statistics, sys
rows = [list(map(float, l.split())) for l in sys.stdin if l.strip()]
cols = ["lcm_small", "lcm_large", "lcm_cpu_s", "ours_small", "ours_large", "ours_cpu_s", "publish_small_msg_s", "publish_large_msg_s"]
med = {c: statistics.median(r[i] for r in rows) for i, c in enumerate(cols)}
rep = {"published": {"small": {"count": '$SMALL_N', "bytes": '$SMALL_B'}, "large": {"count": '$LARGE_N', "bytes": '$LARGE_B'}},
       "runs": [dict(zip(cols, r)) for r in rows], "median": med,
       "cpu_ratio_ours_over_lcm": med["ours_cpu_s"] / med["lcm_cpu_s"] if med["lcm_cpu_s"] else None}
json.dump(rep, open("'"$OUT"'/bench_logger.json", "w"), indent=2)
n = '$SMALL_N' + '$LARGE_N'
print("median of %d runs (published: 100 B at %d msg/s, 10 KB at %d msg/s):" % (len(rows), med["publish_small_msg_s"], med["publish_large_msg_s"]))
print("  %-14s %12s %12s %10s %16s" % ("logger", "100 B", "10 KB", "CPU [s]", "CPU/msg [us]"))
for name, p in (("lcm-logger", "lcm"), ("lcmloc-logger", "ours")):
  rec = med[p + "_small"] + med[p + "_large"]
  print("  %-14s %12d %12d %10.2f %16.1f" % (name, med[p + "_small"], med[p + "_large"], med[p + "_cpu_s"],
        1e6 * med[p + "_cpu_s"] / rec if rec else float("nan")))
print("report: '"$OUT"'/bench_logger.json")
'

#!/usr/bin/env bash
# lcm-spy with the pose view under Xvfb during a replayed ruler run: lcmloc-replay writes the
# ruler log's estimates (POSE, GATE), lcm-logplayer plays them on a private udpm port, and
# SpyXvfbCheck starts lcm-spy, opens the view and checks a screenshot's pixels.
# Skipped (exit 77) without xvfb-run (Debian package xvfb).
# usage: spy_xvfb.sh JAVA CLASSPATH REPLAY_BIN INPUT_LOG MAP_CSV PNG_OUT
set -euo pipefail
java="$1" classpath="$2" replay="$3" input="$4" map="$5" png="$6"
for tool in xvfb-run lcm-logplayer; do
  command -v "$tool" > /dev/null || { echo "SKIP: $tool not installed (apt-get install xvfb liblcm-bin)"; exit 77; }
done
work="$(mktemp -d)"
player=""
cleanup() {
  [[ -z $player ]] || kill "$player" 2> /dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
"$replay" "$input" -o "$work/run.lcmlog" > "$work/replay.out" 2>&1 || { cat "$work/replay.out"; exit 1; }
url="udpm://239.255.76.67:$((20000 + RANDOM % 20000))?ttl=0"
# The run again and again at 2x, so that the bus carries estimates whenever the view looks.
(while :; do lcm-logplayer -s 2 -l "$url" "$work/run.lcmlog" > /dev/null 2>&1 || sleep 1; done) &
player=$!
export LCM_DEFAULT_URL="$url" LCMLOC_SPY_MAP="$map"
export JDK_JAVA_OPTIONS="-XX:+IgnoreUnrecognizedVMOptions"
xvfb-run -a -s "-screen 0 1280x1024x24" "$java" -cp "$classpath" lcmloc.spy.SpyXvfbCheck "$url" "$png"

#!/usr/bin/env bash
# lcm-spy with the pose view under Xvfb during a replayed ruler run: lcmloc-replay writes the
# ruler log's estimates (POSE, GATE), lcm-logplayer plays them on a private udpm port, and
# SpyXvfbCheck starts lcm-spy, opens the view and checks a screenshot's pixels.
# Skipped (exit 77) without xvfb-run (Debian package xvfb).
# lcm-spy runs as tools/spy.sh runs it: LCM (and jchart2d) on java's class path, the lcmloc jars
# (PLUGIN_CLASSPATH) in the environment's CLASSPATH.
# usage: spy_xvfb.sh JAVA CHECK_CLASSPATH PLUGIN_CLASSPATH REPLAY_BIN INPUT_LOG MAP_CSV PNG_OUT
set -euo pipefail
java="$1" classpath="$2" plugin_classpath="$3" replay="$4" input="$5" map="$6" png="$7"
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
export CLASSPATH="$plugin_classpath" LCM_DEFAULT_URL="$url" LCMLOC_SPY_MAP="$map"
export JDK_JAVA_OPTIONS="-XX:+IgnoreUnrecognizedVMOptions"
xvfb-run -a -s "-screen 0 1280x1024x24" "$java" -cp "$classpath" lcmloc.spytest.SpyXvfbCheck "$url" "$png"

#!/usr/bin/env bash
# Starts lcm-spy with the lcmloc message types, so it decodes every lcmloc channel, and with the
# lcmloc pose view plugin (right-click a pose_t channel such as POSE).
set -euo pipefail

usage() {
  cat << 'USAGE'
usage: tools/spy.sh [--build-dir DIR] [--lcm-url URL] [--map FILE]
  Starts lcm-spy (needs a display) with
  CLASSPATH=<build>/share/java/lcmloc_types.jar:<build>/share/java/lcmloc_spy.jar:<lcm.jar>.
  Right-click a pose_t channel (POSE, POSE_<FILTER>) and choose "lcmloc pose view": the track,
  the 3-sigma ellipse (scaled up to be visible, the factor printed), the map, GATE's accepted
  (green) and rejected (red) decisions and the NIS strip against its 95 % chi-square band.
  --build-dir DIR  build directory holding share/java/lcmloc_{types,spy}.jar (default: build/)
  --lcm-url URL    LCM URL to watch (default: $LCM_DEFAULT_URL, else
                   udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304)
  --map FILE       map CSV (id,x,y: the system's fusion.map_file, e.g. config/paper_map.csv)
                   drawn by the pose view (default: $LCMLOC_SPY_MAP, else no map)
  Environment: LCMLOC_SPY_GATE names the gate channel (default GATE).
USAGE
}

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${LCMLOC_BUILD_DIR:-$root/build}"
url="${LCM_DEFAULT_URL:-udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304}"
map="${LCMLOC_SPY_MAP:-}"
while (($# > 0)); do
  case "$1" in
    --build-dir) build="${2:?--build-dir needs a directory}"; shift ;;
    --lcm-url) url="${2:?--lcm-url needs a URL}"; shift ;;
    --map) map="${2:?--map needs a file}"; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "unknown argument: $1" >&2; usage >&2; exit 2 ;;
  esac
  shift
done

jar="$build/share/java/lcmloc_types.jar"
if [[ ! -f $jar ]]; then
  echo "types jar not found: $jar (build it: cmake --build $build --target lcmloc_types_jar)" >&2
  exit 1
fi
plugin_jar="$build/share/java/lcmloc_spy.jar"
if [[ ! -f $plugin_jar ]]; then
  echo "plugin jar not found: $plugin_jar (build it: cmake --build $build --target lcmloc_spy_jar)" >&2
  exit 1
fi
if [[ -n $map ]]; then
  [[ -r $map ]] || { echo "map file not readable: $map" >&2; exit 1; }
  map="$(cd "$(dirname "$map")" && pwd)/$(basename "$map")"
fi
lcm_jar="$(pkg-config --variable=classpath lcm-java 2> /dev/null || true)"
lcm_jar="${lcm_jar:-/usr/share/java/lcm.jar}"
command -v lcm-spy > /dev/null || { echo "lcm-spy not found (install liblcm-bin)" >&2; exit 1; }

export CLASSPATH="$jar:$plugin_jar:$lcm_jar${CLASSPATH:+:$CLASSPATH}"
# The plugin subscribes through LCM.getSingleton(), which uses LCM_DEFAULT_URL: lcm-spy's URL.
export LCM_DEFAULT_URL="$url"
export LCMLOC_SPY_MAP="$map"
# Debian's lcm-spy passes -Xincgc, which Java 17 rejects unless told to ignore it.
export JDK_JAVA_OPTIONS="-XX:+IgnoreUnrecognizedVMOptions${JDK_JAVA_OPTIONS:+ $JDK_JAVA_OPTIONS}"
exec lcm-spy --lcm-url="$url"

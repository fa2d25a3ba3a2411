#!/usr/bin/env bash
# Starts lcm-spy with the lcmloc message types, so it decodes every lcmloc channel.
set -euo pipefail

usage() {
  cat << 'USAGE'
usage: tools/spy.sh [--build-dir DIR] [--lcm-url URL]
  Starts lcm-spy (needs a display) with CLASSPATH=<build>/share/java/lcmloc_types.jar:<lcm.jar>.
  --build-dir DIR  build directory holding share/java/lcmloc_types.jar (default: build/)
  --lcm-url URL    LCM URL to watch (default: $LCM_DEFAULT_URL, else
                   udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304)
USAGE
}

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${LCMLOC_BUILD_DIR:-$root/build}"
url="${LCM_DEFAULT_URL:-udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304}"
while (($# > 0)); do
  case "$1" in
    --build-dir) build="${2:?--build-dir needs a directory}"; shift ;;
    --lcm-url) url="${2:?--lcm-url needs a URL}"; shift ;;
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
lcm_jar="$(pkg-config --variable=classpath lcm-java 2> /dev/null || true)"
lcm_jar="${lcm_jar:-/usr/share/java/lcm.jar}"
command -v lcm-spy > /dev/null || { echo "lcm-spy not found (install liblcm-bin)" >&2; exit 1; }

export CLASSPATH="$jar:$lcm_jar${CLASSPATH:+:$CLASSPATH}"
# Debian's lcm-spy passes -Xincgc, which Java 17 rejects unless told to ignore it.
export JDK_JAVA_OPTIONS="-XX:+IgnoreUnrecognizedVMOptions${JDK_JAVA_OPTIONS:+ $JDK_JAVA_OPTIONS}"
exec lcm-spy --lcm-url="$url"

# shellcheck shell=bash
# Shared set-up of tools/test.sh and tools/demo.sh (sourced, not run):
#   lcmloc_install_packages [P...]  installs the Debian packages that are missing (apt-get update
#                            first; skipped entirely when everything is present): P..., by
#                            default LCMLOC_PACKAGES
#   lcmloc_multicast_route   adds the loopback multicast route udpm:// needs, if there is none
#   lcmloc_build             configures build/ (Release) and builds with all cores
# Environment: LCMLOC_BUILD_DIR (default <repo>/build).

LCMLOC_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
LCMLOC_BUILD_DIR="${LCMLOC_BUILD_DIR:-$LCMLOC_ROOT/build}"
LCMLOC_PACKAGES=(
  build-essential cmake pkg-config
  liblcm-dev liblcm-bin liblcm-java libglib2.0-dev
  libeigen3-dev libspdlog-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev googletest libbenchmark-dev libnanoflann-dev
  default-jdk-headless libjchart2d-java
  gnuplot-nox iproute2 xvfb xauth
  gpsd gpsd-clients libgps-dev libgeographiclib-dev
  util-linux time bc procps
  libboost-dev
)
# What the sanitizer build and the fuzz targets need besides (tools/sanitize.sh, tools/fuzz.sh):
# clang, its runtimes (libFuzzer, ASan, UBSan: libclang-rt-14-dev, only recommended by clang)
# and llvm-symbolizer (llvm-14) for the reports' stack traces.
LCMLOC_SANITIZER_PACKAGES=(clang libclang-rt-14-dev llvm-14)

lcmloc_log() { echo "[lcmloc] $*" >&2; }

lcmloc_as_root() {
  if [[ $(id -u) -eq 0 ]]; then "$@"
  elif command -v sudo > /dev/null; then sudo "$@"
  else lcmloc_log "need root for: $*"; return 1
  fi
}

lcmloc_install_packages() {
  local missing=() p wanted=("$@")
  ((${#wanted[@]})) || wanted=("${LCMLOC_PACKAGES[@]}")
  for p in "${wanted[@]}"; do
    dpkg-query -W -f='${Status}\n' "$p" 2> /dev/null | grep -q '^install ok installed$' || missing+=("$p")
  done
  if ((${#missing[@]} == 0)); then
    lcmloc_log "all ${#wanted[@]} packages present"
    return 0
  fi
  lcmloc_log "installing missing packages: ${missing[*]}"
  lcmloc_as_root apt-get update
  lcmloc_as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}"
}

lcmloc_multicast_route() {
  if ip route show 2> /dev/null | grep -q '^224\.0\.0\.0/4'; then return 0; fi
  lcmloc_log "no multicast route: adding 224.0.0.0/4 dev lo (loopback multicast for udpm://)"
  lcmloc_as_root ip route add 224.0.0.0/4 dev lo ||
    lcmloc_log "WARNING: could not add the multicast route; udpm:// tests may fail"
}

lcmloc_build() {
  cmake -S "$LCMLOC_ROOT" -B "$LCMLOC_BUILD_DIR" -DCMAKE_BUILD_TYPE=Release
  cmake --build "$LCMLOC_BUILD_DIR" -j "$(nproc)"
}

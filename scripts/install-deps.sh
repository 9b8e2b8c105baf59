#!/usr/bin/env bash
# Installs the Debian 12 packages peritwin needs. Idempotent: does nothing when all are present.
# Runs as root (CI, the developers' machines) or through sudo when available.
set -euo pipefail

packages=(
  cmake g++ make pkg-config
  libeigen3-dev libsuitesparse-dev
  # OpenBLAS: CHOLMOD's supernodal factorization of a 60k-node model takes ~3 s with it and ~20 s
  # with Debian's reference BLAS on a 2-core machine (issue 2).
  libopenblas0-pthread
  libgtest-dev
  liblcm-dev liblcm-bin liblcm-java libglib2.0-dev default-jre-headless
  libhdf5-dev libspdlog-dev libtomlplusplus-dev libcli11-dev libpng-dev nlohmann-json3-dev
  # HMAC-SHA256 of the signed messages and key generation (messages/auth.h, issue 14).
  libsodium-dev
  # systemd-analyze verify of the fleet's unit examples/peritwin@.service (its test).
  systemd
  # The web dashboard (dashboard/, peritwin-dashboard): HTTP server, Chart.js served from the
  # package's file (no CDN), and headless chromium for its browser test.
  libcpp-httplib-dev libjs-chart.js chromium
  # lcm-spy with the peritwin types (scripts/spy.sh, issue 17): a JDK builds peritwin_msgs.jar,
  # Spy is a window (the full JRE's AWT), its message viewer and plots need jchart2d, and its test
  # runs it under Xvfb (xvfb-run needs xauth).
  default-jdk-headless default-jre libjchart2d-java xvfb xauth
  # The PNG pictures (outputs/damage_png.cpp): drawn with cairo, text set by pango in fontconfig's
  # Sans, which is DejaVu Sans on Debian (fonts-dejavu-core: the font exists on a fresh machine).
  # libpng-dev above: the tests read the pictures back with libpng, not with cairo.
  libcairo2-dev libpango1.0-dev fonts-dejavu-core
  # The rooms check (scripts/check-rooms.py, CTest rooms.*): docs/architecture.md's map enforced.
  python3
)
# The fuzz targets and the sanitizer build (scripts/fuzz.sh, scripts/sanitize.sh, which set
# PERITWIN_SANITIZER_DEPS=1): clang 14 with its sanitizer and libFuzzer runtimes.
if [ "${PERITWIN_SANITIZER_DEPS:-0}" = 1 ]; then
  packages+=(clang libclang-rt-14-dev libfuzzer-14-dev)
fi

# The ParaView check of the results files (scripts/check-results-paraview.sh, which sets
# PERITWIN_PARAVIEW_DEPS=1): ParaView 5.11 with its Python (pvbatch), about 545 MB installed.
if [ "${PERITWIN_PARAVIEW_DEPS:-0}" = 1 ]; then
  packages+=(paraview python3-paraview)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
echo "install-deps: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null

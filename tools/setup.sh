#!/usr/bin/env bash
# Installs Strata's build and test dependencies from Debian 12 packages.
# Idempotent: skips apt-get when every package is already installed.
set -euo pipefail
PKGS=(cmake g++ make pkg-config libopenmesh-dev libosd-dev libeigen3-dev libglm-dev
      libglfw3-dev libgl-dev libegl-dev libgl1-mesa-dri libimgui-dev libstb-dev libgtest-dev
      nlohmann-json3-dev libcli11-dev libtbb-dev libcgal-dev libgmp-dev libmpfr-dev libsuitesparse-dev
      libopenblas0-serial zlib1g-dev python3 xvfb xauth)
# libopenblas0-serial: Debian's alternatives then give CHOLMOD an optimized single-threaded BLAS
# instead of the reference one (the volume solver's factorizations run about twice as fast).
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
bash "$(dirname "$0")/fetch_scans.sh"

#!/usr/bin/env bash
# Installs the Debian packages millcharge needs. Idempotent: packages already
# present are skipped, and `apt-get update` runs at most once per call.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  ocl-icd-opencl-dev opencl-clhpp-headers opencl-c-headers pocl-opencl-icd clinfo
  mesa-opencl-icd
  catch2 libtomlplusplus-dev nlohmann-json3-dev libcli11-dev libfmt-dev libstb-dev
  fonts-dejavu-core  # the PNG plots' font, built into the program at build time (src/io/plot_font_data.cpp)
  libglfw3-dev libglew-dev libglm-dev libimgui-dev
  xvfb xauth libgl1-mesa-dri python3
  munge slurmctld slurmd slurm-client  # the sweep tier's one-machine Slurm cluster (scripts/slurm_local.sh)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"

#!/usr/bin/env bash
# Installs what dentsim needs from Debian 12 packages, only what is missing (idempotent).
# Called by scripts/run.sh and scripts/test.sh; safe to run by hand.
set -euo pipefail

PACKAGES=(
  build-essential cmake ccache pkg-config
  libmujoco-dev libqhull-dev libeigen3-dev libceres-dev libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev libfmt-dev libpng-dev libcairo2-dev
  # benchmark-only (bench/tooth_bench.cc compares the tooth query; the build works without them)
  libopenvdb-dev libboost-dev liboctomap-dev
  clang libclang-rt-14-dev  # the fuzz flavour: clang with libFuzzer (scripts/build.sh fuzz)
  libgdcm-dev libnifti2-dev libteem-dev
  # the 3-D view (view/, issue #19): OpenGL 3.3 through GLVND, EGL (headless, Mesa's surfaceless
  # platform), GLFW (the window), Xvfb (the viewer's test under a virtual display)
  libgl-dev libegl-dev libegl-mesa0 libgl1-mesa-dri libglfw3-dev xvfb xauth
  # the library for other programs (issue #20): the Python module (pybind11, NumPy; pytest runs
  # its suite, matplotlib the example plot), sweeps over MPI (OpenMPI; the build works without)
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib
  libopenmpi-dev openmpi-bin
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
# The downloaded package files (~1.4 GB for a fresh Debian 12 machine) are not needed once
# installed: a machine with little disk (CI's have had under 1 GB free) needs the room to build.
before=$(du -sm /var/cache/apt/archives 2>/dev/null | cut -f1 || echo 0)
$SUDO apt-get clean
echo "setup: installed ${#missing[@]} packages; apt-get clean freed ${before:-0} MB of downloaded package files"

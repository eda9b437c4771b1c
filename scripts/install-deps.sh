#!/usr/bin/env bash
# Install exactly the Debian 12 packages lamina needs to build, test and validate.
# Idempotent: packages already present are skipped; apt is only called when something is missing.
#   scripts/install-deps.sh           build, test and validation dependencies
#   scripts/install-deps.sh --peers   also the side-by-side benchmark peers (bench/README.md):
#                                     CalculiX (calculix-ccx), LAMMPS (lammps)
# libopenblas0-openmp replaces Debian's reference BLAS (through update-alternatives) under CHOLMOD's
# supernodal factorisation: the EFG factor of R1a at 21 x 21 x 5 nodes, box kappa 3, takes 3.8 s with
# it against 49 s with the reference BLAS (measured 2026-12-02); its OpenMP build follows --threads.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libsuitesparse-dev libspectra-dev
  libyaml-cpp-dev libmuparser-dev libcli11-dev libfmt-dev nlohmann-json3-dev
  libnanoflann-dev libgmsh-dev zlib1g-dev
  libopenblas0-openmp
  libgtest-dev libbenchmark-dev
  python3 python3-matplotlib python3-numpy python3-vtk9
  python3-dev pybind11-dev python3-pytest python3-yaml
  libopenmpi-dev openmpi-bin libtrilinos-zoltan-dev petsc-dev libslepc-real-dev
)
if [ "${1:-}" = "--peers" ]; then
  PACKAGES+=(calculix-ccx lammps)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "install-deps: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"

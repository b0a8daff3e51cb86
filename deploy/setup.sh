#!/usr/bin/env bash
# Installs every Debian package the project needs. Idempotent and non-interactive.
# Usage: deploy/setup.sh            (as root, or through sudo)
#        TELEOP_SETUP_VIEWER=0 deploy/setup.sh   (skip the OpenGL viewer packages)
#        TELEOP_SETUP_VENDORS=0 deploy/setup.sh  (skip the optional other-vendor DDS used only by
#                                                 tests/integration/other_vendor_test.cpp)
#        TELEOP_SETUP_PEERS=0 deploy/setup.sh    (skip the optional peer engines used only by
#                                                 `teleop_bench peers`: Bullet, MuJoCo)
#        TELEOP_SETUP_SLURM=0 deploy/setup.sh    (skip the Slurm daemons used only by
#                                                 tests/tools/campaign_slurm.sh)
#        TELEOP_SETUP_MESHER=0 deploy/setup.sh   (skip gmsh, which fills surface files with
#                                                 tetrahedra for model fem)
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev
  libfastrtps-dev libfastcdr-dev fastdds-tools fastddsgen default-jre-headless
  libode-dev libfcl-dev libassimp-dev
  googletest libgtest-dev libgmock-dev libbenchmark-dev
  libyaml-cpp-dev libcli11-dev
  libsqlite3-dev libzstd-dev libevdev-dev tmux
  libwebsocketpp-dev libasio-dev libjsoncpp-dev  # teleop_bridge (Foxglove WebSocket protocol)
  openssl libssl-dev  # DDS Security: deploy/make_security.sh; common/dds/security_check.cpp
  python3-matplotlib python3-numpy
  pybind11-dev python3-dev python3-pytest  # the Python module teleop (client/python) and its test
  clang-format
  clang libclang-rt-dev   # libFuzzer + sanitizers of the fuzz targets (tests/fuzz, deploy/fuzz.sh)
)
# Node.js and npm: tests/node reads MCAP recordings with the MCAP project's own reader
# (@mcap/core; `npm ci` from tests/node/package-lock.json, run by deploy/build.sh). A Node.js
# already on the PATH (NodeSource's package bundles npm and conflicts with Debian's npm) is used.
if ! command -v npm >/dev/null 2>&1; then
  packages+=(nodejs npm)
fi
if [ "${TELEOP_SETUP_VIEWER:-1}" = "1" ]; then
  packages+=(libglfw3-dev libgl-dev libimgui-dev zlib1g-dev xvfb xauth)
fi
# optional, tests only: Eclipse Cyclone DDS (C library + idlc) builds teleop_cyclone_reader,
# the other-vendor reader of the interoperability test; without it that test skips
if [ "${TELEOP_SETUP_VENDORS:-1}" = "1" ]; then
  packages+=(cyclonedds-dev cyclonedds-tools)
fi

# optional, tests only: a single-node Slurm cluster (slurmctld, slurmd, munge, sbatch) that
# tests/tools/campaign_slurm.sh starts in a temporary folder to run a campaign as an array job;
# without them that test skips
if [ "${TELEOP_SETUP_SLURM:-1}" = "1" ]; then
  packages+=(slurmctld slurmd slurm-client munge)
fi

# optional: gmsh fills a closed surface file with tetrahedra for a `model: fem` body that names a
# `mesh_file` (run as a program, never linked; the shipped ball meshes do not need it) and the
# test of that path; without it such a scene is refused with a message saying so
if [ "${TELEOP_SETUP_MESHER:-1}" = "1" ]; then
  packages+=(gmsh)
fi

# optional, benchmarks only: Bullet's soft body (and MuJoCo 2.2.2, which has no mesh-based soft
# body to compare: docs/results.md) for `teleop_bench peers`; without them that command skips
if [ "${TELEOP_SETUP_PEERS:-1}" = "1" ]; then
  packages+=(libbullet-dev libmujoco-dev)
fi

sudo_cmd=()
if [ "$(id -u)" != "0" ]; then
  if command -v sudo >/dev/null 2>&1; then
    sudo_cmd=(sudo)
  else
    echo "deploy/setup.sh: must run as root or have sudo available" >&2
    exit 1
  fi
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ "${#missing[@]}" -eq 0 ]; then
  echo "deploy/setup.sh: all ${#packages[@]} packages already installed"
  exit 0
fi

echo "deploy/setup.sh: installing ${#missing[@]} missing packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "deploy/setup.sh: done"

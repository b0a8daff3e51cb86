#!/usr/bin/env bash
# Installs the Debian packages the project needs. Idempotent and non-interactive.
# By default only what a session needs (deploy/run_session.sh: teleop_server, teleop_master, the
# viewer and the charts); TELEOP_SETUP_TESTS=1 (deploy/run_tests.sh sets it) adds the packages of
# the tools, tests, benchmarks and fuzz runs.
# Usage: deploy/setup.sh                          (as root, or through sudo)
#        TELEOP_SETUP_TESTS=1 deploy/setup.sh     (add the tools', tests' and benchmarks' packages)
#        TELEOP_SETUP_VIEWER=0 deploy/setup.sh    (skip the OpenGL viewer packages)
#   with TELEOP_SETUP_TESTS=1, each of these skips an optional set the tests use when present:
#        TELEOP_SETUP_VENDORS=0   (the other-vendor DDS of tests/integration/other_vendor_test.cpp)
#        TELEOP_SETUP_PEERS=0     (the peer engines of `teleop_bench peers`: Bullet, MuJoCo)
#        TELEOP_SETUP_SLURM=0     (the Slurm daemons of tests/tools/campaign_slurm.sh)
#        TELEOP_SETUP_MESHER=0    (gmsh, which fills surface files with tetrahedra for model fem)
set -euo pipefail

# the session: the compiler, CMake, Eigen, Fast DDS, ODE, assimp, yaml-cpp, CLI11, nlohmann-json
# (summaries, monitor lines, events), OpenSSL
# (DDS Security checks), libevdev (the evdev device driver) and the charts' matplotlib
packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev
  libfastrtps-dev libfastcdr-dev fastdds-tools fastddsgen default-jre-headless
  libode-dev libassimp-dev
  libyaml-cpp-dev libcli11-dev
  nlohmann-json3-dev  # JSON written and read through nlohmann::json (common/util/json.hpp)
  libevdev-dev
  openssl libssl-dev  # DDS Security: deploy/make_security.sh; common/dds/security_check.cpp
  python3-matplotlib python3-numpy
)
if [ "${TELEOP_SETUP_VIEWER:-1}" = "1" ]; then
  packages+=(libglfw3-dev libgl-dev libimgui-dev zlib1g-dev)
fi

if [ "${TELEOP_SETUP_TESTS:-0}" = "1" ]; then
  packages+=(
    libfcl-dev  # the reference the collision tests and benchmarks compare against
    googletest libgtest-dev libgmock-dev libbenchmark-dev
    libsqlite3-dev libzstd-dev  # recordings (teleop::recording: the tools)
    tmux        # the monitor's screen-mode test
    libwebsocketpp-dev libasio-dev libjsoncpp-dev  # teleop_bridge (Foxglove WebSocket protocol;
                                                   # libssl-dev above: its TLS)
    chromium  # the bridge page's test: headless Chromium opens it (tests/node/page_check.mjs)
    pybind11-dev python3-dev python3-pytest  # the Python module teleop (client/python), its test
    clang-format
    clang-tidy  # deploy/tidy.sh: the checks of .clang-tidy, run by deploy/run_tests.sh
    clang libclang-rt-dev  # libFuzzer + sanitizers of the fuzz targets (tests/fuzz, deploy/fuzz.sh)
  )
  if [ "${TELEOP_SETUP_VIEWER:-1}" = "1" ]; then
    packages+=(xvfb xauth)  # the viewer's headless tests
  fi
  # Node.js and npm: tests/node reads MCAP recordings with the MCAP project's own reader
  # (@mcap/core; `npm ci` from tests/node/package-lock.json, run by deploy/build.sh --tests). A
  # Node.js already on the PATH (NodeSource's package bundles npm and conflicts with Debian's
  # npm) is used.
  if ! command -v npm >/dev/null 2>&1; then
    packages+=(nodejs npm)
  fi
  # optional: Eclipse Cyclone DDS (C library + idlc) builds teleop_cyclone_reader, the
  # other-vendor reader of the interoperability test; without it that test skips
  if [ "${TELEOP_SETUP_VENDORS:-1}" = "1" ]; then
    packages+=(cyclonedds-dev cyclonedds-tools)
  fi
  # optional: a single-node Slurm cluster (slurmctld, slurmd, munge, sbatch) that
  # tests/tools/campaign_slurm.sh starts in a temporary folder to run a campaign as an array
  # job; without them that test skips
  if [ "${TELEOP_SETUP_SLURM:-1}" = "1" ]; then
    packages+=(slurmctld slurmd slurm-client munge)
  fi
  # optional: gmsh fills a closed surface file with tetrahedra for a `model: fem` body that
  # names a `mesh_file` (run as a program, never linked; the shipped ball meshes do not need
  # it) and the test of that path; without it such a scene is refused with a message saying so
  if [ "${TELEOP_SETUP_MESHER:-1}" = "1" ]; then
    packages+=(gmsh)
  fi
  # optional, benchmarks only: Bullet's soft body (and MuJoCo 2.2.2, which has no mesh-based
  # soft body to compare: docs/results.md) for `teleop_bench peers`; without them it skips
  if [ "${TELEOP_SETUP_PEERS:-1}" = "1" ]; then
    packages+=(libbullet-dev libmujoco-dev)
  fi
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

#!/usr/bin/env bash
# The installed package as another project uses it: checks that docs/deformable.md shows this
# folder's CMakeLists.txt and press_ball.cpp verbatim, installs the build tree into a temporary
# prefix (cmake --install), configures and builds this folder against it with
# find_package(teleop), runs press_ball (it reads its scene from the prefix's share/teleop), and
# checks that the installed teleop_server finds its default scene there too.
#   run_consumer_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src="$1"
build="$2"
here="$src/tests/consumer"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

for f in CMakeLists.txt press_ball.cpp; do
  if ! /usr/bin/python3 -c 'import sys; sys.exit(open(sys.argv[1]).read() not in open(sys.argv[2]).read())' \
    "$here/$f" "$src/docs/deformable.md"; then
    echo "FAILED: docs/deformable.md does not show tests/consumer/$f as it is"
    exit 1
  fi
done

cmake --install "$build" --prefix "$work/prefix" >"$work/install.log" || {
  cat "$work/install.log"
  exit 1
}
launcher=()
if [ -n "${TELEOP_CONSUMER_LAUNCHER:-}" ]; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER="$TELEOP_CONSUMER_LAUNCHER")
fi
# only the installed tree: no package registry, nothing from the build tree
cmake -S "$here" -B "$work/build" -G Ninja -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" \
  >"$work/configure.log" || {
  cat "$work/configure.log"
  exit 1
}
cmake --build "$work/build" >"$work/build.log" || {
  cat "$work/build.log"
  exit 1
}

# the consumer is outside the prefix: TELEOP_DATA_DIR names the prefix's data
TELEOP_DATA_DIR="$work/prefix/share/teleop" "$work/build/press_ball"

# an installed program finds its data beside it: the default scene of the prefix
scene="$("$work/prefix/bin/teleop_server" --help | grep -o -- '--scene TEXT=[^ ]*' | cut -d= -f2)"
if [ "$scene" != "$work/prefix/share/teleop/scenes/default.yaml" ]; then
  echo "FAILED: the installed teleop_server's default scene is '$scene'"
  exit 1
fi
"$work/prefix/bin/teleop_server" --version
echo "ok: built against $work/prefix, and the installed server reads $scene"

# Sourced by the Node ctest launchers: `require_node DIR PACKAGE` exits 77 (skipped) when node is
# not installed and 1 when DIR/node_modules lacks PACKAGE (npm ci not run).
require_node() {
  if ! command -v node >/dev/null 2>&1; then
    echo "skipped: node is not installed (deploy/setup.sh installs nodejs and npm)"
    exit 77
  fi
  if [ ! -d "$1/node_modules/$2" ]; then
    echo "FAILED: $1/node_modules is missing: run 'npm ci' in tests/node (deploy/build.sh does)"
    exit 1
  fi
}

// teleop_bench <name> --out DIR: benchmark sweeps that write CSV data and charts.
#include "common/util/registry.hpp"

int main(int argc, char** argv) {
  return teleop::run_registry_main("bench", "teleop_bench", argc, argv);
}

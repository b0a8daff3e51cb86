// teleop_experiment <name> --out DIR: the paper's experiments, each writing CSV and a chart.
#include "common/util/registry.hpp"

int main(int argc, char** argv) {
  return teleop::run_registry_main("experiments", "teleop_experiment", argc, argv);
}

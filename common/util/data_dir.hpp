#pragma once
// Where the programs find their data: the scenes, the Fast DDS profiles, the data tables and
// meshes, the chart scripts and the reference results. An installed tree keeps them in
// <prefix>/share/teleop/{scenes,profiles,data,charts,reference}; a build-tree run reads them
// from the source tree (deploy/scenes, deploy/profiles, deploy/data, tests/charts,
// tests/reference).
#include <string>

namespace teleop {

/// The path of `relative` (e.g. "scenes/default.yaml", "profiles", "charts/session.py") in the
/// first of these that holds the folder named by its first component:
///   1. $TELEOP_DATA_DIR, when set and not empty (an installed tree that was moved);
///   2. <folder of the running program>/../share/teleop (an installed program);
///   3. <install prefix configured at build time>/share/teleop (a program of another project
///      linking the installed libraries);
///   4. the source tree the libraries were built from (a build-tree run).
/// When none holds it, the source-tree path is returned (a later open names it in its error).
std::string data_path(const std::string& relative);

}  // namespace teleop

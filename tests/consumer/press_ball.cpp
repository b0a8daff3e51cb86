// The deformable ball of a shipped scene, on the floor, pressed on its top node for 0.5 s.
#include <cstdio>
#include <exception>
#include <vector>

#include "common/config/config.hpp"
#include "common/util/data_dir.hpp"
#include "common/util/version.hpp"
#include "server/deformable/deformable.hpp"
namespace dm = teleop::sim::deformable;

int main() try {
  // <prefix>/share/teleop/scenes (or $TELEOP_DATA_DIR/scenes): common/util/data_dir.hpp
  auto scene = teleop::config::Node::load_file(teleop::data_path("scenes/sphere_gravity.yaml"));
  dm::DeformableParams params = dm::load_deformable_params(scene.at("deformable"));  // validated
  teleop::mesh::TriMesh mesh = dm::make_mesh_for(params);  // icosphere or mesh_file
  std::vector<teleop::sim::Plane> planes(1);               // the floor z = 0 (Plane's defaults)
  dm::DeformableModel model = dm::make_model(mesh, params, planes);  // immutable
  dm::DeformableState state = dm::make_state(model);                 // all scratch allocated here
  teleop::sim::EventQueue events;
  Eigen::Index top = 0;
  const double rest_top_m = state.x.row(2).maxCoeff(&top);
  const Eigen::Vector3d tip_force_n(0.0, 0.0, -10.0);
  for (int i = 0; i < 500; ++i) {  // every physics step (no allocation, no exception):
    state.f_ext.setZero();
    state.f_ext.col(top) += tip_force_n;  // caller's loads [N], kept by step()
    dm::StepStatus st = dm::step(model, state, 1e-3, &events);  // kOk, kSleeping, kFaultReset, ...
    if (st == dm::StepStatus::kFaultReset || st == dm::StepStatus::kBadInput) {
      std::fprintf(stderr, "press_ball: step %d failed (status %d)\n", i, static_cast<int>(st));
      return 1;
    }
  }
  std::printf("teleop %s: top node %.1f mm -> %.1f mm, %d floor contacts\n",
              teleop::version_string().c_str(), 1e3 * rest_top_m, 1e3 * state.x(2, top),
              state.contact_count);
  return state.x(2, top) < rest_top_m ? 0 : 1;    // pressed down: it moved down
} catch (const teleop::config::ConfigError& e) {  // the scene file: named in the message
  std::fprintf(stderr, "press_ball: %s\n", e.what());
  return 2;
} catch (const std::exception& e) {
  std::fprintf(stderr, "press_ball: %s\n", e.what());
  return 1;
}

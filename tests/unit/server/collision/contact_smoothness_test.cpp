// While the tip loads the default sphere slowly and steadily, the force is
// monotone and changes little from step to step (no drop as the node penalty takes over from the
// proxy spring), at several tip positions over the icosphere's facets and at several speeds. The
// sphere is the contact-force experiment's: the paper's default body, settled on the floor under
// gravity, the tip kinematic (server/experiments/contact_experiments.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "server/collision/tip_mesh_contact.hpp"
#include "server/deformable/deformable.hpp"

namespace tc = teleop::sim::collision;
namespace df = teleop::sim::deformable;
using Eigen::Vector3d;

namespace {

struct Loading {
  double largest_drop_n = 0.0;  // largest fall of |F| from one step to the next
  double largest_step_n = 0.0;  // largest change of |F| from one step to the next
  double final_force_n = 0.0;
  int steps = 0;
};

/// The tip (radius 5 cm) over (x, y) comes down at `speed` [m/s] until 20 mm past first contact.
Loading load(double x, double y, double speed) {
  df::DeformableParams params;
  teleop::sim::Plane floor;
  floor.id = 0;
  const auto mesh = df::make_mesh_for(params);
  const df::DeformableModel model = df::make_model(mesh, params, {floor});
  df::DeformableState state = df::make_state(model);
  const double dt = 1e-3, r = 0.05;
  for (int i = 0; i < 1500; ++i) df::step(model, state, dt, nullptr);  // settle on the floor
  double top = -1e9;
  for (int i = 0; i < state.x.cols(); ++i) top = std::max(top, state.x(2, i));
  tc::TipContactParams cp;  // the experiment's contact: 300 N/m, 1 N s/m, mu 0.5
  cp.stiffness_n_per_m = 300.0;
  cp.damping_ns_per_m = 1.0;
  cp.friction_static = 0.5;
  cp.friction_kinetic = 0.4;
  tc::TipMeshContact contact(cp);
  contact.reset(state.x, model.mesh.triangles);
  Vector3d tip(x, y, top + r + 0.003), prev = tip;
  const Vector3d vel(0.0, 0.0, -speed);
  double z_touch = NAN, f_prev = 0.0;
  Loading out;
  for (int n = 0; n < 200000; ++n) {
    tip += vel * dt;
    state.f_ext.setZero();
    const tc::TipContactResult res =
        contact.update(state.x, &state.v, prev, tip, r, vel, dt, state.f_ext);
    prev = tip;
    if (res.in_contact && std::isnan(z_touch)) z_touch = tip.z();
    const double f = res.force_on_tip_n.norm();
    if (!std::isnan(z_touch)) {
      out.largest_drop_n = std::max(out.largest_drop_n, f_prev - f);
      out.largest_step_n = std::max(out.largest_step_n, std::abs(f - f_prev));
      ++out.steps;
      if (z_touch - tip.z() >= 0.02) break;
    }
    f_prev = f;
    if (res.in_contact) df::wake(state);
    df::step(model, state, dt, nullptr);
  }
  out.final_force_n = f_prev;
  return out;
}

TEST(ContactSmoothness, LoadingTheSphereIsMonotoneWithBoundedStepsEverywhere) {
  // positions on the top cap (different facets, edges and vertices of the level-4 icosphere)
  // and speeds from a slow press to a brisk one
  const double positions[][2] = {{0.0, 0.0}, {0.011, 0.0}, {0.019, 0.012}, {-0.027, 0.021}};
  for (const double speed : {0.005, 0.01, 0.03}) {
    // the force's own rate: the stiffest secant of the curve (about 700 N/m at 20 mm, the
    // Hertz-like stiffening) times the speed, three times over, plus what the body's own
    // vibration adds (5 mN)
    const double bound_n = 3.0 * 700.0 * speed * 1e-3 + 0.005;
    for (const auto& p : positions) {
      const Loading l = load(p[0], p[1], speed);
      std::printf(
          "[ loading  ] at (%+.3f, %+.3f) m, %.3f m/s: %d steps, final %.3f N, largest "
          "drop %.4f N, largest step %.4f N (bound %.4f N)\n",
          p[0], p[1], speed, l.steps, l.final_force_n, l.largest_drop_n, l.largest_step_n, bound_n);
      EXPECT_GT(l.final_force_n, 1.0);
      // monotone, within 2 mN of the body's own vibration (before the blended hand-over of
      // the node penalty: drops of 0.21-0.24 N at every position and speed here)
      EXPECT_LE(l.largest_drop_n, 2e-3) << p[0] << " " << p[1] << " " << speed;
      EXPECT_LE(l.largest_step_n, bound_n) << p[0] << " " << p[1] << " " << speed;
    }
  }
}

}  // namespace

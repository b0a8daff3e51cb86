// The tip against the real deformable sphere (server/deformable, default mass-spring model,
// level 4): press 30 mm and release without creating energy, forces equal and opposite,
// stable under both the symplectic and the implicit integrator.
#include <gtest/gtest.h>

#include "server/collision/tip_mesh_contact.hpp"
#include "server/deformable/deformable.hpp"

namespace tc = teleop::sim::collision;
namespace df = teleop::sim::deformable;
using Eigen::Vector3d;

namespace {

struct CycleResult {
  double work_on_tip_j = 0.0;  // trapezoid sum of F . dc
  double body_energy_end_j = 0.0;
  double peak_force_n = 0.0;
  double max_step_jump_n = 0.0;
  int contact_steps = 0;
  std::uint64_t faults = 0;
};

CycleResult press_release(df::IntegratorKind integrator, double speed) {
  df::DeformableParams params;
  params.integrator = integrator;
  params.gravity_mps2.setZero();
  params.centre_m = Vector3d::Zero();
  const auto mesh = df::make_mesh_for(params);
  const df::DeformableModel model = df::make_model(mesh, params);
  df::DeformableState state = df::make_state(model);
  // hold the bottom cap still so the body cannot be pushed away
  for (int i = 0; i < state.x.cols(); ++i) {
    if (state.x(2, i) < -0.2) {
      state.pinned[static_cast<std::size_t>(i)] = 1;
      state.pin_target.col(i) = state.x.col(i);
    }
  }
  tc::TipMeshContact contact;  // library defaults
  contact.reset(state.x, model.mesh.triangles);
  const double dt = 1e-3, r = 0.05;
  const int n_half = static_cast<int>(std::ceil((0.005 + 0.03) / (speed * dt)));
  Vector3d prev(0.0, 0.0, 0.25 + r + 0.005), f_prev = Vector3d::Zero();
  CycleResult out;
  for (int i = 1; i <= 2 * n_half + 300; ++i) {
    const double s = i <= n_half ? i : std::max(0, 2 * n_half - i);
    const Vector3d now(0.0, 0.0, 0.25 + r + 0.005 - s * speed * dt);
    const Vector3d vel = (now - prev) / dt;
    state.f_ext.setZero();
    const auto res = contact.update(state.x, &state.v, prev, now, r, vel, dt, state.f_ext);
    EXPECT_NEAR((state.f_ext.rowwise().sum() + res.force_on_tip_n).norm(), 0.0, 1e-9);
    out.work_on_tip_j += 0.5 * (res.force_on_tip_n + f_prev).dot(now - prev);
    out.peak_force_n = std::max(out.peak_force_n, res.force_on_tip_n.norm());
    out.max_step_jump_n = std::max(out.max_step_jump_n, (res.force_on_tip_n - f_prev).norm());
    out.contact_steps += res.in_contact ? 1 : 0;
    f_prev = res.force_on_tip_n;
    prev = now;
    if (res.in_contact) df::wake(state);
    df::step(model, state, dt, nullptr);
  }
  out.body_energy_end_j = df::kinetic_energy(model, state) + df::elastic_energy(model, state);
  out.faults = state.fault_count + contact.fault_count();
  return out;
}

}  // namespace

TEST(TipOnDeformableSphere, PressAndReleaseCreatesNoEnergy) {
  for (const auto integ :
       {df::IntegratorKind::kSymplecticEuler, df::IntegratorKind::kImplicitEuler}) {
    for (const double speed : {0.05, 0.3}) {
      const CycleResult c = press_release(integ, speed);
      std::printf(
          "%s %.2f m/s: work on tip %.5f J, body energy left %.5f J, peak %.2f N, "
          "max step change %.3f N\n",
          df::to_string(integ), speed, c.work_on_tip_j, c.body_energy_end_j, c.peak_force_n,
          c.max_step_jump_n);
      EXPECT_EQ(c.faults, 0u);
      EXPECT_GT(c.contact_steps, 100);
      EXPECT_GT(c.peak_force_n, 1.0);
      EXPECT_LT(c.peak_force_n, 100.0);
      // no spike: at 0.05 m/s the force moves by well under 1 N per 1 ms step
      if (speed < 0.1) {
        EXPECT_LT(c.max_step_jump_n, 1.0);
      }
      // energy stored at the deepest point is at most about F_peak * 30 mm / 2; the tip may
      // not get back more than it put in (2 % of that), nor the body keep more than it got
      const double scale = 0.5 * c.peak_force_n * 0.03;
      EXPECT_LE(c.work_on_tip_j, 0.02 * scale);
      EXPECT_LE(c.body_energy_end_j, -c.work_on_tip_j + 0.02 * scale);
    }
  }
}

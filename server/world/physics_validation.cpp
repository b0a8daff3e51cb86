// Measurements of a deformable ball against Hertz, Lamb and its sag (physics_validation.hpp).
#include "server/world/physics_validation.hpp"

#include "common/sim/hertz.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "common/mesh/tri_mesh.hpp"
#include "common/util/data_dir.hpp"
#include "server/deformable/material.hpp"
#include "server/world/world.hpp"
#include "server/world/world_model.hpp"

namespace teleop::sim::validation {

namespace df = teleop::sim::deformable;

Material foam() {
  const double volume = 4.0 / 3.0 * M_PI * kBallRadiusM * kBallRadiusM * kBallRadiusM;
  return {"foam", 6000.0, 0.3, 2.0 / volume};
}

Material silicone() { return {"silicone", 50e3, 0.45, 1100.0}; }

double contact_modulus_pa(const Material& m) {
  return m.youngs_modulus_pa / (1.0 - m.poisson_ratio * m.poisson_ratio);
}

double hertz_force_n(double e_star_pa, double r_eff_m, double depth_m) {
  return hertz::force_n(e_star_pa, r_eff_m, depth_m);
}

double hertz_depth_m(double e_star_pa, double r_eff_m, double force_n) {
  return hertz::depth_m(e_star_pa, r_eff_m, force_n);
}

double hertz_floor_travel_m(const Material& m, double ball_r_m, double tip_r_m, double force_n,
                            double preload_n) {
  return hertz::floor_travel_m(contact_modulus_pa(m), ball_r_m, tip_r_m, force_n, preload_n);
}

double hertz_floor_force_n(const Material& m, double ball_r_m, double tip_r_m, double travel_m,
                           double preload_n) {
  return hertz::floor_force_n(contact_modulus_pa(m), ball_r_m, tip_r_m, travel_m, preload_n);
}

double hertz_tip_force_n(const Material& m, double ball_r_m, double tip_r_m, double depth_m) {
  return hertz::force_n(contact_modulus_pa(m), 1.0 / (1.0 / tip_r_m + 1.0 / ball_r_m), depth_m);
}

const char* to_string(LambMode mode) {
  switch (mode) {
    case LambMode::kS2:
      return "S2";
    case LambMode::kT2:
      return "T2";
    case LambMode::kS0:
      return "S0";
  }
  return "?";
}

double lamb_eta(LambMode mode, double nu) {
  switch (mode) {
    case LambMode::kT2:
      return df::lamb_eta_t2();
    case LambMode::kS0:
      return df::lamb_eta_s0(nu);
    case LambMode::kS2:
      return df::lamb_eta_s2(nu);
  }
  return 0.0;
}

double lamb_frequency_hz(LambMode mode, const Material& m, double radius_m) {
  const double ct =
      std::sqrt(m.youngs_modulus_pa / (2.0 * m.density_kg_per_m3 * (1.0 + m.poisson_ratio)));
  return lamb_eta(mode, m.poisson_ratio) * ct / (2.0 * M_PI * radius_m);
}

df::DeformableParams ball_params(df::ModelKind model, df::IntegratorKind integrator, int level,
                                 const Material& material) {
  df::DeformableParams p;
  p.model = model;
  p.integrator = integrator;
  p.level = level;
  p.radius_m = kBallRadiusM;
  p.youngs_modulus_pa = material.youngs_modulus_pa;
  p.poisson_ratio = material.poisson_ratio;
  p.mass_kg = material.density_kg_per_m3 * 4.0 / 3.0 * M_PI * std::pow(kBallRadiusM, 3);
  p.sleep_time_s = 1e9;  // measurements never sleep
  if (model == df::ModelKind::kFem) {
    p.centre_m = Eigen::Vector3d(0, 0, kBallRadiusM);  // the shipped balls have nodes at the poles
    p.stiffness_damping_s = 1e-4;
    p.mass_damping_per_s = 5.0;
    return p;
  }
  if (model == df::ModelKind::kMassSpring) p.springs_from_material = true;  // as a scene's body
  if (model != df::ModelKind::kMassSpring) p.radial_stiffness_n_per_m3 = 0.0;
  if (model == df::ModelKind::kMassSpring && integrator == df::IntegratorKind::kSymplecticEuler) {
    p.kernel = df::default_kernel(model, integrator);
  }
  const teleop::mesh::TriMesh m =
      teleop::mesh::make_icosphere(level, kBallRadiusM, Eigen::Vector3d::Zero());
  p.centre_m = Eigen::Vector3d(0, 0, -m.vertices.row(2).minCoeff());
  return p;
}

namespace {

// Dynamic relaxation: every velocity of the body scaled by `factor` (quasi-static runs).
void relax(df::DeformableState& s, double factor) {
  s.v *= factor;
  s.centre_v *= factor;
}

// The same for the velocities relative to the body's mean velocity: damps deformation, never
// resists the body's translation (which a free ball needs to reach the floor).
void relax_relative(const df::DeformableModel& m, df::DeformableState& s, double factor) {
  const int n = m.state_node_count();
  Eigen::Vector3d mv = m.centre_mass_kg * s.centre_v;
  for (int i = 0; i < n; ++i) {
    mv += (i < m.node_count ? m.mass_kg(i) : m.fem.mass_kg(i)) * s.v.col(i);
  }
  const Eigen::Vector3d vmean = mv / m.total_mass_kg;
  for (int i = 0; i < n; ++i) s.v.col(i) = vmean + factor * (s.v.col(i) - vmean);
  s.centre_v = vmean + factor * (s.centre_v - vmean);
}

int tet_count(const df::DeformableModel& m) {
  return m.params.model == df::ModelKind::kFem ? m.fem.tet_count : 0;
}

// Pins the inner nodes within kHeldRadiusM of the centre (at least the nearest one) where they
// are.
void hold_centre(const df::DeformableModel& m, df::DeformableState& s) {
  double nearest = 1e30;
  for (int i = m.node_count; i < m.fem.node_count; ++i) {
    nearest = std::min(nearest, (m.fem.rest.col(i) - m.rest_centre_m).norm());
  }
  const double held_r = std::max(kHeldRadiusM, nearest);
  for (int i = m.node_count; i < m.fem.node_count; ++i) {
    if ((m.fem.rest.col(i) - m.rest_centre_m).norm() <= held_r) {
      s.pinned[static_cast<std::size_t>(i)] = 1;
      s.pin_target.col(i) = s.x.col(i);
    }
  }
}

// The highest surface node above z_top: its height into z_top and its x, y into xy.
void top_node(const df::DeformableModel& m, const df::DeformableState& s, double& z_top,
              Eigen::Vector2d& xy) {
  for (int i = 0; i < m.node_count; ++i) {
    if (s.x(2, i) > z_top) {
      z_top = s.x(2, i);
      xy = s.x.col(i).head<2>();
    }
  }
}

}  // namespace

PressResult press_ball(const df::DeformableParams& params_in, Support support, bool gravity,
                       const std::vector<double>& travels_m, double speed_mps, double settle_s,
                       double relax_factor) {
  const double dt = 1e-3, r = kTipRadiusM;
  df::DeformableParams params = params_in;
  if (!gravity || support == Support::kHeldCentre) params.gravity_mps2.setZero();
  params.mass_damping_per_s = 0.0;
  std::vector<Plane> planes;
  if (support == Support::kFloor) planes.push_back(Plane{});
  ToolModel tool;
  tool.radius_m = r;
  WorldModel world = tool_world_model(tool, Eigen::Vector3d(0.0, 0.0, 3.0), 1.0 / dt);
  DeformableBodyModel& body = world.bodies.emplace_back();
  body.body = df::make_model(params, planes);
  WorldData data = make_world_data(world);
  df::DeformableState& s = data.bodies[0].state;
  const df::DeformableModel& m = world.bodies[0].body;
  PressResult out;
  out.travel_m = travels_m;
  out.force_n.assign(travels_m.size(), std::numeric_limits<double>::quiet_NaN());
  out.nodes = m.state_node_count();
  out.tets = tet_count(m);
  const Eigen::Vector3d c_rest = df::centroid(m, s);
  if (support == Support::kHeldCentre) {
    if (params.model != df::ModelKind::kFem) return out;  // surface models have no inside
    hold_centre(m, s);
  }
  int top = 0;
  for (int i = 0; i < m.node_count; ++i) top = s.x(2, i) > s.x(2, top) ? i : top;
  const double top_rest = s.x(2, top);
  EventQueue events;
  WorldCommand cmd;
  cmd.kinematic = true;
  cmd.position_m = data.out.tip_position_m;
  const int settle_steps = static_cast<int>(std::lround(settle_s / dt));
  for (int k = 0; k < settle_steps; ++k) {
    world_step(world, data, cmd, dt, events);
    relax(s, 0.97);
  }
  out.sag_top_m = top_rest - s.x(2, top);
  out.sag_centre_m = c_rest.z() - df::centroid(m, s).z();
  out.floor_force_n = s.plane_force_n.z();
  // the tip just above the top node, then straight down
  double z_top = -1e9;
  Eigen::Vector2d xy(0, 0);
  top_node(m, s, z_top, xy);
  const double z_touch = z_top + r;
  Eigen::Vector3d tip(xy.x(), xy.y(), z_touch + 0.002);
  place_tool(world, data, tip);
  cmd.position_m = tip;
  cmd.velocity_mps = Eigen::Vector3d(0, 0, -speed_mps);
  double prev_travel = -1.0, prev_force = 0.0;
  std::size_t next = 0;
  const double last = travels_m.empty() ? 0.0 : travels_m.back();
  const auto t0 = std::chrono::steady_clock::now();
  int steps = 0;
  while (next < travels_m.size() && steps < 10'000'000) {
    tip.z() -= speed_mps * dt;
    cmd.position_m = tip;
    world_step(world, data, cmd, dt, events);
    relax_relative(m, s, relax_factor);
    ++steps;
    const double travel = z_touch - tip.z();
    const double force =
        data.bodies[0].last.in_contact ? data.bodies[0].last.force_on_tip_n.z() : 0.0;
    while (next < travels_m.size() && travel >= travels_m[next]) {
      const double w = (travels_m[next] - prev_travel) / (travel - prev_travel);
      out.force_n[next] = prev_force + w * (force - prev_force);
      ++next;
    }
    prev_travel = travel;
    prev_force = force;
    if (travel > last + 0.01) break;
  }
  const auto t1 = std::chrono::steady_clock::now();
  out.step_us =
      steps > 0 ? std::chrono::duration<double, std::micro>(t1 - t0).count() / steps : 0.0;
  out.faults = s.fault_count;
  return out;
}

double free_vibration_hz(df::DeformableParams p, LambMode mode, double duration_s,
                         double expected_hz, double* step_us, std::uint64_t* faults) {
  const double dt = 1e-3;
  p.gravity_mps2.setZero();
  p.stiffness_damping_s = 0.0;
  p.radial_damping_s = 0.0;
  p.mass_damping_per_s = 0.0;
  const df::DeformableModel m = df::make_model(p, {});
  df::DeformableState s = df::make_state(m);
  const int n = m.state_node_count();
  const Eigen::Matrix3Xd x0 = s.x;
  const Eigen::Vector3d c0 = df::centroid(m, s);
  Eigen::Matrix3Xd phi(3, n);
  for (int i = 0; i < n; ++i) phi.col(i) = lamb_mode_field(mode, (x0.col(i) - c0) / kBallRadiusM);
  const double vmax = phi.colwise().norm().maxCoeff();
  s.v = phi * (0.02 / vmax);  // 2 cm/s at most: a small-strain vibration
  Eigen::VectorXd mass(n);
  for (int i = 0; i < n; ++i) mass(i) = i < m.node_count ? m.mass_kg(i) : m.fem.mass_kg(i);
  const int steps = static_cast<int>(std::lround(duration_s / dt));
  std::vector<double> q(static_cast<std::size_t>(steps));
  const auto t0 = std::chrono::steady_clock::now();
  int done = 0;
  for (; done < steps; ++done) {
    // a blow-up resets the body to rest: the rest of the run would measure nothing
    if (df::step(m, s, dt, nullptr) == df::StepStatus::kFaultReset) break;
    const Eigen::Vector3d c = df::centroid(m, s);
    double acc = 0.0;
    for (int i = 0; i < n; ++i)
      acc += mass(i) * ((s.x.col(i) - c) - (x0.col(i) - c0)).dot(phi.col(i));
    q[static_cast<std::size_t>(done)] = acc;
  }
  const auto t1 = std::chrono::steady_clock::now();
  if (step_us) {
    *step_us = std::chrono::duration<double, std::micro>(t1 - t0).count() / std::max(done, 1);
  }
  if (faults) *faults = s.fault_count;
  if (s.fault_count > 0) return std::numeric_limits<double>::quiet_NaN();
  return dominant_frequency_hz(q, dt, expected_hz);
}

Eigen::Vector3d lamb_mode_field(LambMode mode, const Eigen::Vector3d& q) {
  switch (mode) {
    case LambMode::kS2:
      return Eigen::Vector3d(q.x(), q.y(), -2.0 * q.z());
    case LambMode::kT2:
      return Eigen::Vector3d(q.y() * q.z(), -q.x() * q.z(), 0.0);
    case LambMode::kS0:
      return q;
  }
  return Eigen::Vector3d::Zero();
}

std::string travel_mm_text(double travel_m) {
  if (!(travel_m > 0.0)) return "";
  char b[32];
  std::snprintf(b, sizeof b, "%g", travel_m * 1e3);
  return b;
}

std::string calculix_key(const std::string& material, const std::string& case_name,
                         const std::string& quantity, double travel_m) {
  return material + "," + case_name + "," + quantity + "," + travel_mm_text(travel_m);
}

std::map<std::string, double> calculix_reference() {
  std::map<std::string, double> out;
  std::ifstream in(data_path("reference/calculix/ball_reference.csv"));
  std::string line;
  std::getline(in, line);  // header: material,case,quantity,travel_mm,value,unit,theory,mesh,notes
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string cell;
    while (f.size() < 8 && std::getline(ss, cell, ',')) f.push_back(cell);
    if (f.size() < 8 || f[7] != "fine" || f[6] != "small_strain" || f[4].empty()) continue;
    const double travel_m = f[3].empty() ? 0.0 : 1e-3 * std::strtod(f[3].c_str(), nullptr);
    out[calculix_key(f[0], f[1], f[2], travel_m)] = std::strtod(f[4].c_str(), nullptr);
  }
  return out;
}

double dominant_frequency_hz(const std::vector<double>& q, double dt, double expected_hz) {
  const int steps = static_cast<int>(q.size());
  if (steps < 8) return std::numeric_limits<double>::quiet_NaN();
  double mean = 0.0;
  for (double v : q) mean += v;
  mean /= static_cast<double>(steps);
  auto power = [&](double f) {
    std::complex<double> acc(0.0, 0.0);
    for (int k = 0; k < steps; ++k) {
      const double w = 0.5 - 0.5 * std::cos(2.0 * M_PI * k / (steps - 1));
      acc +=
          w * (q[static_cast<std::size_t>(k)] - mean) * std::polar(1.0, -2.0 * M_PI * f * k * dt);
    }
    return std::norm(acc);
  };
  const double lo = 0.3 * expected_hz, hi = 2.5 * expected_hz, df_hz = 0.002 * expected_hz;
  double best_f = lo, best_p = -1.0;
  for (double f = lo; f <= hi; f += df_hz) {
    const double pw = power(f);
    if (pw > best_p) {
      best_p = pw;
      best_f = f;
    }
  }
  // a peak on the edge of the range is no vibration in it (damped out, or drifting)
  if (best_f < lo + 1.5 * df_hz || best_f > hi - 1.5 * df_hz) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  const double pm = power(best_f - df_hz), pp = power(best_f + df_hz);
  const double den = pm - 2.0 * best_p + pp;
  const double shift = den != 0.0 ? 0.5 * (pm - pp) / den : 0.0;
  return best_f + std::clamp(shift, -1.0, 1.0) * df_hz;
}

}  // namespace teleop::sim::validation

// teleop_experiment contact-force-curve: the tip, moved kinematically, presses into the
// deformable sphere (radius 0.25 m, level 4, the default mass-spring model, resting on the
// floor under gravity) to 30 mm and is withdrawn, at several speeds. The world is a tool world
// with the sphere as its one body, advanced by world_step (the tool a kinematic probe,
// WorldCommand::kinematic), as the server advances its scene. The reaction force
// against the deformation reproduces the paper's Figs. 16-17; a linear law F = k x and the
// Hertz law F = c x^(3/2) are fitted to the same data for comparison.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "common/util/csv.hpp"
#include "common/util/registry.hpp"
#include "server/collision/tip_mesh_contact.hpp"
#include "server/deformable/deformable.hpp"
#include "server/world/world.hpp"
#include "server/world/world_model.hpp"

namespace {

namespace tc = teleop::sim::collision;
namespace df = teleop::sim::deformable;

struct Fit {
  double k_lin = 0, rms_lin = 0, c_hertz = 0, rms_hertz = 0;
};

Fit fit_laws(const std::vector<double>& x, const std::vector<double>& f) {
  Fit r;
  double sxf = 0, sxx = 0, shf = 0, shh = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double h = std::pow(x[i], 1.5);
    sxf += x[i] * f[i];
    sxx += x[i] * x[i];
    shf += h * f[i];
    shh += h * h;
  }
  r.k_lin = sxx > 0 ? sxf / sxx : 0;
  r.c_hertz = shh > 0 ? shf / shh : 0;
  double el = 0, eh = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    el += std::pow(f[i] - r.k_lin * x[i], 2);
    eh += std::pow(f[i] - r.c_hertz * std::pow(x[i], 1.5), 2);
  }
  const double n = std::max<double>(1.0, static_cast<double>(x.size()));
  r.rms_lin = std::sqrt(el / n);
  r.rms_hertz = std::sqrt(eh / n);
  return r;
}

/// The contact law's parameters from --stiffness, --damping and --mu; false (with a message)
/// when one is out of its range.
bool contact_params(const teleop::CommandArgs& args, tc::TipContactParams& cp) {
  cp.stiffness_n_per_m = std::stod(args.option("--stiffness", "300"));
  cp.damping_ns_per_m = std::stod(args.option("--damping", "1"));
  cp.friction_static = std::stod(args.option("--mu", "0.5"));
  cp.friction_kinetic = 0.8 * cp.friction_static;
  if (!(cp.stiffness_n_per_m > 0.0 && cp.stiffness_n_per_m <= 1e6) ||
      !(cp.damping_ns_per_m >= 0.0 && cp.damping_ns_per_m <= 1e4) ||
      !(cp.friction_static >= 0.0 && cp.friction_static <= 10.0)) {
    std::cerr << "contact-force-curve: --stiffness must be in (0, 1e6] N/m (got "
              << cp.stiffness_n_per_m << "), --damping in [0, 1e4] N s/m (got "
              << cp.damping_ns_per_m << "), --mu in [0, 10] (got " << cp.friction_static << ")\n";
    return false;
  }
  return true;
}

/// One press's loading samples (deformation [m], vertical force [N]) and its peak force [N].
struct PressCurve {
  std::vector<double> xs, fs;
  double peak = 0.0;
};

/// One press at `speed` [m/s] from `tip`: the kinematic tip pressed to target_depth, held
/// 100 ms and withdrawn; a CSV row for every step from the first contact on.
PressCurve press_at(const teleop::sim::WorldModel& world, teleop::sim::WorldData& data,
                    teleop::sim::WorldCommand& cmd, teleop::sim::EventQueue& events,
                    Eigen::Vector3d tip, double speed, double dt, double tip_r, double target_depth,
                    teleop::CsvWriter& csv) {
  double t = 0.0, z_touch = NAN;
  int phase = 0, hold_steps = 0;
  PressCurve out;
  std::vector<double>& xs = out.xs;
  std::vector<double>& fs = out.fs;
  double& peak = out.peak;
  const int max_steps = static_cast<int>(4.0 * (target_depth + 0.02) / (speed * dt)) + 2000;
  for (int n = 0; n < max_steps; ++n) {
    // kinematic tip: press, hold 100 ms, withdraw
    Eigen::Vector3d vel = Eigen::Vector3d::Zero();
    if (phase == 0) vel.z() = -speed;
    if (phase == 2) vel.z() = speed;
    tip += vel * dt;
    cmd.position_m = tip;
    cmd.velocity_mps = vel;
    teleop::sim::world_step(world, data, cmd, dt, events);
    const tc::TipContactResult& res = data.bodies[0].last;
    if (res.in_contact && std::isnan(z_touch)) z_touch = res.entry_point_m.z() + tip_r;
    const double deformation = std::isnan(z_touch) ? 0.0 : std::max(0.0, z_touch - tip.z());
    const double deflection =
        res.in_contact ? std::max(0.0, res.entry_point_m.z() - res.contact_point_m.z()) : 0.0;
    if (res.in_contact || phase > 0 || !std::isnan(z_touch)) {
      csv.row({speed, static_cast<double>(phase), t, tip.z(), deformation, deflection,
               res.penetration_m, res.force_on_tip_n.norm(), res.force_on_tip_n.z(),
               res.in_contact ? 1.0 : 0.0, static_cast<double>(res.node_contacts),
               static_cast<double>(res.triangle)});
    }
    if (phase == 0 && res.in_contact) {
      xs.push_back(deformation);
      fs.push_back(res.force_on_tip_n.z());
    }
    peak = std::max(peak, res.force_on_tip_n.norm());
    if (phase == 0 && deformation >= target_depth) phase = 1;
    if (phase == 1 && ++hold_steps >= 100) phase = 2;
    t += dt;
    if (phase == 2 && !res.in_contact && tip.z() > z_touch + 0.005) break;
  }
  return out;
}

int run_contact_force_curve(const teleop::CommandArgs& args) {
  std::filesystem::create_directories(args.out_dir);
  const double dt = 1e-3;
  const double tip_r = 0.05;
  const double target_depth = 0.03;
  const std::vector<double> speeds =
      args.quick ? std::vector<double>{0.05, 0.2} : std::vector<double>{0.01, 0.05, 0.2};

  tc::TipContactParams cp;
  if (!contact_params(args, cp)) return 2;

  teleop::CsvWriter csv(
      (args.out_dir / "contact_force_curve.csv").string(),
      {"speed_mps", "phase", "t_s", "tip_z_m", "deformation_m", "surface_deflection_m",
       "penetration_m", "force_n", "force_z_n", "in_contact", "node_contacts", "triangle"});
  teleop::CsvWriter fits((args.out_dir / "contact_force_fit.csv").string(),
                         {"speed_mps", "k_lin_n_per_m", "rms_lin_n", "c_hertz_n_per_m1p5",
                          "estar_pa", "rms_hertz_n", "peak_force_n", "faults"});
  const double r_eff = 1.0 / (1.0 / tip_r + 1.0 / 0.25);

  teleop::Progress progress("contact-force-curve", static_cast<double>(speeds.size()), "speeds");
  for (const double speed : speeds) {
    df::DeformableParams params;  // the deform module's defaults: the paper's sphere
    const std::string integrator = args.option("--integrator", "");
    if (!integrator.empty()) params.integrator = df::parse_integrator_kind(integrator);
    teleop::sim::Plane floor;
    floor.id = 0;
    floor.name = "floor";
    // the world: a kinematic tool of radius tip_r, far above, and the sphere on the floor
    teleop::sim::ToolModel tool;
    tool.radius_m = tip_r;
    teleop::sim::WorldModel world =
        teleop::sim::tool_world_model(tool, Eigen::Vector3d(0.0, 0.0, 2.0), 1.0 / dt);
    teleop::sim::DeformableBodyModel& body = world.bodies.emplace_back();
    body.body = df::make_model(df::make_mesh_for(params), params, {floor});
    body.contact = cp;
    teleop::sim::WorldData data = teleop::sim::make_world_data(world);
    teleop::sim::EventQueue events;
    teleop::sim::WorldCommand cmd;
    cmd.kinematic = true;
    cmd.position_m = data.out.tip_position_m;
    // settle on the floor (the tip too far away to touch)
    for (int i = 0; i < 1500; ++i) teleop::sim::world_step(world, data, cmd, dt, events);
    const df::DeformableState& state = data.bodies[0].state;
    double top = -1e9;
    for (int i = 0; i < state.x.cols(); ++i) top = std::max(top, state.x(2, i));

    Eigen::Vector3d tip(0.0, 0.0, top + tip_r + 0.005);
    teleop::sim::place_tool(world, data, tip);
    const tc::TipMeshContact& contact = data.bodies[0].contact;
    const PressCurve curve =
        press_at(world, data, cmd, events, tip, speed, dt, tip_r, target_depth, csv);
    const std::vector<double>& xs = curve.xs;
    const std::vector<double>& fs = curve.fs;
    const double peak = curve.peak;
    const Fit fit = fit_laws(xs, fs);
    const double estar = fit.c_hertz / ((4.0 / 3.0) * std::sqrt(r_eff));
    fits.row({speed, fit.k_lin, fit.rms_lin, fit.c_hertz, estar, fit.rms_hertz, peak,
              static_cast<double>(contact.fault_count() + state.fault_count)});
    std::printf(
        "speed %.3f m/s: peak %.2f N; linear k = %.1f N/m (rms %.3f N); Hertz c = %.1f N/m^1.5 "
        "(E* = %.0f Pa, rms %.3f N); closer to %s\n",
        speed, peak, fit.k_lin, fit.rms_lin, fit.c_hertz, estar, fit.rms_hertz,
        fit.rms_lin <= fit.rms_hertz ? "linear" : "Hertz");
    progress.add();
  }
  progress.finish();
  csv.flush();
  fits.flush();
  if (!args.no_chart) {
    teleop::run_chart_script("contact_force_curve.py", {args.out_dir.string()});
  }
  return 0;
}

}  // namespace

TELEOP_REGISTER_COMMAND(experiments, "contact-force-curve",
                        "tip pressed 30 mm into the deformable sphere and withdrawn at several "
                        "speeds: force vs deformation (paper Figs. 16-17) with linear and Hertz "
                        "fits",
                        run_contact_force_curve,
                        teleop::number_option("--stiffness", 0.0, 1e6, "tip contact [N/m], > 0"),
                        teleop::number_option("--damping", 0.0, 1e4, "tip contact [N s/m]"),
                        teleop::number_option("--mu", 0.0, 10.0, "static friction [-]"),
                        teleop::text_option("--integrator", "integrator of the sphere"));

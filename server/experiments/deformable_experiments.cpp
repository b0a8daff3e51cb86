// The paper's experiments on the elastic sphere (Figs. 4-7, 14-16, experiment 2 without robot):
//   teleop_experiment sphere-zero-g      --out DIR [--quick] [--no-chart] [--level L] [--dt S]
//   teleop_experiment navier-free-vertex --out DIR ...
//   teleop_experiment navier-held-vertex --out DIR ...
//   teleop_experiment sphere-gravity     --out DIR ... [--model mass_spring] [--integrator ...]
// Each writes a CSV and a PNG made from it by tests/charts/deformable_*.py, prints a summary and
// returns 0 only if the physical claim holds (shape recovered, body settled, ...).
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/util/csv.hpp"
#include "common/util/registry.hpp"
#include "server/deformable/deformable.hpp"

namespace {

using namespace teleop::sim::deformable;
using teleop::CsvWriter;

// The options' values were checked against their ranges (the registrations at the end of this
// file) before the command runs.
int option_int(const teleop::CommandArgs& a, const std::string& key, int fallback) {
  const std::string v = a.option(key, "");
  return v.empty() ? fallback : std::stoi(v);
}

double option_double(const teleop::CommandArgs& a, const std::string& key, double fallback) {
  const std::string v = a.option(key, "");
  return v.empty() ? fallback : std::stod(v);
}

/// The paper's sphere: radius 0.25 m centred at the origin, zero gravity, never sleeping.
DeformableParams zero_g_params(ModelKind model, int level) {
  DeformableParams p;
  p.model = model;
  p.level = level;
  p.centre_m.setZero();
  p.gravity_mps2.setZero();
  if (model != ModelKind::kMassSpring) p.radial_stiffness_n_per_m3 = 0.0;
  p.sleep_time_s = 1e9;
  return p;
}

/// The node with the largest z: the "surface point" that is disturbed.
int top_node(const DeformableModel& m) {
  int best = 0;
  for (int i = 1; i < m.node_count; ++i) {
    if (m.mesh.vertices(2, i) > m.mesh.vertices(2, best)) best = i;
  }
  return best;
}

/// Largest deviation from the rest shape with translation removed [m].
double shape_error(const DeformableModel& m, const DeformableState& s) {
  const Eigen::Vector3d c = centroid(m, s);
  const Eigen::Vector3d c0 =
      (m.mesh.vertices * m.mass_kg + m.centre_mass_kg * m.rest_centre_m) / m.total_mass_kg;
  double worst = 0.0;
  for (int i = 0; i < m.node_count; ++i) {
    worst = std::max(worst, ((s.x.col(i) - c) - (m.mesh.vertices.col(i) - c0)).norm());
  }
  return worst;
}

void chart(const teleop::CommandArgs& a, const std::string& script, const std::string& csv,
           const std::string& png) {
  if (a.no_chart) return;
  teleop::run_chart_script(script, {(a.out_dir / csv).string(), (a.out_dir / png).string()});
}

// ---------------------------------------------------------------------------------------------
// Experiment 1 (Figs. 14-16): one surface point 5 mm out, released, zero gravity.
int sphere_zero_g(const teleop::CommandArgs& a) {
  const int level = option_int(a, "--level", a.quick ? 2 : 4);
  const double dt = option_double(a, "--dt", 2.5e-4);
  const double t_end = a.quick ? 0.3 : 1.0;
  const double delta = 0.005;
  CsvWriter csv((a.out_dir / "sphere_zero_g.csv").string(),
                {"model", "t_s", "radius_m", "deformation_m", "force_radial_n", "kinetic_j",
                 "shape_error_m"});
  int failures = 0;
  teleop::Progress progress("sphere-zero-g", 3.0 * (std::lround(t_end / dt) + 1), "steps");
  for (ModelKind kind :
       {ModelKind::kMassSpring, ModelKind::kNavierLinear, ModelKind::kNavierCorotational}) {
    const DeformableParams p = zero_g_params(kind, level);
    const DeformableModel m = make_model(make_mesh_for(p), p);
    DeformableState s = make_state(m);
    const int i = top_node(m);
    const double r0 = (m.mesh.vertices.col(i) - m.rest_centre_m).norm();
    s.x.col(i) += delta * (s.x.col(i) - m.rest_centre_m).normalized();
    const double e_start = shape_error(m, s);
    Eigen::Matrix3Xd f;
    const int steps = static_cast<int>(std::lround(t_end / dt));
    const int every = 1;
    for (int k = 0; k <= steps; ++k) {
      if (k % every == 0) {
        internal_forces(m, s, f);
        const Eigen::Vector3d c = body_centre(m, s);
        const Eigen::Vector3d u = (s.x.col(i) - c).normalized();
        const double r = (s.x.col(i) - c).norm();
        csv.row_text({to_string(kind), teleop::format_number(s.sim_time_s),
                      teleop::format_number(r), teleop::format_number(r - r0),
                      teleop::format_number(f.col(i).dot(u)),
                      teleop::format_number(kinetic_energy(m, s)),
                      teleop::format_number(shape_error(m, s))});
      }
      if (k < steps) step(m, s, dt, nullptr);
      progress.add();
    }
    const double e_end = shape_error(m, s);
    const bool ok = e_end < 0.1 * e_start && s.fault_count == 0;
    failures += ok ? 0 : 1;
    std::printf(
        "sphere-zero-g %-20s level %d dt %.2g s: shape error %.3g mm -> %.3g mm after %.2g s%s\n",
        to_string(kind), level, dt, 1e3 * e_start, 1e3 * e_end, t_end, ok ? "" : "  NOT RECOVERED");
  }
  progress.finish();
  csv.flush();
  chart(a, "deformable_zero_g.py", "sphere_zero_g.csv", "sphere_zero_g.png");
  return failures == 0 ? 0 : 1;
}

// ---------------------------------------------------------------------------------------------
// Figs. 4-5: a vertex pushed in and released (linear-strain Navier), phase graph.
int navier_free_vertex(const teleop::CommandArgs& a) {
  const int level = option_int(a, "--level", a.quick ? 2 : 4);
  const double dt = option_double(a, "--dt", 2.5e-4);
  const double t_end = a.quick ? 0.2 : 0.6;
  const double push = 0.005;
  CsvWriter csv((a.out_dir / "navier_free_vertex.csv").string(),
                {"variant", "t_s", "displacement_m", "velocity_mps", "force_radial_n"});
  int failures = 0;
  struct Variant {
    const char* name;
    ModelKind kind;
    bool damped;
  };
  teleop::Progress progress("navier-free-vertex", 3.0 * (std::lround(t_end / dt) + 1), "steps");
  for (const Variant& var :
       {Variant{"linear_damped", ModelKind::kNavierLinear, true},
        Variant{"linear_undamped", ModelKind::kNavierLinear, false},
        Variant{"corotational_damped", ModelKind::kNavierCorotational, true}}) {
    DeformableParams p = zero_g_params(var.kind, level);
    if (!var.damped) {
      p.stiffness_damping_s = 0.0;
      p.mass_damping_per_s = 0.0;
      p.radial_damping_s = 0.0;
    }
    const DeformableModel m = make_model(make_mesh_for(p), p);
    DeformableState s = make_state(m);
    const int i = top_node(m);
    const Eigen::Vector3d u = (m.mesh.vertices.col(i) - m.rest_centre_m).normalized();
    s.x.col(i) -= push * u;
    Eigen::Matrix3Xd f;
    const int steps = static_cast<int>(std::lround(t_end / dt));
    double max_late = 0.0;
    for (int k = 0; k <= steps; ++k) {
      const Eigen::Vector3d c = centroid(m, s);
      const Eigen::Vector3d c0 = m.rest_centre_m;
      const double disp = (s.x.col(i) - c).dot(u) - (m.mesh.vertices.col(i) - c0).dot(u);
      const double vel = (s.v.col(i)).dot(u);
      if (k > steps / 2) max_late = std::max(max_late, std::fabs(disp));
      internal_forces(m, s, f);
      csv.row_text({var.name, teleop::format_number(s.sim_time_s), teleop::format_number(disp),
                    teleop::format_number(vel), teleop::format_number(f.col(i).dot(u))});
      if (k < steps) step(m, s, dt, nullptr);
      progress.add();
    }
    // damped: the vertex spirals into its rest position; undamped: it keeps oscillating
    const bool ok = s.fault_count == 0 && (var.damped ? max_late < 0.2 * push : max_late > 1e-5);
    failures += ok ? 0 : 1;
    std::printf("navier-free-vertex %-20s: |displacement| in the second half <= %.3g mm%s\n",
                var.name, 1e3 * max_late, ok ? "" : "  UNEXPECTED");
  }
  progress.finish();
  csv.flush();
  chart(a, "deformable_navier_free.py", "navier_free_vertex.csv", "navier_free_vertex.png");
  return failures == 0 ? 0 : 1;
}

// ---------------------------------------------------------------------------------------------
// Figs. 6-7: a vertex held 5 mm inside at all times (the opposite one fixed); distance and force
// of a neighbour.
int navier_held_vertex(const teleop::CommandArgs& a) {
  const int level = option_int(a, "--level", a.quick ? 2 : 4);
  const double dt = option_double(a, "--dt", 5e-4);
  const double t_end = a.quick ? 0.5 : 2.0;
  const double push = 0.005;
  CsvWriter csv((a.out_dir / "navier_held_vertex.csv").string(),
                {"model", "t_s", "neighbour_radius_m", "neighbour_displacement_m",
                 "neighbour_force_n", "held_force_n"});
  int failures = 0;
  teleop::Progress progress("navier-held-vertex", 2.0 * (std::lround(t_end / dt) + 1), "steps");
  for (ModelKind kind : {ModelKind::kNavierLinear, ModelKind::kNavierCorotational}) {
    const DeformableParams p = zero_g_params(kind, level);
    const DeformableModel m = make_model(make_mesh_for(p), p);
    DeformableState s = make_state(m);
    const int i = top_node(m);
    const int j = m.mesh.vertex_neighbours[static_cast<std::size_t>(
        m.mesh.vertex_neighbour_offsets[static_cast<std::size_t>(i)])];
    const Eigen::Vector3d u = (m.mesh.vertices.col(i) - m.rest_centre_m).normalized();
    const double rj0 = (m.mesh.vertices.col(j) - m.rest_centre_m).norm();
    s.pinned[static_cast<std::size_t>(i)] = 1;
    s.pin_target.col(i) = m.mesh.vertices.col(i) - push * u;
    // the opposite node is held at rest: the sphere rests on a support. (Holding only one node
    // of a free body in zero gravity just translates the whole body by 5 mm: no dent.)
    int bottom = 0;
    for (int k = 1; k < m.node_count; ++k) {
      if (m.mesh.vertices(2, k) < m.mesh.vertices(2, bottom)) bottom = k;
    }
    s.pinned[static_cast<std::size_t>(bottom)] = 1;
    s.pin_target.col(bottom) = m.mesh.vertices.col(bottom);
    Eigen::Matrix3Xd f;
    const int steps = static_cast<int>(std::lround(t_end / dt));
    const int every = std::max(1, static_cast<int>(std::lround(5e-4 / dt)));
    double final_disp = 0.0;
    for (int k = 0; k <= steps; ++k) {
      if (k % every == 0) {
        internal_forces(m, s, f);
        const double rj = (s.x.col(j) - m.rest_centre_m).norm();
        const Eigen::Vector3d uj = (s.x.col(j) - m.rest_centre_m).normalized();
        final_disp = rj - rj0;
        csv.row_text({to_string(kind), teleop::format_number(s.sim_time_s),
                      teleop::format_number(rj), teleop::format_number(rj - rj0),
                      teleop::format_number(f.col(j).dot(uj)),
                      teleop::format_number(-f.col(i).dot(u))});
      }
      if (k < steps) step(m, s, dt, nullptr);
      progress.add();
    }
    // the neighbour is dragged inward and stays there while the vertex is held
    const bool ok = s.fault_count == 0 && final_disp < -0.05 * push;
    failures += ok ? 0 : 1;
    std::printf("navier-held-vertex %-20s: neighbour %d displaced %.3g mm at t = %.2g s%s\n",
                to_string(kind), j, 1e3 * final_disp, t_end, ok ? "" : "  UNEXPECTED");
  }
  progress.finish();
  csv.flush();
  chart(a, "deformable_navier_held.py", "navier_held_vertex.csv", "navier_held_vertex.png");
  return failures == 0 ? 0 : 1;
}

// ---------------------------------------------------------------------------------------------
// Experiment 2 without the robot: dropped between walls onto the floor, it settles at rest.
int sphere_gravity(const teleop::CommandArgs& a) {
  DeformableParams p;
  p.level = option_int(a, "--level", a.quick ? 2 : 4);
  p.model = parse_model_kind(a.option("--model", "mass_spring"));
  p.integrator = parse_integrator_kind(a.option("--integrator", "symplectic_euler"));
  if (p.model != ModelKind::kMassSpring) p.radial_stiffness_n_per_m3 = 0.0;
  const double dt = option_double(a, "--dt", 1e-3);
  const double drop = 0.15;
  p.centre_m = Eigen::Vector3d(0.02, 0.0, p.radius_m + drop);  // 1 cm from the +x wall
  const double t_end = a.quick ? 5.0 : 6.0;
  std::vector<teleop::sim::Plane> planes(5);
  planes[0].name = "floor";
  const char* names[4] = {"wall+x", "wall-x", "wall+y", "wall-y"};
  const Eigen::Vector3d normals[4] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}};
  for (int k = 0; k < 4; ++k) {
    planes[static_cast<std::size_t>(k + 1)].name = names[k];
    planes[static_cast<std::size_t>(k + 1)].normal = normals[k];
    planes[static_cast<std::size_t>(k + 1)].offset_m = -0.28;  // walls at |x|, |y| = 0.28 m
  }
  const DeformableModel m = make_model(make_mesh_for(p), p, planes);
  DeformableState s = make_state(m);
  teleop::sim::EventQueue events;
  CsvWriter csv((a.out_dir / "sphere_gravity.csv").string(),
                {"t_s", "centroid_x_m", "centroid_z_m", "lowest_z_m", "kinetic_j",
                 "plane_force_z_n", "plane_force_x_n", "contacts", "sleeping"});
  const int steps = static_cast<int>(std::lround(t_end / dt));
  const int every = std::max(1, static_cast<int>(std::lround(2e-3 / dt)));
  int sleeping_steps = 0;
  teleop::Progress progress("sphere-gravity", steps + 1.0, "steps");
  for (int k = 0; k <= steps; ++k) {
    if (k % every == 0) {
      const Eigen::Vector3d c = centroid(m, s);
      csv.row({s.sim_time_s, c.x(), c.z(), s.x.row(2).minCoeff(), kinetic_energy(m, s),
               s.plane_force_n.z(), s.plane_force_n.x(), static_cast<double>(s.contact_count),
               s.sleeping ? 1.0 : 0.0});
    }
    if (k < steps && step(m, s, dt, &events) == StepStatus::kSleeping) ++sleeping_steps;
    progress.add();
  }
  progress.finish();
  csv.flush();
  const Eigen::Vector3d c = centroid(m, s);
  const double weight = m.total_mass_kg * 9.81;
  const bool ok = s.fault_count == 0 && s.sleeping && c.z() > 0.8 * p.radius_m &&
                  c.z() < p.radius_m && s.x.row(2).minCoeff() > -0.01;
  std::printf(
      "sphere-gravity %s/%s level %d dt %.2g s: centroid z %.4f m (rest radius %.3f), lowest "
      "node z %.2g mm, floor force %.2f N (weight %.2f N), sleeping %s (%d steps skipped), "
      "faults %llu%s\n",
      to_string(p.model), to_string(p.integrator), p.level, dt, c.z(), p.radius_m,
      1e3 * s.x.row(2).minCoeff(), s.plane_force_n.z(), weight, s.sleeping ? "yes" : "no",
      sleeping_steps, static_cast<unsigned long long>(s.fault_count), ok ? "" : "  NOT SETTLED");
  chart(a, "deformable_gravity.py", "sphere_gravity.csv", "sphere_gravity.png");
  return ok ? 0 : 1;
}

TELEOP_REGISTER_COMMAND(experiments, "sphere-zero-g",
                        "experiment 1 (Figs. 14-16): a surface point 5 mm out, released, g = 0",
                        sphere_zero_g, teleop::integer_option("--level", 0, 6, "icosphere level"),
                        teleop::number_option("--dt", 1e-6, 1e-2, "time step [s]"));
TELEOP_REGISTER_COMMAND(experiments, "navier-free-vertex",
                        "Figs. 4-5: Navier sphere, a vertex pushed in and released (phase graph)",
                        navier_free_vertex,
                        teleop::integer_option("--level", 0, 6, "icosphere level"),
                        teleop::number_option("--dt", 1e-6, 1e-2, "time step [s]"));
TELEOP_REGISTER_COMMAND(experiments, "navier-held-vertex",
                        "Figs. 6-7: Navier sphere, a vertex held in; a neighbour's distance, force",
                        navier_held_vertex,
                        teleop::integer_option("--level", 0, 6, "icosphere level"),
                        teleop::number_option("--dt", 1e-6, 1e-2, "time step [s]"));
TELEOP_REGISTER_COMMAND(experiments, "sphere-gravity",
                        "experiment 2 without robot: dropped between walls, settles on the floor",
                        sphere_gravity, teleop::integer_option("--level", 0, 6, "icosphere level"),
                        teleop::number_option("--dt", 1e-6, 1e-2, "time step [s]"),
                        teleop::text_option("--model", "deformable model"),
                        teleop::text_option("--integrator", "integrator"));

}  // namespace

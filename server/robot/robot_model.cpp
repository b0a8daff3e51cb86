#include "server/robot/robot_model.hpp"

#include "server/robot/ik_params.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

#include "common/mesh/tri_mesh.hpp"
#include "common/util/data_dir.hpp"

namespace teleop::sim::robot {

namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Vector3d vec3(const config::Node& n, const std::string& key, double lo, double hi) {
  const std::vector<double> v = n.numbers(key, 3, lo, hi);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

Eigen::Vector3d vec3_or(const config::Node& n, const std::string& key,
                        const Eigen::Vector3d& fallback, double lo, double hi) {
  if (!n.has(key)) return fallback;
  return vec3(n, key, lo, hi);
}

Eigen::Matrix3d rpy_matrix(const Eigen::Vector3d& rpy_rad) {
  return (Eigen::AngleAxisd(rpy_rad.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy_rad.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy_rad.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// Reads a symmetric inertia tensor given as [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] and checks that it
// is physically possible (positive principal moments obeying the triangle inequality).
Eigen::Matrix3d inertia(const config::Node& n, const std::string& key) {
  if (!n.has(key)) n.fail(key, "is required but missing");
  const config::Node c = n.at(key);
  if (!c.is_sequence() || (c.size() != 3 && c.size() != 6)) {
    n.fail(key,
           "must be a list of 3 ([Ixx, Iyy, Izz]) or 6 ([Ixx, Iyy, Izz, Ixy, Ixz, Iyz]) "
           "numbers [kg m^2]");
  }
  const std::vector<double> v = n.numbers(key, c.size(), -1e4, 1e4);
  Eigen::Matrix3d i = Eigen::Matrix3d::Zero();
  i(0, 0) = v[0];
  i(1, 1) = v[1];
  i(2, 2) = v[2];
  if (v.size() == 6) {
    i(0, 1) = i(1, 0) = v[3];
    i(0, 2) = i(2, 0) = v[4];
    i(1, 2) = i(2, 1) = v[5];
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(i);
  const Eigen::Vector3d& p = es.eigenvalues();
  const double tol = 1e-12 + 1e-9 * p.cwiseAbs().maxCoeff();
  if (p.minCoeff() <= 0.0) {
    n.fail(key, "principal moments must be > 0 [kg m^2]; the smallest is " +
                    std::to_string(p.minCoeff()));
  }
  if (p(0) + p(1) < p(2) - tol || p(0) + p(2) < p(1) - tol || p(1) + p(2) < p(0) - tol) {
    n.fail(key,
           "principal moments violate the triangle inequality (A + B >= C): not a rigid "
           "body");
  }
  return i;
}

// Axis-aligned bounding box of every vertex of a mesh file, scaled [m].
bool mesh_bounds(const std::string& file, double scale, Eigen::Vector3d& lo, Eigen::Vector3d& hi,
                 std::string& error) {
  try {
    mesh::check_mesh_file(file);
  } catch (const mesh::MeshError& e) {
    error = e.what();
    return false;
  }
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(file, aiProcess_Triangulate);
  if (!scene || !scene->mRootNode) {
    error = importer.GetErrorString();
    return false;
  }
  lo.setConstant(std::numeric_limits<double>::infinity());
  hi = -lo;
  std::size_t count = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    for (unsigned k = 0; k < mesh->mNumVertices; ++k) {
      const Eigen::Vector3d p(mesh->mVertices[k].x, mesh->mVertices[k].y, mesh->mVertices[k].z);
      if (!p.allFinite()) {
        error = "vertex " + std::to_string(k) + " has a coordinate that is not a finite number";
        return false;
      }
      lo = lo.cwiseMin(scale * p);
      hi = hi.cwiseMax(scale * p);
      ++count;
    }
  }
  if (count == 0) {
    error = "the mesh has no vertices";
    return false;
  }
  return true;
}

LinkModel load_link(const config::Node& ln, int index, const std::filesystem::path& dir) {
  ln.reject_unknown_keys(
      {"name", "dh", "mass_kg", "com_m", "inertia_kgm2", "box", "mesh", "joint"});
  LinkModel l;
  l.name = ln.string_or("name", "link" + std::to_string(index + 1));

  const config::Node dh = ln.at("dh");
  dh.reject_unknown_keys({"a_m", "alpha_deg", "d_m", "theta_offset_deg"});
  l.dh.a_m = dh.number_or("a_m", 0.0, -5.0, 5.0);
  l.dh.alpha_rad = dh.number_or("alpha_deg", 0.0, -360.0, 360.0) * kDeg;
  l.dh.d_m = dh.number_or("d_m", 0.0, -5.0, 5.0);
  l.dh.theta_offset_rad = dh.number_or("theta_offset_deg", 0.0, -360.0, 360.0) * kDeg;

  l.mass_kg = ln.number("mass_kg", 1e-4, 1e4);
  l.com_m = vec3_or(ln, "com_m", Eigen::Vector3d::Zero(), -5.0, 5.0);
  l.inertia_kgm2 = inertia(ln, "inertia_kgm2");

  bool have_box = false;
  if (ln.has("box")) {
    const config::Node b = ln.at("box");
    b.reject_unknown_keys({"size_m", "center_m"});
    l.box_size_m = vec3(b, "size_m", 1e-3, 5.0);
    l.box_center_m = vec3_or(b, "center_m", Eigen::Vector3d::Zero(), -5.0, 5.0);
    have_box = true;
  }
  if (ln.has("mesh")) {
    const config::Node m = ln.at("mesh");
    m.reject_unknown_keys({"file", "scale"});
    std::filesystem::path f = m.string("file");
    if (f.is_relative()) f = dir / f;
    const double scale = m.number_or("scale", 1.0, 1e-6, 1e6);
    Eigen::Vector3d lo, hi;
    std::string error;
    if (!mesh_bounds(f.string(), scale, lo, hi, error)) {
      m.fail("file", "cannot load mesh '" + f.string() + "': " + error);
    }
    l.mesh_file = f.string();
    if (!have_box) {
      l.box_size_m = (hi - lo).cwiseMax(Eigen::Vector3d::Constant(1e-3));
      l.box_center_m = 0.5 * (hi + lo);
      have_box = true;
    }
  }
  if (!have_box) ln.fail("box", "is required (or a mesh from which to take it) but missing");

  const config::Node j = ln.at("joint");
  j.reject_unknown_keys({"limits_deg", "max_speed_radps", "torque_limit_nm", "viscous_nms_per_rad",
                         "coulomb_nm", "kp_nm_per_rad", "kd_nms_per_rad"});
  const std::vector<double> lim = j.numbers("limits_deg", 2, -720.0, 720.0);
  if (!(lim[0] < lim[1])) {
    j.fail("limits_deg", "lower limit " + std::to_string(lim[0]) +
                             " must be below the upper limit " + std::to_string(lim[1]));
  }
  l.q_min_rad = lim[0] * kDeg;
  l.q_max_rad = lim[1] * kDeg;
  l.qd_max_radps = j.number_or("max_speed_radps", 3.0, 1e-3, 100.0);
  l.torque_limit_nm = j.number("torque_limit_nm", 1e-3, 1e5);
  l.viscous_nms_per_rad = j.number_or("viscous_nms_per_rad", 0.0, 0.0, 1e4);
  l.coulomb_nm = j.number_or("coulomb_nm", 0.0, 0.0, 1e4);
  l.kp_nm_per_rad = j.number("kp_nm_per_rad", 0.0, 1e7);
  l.kd_nms_per_rad = j.number("kd_nms_per_rad", 1e-6, 1e6);
  return l;
}

}  // namespace

void combine_masses(double m1_kg, const Eigen::Vector3d& c1_m, const Eigen::Matrix3d& i1_kgm2,
                    double m2_kg, const Eigen::Vector3d& c2_m, const Eigen::Matrix3d& i2_kgm2,
                    double& m_kg, Eigen::Vector3d& c_m, Eigen::Matrix3d& i_kgm2) {
  m_kg = m1_kg + m2_kg;
  c_m = (m1_kg * c1_m + m2_kg * c2_m) / m_kg;
  // parallel axis: I_c = I_own + m (|r|^2 1 - r r^T), r from the new COM
  auto shift = [](double m, const Eigen::Vector3d& r) -> Eigen::Matrix3d {
    return m * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
  };
  i_kgm2 = i1_kgm2 + shift(m1_kg, c1_m - c_m) + i2_kgm2 + shift(m2_kg, c2_m - c_m);
}

/// Each joint's friction compensation at its speed limit must leave torque for the PD: the
/// feed-forward f (b qd_max + Fc) is clamped to the torque limit and the PD row gets only what
/// is left, so a joint whose compensation reaches the limit is driven open loop.
void check_friction_compensation(const config::Node& links, const RobotModel& m) {
  const double fc = m.ik.friction_compensation;
  for (int i = 0; i < m.n; ++i) {
    const LinkModel& l = m.links[i];
    const double tau = fc * (l.viscous_nms_per_rad * l.qd_max_radps + l.coulomb_nm);
    if (tau < kMaxFrictionShare * l.torque_limit_nm) continue;
    const config::Node j = links.at(static_cast<std::size_t>(i)).at("joint");
    const bool viscous = l.viscous_nms_per_rad * l.qd_max_radps >= l.coulomb_nm;
    std::ostringstream os;
    os << "value " << (viscous ? l.viscous_nms_per_rad : l.coulomb_nm)
       << ": the friction compensation at the joint's speed limit, ik.friction_compensation " << fc
       << " x (viscous_nms_per_rad " << l.viscous_nms_per_rad << " x max_speed_radps "
       << l.qd_max_radps << " + coulomb_nm " << l.coulomb_nm << ") = " << tau
       << " N m, must stay below " << kMaxFrictionShare << " of torque_limit_nm "
       << l.torque_limit_nm << " (the PD gets only the torque the feed-forward leaves)";
    j.fail(viscous ? "viscous_nms_per_rad" : "coulomb_nm", os.str());
  }
}

namespace {

/// The `ik:` mapping over the defaults in `p`, each field checked against its range.
void load_ik_params(const config::Node& k, IkParams& p) {
  k.reject_unknown_keys(config::field_keys(ik_field_params()));
  config::read_fields(k, ik_field_params(), p);
}

}  // namespace

RobotModel load_robot_model(const config::Node& rn) {
  if (!rn.is_map()) {
    throw config::ConfigError(rn.file() + ": field '" + rn.path() + "' must be a mapping");
  }
  rn.reject_unknown_keys(
      {"name", "source", "base", "gravity_mps2", "tip", "home_deg", "ik", "links"});
  const std::filesystem::path dir = std::filesystem::path(rn.file()).parent_path();
  RobotModel m;
  m.name = rn.string_or("name", "robot");
  m.source = rn.string_or("source", "");

  if (rn.has("base")) {
    const config::Node b = rn.at("base");
    b.reject_unknown_keys({"position_m", "rpy_deg"});
    m.base.translation() = vec3_or(b, "position_m", Eigen::Vector3d::Zero(), -100.0, 100.0);
    m.base.linear() =
        rpy_matrix(vec3_or(b, "rpy_deg", Eigen::Vector3d::Zero(), -360.0, 360.0) * kDeg);
  }
  m.gravity_mps2 = vec3_or(rn, "gravity_mps2", m.gravity_mps2, -100.0, 100.0);

  const config::Node links = rn.at("links");
  if (!links.is_sequence() || links.size() < 1 || links.size() > kMaxJoints) {
    rn.fail("links", "must be a list of 1 to " + std::to_string(kMaxJoints) + " links; it has " +
                         std::to_string(links.size()));
  }
  m.n = static_cast<int>(links.size());
  for (int i = 0; i < m.n; ++i) m.links[i] = load_link(links.at(i), i, dir);

  const config::Node tip = rn.at("tip");
  tip.reject_unknown_keys({"radius_m", "mass_kg", "offset_m"});
  m.tip_radius_m = tip.number("radius_m", 1e-3, 1.0);
  m.tip_mass_kg = tip.number_or("mass_kg", 0.0, 0.0, 100.0);
  m.tool_offset_m = vec3_or(tip, "offset_m", Eigen::Vector3d::Zero(), -2.0, 2.0);
  if (m.tip_mass_kg > 0.0) {
    LinkModel& last = m.links[m.n - 1];
    const Eigen::Matrix3d i_tip = 0.4 * m.tip_mass_kg * m.tip_radius_m * m.tip_radius_m *
                                  Eigen::Matrix3d::Identity();  // solid sphere
    combine_masses(last.mass_kg, last.com_m, last.inertia_kgm2, m.tip_mass_kg, m.tool_offset_m,
                   i_tip, last.mass_kg, last.com_m, last.inertia_kgm2);
  }

  if (rn.has("ik")) load_ik_params(rn.at("ik"), m.ik);

  m.q_home.setZero(m.n);
  if (rn.has("home_deg")) {
    const std::vector<double> h = rn.numbers("home_deg", m.n, -720.0, 720.0);
    for (int i = 0; i < m.n; ++i) {
      const double q = h[i] * kDeg;
      if (q < m.links[i].q_min_rad || q > m.links[i].q_max_rad) {
        rn.fail("home_deg",
                "joint " + std::to_string(i + 1) + " value " + std::to_string(h[i]) +
                    " is outside its limits " +
                    config::range_text(m.links[i].q_min_rad / kDeg, m.links[i].q_max_rad / kDeg));
      }
      m.q_home(i) = q;
    }
  } else {
    for (int i = 0; i < m.n; ++i)
      m.q_home(i) = std::clamp(0.0, m.links[i].q_min_rad, m.links[i].q_max_rad);
  }
  check_friction_compensation(links, m);
  return m;
}

RobotModel load_robot_model_file(const std::string& file) {
  const config::Node root = config::Node::load_file(file);
  return load_robot_model(root.at("robot"));
}

std::string default_robot_scene_path() { return data_path("scenes/robot_puma560.yaml"); }

}  // namespace teleop::sim::robot

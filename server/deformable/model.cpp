// Building the deformable model (masses, springs, Navier coefficients) and its state.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <utility>
#include <vector>

#include "server/deformable/deformable.hpp"
#include "server/deformable/fem.hpp"
#include "server/deformable/material.hpp"

namespace teleop::sim::deformable {

namespace {

[[noreturn]] void bad(const std::string& what) {
  throw config::ConfigError("deformable parameters: " + what);
}

void check_range(const char* name, double v, double lo, double hi) {
  if (!(v >= lo && v <= hi)) {
    bad(std::string(name) + " = " + std::to_string(v) + " is outside " +
        config::range_text(lo, hi));
  }
}

// Kernel simd: every node's neighbours (ascending), padded to the largest valence with the node
// itself at k = 0, slot-major so that a vector of consecutive nodes reads consecutive entries.
void build_simd_tables(DeformableModel& m) {
  const int n = m.node_count;
  const auto& off = m.node_edge_offsets;
  int width = 0;
  for (int i = 0; i < n; ++i) {
    width =
        std::max(width, off[static_cast<std::size_t>(i) + 1] - off[static_cast<std::size_t>(i)]);
  }
  const int stride = (n + 15) / 16 * 16;
  m.simd_width = width;
  m.simd_stride = stride;
  const std::size_t total = static_cast<std::size_t>(width) * static_cast<std::size_t>(stride);
  m.simd_neighbour.assign(total, 0);
  m.simd_k.assign(total, 0.0f);
  m.simd_rest.assign(total, 0.0f);
  m.simd_radial_k.assign(static_cast<std::size_t>(stride), 0.0f);
  m.simd_radial_rest.assign(static_cast<std::size_t>(stride), 0.0f);
  m.simd_dof_mass.resize(3 * static_cast<std::size_t>(n));
  m.simd_dof_inv_mass.resize(3 * static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      m.simd_dof_mass[static_cast<std::size_t>(3 * i + c)] = m.mass_kg(i);
      m.simd_dof_inv_mass[static_cast<std::size_t>(3 * i + c)] = m.inv_mass(i);
    }
  }
  std::vector<std::pair<int, int>> ring;  // (neighbour, edge)
  for (int i = 0; i < stride; ++i) {
    ring.clear();
    if (i < n) {
      for (int k = off[static_cast<std::size_t>(i)]; k < off[static_cast<std::size_t>(i) + 1];
           ++k) {
        const int code = m.node_edges[static_cast<std::size_t>(k)];
        const int e = code >= 0 ? code : ~code;
        ring.emplace_back(code >= 0 ? m.edges(1, e) : m.edges(0, e), e);
      }
      std::sort(ring.begin(), ring.end());
      m.simd_radial_k[static_cast<std::size_t>(i)] = static_cast<float>(m.radial_k(i));
      m.simd_radial_rest[static_cast<std::size_t>(i)] = static_cast<float>(m.radial_rest_m(i));
    }
    for (int slot = 0; slot < width; ++slot) {
      const std::size_t o = static_cast<std::size_t>(slot) * static_cast<std::size_t>(stride) +
                            static_cast<std::size_t>(i);
      if (slot < static_cast<int>(ring.size())) {
        const int e = ring[static_cast<std::size_t>(slot)].second;
        m.simd_neighbour[o] = 8 * ring[static_cast<std::size_t>(slot)].first;
        m.simd_k[o] = static_cast<float>(m.edge_k_iso(e));
        m.simd_rest[o] = static_cast<float>(m.rest_length_m(e));
      } else {
        m.simd_neighbour[o] = 8 * i;  // itself: zero length, k = 0, no force
      }
    }
  }
}

// Rejects parameters out of range, a kernel the model and integrator cannot use, more than 8
// planes and a mesh without adjacency tables or not a closed manifold.
void check_inputs(const teleop::mesh::TriMesh& mesh, const DeformableParams& params,
                  const std::vector<Plane>& planes) {
  check_range("mass_kg", params.mass_kg, 1e-6, 1e6);
  check_range("density_kg_per_m3", params.density_kg_per_m3, 0.0, 1e5);
  check_range("centre_mass_fraction", params.centre_mass_fraction, 0.01, 0.9);
  check_range("edge_stiffness_n_per_m", params.edge_stiffness_n_per_m, 0.0, 1e9);
  check_range("radial_stiffness_n_per_m3", params.radial_stiffness_n_per_m3, 0.0, 1e12);
  check_range("youngs_modulus_pa", params.youngs_modulus_pa, 1e-3, 1e12);
  check_range("poisson_ratio", params.poisson_ratio, 0.0, 0.49);
  check_range("stiffness_damping_s", params.stiffness_damping_s, 0.0, 1.0);
  check_range("radial_damping_s", params.radial_damping_s, 0.0, 1.0);
  check_range("mass_damping_per_s", params.mass_damping_per_s, 0.0, 1e4);
  check_range("contact_frequency_rad_per_s", params.contact_frequency_rad_per_s, 0.0, 1e7);
  check_range("contact_damping_ratio", params.contact_damping_ratio, 0.0, 100.0);
  check_range("cg_max_iterations", params.cg_max_iterations, 1, 1e5);
  check_range("max_speed_mps", params.max_speed_mps, 1e-6, 1e9);
  check_range("max_substeps", params.max_substeps, 1, 1e5);
  check_range("min_substeps", params.min_substeps, 1, 1e5);
  if (!params.gravity_mps2.allFinite()) bad("gravity_mps2 must be finite");
  if (params.kernel == KernelKind::kSimd &&
      (params.model != ModelKind::kMassSpring ||
       params.integrator != IntegratorKind::kSymplecticEuler)) {
    bad(std::string("kernel = simd needs model mass_spring and integrator symplectic_euler, got ") +
        to_string(params.model) + " and " + to_string(params.integrator));
  }
  if (planes.size() > 8) bad("at most 8 planes, got " + std::to_string(planes.size()));
  if (static_cast<int>(mesh.vertex_face_offsets.size()) != mesh.vertex_count() + 1) {
    throw teleop::mesh::MeshError("make_model: the mesh has no adjacency tables");
  }
  teleop::mesh::validate_closed_manifold(mesh);
}

// Node areas (a third of each adjacent triangle), volume and its centroid, masses (surface
// nodes by area, the centre node its fraction), and the Lame coefficients from E and nu.
void set_geometry_and_masses(DeformableModel& m) {
  const DeformableParams& p = m.params;
  const teleop::mesh::TriMesh& mesh = m.mesh;
  const int n = m.node_count;
  const Eigen::Matrix3Xd& X = mesh.vertices;
  m.area_m2 = Eigen::VectorXd::Zero(n);
  double vol6 = 0.0;
  Eigen::Vector3d vc = Eigen::Vector3d::Zero();
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const int a = mesh.triangles(0, t), b = mesh.triangles(1, t), c = mesh.triangles(2, t);
    const double area = 0.5 * (X.col(b) - X.col(a)).cross(X.col(c) - X.col(a)).norm();
    m.area_m2(a) += area / 3.0;
    m.area_m2(b) += area / 3.0;
    m.area_m2(c) += area / 3.0;
    const double v6 = X.col(a).dot(X.col(b).cross(X.col(c)));
    vol6 += v6;
    vc += v6 * (X.col(a) + X.col(b) + X.col(c)) / 4.0;
  }
  m.volume_m3 = vol6 / 6.0;
  m.rest_centre_m = vc / vol6;

  // masses
  const double total_area = m.area_m2.sum();
  m.total_mass_kg = p.density_kg_per_m3 > 0.0 ? p.density_kg_per_m3 * m.volume_m3 : p.mass_kg;
  m.density_kg_per_m3 = m.total_mass_kg / m.volume_m3;
  m.has_centre = p.radial_stiffness_n_per_m3 > 0.0;
  m.centre_mass_kg = m.has_centre ? p.centre_mass_fraction * m.total_mass_kg : 0.0;
  const double surface_mass = m.total_mass_kg - m.centre_mass_kg;
  m.mass_kg = surface_mass * m.area_m2 / total_area;
  m.inv_mass = m.mass_kg.cwiseInverse();

  // Lame coefficients from E and nu
  const double E = p.youngs_modulus_pa, nu = p.poisson_ratio;
  m.lame_lambda_pa = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  m.lame_mu_pa = E / (2.0 * (1.0 + nu));
}

// Edges, sorted by (first node, second node) with first < second, their rest lengths and
// directions, and the per-node edge tables of the fused step and of the gather.
void build_edge_tables(DeformableModel& m) {
  const int n = m.node_count;
  const Eigen::Matrix3Xd& X = m.mesh.vertices;
  // edges, sorted by (first node, second node) with first < second: the fused step visits the
  // nodes in order and needs the edges of each node as one range
  const int ne = m.mesh.edge_count();
  {
    std::vector<std::pair<int, int>> sorted(static_cast<std::size_t>(ne));
    for (int e = 0; e < ne; ++e) {
      const int a = m.mesh.edges(0, e), b = m.mesh.edges(1, e);
      sorted[static_cast<std::size_t>(e)] = {std::min(a, b), std::max(a, b)};
    }
    std::sort(sorted.begin(), sorted.end());
    m.edges.resize(2, ne);
    for (int e = 0; e < ne; ++e) {
      m.edges(0, e) = sorted[static_cast<std::size_t>(e)].first;
      m.edges(1, e) = sorted[static_cast<std::size_t>(e)].second;
    }
  }
  m.first_edge_offsets.assign(static_cast<std::size_t>(n) + 1, 0);
  for (int e = 0; e < ne; ++e) ++m.first_edge_offsets[static_cast<std::size_t>(m.edges(0, e)) + 1];
  m.second_node3.resize(static_cast<std::size_t>(ne));
  for (int e = 0; e < ne; ++e) m.second_node3[static_cast<std::size_t>(e)] = 3 * m.edges(1, e);
  for (int i = 0; i < n; ++i) {
    m.first_edge_offsets[static_cast<std::size_t>(i) + 1] +=
        m.first_edge_offsets[static_cast<std::size_t>(i)];
  }
  m.rest_length_m.resize(ne);
  m.rest_dir.resize(3, ne);
  for (int e = 0; e < ne; ++e) {
    const Eigen::Vector3d d = X.col(m.edges(1, e)) - X.col(m.edges(0, e));
    m.rest_length_m(e) = d.norm();
    m.rest_dir.col(e) = d / m.rest_length_m(e);
  }
  // incident edges of every node (for the gather of edge forces)
  m.node_edge_offsets.assign(static_cast<std::size_t>(n) + 1, 0);
  for (int e = 0; e < ne; ++e) {
    ++m.node_edge_offsets[static_cast<std::size_t>(m.edges(0, e)) + 1];
    ++m.node_edge_offsets[static_cast<std::size_t>(m.edges(1, e)) + 1];
  }
  for (int i = 0; i < n; ++i) {
    m.node_edge_offsets[static_cast<std::size_t>(i) + 1] +=
        m.node_edge_offsets[static_cast<std::size_t>(i)];
  }
  m.node_edges.assign(static_cast<std::size_t>(2 * ne), 0);
  {
    std::vector<int> fill(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      fill[static_cast<std::size_t>(i)] = m.node_edge_offsets[static_cast<std::size_t>(i)];
    }
    for (int e = 0; e < ne; ++e) {
      m.node_edges[static_cast<std::size_t>(fill[static_cast<std::size_t>(m.edges(0, e))]++)] = e;
      m.node_edges[static_cast<std::size_t>(fill[static_cast<std::size_t>(m.edges(1, e))]++)] = ~e;
    }
  }
}

// Edge stiffness: the spring constant (mass-spring) or the Navier coefficients.
void set_edge_stiffness(DeformableModel& m) {
  const DeformableParams& p = m.params;
  const int n = m.node_count;
  const int ne = static_cast<int>(m.edges.cols());
  m.edge_k_iso.resize(ne);
  m.edge_k_dir.resize(ne);
  if (p.model == ModelKind::kMassSpring) {
    m.edge_k_iso.setConstant(p.edge_stiffness_n_per_m);
    m.edge_k_dir.setZero();
  } else {
    // eq. (2): V_i (mu Lap d + (lambda + mu) grad div d)_i with the finite differences
    //   Lap d_i = 2 / S_i sum_j (d_j - d_i) / l_ij,
    //   grad div d_i = 2 / S_i sum_j ((d_j - d_i).u) u / l_ij,   S_i = sum_j l_ij,
    // V_i = node volume share. The weight 2 V_i / S_i is averaged over the two ends of each
    // edge so that the stiffness is symmetric (momentum and energy conserving).
    Eigen::VectorXd s_sum = Eigen::VectorXd::Zero(n);
    for (int e = 0; e < ne; ++e) {
      s_sum(m.edges(0, e)) += m.rest_length_m(e);
      s_sum(m.edges(1, e)) += m.rest_length_m(e);
    }
    const Eigen::VectorXd vol_i = m.volume_m3 * m.area_m2 / m.area_m2.sum();
    for (int e = 0; e < ne; ++e) {
      const int i = m.edges(0, e), j = m.edges(1, e);
      const double w = vol_i(i) / s_sum(i) + vol_i(j) / s_sum(j);
      m.edge_k_iso(e) = m.lame_mu_pa * w / m.rest_length_m(e);
      m.edge_k_dir(e) = (m.lame_lambda_pa + m.lame_mu_pa) * w / m.rest_length_m(e);
    }
  }
}

// Radial springs to the centre node (if any), the planes (normals made unit length) and the
// contact spring and damper of every node.
void set_radial_and_contact(DeformableModel& m, const std::vector<Plane>& planes) {
  const DeformableParams& p = m.params;
  const int n = m.node_count;
  const Eigen::Matrix3Xd& X = m.mesh.vertices;
  // radial springs to the centre node
  m.radial_k = Eigen::VectorXd::Zero(n);
  m.radial_rest_m = Eigen::VectorXd::Zero(n);
  if (m.has_centre) {
    m.radial_k = p.radial_stiffness_n_per_m3 * m.area_m2;
    for (int i = 0; i < n; ++i) m.radial_rest_m(i) = (X.col(i) - m.rest_centre_m).norm();
  }

  // contact with planes
  m.plane_count = static_cast<int>(planes.size());
  for (std::size_t k = 0; k < planes.size(); ++k) {
    m.planes[k] = planes[k];
    const double nn = planes[k].normal.norm();
    if (!(nn > 0.0) || !std::isfinite(planes[k].offset_m)) {
      bad("plane '" + planes[k].name + "' has a zero or non-finite normal/offset");
    }
    m.planes[k].normal /= nn;
  }
  const double w = p.contact_frequency_rad_per_s;
  m.contact_k = m.mass_kg * w * w;
  m.contact_c = m.mass_kg * (2.0 * p.contact_damping_ratio * w);
}

}  // namespace

teleop::mesh::TriMesh make_mesh_for(const DeformableParams& p) {
  if (p.mesh_file.empty()) return teleop::mesh::make_icosphere(p.level, p.radius_m, p.centre_m);
  teleop::mesh::LoadOptions opt;
  opt.scale = p.mesh_scale;
  teleop::mesh::TriMesh m = teleop::mesh::load_mesh(p.mesh_file, opt);
  m.vertices.colwise() += p.centre_m;
  return m;
}

namespace {

// The co-rotational tables of DeformableModel (corot_*): see deformable.hpp.
void build_corotational_tables(DeformableModel& m) {
  const Eigen::Matrix3Xd& X = m.mesh.vertices;
  const int n = m.node_count;
  Eigen::Vector3d c0 = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) c0 += m.mass_kg(i) * X.col(i);
  c0 *= 1.0 / m.mass_kg.sum();
  const auto& off = m.mesh.vertex_neighbour_offsets;
  const auto& nb = m.mesh.vertex_neighbours;
  const auto& eoff = m.node_edge_offsets;
  int w = 0;
  for (int i = 0; i < n; ++i) {
    const auto iu = static_cast<std::size_t>(i);
    w = std::max({w, off[iu + 1] - off[iu], eoff[iu + 1] - eoff[iu]});
  }
  m.corot_width = w;
  const auto wu = static_cast<std::size_t>(w);
  const auto nu = static_cast<std::size_t>(n);
  m.corot_nb.assign(nu * wu, 0);
  m.corot_ring_rest.assign(3 * nu * wu, 0.0);
  m.corot_node_e.assign(3 * nu, 0.0);
  for (int i = 0; i < n; ++i) {
    const auto iu = static_cast<std::size_t>(i);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double len2 = 0.0;
    std::size_t slot = iu * wu;
    for (int k = off[iu]; k < off[iu + 1]; ++k, ++slot) {
      const int j = nb[static_cast<std::size_t>(k)];
      const Eigen::Vector3d d = X.col(j) - X.col(i);
      m.corot_nb[slot] = j;
      for (int c = 0; c < 3; ++c) m.corot_ring_rest[3 * slot + static_cast<std::size_t>(c)] = d[c];
      sum += d;
      len2 += d.squaredNorm();
    }
    for (; slot < (iu + 1) * wu; ++slot) m.corot_nb[slot] = i;  // D = 0: adds nothing
    const Eigen::Vector3d rx = X.col(i) - c0;
    const double r2 = rx.squaredNorm();
    const Eigen::Vector3d e =
        (r2 > 0.0 ? Eigen::Vector3d((len2 / r2) * rx) : Eigen::Vector3d::Zero()) - sum;
    for (int c = 0; c < 3; ++c) m.corot_node_e[3 * iu + static_cast<std::size_t>(c)] = e[c];
  }
  // the same, four nodes per group, lane-major (the last n mod 4 nodes have no group)
  const std::size_t groups = nu / 4;
  m.corot_ring_rest4.assign(12 * groups * wu, 0.0);
  m.corot_node_e4.assign(12 * groups, 0.0);
  for (std::size_t g = 0; g < groups; ++g) {
    for (std::size_t l = 0; l < 4; ++l) {
      const std::size_t i = 4 * g + l;
      for (std::size_t c = 0; c < 3; ++c) {
        m.corot_node_e4[12 * g + 4 * c + l] = m.corot_node_e[3 * i + c];
        for (std::size_t k = 0; k < wu; ++k) {
          m.corot_ring_rest4[12 * (g * wu + k) + 4 * c + l] =
              m.corot_ring_rest[3 * (i * wu + k) + c];
        }
      }
    }
  }
  const auto ne = static_cast<std::size_t>(m.edges.cols());
  m.corot_edge.assign(4 * ne, 0.0);
  for (std::size_t e = 0; e < ne; ++e) {
    const auto ei = static_cast<Eigen::Index>(e);
    const Eigen::Vector3d d = X.col(m.edges(1, ei)) - X.col(m.edges(0, ei));
    for (int c = 0; c < 3; ++c) m.corot_edge[4 * e + static_cast<std::size_t>(c)] = d[c];
    m.corot_edge[4 * e + 3] = 1.0 / d.squaredNorm();
  }
}

}  // namespace

DeformableModel make_model(const teleop::mesh::TriMesh& mesh, const DeformableParams& params,
                           const std::vector<Plane>& planes) {
  if (params.model == ModelKind::kFem) {
    bad("model fem needs a tetrahedral mesh: build it with make_model(params, planes) or "
        "make_model(tet_mesh, params, planes)");
  }
  check_inputs(mesh, params, planes);
  DeformableModel m;
  m.params = params;
  if (params.model == ModelKind::kMassSpring && params.springs_from_material) {
    // the sphere the body stands for: the icosphere's radius, or a mesh's volume-equivalent one
    const double radius_m =
        params.mesh_file.empty()
            ? params.radius_m
            : std::cbrt(3.0 * std::fabs(teleop::mesh::enclosed_volume(mesh)) / (4.0 * M_PI));
    const MassSpringStiffness k = mass_spring_from_material(
        params.youngs_modulus_pa, params.poisson_ratio, radius_m, params.centre_mass_fraction);
    m.params.edge_stiffness_n_per_m = k.edge_n_per_m;
    m.params.radial_stiffness_n_per_m3 = k.radial_n_per_m3;
  }
  m.mesh = mesh;
  m.node_count = mesh.vertex_count();
  set_geometry_and_masses(m);
  build_edge_tables(m);
  set_edge_stiffness(m);
  set_radial_and_contact(m, planes);
  if (params.kernel == KernelKind::kSimd) build_simd_tables(m);
  if (params.model == ModelKind::kNavierCorotational) build_corotational_tables(m);
  update_stable_step(m);
  return m;
}

DeformableModel make_model(const teleop::mesh::TetMesh& tets, const DeformableParams& params,
                           const std::vector<Plane>& planes) {
  if (params.model != ModelKind::kFem) {
    bad(std::string("a tetrahedral mesh is for model fem, not ") + to_string(params.model));
  }
  check_inputs(tets.surface, params, planes);
  check_range("contact_pressure_stiffness_pa_per_m", params.contact_pressure_stiffness_pa_per_m,
              0.0, 1e15);
  DeformableModel m;
  m.params = params;
  m.mesh = tets.surface;
  m.node_count = tets.surface_vertex_count;
  set_radial_and_contact(m, planes);  // planes (the springs are the FEM's, set below)
  m.radial_k.resize(0);
  m.radial_rest_m.resize(0);
  detail::build_fem(m, tets);
  update_stable_step(m);
  detail::fem_scale_masses(m);
  return m;
}

DeformableModel make_model(const DeformableParams& params, const std::vector<Plane>& planes) {
  if (params.model == ModelKind::kFem) return make_model(make_tet_mesh_for(params), params, planes);
  return make_model(make_mesh_for(params), params, planes);
}

teleop::mesh::TetMesh make_tet_mesh_for(const DeformableParams& p) {
  if (!p.tet_mesh_file.empty()) {
    return teleop::mesh::load_tet_mesh(p.tet_mesh_file, p.mesh_scale, p.centre_m);
  }
  if (!p.mesh_file.empty()) {
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
    // fuzz builds only (tests/fuzz): no child processes or temporary files from a fuzzed scene
    throw teleop::mesh::MeshError("fuzz build: filling a surface with gmsh is not run");
#endif
    const teleop::mesh::TriMesh surface = make_mesh_for(p);
    const double edge = p.tet_max_edge_m > 0.0
                            ? p.tet_max_edge_m
                            : std::cbrt(std::fabs(teleop::mesh::enclosed_volume(surface))) / 6.0;
    std::error_code ec;
    const std::string tmp = std::filesystem::temp_directory_path(ec).string();
    return teleop::mesh::tetrahedralize(surface, edge, ec ? std::string("/tmp") : tmp);
  }
  return teleop::mesh::ball_tet_mesh(p.level, p.radius_m, p.centre_m);
}

DeformableState make_state(const DeformableModel& m) {
  if (m.params.model == ModelKind::kFem) {
    DeformableState s;
    detail::init_fem_state(m, s);
    s.last_good_centroid = centroid(m, s);
    return s;
  }
  const int n = m.node_count;
  const int ne = static_cast<int>(m.edges.cols());
  DeformableState s;
  s.x = m.mesh.vertices;
  s.v = Eigen::Matrix3Xd::Zero(3, n);
  s.f_ext = Eigen::Matrix3Xd::Zero(3, n);
  s.pinned.assign(static_cast<std::size_t>(n), 0);
  s.pin_target = s.x;
  s.centre_x = m.rest_centre_m;
  s.centre_v.setZero();
  s.force = Eigen::Matrix3Xd::Zero(3, n);
  for (Eigen::Matrix3Xd* w : {&s.work_f, &s.work_dv, &s.work_r, &s.work_z, &s.work_p, &s.work_ap,
                              &s.work_diag, &s.work_b}) {
    *w = Eigen::Matrix3Xd::Zero(3, n + 1);
  }
  s.edge_scratch = Eigen::VectorXd::Zero(ne);
  s.edge_length2 = Eigen::VectorXd::Zero(ne);
  s.node_length2 = Eigen::VectorXd::Zero(n);
  s.edge_force = Eigen::Matrix3Xd::Zero(3, ne);
  s.node_scratch = Eigen::VectorXd::Zero(n);
  s.edge_dir = Eigen::Matrix3Xd::Zero(3, ne);
  s.edge_coef = Eigen::Matrix4Xd::Zero(4, ne);
  s.radial_dir = Eigen::Matrix3Xd::Zero(3, n);
  s.radial_coef = Eigen::Matrix4Xd::Zero(4, n);
  const int cap = n * std::max(m.plane_count, 1);
  s.contact_node.assign(static_cast<std::size_t>(cap), -1);
  s.contact_normal = Eigen::Matrix3Xd::Zero(3, cap);
  s.contact_coef = Eigen::Matrix4Xd::Zero(4, cap);
  s.rotation.assign(static_cast<std::size_t>(n), Eigen::Matrix3d::Identity());
  s.rotation_q.assign(static_cast<std::size_t>(n), Eigen::Quaterniond::Identity());
  if (m.params.kernel == KernelKind::kSimd) {
    s.simd_pack.assign(8 * static_cast<std::size_t>(m.simd_stride), 0.0f);
  }
  if (m.params.model == ModelKind::kNavierCorotational) {
    s.corot_pack.assign(8 * static_cast<std::size_t>(n), 0.0);  // x - c, then q (4 + 4 per node)
    s.corot_frame.assign(24 * static_cast<std::size_t>(n), 0.0);
    s.corot_force.assign(4 * static_cast<std::size_t>(n), 0.0);  // edge reactions per node
  }
  s.pin_goal = Eigen::Matrix3Xd::Zero(3, n);
  s.pin_start = Eigen::Matrix3Xd::Zero(3, n);
  s.last_good_centroid = centroid(m, s);
  return s;
}

Eigen::Vector3d centroid(const DeformableModel& m, const DeformableState& s) {
  if (m.params.model == ModelKind::kFem) return s.x * m.fem.weight_kg / m.total_mass_kg;
  Eigen::Vector3d c = s.x * m.mass_kg;
  c += m.centre_mass_kg * s.centre_x;
  return c / m.total_mass_kg;
}

Eigen::Vector3d body_centre(const DeformableModel& m, const DeformableState& s) {
  if (m.has_centre) return s.centre_x;
  return centroid(m, s);
}

double kinetic_energy(const DeformableModel& m, const DeformableState& s) {
  double e = 0.0;
  if (m.params.model == ModelKind::kFem) {
    for (int i = 0; i < m.fem.node_count; ++i) e += m.fem.mass_kg(i) * s.v.col(i).squaredNorm();
    return 0.5 * e;
  }
  for (int i = 0; i < m.node_count; ++i) e += m.mass_kg(i) * s.v.col(i).squaredNorm();
  e += m.centre_mass_kg * s.centre_v.squaredNorm();
  return 0.5 * e;
}

double elastic_energy(const DeformableModel& m, const DeformableState& s) {
  if (m.params.model == ModelKind::kFem) return detail::fem_elastic_energy(m, s);
  double e = 0.0;
  const Eigen::Matrix3Xd& X = m.mesh.vertices;
  for (int k = 0; k < m.edges.cols(); ++k) {
    const int i = m.edges(0, k), j = m.edges(1, k);
    const Eigen::Vector3d d = s.x.col(j) - s.x.col(i);
    if (m.params.model == ModelKind::kMassSpring) {
      const double stretch = d.norm() - m.rest_length_m(k);
      e += m.edge_k_iso(k) * stretch * stretch;
    } else {
      Eigen::Vector3d strain;
      if (m.params.model == ModelKind::kNavierLinear) {
        strain = d - (X.col(j) - X.col(i));
      } else {
        const Eigen::Matrix3d r = 0.5 * (s.rotation[static_cast<std::size_t>(i)] +
                                         s.rotation[static_cast<std::size_t>(j)]);
        strain = r.transpose() * d - (X.col(j) - X.col(i));
      }
      const double along = strain.dot(m.rest_dir.col(k));
      e += m.edge_k_iso(k) * strain.squaredNorm() + m.edge_k_dir(k) * along * along;
    }
  }
  if (m.has_centre) {
    for (int i = 0; i < m.node_count; ++i) {
      const double stretch = (s.x.col(i) - s.centre_x).norm() - m.radial_rest_m(i);
      e += m.radial_k(i) * stretch * stretch;
    }
  }
  return 0.5 * e;
}

double potential_energy(const DeformableModel& m, const DeformableState& s) {
  double e = elastic_energy(m, s);
  const Eigen::Vector3d& g = m.params.gravity_mps2;
  if (m.params.model == ModelKind::kFem) {
    for (int i = m.node_count; i < m.fem.node_count; ++i)
      e -= m.fem.weight_kg(i) * g.dot(s.x.col(i));
  }
  const bool fem = m.params.model == ModelKind::kFem;
  for (int i = 0; i < m.node_count; ++i) {
    e -= (fem ? m.fem.weight_kg(i) : m.mass_kg(i)) * g.dot(s.x.col(i));
    for (int k = 0; k < m.plane_count; ++k) {
      const double d = m.planes[static_cast<std::size_t>(k)].signed_distance(s.x.col(i));
      if (d < 0.0) e += 0.5 * m.contact_k(i) * d * d;
    }
  }
  e -= m.centre_mass_kg * g.dot(s.centre_x);
  return e;
}

}  // namespace teleop::sim::deformable

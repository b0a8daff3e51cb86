// Tetrahedral meshes: tables, boundary extraction, the MSH 2.2 reader and the gmsh bridge.
#include "common/mesh/tet_mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unordered_map>
#include <vector>

#include <unistd.h>

#include "common/util/data_dir.hpp"

namespace teleop::mesh {

namespace {

double signed_volume(const Eigen::Matrix3Xd& v, int a, int b, int c, int d) {
  const Eigen::Vector3d e1 = v.col(b) - v.col(a);
  const Eigen::Vector3d e2 = v.col(c) - v.col(a);
  const Eigen::Vector3d e3 = v.col(d) - v.col(a);
  return e1.dot(e2.cross(e3)) / 6.0;
}

std::string where(const Eigen::Vector3d& p) {
  std::ostringstream os;
  os << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return os.str();
}

}  // namespace

double tet_volume(const TetMesh& mesh, int t) {
  const auto c = mesh.tets.col(t);
  return signed_volume(mesh.vertices, c(0), c(1), c(2), c(3));
}

double total_volume(const TetMesh& mesh) {
  double v = 0.0;
  for (int t = 0; t < mesh.tet_count(); ++t) v += tet_volume(mesh, t);
  return v;
}

namespace {

/// `tets_in` checked (node indices in range, no degenerate tetrahedron) and each tetrahedron
/// ordered to a positive volume.
Eigen::Matrix4Xi oriented_tets(const Eigen::Matrix3Xd& vertices, const Eigen::Matrix4Xi& tets_in) {
  const int nv = static_cast<int>(vertices.cols());
  const int nt = static_cast<int>(tets_in.cols());
  const Eigen::Vector3d lo = vertices.rowwise().minCoeff(), hi = vertices.rowwise().maxCoeff();
  const double box_volume = (hi - lo).prod();
  Eigen::Matrix4Xi tets = tets_in;
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k) {
      const int i = tets(k, t);
      if (i < 0 || i >= nv) {
        throw MeshError("tetrahedron " + std::to_string(t) + " refers to node " +
                        std::to_string(i) + ", but there are " + std::to_string(nv) + " nodes");
      }
    }
    const double vol = signed_volume(vertices, tets(0, t), tets(1, t), tets(2, t), tets(3, t));
    if (!(std::fabs(vol) > 1e-12 * box_volume)) {
      throw MeshError("degenerate tetrahedron " + std::to_string(t) + " at " +
                      where(vertices.col(tets(0, t))) + ": volume " + std::to_string(vol) + " m^3");
    }
    if (vol < 0.0) std::swap(tets(1, t), tets(2, t));
  }
  return tets;
}

/// The boundary: the faces that belong to one tetrahedron, oriented outward; a face shared by
/// more than two tetrahedra is refused.
std::vector<std::array<int, 3>> boundary_faces(const Eigen::Matrix3Xd& vertices,
                                               const Eigen::Matrix4Xi& tets) {
  struct Face {
    std::array<int, 3> key;  // sorted
    std::array<int, 3> tri;  // outward
  };
  const int nt = static_cast<int>(tets.cols());
  std::vector<Face> faces;
  faces.reserve(static_cast<std::size_t>(nt) * 4);
  for (int t = 0; t < nt; ++t) {
    const int a = tets(0, t), b = tets(1, t), c = tets(2, t), d = tets(3, t);
    for (const std::array<int, 3>& f : {std::array<int, 3>{a, c, b}, std::array<int, 3>{a, b, d},
                                        std::array<int, 3>{a, d, c}, std::array<int, 3>{b, c, d}}) {
      std::array<int, 3> key = f;
      std::sort(key.begin(), key.end());
      faces.push_back({key, f});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const Face& x, const Face& y) { return x.key < y.key; });
  std::vector<std::array<int, 3>> boundary;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i == 1) {
      boundary.push_back(faces[i].tri);
    } else if (j - i > 2) {
      throw MeshError("non-manifold face (" + std::to_string(faces[i].key[0]) + ", " +
                      std::to_string(faces[i].key[1]) + ", " + std::to_string(faces[i].key[2]) +
                      ") at " + where(vertices.col(faces[i].key[0])) + " is shared by " +
                      std::to_string(j - i) + " tetrahedra");
    }
    i = j;
  }
  return boundary;
}

/// The new index of each of `nv` nodes: boundary nodes first, then interior nodes, each in
/// their old order; -1 for a node no tetrahedron uses. `boundary_count` gets the number of
/// boundary nodes, `used_count` the number of used ones.
std::vector<int> boundary_first_order(int nv, const Eigen::Matrix4Xi& tets,
                                      const std::vector<std::array<int, 3>>& boundary,
                                      int& boundary_count, int& used_count) {
  std::vector<int> role(static_cast<std::size_t>(nv), 0);  // 0 unused, 1 interior, 2 boundary
  for (int t = 0; t < static_cast<int>(tets.cols()); ++t) {
    for (int k = 0; k < 4; ++k) role[static_cast<std::size_t>(tets(k, t))] = 1;
  }
  for (const auto& f : boundary) {
    for (int i : f) role[static_cast<std::size_t>(i)] = 2;
  }
  std::vector<int> new_index(static_cast<std::size_t>(nv), -1);
  int next = 0;
  for (int pass = 2; pass >= 1; --pass) {
    for (int i = 0; i < nv; ++i) {
      if (role[static_cast<std::size_t>(i)] == pass)
        new_index[static_cast<std::size_t>(i)] = next++;
    }
  }
  used_count = next;
  boundary_count = 0;
  for (int i = 0; i < nv; ++i) boundary_count += role[static_cast<std::size_t>(i)] == 2 ? 1 : 0;
  return new_index;
}

}  // namespace

TetMesh make_tet_mesh(const Eigen::Matrix3Xd& vertices, const Eigen::Matrix4Xi& tets_in) {
  const int nv = static_cast<int>(vertices.cols());
  const int nt = static_cast<int>(tets_in.cols());
  if (nv < 4 || nt < 1) {
    throw MeshError("a tetrahedral mesh needs at least 4 nodes and 1 tetrahedron (has " +
                    std::to_string(nv) + " and " + std::to_string(nt) + ")");
  }
  for (int i = 0; i < nv; ++i) {
    if (!vertices.col(i).allFinite()) {
      throw MeshError("node " + std::to_string(i) + " has a non-finite coordinate");
    }
  }
  const Eigen::Matrix4Xi tets = oriented_tets(vertices, tets_in);
  const std::vector<std::array<int, 3>> boundary = boundary_faces(vertices, tets);

  // renumber: boundary nodes first, then interior nodes; unused dropped
  int ns = 0, next = 0;
  const std::vector<int> new_index = boundary_first_order(nv, tets, boundary, ns, next);
  TetMesh out;
  out.vertices.resize(3, next);
  for (int i = 0; i < nv; ++i) {
    if (new_index[static_cast<std::size_t>(i)] >= 0) {
      out.vertices.col(new_index[static_cast<std::size_t>(i)]) = vertices.col(i);
    }
  }
  out.tets.resize(4, nt);
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k) out.tets(k, t) = new_index[static_cast<std::size_t>(tets(k, t))];
  }
  out.surface_vertex_count = ns;
  Eigen::Matrix3Xi tris(3, static_cast<Eigen::Index>(boundary.size()));
  for (std::size_t f = 0; f < boundary.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      tris(k, static_cast<Eigen::Index>(f)) =
          new_index[static_cast<std::size_t>(boundary[f][static_cast<std::size_t>(k)])];
    }
  }
  try {
    out.surface = make_mesh(out.vertices.leftCols(ns), tris);
  } catch (const MeshError& e) {
    throw MeshError(std::string("the boundary of the tetrahedral mesh is not a closed manifold: ") +
                    e.what());
  }
  return out;
}

namespace {

/// Reads an MSH file line by line (a trailing '\r' dropped) and makes errors that name the
/// file and the line.
class MshLines {
 public:
  MshLines(const std::string& path, std::istream& in) : path_(path), in_(in) {}

  /// The next line into line(); false at the end of the file.
  bool next() {
    if (!std::getline(in_, line_)) return false;
    ++line_no_;
    if (!line_.empty() && line_.back() == '\r') line_.pop_back();
    return true;
  }
  const std::string& line() const { return line_; }
  MeshError fail(const std::string& why) const {
    return MeshError(path_ + ": line " + std::to_string(line_no_) + ": " + why);
  }

 private:
  const std::string& path_;
  std::istream& in_;
  std::string line_;
  int line_no_ = 0;
};

/// The line after $MeshFormat: MSH 2.x ASCII only.
void read_mesh_format(MshLines& r) {
  if (!r.next()) throw r.fail("$MeshFormat has no content");
  std::istringstream is(r.line());
  double version = 0.0;
  int file_type = -1, data_size = 0;
  if (!(is >> version >> file_type >> data_size)) throw r.fail("bad $MeshFormat line");
  if (version < 2.0 || version >= 3.0) {
    throw r.fail("MSH version " + std::to_string(version) +
                 " is not supported: write MSH 2.2 (gmsh -format msh22)");
  }
  if (file_type != 0) throw r.fail("binary MSH is not supported: write ASCII (gmsh -format msh22)");
}

/// The $Nodes section after its header: each node scaled and moved into `nodes`, its id
/// mapped to its index in `id_to_index`.
void read_nodes(MshLines& r, double scale, const Eigen::Vector3d& offset_m,
                std::vector<Eigen::Vector3d>& nodes,
                std::unordered_map<long long, int>& id_to_index) {
  if (!r.next()) throw r.fail("$Nodes has no count");
  long long n = -1;
  std::istringstream cs(r.line());
  if (!(cs >> n) || n < 4 || n > kMaxMeshVertices) {
    throw r.fail("node count '" + r.line() + "' is not in [4, " + std::to_string(kMaxMeshVertices) +
                 "]");
  }
  nodes.reserve(static_cast<std::size_t>(n));
  for (long long k = 0; k < n; ++k) {
    if (!r.next()) throw r.fail("the file ends inside $Nodes");
    std::istringstream is(r.line());
    long long id = 0;
    double x = 0, y = 0, z = 0;
    if (!(is >> id >> x >> y >> z)) throw r.fail("bad node line '" + r.line() + "'");
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      throw r.fail("node " + std::to_string(id) + " has a non-finite coordinate");
    }
    if (!id_to_index.emplace(id, static_cast<int>(nodes.size())).second) {
      throw r.fail("node id " + std::to_string(id) + " appears twice");
    }
    nodes.emplace_back(Eigen::Vector3d(x, y, z) * scale + offset_m);
  }
  if (!r.next() || r.line() != "$EndNodes") throw r.fail("expected $EndNodes");
}

/// The $Elements section after its header: the node ids of each 4-node tetrahedron into
/// `raw_tets` (other element types skipped).
void read_elements(MshLines& r, std::vector<std::array<long long, 4>>& raw_tets) {
  if (!r.next()) throw r.fail("$Elements has no count");
  long long n = -1;
  std::istringstream cs(r.line());
  if (!(cs >> n) || n < 1 || n > 8LL * kMaxMeshVertices)
    throw r.fail("bad element count '" + r.line() + "'");
  for (long long k = 0; k < n; ++k) {
    if (!r.next()) throw r.fail("the file ends inside $Elements");
    std::istringstream is(r.line());
    long long id = 0, type = 0, ntags = 0;
    if (!(is >> id >> type >> ntags) || ntags < 0 || ntags > 64) {
      throw r.fail("bad element line '" + r.line() + "'");
    }
    for (long long t = 0; t < ntags; ++t) {
      long long tag;
      if (!(is >> tag)) throw r.fail("bad element tags in '" + r.line() + "'");
    }
    if (type != 4) continue;  // only 4-node tetrahedra
    std::array<long long, 4> v{};
    for (auto& x : v) {
      if (!(is >> x)) throw r.fail("a tetrahedron needs 4 node ids: '" + r.line() + "'");
    }
    raw_tets.push_back(v);
  }
  if (!r.next() || r.line() != "$EndElements") throw r.fail("expected $EndElements");
}

/// The tetrahedra of `raw_tets` with node ids turned into node indices.
Eigen::Matrix4Xi tets_by_index(const std::string& path,
                               const std::vector<std::array<long long, 4>>& raw_tets,
                               const std::unordered_map<long long, int>& id_to_index) {
  Eigen::Matrix4Xi t(4, static_cast<Eigen::Index>(raw_tets.size()));
  for (std::size_t e = 0; e < raw_tets.size(); ++e) {
    for (int k = 0; k < 4; ++k) {
      const auto it = id_to_index.find(raw_tets[e][static_cast<std::size_t>(k)]);
      if (it == id_to_index.end()) {
        throw MeshError(path + ": tetrahedron " + std::to_string(e) + " refers to node id " +
                        std::to_string(raw_tets[e][static_cast<std::size_t>(k)]) +
                        ", which $Nodes does not define");
      }
      t(k, static_cast<Eigen::Index>(e)) = it->second;
    }
  }
  return t;
}

}  // namespace

TetMesh load_tet_mesh(const std::string& path, double scale, const Eigen::Vector3d& offset_m) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (path.empty()) throw MeshError("the tetrahedral mesh file name is empty");
  if (!fs::is_regular_file(path, ec)) {
    throw MeshError(path + ": no such regular file (a gmsh MSH 2.2 ASCII tetrahedral mesh)");
  }
  if (fs::file_size(path, ec) > kMaxMeshFileBytes) {
    throw MeshError(path + ": larger than " + std::to_string(kMaxMeshFileBytes >> 20) + " MiB");
  }
  std::ifstream in(path);
  if (!in) throw MeshError(path + ": cannot be opened");
  MshLines r(path, in);
  bool have_format = false, have_nodes = false, have_elements = false;
  std::unordered_map<long long, int> id_to_index;
  std::vector<Eigen::Vector3d> nodes;
  std::vector<std::array<long long, 4>> raw_tets;
  while (r.next()) {
    if (r.line() == "$MeshFormat") {
      read_mesh_format(r);
      have_format = true;
    } else if (r.line() == "$Nodes") {
      read_nodes(r, scale, offset_m, nodes, id_to_index);
      have_nodes = true;
    } else if (r.line() == "$Elements") {
      read_elements(r, raw_tets);
      have_elements = true;
    }
  }
  if (!have_format) throw MeshError(path + ": no $MeshFormat section (not a gmsh MSH file)");
  if (!have_nodes || !have_elements) throw MeshError(path + ": missing $Nodes or $Elements");
  if (raw_tets.empty()) throw MeshError(path + ": no 4-node tetrahedra (element type 4)");
  Eigen::Matrix3Xd v(3, static_cast<Eigen::Index>(nodes.size()));
  for (std::size_t i = 0; i < nodes.size(); ++i) v.col(static_cast<Eigen::Index>(i)) = nodes[i];
  const Eigen::Matrix4Xi t = tets_by_index(path, raw_tets, id_to_index);
  try {
    return make_tet_mesh(v, t);
  } catch (const MeshError& e) {
    throw MeshError(path + ": " + e.what());
  }
}

std::string ball_tet_mesh_path(int level) {
  const std::string dir = data_path("data/tet");
  return dir + "/ball_L" + std::to_string(level) + ".msh";
}

TetMesh ball_tet_mesh(int level, double radius_m, const Eigen::Vector3d& centre_m) {
  if (level < 1 || level > kMaxBallTetLevel) {
    throw MeshError("ball tetrahedral mesh level " + std::to_string(level) + " is not in [1, " +
                    std::to_string(kMaxBallTetLevel) + "]");
  }
  if (!(radius_m > 0.0)) throw MeshError("ball radius_m must be > 0");
  return load_tet_mesh(ball_tet_mesh_path(level), radius_m, centre_m);
}

TetMesh tetrahedralize(const TriMesh& surface, double max_edge_m, const std::string& work_dir) {
  namespace fs = std::filesystem;
  if (!(max_edge_m > 0.0) || !std::isfinite(max_edge_m)) {
    throw MeshError("tetrahedralize: max_edge_m must be > 0");
  }
  if (std::system("command -v gmsh > /dev/null 2>&1") != 0) {
    throw MeshError(
        "a volumetric mesh of a surface file needs gmsh (Debian package 'gmsh'), which is not "
        "installed: apt-get install gmsh, or give a tetrahedral mesh (tet_mesh_file)");
  }
  std::error_code ec;
  const fs::path dir = fs::path(work_dir) / ("teleop_tet_" + std::to_string(::getpid()));
  fs::create_directories(dir, ec);
  if (ec) throw MeshError("tetrahedralize: cannot create " + dir.string() + ": " + ec.message());
  const fs::path stl = dir / "surface.stl", geo = dir / "volume.geo", msh = dir / "volume.msh",
                 log = dir / "gmsh.log";
  {
    std::ofstream o(stl);
    o.precision(17);
    o << "solid s\n";
    for (int t = 0; t < surface.triangle_count(); ++t) {
      o << " facet normal 0 0 0\n  outer loop\n";
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d p = surface.vertices.col(surface.triangles(k, t));
        o << "   vertex " << p.x() << " " << p.y() << " " << p.z() << "\n";
      }
      o << "  endloop\n endfacet\n";
    }
    o << "endsolid s\n";
    std::ofstream g(geo);
    g.precision(17);
    g << "Merge \"surface.stl\";\nSurface Loop(1) = {1};\nVolume(1) = {1};\n"
      << "Mesh.MeshSizeMax = " << max_edge_m << ";\nMesh.Algorithm3D = 1;\nMesh.Optimize = 1;\n"
      << "Mesh.RandomSeed = 1;\n";
    if (!o || !g) throw MeshError("tetrahedralize: cannot write into " + dir.string());
  }
  const std::string cmd =
      "cd '" + dir.string() +
      "' && gmsh volume.geo -3 -format msh22 -o volume.msh -v 2 > gmsh.log 2>&1";
  const int rc = std::system(cmd.c_str());
  TetMesh out;
  std::string error;
  if (rc != 0 || !fs::exists(msh, ec)) {
    std::ifstream l(log);
    std::stringstream ss;
    ss << l.rdbuf();
    error = "gmsh failed to fill the surface with tetrahedra (exit " + std::to_string(rc) +
            "): " + ss.str().substr(0, 400);
  } else {
    try {
      out = load_tet_mesh(msh.string());
      if (out.surface_vertex_count != surface.vertex_count() ||
          out.surface.triangle_count() != surface.triangle_count()) {
        error = "gmsh changed the boundary (" + std::to_string(surface.vertex_count()) +
                " vertices, " + std::to_string(surface.triangle_count()) + " triangles in; " +
                std::to_string(out.surface_vertex_count) + ", " +
                std::to_string(out.surface.triangle_count()) + " out)";
      }
    } catch (const MeshError& e) {
      error = e.what();
    }
  }
  fs::remove_all(dir, ec);
  if (!error.empty()) throw MeshError("tetrahedralize: " + error);
  return out;
}

}  // namespace teleop::mesh

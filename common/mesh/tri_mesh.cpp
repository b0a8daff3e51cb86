#include "common/mesh/tri_mesh.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unordered_map>
#include <utility>
#include <vector>

namespace teleop::mesh {

namespace {

std::uint64_t edge_key(int a, int b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b));
  const auto hi = static_cast<std::uint64_t>(std::max(a, b));
  return (lo << 32) | hi;
}

std::string point_text(const Eigen::Vector3d& p) {
  std::ostringstream os;
  os << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return os.str();
}

// Reverse Cuthill-McKee order of the vertices of a triangle list (order[new] = old): a
// breadth-first walk from vertex 0, each vertex's unvisited neighbours taken by increasing
// valence then index, the walk reversed. Neighbours end up close in memory, which is what the
// node loops of the deformable models want (docs/deformable.md, "Vertex order", has the
// figures). Deterministic (no ties left to a hash order).
std::vector<int> reverse_cuthill_mckee(int n, const std::vector<std::array<int, 3>>& tris) {
  std::vector<std::vector<int>> nb(static_cast<std::size_t>(n));
  for (const auto& t : tris) {
    for (int k = 0; k < 3; ++k) {
      nb[static_cast<std::size_t>(t[k])].push_back(t[(k + 1) % 3]);
      nb[static_cast<std::size_t>(t[k])].push_back(t[(k + 2) % 3]);
    }
  }
  for (auto& v : nb) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
  }
  const auto valence = [&](int i) { return nb[static_cast<std::size_t>(i)].size(); };
  std::vector<int> order;
  order.reserve(static_cast<std::size_t>(n));
  std::vector<char> seen(static_cast<std::size_t>(n), 0);
  std::vector<int> next;
  for (int root = 0; root < n; ++root) {  // one walk per connected part (one for a sphere)
    if (seen[static_cast<std::size_t>(root)]) continue;
    seen[static_cast<std::size_t>(root)] = 1;
    std::size_t head = order.size();
    order.push_back(root);
    while (head < order.size()) {
      const int i = order[head++];
      next.clear();
      for (const int j : nb[static_cast<std::size_t>(i)]) {
        if (!seen[static_cast<std::size_t>(j)]) {
          seen[static_cast<std::size_t>(j)] = 1;
          next.push_back(j);
        }
      }
      std::sort(next.begin(), next.end(), [&](int a, int b) {
        return valence(a) != valence(b) ? valence(a) < valence(b) : a < b;
      });
      order.insert(order.end(), next.begin(), next.end());
    }
  }
  std::reverse(order.begin(), order.end());
  return order;
}

}  // namespace

int icosphere_vertex_count(int level) { return 10 * (1 << (2 * level)) + 2; }
int icosphere_triangle_count(int level) { return 20 * (1 << (2 * level)); }

TriMesh make_icosphere(int level, double radius_m, const Eigen::Vector3d& centre_m) {
  if (level < 0 || level > 6) {
    throw MeshError("make_icosphere: level " + std::to_string(level) +
                    " is outside the allowed range [0, 6]");
  }
  if (!(radius_m > 0.0) || !std::isfinite(radius_m)) {
    throw MeshError("make_icosphere: radius_m " + std::to_string(radius_m) + " must be > 0");
  }
  // icosahedron: the 12 vertices (0, +-1, +-phi) and their cyclic permutations
  const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> pts = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                                      {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                                      {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
  for (auto& p : pts) p.normalize();
  std::vector<std::array<int, 3>> tris = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  // orient every face outward (normal along its centroid)
  for (auto& t : tris) {
    const Eigen::Vector3d n = (pts[t[1]] - pts[t[0]]).cross(pts[t[2]] - pts[t[0]]);
    if (n.dot(pts[t[0]] + pts[t[1]] + pts[t[2]]) < 0.0) std::swap(t[1], t[2]);
  }
  // subdivide: each triangle into four, midpoints pushed onto the unit sphere
  for (int l = 0; l < level; ++l) {
    std::unordered_map<std::uint64_t, int> midpoint;
    midpoint.reserve(tris.size() * 2);
    auto mid = [&](int a, int b) {
      const auto key = edge_key(a, b);
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      pts.push_back((pts[a] + pts[b]).normalized());
      const int id = static_cast<int>(pts.size()) - 1;
      midpoint.emplace(key, id);
      return id;
    };
    std::vector<std::array<int, 3>> next;
    next.reserve(tris.size() * 4);
    for (const auto& t : tris) {
      const int ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({t[1], bc, ab});
      next.push_back({t[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    tris.swap(next);
  }
  // the icosahedron's 12 vertices first (vertex k is the same point at every level), then the
  // others in reverse Cuthill-McKee order (neighbours close in memory); triangles relabelled and
  // sorted by their smallest vertex (stable; each keeps its orientation)
  std::vector<int> order(12);
  for (int k = 0; k < 12; ++k) order[static_cast<std::size_t>(k)] = k;
  for (const int v : reverse_cuthill_mckee(static_cast<int>(pts.size()), tris)) {
    if (v >= 12) order.push_back(v);
  }
  std::vector<int> label(pts.size());
  for (std::size_t k = 0; k < order.size(); ++k)
    label[static_cast<std::size_t>(order[k])] = static_cast<int>(k);
  for (auto& t : tris) {
    for (int& v : t) v = label[static_cast<std::size_t>(v)];
  }
  std::stable_sort(tris.begin(), tris.end(), [](const auto& a, const auto& b) {
    return std::min({a[0], a[1], a[2]}) < std::min({b[0], b[1], b[2]});
  });
  TriMesh m;
  m.vertices.resize(3, static_cast<Eigen::Index>(pts.size()));
  for (std::size_t k = 0; k < order.size(); ++k) {
    m.vertices.col(static_cast<Eigen::Index>(k)) =
        centre_m + radius_m * pts[static_cast<std::size_t>(order[k])];
  }
  m.triangles.resize(3, static_cast<Eigen::Index>(tris.size()));
  for (std::size_t t = 0; t < tris.size(); ++t) {
    m.triangles.col(static_cast<Eigen::Index>(t)) << tris[t][0], tris[t][1], tris[t][2];
  }
  build_adjacency(m);
  validate_closed_manifold(m);
  return m;
}

void build_adjacency(TriMesh& m) {
  const int nv = m.vertex_count();
  const int nt = m.triangle_count();
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const int i = m.triangles(k, t);
      if (i < 0 || i >= nv) {
        throw MeshError("triangle " + std::to_string(t) + " refers to vertex " + std::to_string(i) +
                        ", but the mesh has only " + std::to_string(nv) + " vertices");
      }
    }
  }
  // unique undirected edges, sorted by (a, b)
  std::vector<std::uint64_t> keys;
  keys.reserve(3 * static_cast<std::size_t>(std::max(nt, 0)));
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const int a = m.triangles(k, t), b = m.triangles((k + 1) % 3, t);
      if (a != b) keys.push_back(edge_key(a, b));
    }
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  m.edges.resize(2, static_cast<Eigen::Index>(keys.size()));
  for (std::size_t e = 0; e < keys.size(); ++e) {
    m.edges(0, static_cast<Eigen::Index>(e)) = static_cast<int>(keys[e] >> 32);
    m.edges(1, static_cast<Eigen::Index>(e)) = static_cast<int>(keys[e] & 0xffffffffu);
  }
  // faces of each vertex (Fig. 3, column "Faces"), ascending by construction
  m.vertex_face_offsets.assign(static_cast<std::size_t>(nv) + 1, 0);
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const int i = m.triangles(k, t);
      // a triangle with a repeated vertex is listed once for it
      if (k > 0 && m.triangles(0, t) == i) continue;
      if (k > 1 && m.triangles(1, t) == i) continue;
      ++m.vertex_face_offsets[static_cast<std::size_t>(i) + 1];
    }
  }
  for (int i = 0; i < nv; ++i) {
    m.vertex_face_offsets[static_cast<std::size_t>(i) + 1] +=
        m.vertex_face_offsets[static_cast<std::size_t>(i)];
  }
  m.vertex_faces.assign(static_cast<std::size_t>(m.vertex_face_offsets.back()), -1);
  {
    std::vector<int> fill(m.vertex_face_offsets.begin(), m.vertex_face_offsets.end() - 1);
    for (int t = 0; t < nt; ++t) {
      for (int k = 0; k < 3; ++k) {
        const int i = m.triangles(k, t);
        if (k > 0 && m.triangles(0, t) == i) continue;
        if (k > 1 && m.triangles(1, t) == i) continue;
        m.vertex_faces[static_cast<std::size_t>(fill[static_cast<std::size_t>(i)]++)] = t;
      }
    }
  }
  // first neighbours of each vertex, from the edge list
  m.vertex_neighbour_offsets.assign(static_cast<std::size_t>(nv) + 1, 0);
  for (int e = 0; e < m.edge_count(); ++e) {
    ++m.vertex_neighbour_offsets[static_cast<std::size_t>(m.edges(0, e)) + 1];
    ++m.vertex_neighbour_offsets[static_cast<std::size_t>(m.edges(1, e)) + 1];
  }
  for (int i = 0; i < nv; ++i) {
    m.vertex_neighbour_offsets[static_cast<std::size_t>(i) + 1] +=
        m.vertex_neighbour_offsets[static_cast<std::size_t>(i)];
  }
  m.vertex_neighbours.assign(static_cast<std::size_t>(m.vertex_neighbour_offsets.back()), -1);
  {
    std::vector<int> fill(m.vertex_neighbour_offsets.begin(), m.vertex_neighbour_offsets.end() - 1);
    for (int e = 0; e < m.edge_count(); ++e) {
      const int a = m.edges(0, e), b = m.edges(1, e);
      m.vertex_neighbours[static_cast<std::size_t>(fill[static_cast<std::size_t>(a)]++)] = b;
      m.vertex_neighbours[static_cast<std::size_t>(fill[static_cast<std::size_t>(b)]++)] = a;
    }
  }
  for (int i = 0; i < nv; ++i) {
    std::sort(
        m.vertex_neighbours.begin() + m.vertex_neighbour_offsets[static_cast<std::size_t>(i)],
        m.vertex_neighbours.begin() + m.vertex_neighbour_offsets[static_cast<std::size_t>(i) + 1]);
  }
}

namespace {

/// Degenerate triangles refused: a repeated vertex or (near) zero area.
void check_no_degenerate_triangle(const TriMesh& m) {
  // a triangle is degenerate when its area is below 1e-6 of its longest edge squared (a
  // sliver of aspect ratio ~1e6; float-stored files put collinear points ~1e-8 off the line)
  constexpr double kMinAreaRatio = 1e-6;
  for (int t = 0; t < m.triangle_count(); ++t) {
    const int a = m.triangles(0, t), b = m.triangles(1, t), c = m.triangles(2, t);
    if (a == b || b == c || c == a) {
      throw MeshError("degenerate triangle " + std::to_string(t) + " (" + std::to_string(a) + ", " +
                      std::to_string(b) + ", " + std::to_string(c) + ") repeats a vertex");
    }
    const Eigen::Vector3d ab = m.vertices.col(b) - m.vertices.col(a);
    const Eigen::Vector3d ac = m.vertices.col(c) - m.vertices.col(a);
    const Eigen::Vector3d bc = m.vertices.col(c) - m.vertices.col(b);
    const double area = 0.5 * ab.cross(ac).norm();
    const double longest2 = std::max({ab.squaredNorm(), ac.squaredNorm(), bc.squaredNorm()});
    if (!(area > kMinAreaRatio * longest2)) {
      std::ostringstream os;
      os << "degenerate triangle " << t << " (" << a << ", " << b << ", " << c
         << ") has zero area (" << area << " m^2) at " << point_text(m.vertices.col(a));
      throw MeshError(os.str());
    }
  }
}

/// Every undirected edge: exactly two triangles, traversed in opposite directions.
void check_edges_shared_by_two(const TriMesh& m) {
  struct Use {
    std::uint64_t key;
    int tri;
    bool forward;  // a < b in the triangle's winding
  };
  const int nt = m.triangle_count();
  std::vector<Use> uses;
  uses.reserve(static_cast<std::size_t>(nt) * 3);
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const int a = m.triangles(k, t), b = m.triangles((k + 1) % 3, t);
      uses.push_back({edge_key(a, b), t, a < b});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const Use& x, const Use& y) {
    return x.key != y.key ? x.key < y.key : x.tri < y.tri;
  });
  for (std::size_t s = 0; s < uses.size();) {
    std::size_t e = s;
    while (e < uses.size() && uses[e].key == uses[s].key) ++e;
    const int a = static_cast<int>(uses[s].key >> 32);
    const int b = static_cast<int>(uses[s].key & 0xffffffffu);
    const std::string edge = "edge (" + std::to_string(a) + ", " + std::to_string(b) + ") at " +
                             point_text(0.5 * (m.vertices.col(a) + m.vertices.col(b)));
    const std::size_t n = e - s;
    if (n == 1) {
      throw MeshError("open surface: " + edge + " belongs to only one triangle (" +
                      std::to_string(uses[s].tri) + "); the mesh has a hole or boundary");
    }
    if (n > 2) {
      std::string list;
      for (std::size_t k = s; k < e; ++k) list += (k > s ? ", " : "") + std::to_string(uses[k].tri);
      throw MeshError("non-manifold " + edge + " is shared by " + std::to_string(n) +
                      " triangles (" + list + ")");
    }
    if (uses[s].forward == uses[s + 1].forward) {
      throw MeshError("inconsistent orientation: triangles " + std::to_string(uses[s].tri) +
                      " and " + std::to_string(uses[s + 1].tri) + " traverse " + edge +
                      " in the same direction");
    }
    s = e;
  }
}

/// Every vertex: its triangles form one closed fan (else two surfaces touch at the vertex).
void check_vertex_fans(const TriMesh& m) {
  const int nv = m.vertex_count();
  std::vector<int> next_of(static_cast<std::size_t>(nv), -1);
  for (int i = 0; i < nv; ++i) {
    const int f0 = m.vertex_face_offsets[static_cast<std::size_t>(i)];
    const int f1 = m.vertex_face_offsets[static_cast<std::size_t>(i) + 1];
    int start = -1;
    for (int f = f0; f < f1; ++f) {
      const int t = m.vertex_faces[static_cast<std::size_t>(f)];
      int k = 0;
      while (m.triangles(k, t) != i) ++k;
      const int p = m.triangles((k + 1) % 3, t), q = m.triangles((k + 2) % 3, t);
      next_of[static_cast<std::size_t>(p)] = q;
      if (start < 0) start = p;
    }
    int steps = 0, cur = start;
    do {
      cur = next_of[static_cast<std::size_t>(cur)];
      ++steps;
    } while (cur != start && cur >= 0 && steps <= f1 - f0);
    // clean up for the next vertex
    for (int f = f0; f < f1; ++f) {
      const int t = m.vertex_faces[static_cast<std::size_t>(f)];
      for (int k = 0; k < 3; ++k) next_of[static_cast<std::size_t>(m.triangles(k, t))] = -1;
    }
    if (steps != f1 - f0) {
      throw MeshError("non-manifold vertex " + std::to_string(i) + " at " +
                      point_text(m.vertices.col(i)) + ": its " + std::to_string(f1 - f0) +
                      " triangles do not form a single fan (surfaces touch at a point)");
    }
  }
}

}  // namespace

void validate_closed_manifold(const TriMesh& m) {
  const int nv = m.vertex_count();
  const int nt = m.triangle_count();
  if (nt < 4 || nv < 4) {
    throw MeshError("the mesh has " + std::to_string(nv) + " vertices and " + std::to_string(nt) +
                    " triangles; a closed surface needs at least 4 of each");
  }
  if (static_cast<int>(m.vertex_face_offsets.size()) != nv + 1 ||
      static_cast<int>(m.vertex_neighbour_offsets.size()) != nv + 1) {
    throw MeshError("adjacency tables are missing or stale: call build_adjacency() first");
  }
  if (!m.vertices.allFinite()) {
    for (int i = 0; i < nv; ++i) {
      if (!m.vertices.col(i).allFinite()) {
        throw MeshError("vertex " + std::to_string(i) + " has a non-finite coordinate");
      }
    }
  }
  check_no_degenerate_triangle(m);
  // unused vertices
  for (int i = 0; i < nv; ++i) {
    if (m.face_count_of(i) == 0) {
      throw MeshError("vertex " + std::to_string(i) + " at " + point_text(m.vertices.col(i)) +
                      " is not used by any triangle");
    }
  }
  check_edges_shared_by_two(m);
  check_vertex_fans(m);
  const double vol = enclosed_volume(m);
  if (!(vol > 0.0)) {
    std::ostringstream os;
    os << "the surface is oriented inward: enclosed volume " << vol
       << " m^3 is not positive (triangles must be counter-clockwise seen from outside)";
    throw MeshError(os.str());
  }
}

double enclosed_volume(const TriMesh& m) {
  double v6 = 0.0;
  for (int t = 0; t < m.triangle_count(); ++t) {
    v6 += m.vertices.col(m.triangles(0, t))
              .dot(m.vertices.col(m.triangles(1, t)).cross(m.vertices.col(m.triangles(2, t))));
  }
  return v6 / 6.0;
}

TriMesh make_mesh(Eigen::Matrix3Xd vertices, Eigen::Matrix3Xi triangles) {
  TriMesh m;
  m.vertices = std::move(vertices);
  m.triangles = std::move(triangles);
  build_adjacency(m);
  validate_closed_manifold(m);
  return m;
}

void check_mesh_format(const std::string& extension) {
  std::string e = extension;
  if (!e.empty() && e[0] == '.') e.erase(0, 1);
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (e != "obj" && e != "stl" && e != "ply") {
    throw MeshError("mesh format '" + extension +
                    "' is not supported: use OBJ, STL or PLY (the importers that are checked; "
                    "Debian's assimp 5.2.5 aborts the whole process on some malformed files of "
                    "other formats, e.g. OFF)");
  }
}

namespace {

// Debian's assimp 5.2.5 never returns from some malformed PLY headers (tests/fuzz found one of
// 263 bytes: tests/fuzz/corpus/mesh/regression_ply_header_hang). A PLY file reaches it only with
// a header of the standard's grammar: "ply", "format ascii|binary_little_endian|
// binary_big_endian 1.0", then comment / obj_info / element NAME COUNT / property TYPE NAME /
// property list TYPE TYPE NAME lines, each property after an element, and "end_header", all
// within the first 64 KB.
bool ply_type(const std::string& t) {
  static const char* const kTypes[] = {"char",  "uchar",  "short",   "ushort", "int",   "uint",
                                       "float", "double", "int8",    "uint8",  "int16", "uint16",
                                       "int32", "uint32", "float32", "float64"};
  for (const char* k : kTypes) {
    if (t == k) return true;
  }
  return false;
}

void check_ply_header(const char* data, std::size_t size, const std::string& name) {
  constexpr std::size_t kMaxHeader = 64 * 1024;
  const std::string text(data, std::min(size, kMaxHeader));
  std::size_t pos = 0, line_no = 0;
  bool have_format = false, have_element = false;
  auto fail = [&](const std::string& why) {
    throw MeshError(name + ": PLY header line " + std::to_string(line_no) + ": " + why +
                    " (a PLY header is 'ply', 'format ascii|binary_little_endian|"
                    "binary_big_endian 1.0', element / property / comment lines, 'end_header')");
  };
  while (true) {
    const std::size_t nl = text.find('\n', pos);
    ++line_no;
    if (nl == std::string::npos) fail("no 'end_header' within the first 64 KB");
    std::string line = text.substr(pos, nl - pos);
    pos = nl + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream in(line);
    std::vector<std::string> w;
    for (std::string x; in >> x;) w.push_back(x);
    if (line_no == 1) {
      if (line != "ply") fail("the file must start with the line 'ply'");
      continue;
    }
    if (w.empty()) fail("an empty line");
    if (w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") {
      if (w.size() != 1) fail("'end_header' takes nothing after it");
      if (!have_format || !have_element) fail("'end_header' before a format and an element");
      return;
    }
    if (w[0] == "format") {
      if (have_format || w.size() != 3 || w[2] != "1.0" ||
          (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian")) {
        fail("a bad or second 'format' line");
      }
      have_format = true;
    } else if (w[0] == "element") {
      if (!have_format || w.size() != 3 || w[2].empty() ||
          w[2].find_first_not_of("0123456789") != std::string::npos || w[2].size() > 9) {
        fail("'element NAME COUNT' (after the format, COUNT a number below 1e9)");
      }
      have_element = true;
    } else if (w[0] == "property") {
      const bool list = w.size() == 5 && w[1] == "list" && ply_type(w[2]) && ply_type(w[3]);
      const bool scalar = w.size() == 3 && ply_type(w[1]);
      if (!have_element || !(list || scalar)) {
        fail("'property TYPE NAME' or 'property list TYPE TYPE NAME' after an element");
      }
    } else {
      fail("'" + w[0].substr(0, 32) + "' is not a PLY header keyword");
    }
  }
}

bool is_ply(const std::string& extension) {
  std::string e = extension;
  if (!e.empty() && e[0] == '.') e.erase(0, 1);
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e == "ply";
}

}  // namespace

void check_mesh_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (path.empty()) throw MeshError("the mesh file name is empty");
  if (fs::is_directory(path, ec)) throw MeshError(path + ": is a directory, not a mesh file");
  if (!fs::exists(path, ec)) throw MeshError(path + ": no such file");
  if (!fs::is_regular_file(path, ec)) {
    throw MeshError(path + ": is not a regular file (a device, pipe or socket)");
  }
  check_mesh_format(fs::path(path).extension().string());
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw MeshError(path + ": cannot read the file size: " + ec.message());
  if (size == 0) throw MeshError(path + ": the file is empty");
  if (size > kMaxMeshFileBytes) {
    throw MeshError(path + ": " + std::to_string(size >> 20) + " MB is larger than the " +
                    std::to_string(kMaxMeshFileBytes >> 20) + " MB a mesh file may have");
  }
  if (is_ply(fs::path(path).extension().string())) {
    std::ifstream f(path, std::ios::binary);
    std::string head(64 * 1024, '\0');
    f.read(head.data(), static_cast<std::streamsize>(head.size()));
    check_ply_header(head.data(), static_cast<std::size_t>(f.gcount()), path);
  }
}

namespace {
// The importer's flags: triangulate polygons and bake node transforms; no welding or clean-up
// by assimp, so that defects are reported rather than silently repaired.
constexpr unsigned kImportFlags = aiProcess_Triangulate | aiProcess_PreTransformVertices;

TriMesh mesh_from_scene(const aiScene* scene, const std::string& path, const LoadOptions& options);
}  // namespace

TriMesh load_mesh(const std::string& path, const LoadOptions& options) {
  check_mesh_file(path);
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, kImportFlags);
  if (scene == nullptr) {
    throw MeshError(path + ": cannot read mesh: " + importer.GetErrorString());
  }
  return mesh_from_scene(scene, path, options);
}

TriMesh load_mesh_from_memory(const void* data, std::size_t size, const std::string& format_hint,
                              const std::string& name, const LoadOptions& options) {
  if (size == 0) throw MeshError(name + ": the mesh is empty");
  try {
    check_mesh_format(format_hint);
  } catch (const MeshError& e) {
    throw MeshError(name + ": " + e.what());
  }
  if (is_ply(format_hint)) check_ply_header(static_cast<const char*>(data), size, name);
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFileFromMemory(data, size, kImportFlags, format_hint.c_str());
  if (scene == nullptr) {
    throw MeshError(name + ": cannot read mesh: " + importer.GetErrorString());
  }
  return mesh_from_scene(scene, name, options);
}

namespace {

/// The vertices (scaled) and triangles of every mesh of `scene` appended into one soup,
/// indices offset to it; points, lines and out-of-range indices refused.
void scene_soup(const aiScene* scene, const std::string& path, double scale,
                std::vector<Eigen::Vector3d>& raw, std::vector<std::array<int, 3>>& tris) {
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
    const aiMesh* am = scene->mMeshes[mi];
    const int base = static_cast<int>(raw.size());
    if (raw.size() + am->mNumVertices > static_cast<std::size_t>(kMaxMeshVertices)) {
      throw MeshError(path + ": more than " + std::to_string(kMaxMeshVertices) + " vertices");
    }
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D& p = am->mVertices[v];
      const Eigen::Vector3d q(scale * static_cast<double>(p.x), scale * static_cast<double>(p.y),
                              scale * static_cast<double>(p.z));
      if (!q.allFinite()) {
        throw MeshError(path + ": mesh " + std::to_string(mi) + " vertex " + std::to_string(v) +
                        " has a coordinate that is not a finite number");
      }
      raw.push_back(q);
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) {
        throw MeshError(path + ": mesh " + std::to_string(mi) + " face " + std::to_string(f) +
                        " has " + std::to_string(face.mNumIndices) +
                        " indices: points and lines are not a surface");
      }
      for (unsigned k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= am->mNumVertices) {
          throw MeshError(path + ": mesh " + std::to_string(mi) + " face " + std::to_string(f) +
                          " refers to vertex " + std::to_string(face.mIndices[k]) + " of " +
                          std::to_string(am->mNumVertices));
        }
      }
      tris.push_back({base + static_cast<int>(face.mIndices[0]),
                      base + static_cast<int>(face.mIndices[1]),
                      base + static_cast<int>(face.mIndices[2])});
    }
  }
}

/// Duplicate points welded: `welded` gets one point per cluster within weld_tolerance of the
/// bounding-box diagonal; the result maps each raw point to its welded index.
std::vector<int> weld(const std::vector<Eigen::Vector3d>& raw, double weld_tolerance,
                      std::vector<Eigen::Vector3d>& welded) {
  // hash on a grid of cell = tolerance, compare with the 27 nearby cells
  Eigen::Vector3d lo = raw[0], hi = raw[0];
  for (const auto& p : raw) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double tol = std::max(weld_tolerance * (hi - lo).norm(), 1e-300);
  auto cell_of = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3<long long>(static_cast<long long>(std::floor((p.x() - lo.x()) / tol)),
                                     static_cast<long long>(std::floor((p.y() - lo.y()) / tol)),
                                     static_cast<long long>(std::floor((p.z() - lo.z()) / tol)));
  };
  auto hash = [](long long x, long long y, long long z) {
    return static_cast<std::uint64_t>(x) * 73856093ULL ^
           static_cast<std::uint64_t>(y) * 19349663ULL ^
           static_cast<std::uint64_t>(z) * 83492791ULL;
  };
  std::unordered_map<std::uint64_t, std::vector<int>> grid;
  std::vector<int> remap(raw.size(), -1);
  for (std::size_t i = 0; i < raw.size(); ++i) {
    const auto c = cell_of(raw[i]);
    int found = -1;
    for (long long dx = -1; dx <= 1 && found < 0; ++dx) {
      for (long long dy = -1; dy <= 1 && found < 0; ++dy) {
        for (long long dz = -1; dz <= 1 && found < 0; ++dz) {
          auto it = grid.find(hash(c.x() + dx, c.y() + dy, c.z() + dz));
          if (it == grid.end()) continue;
          for (int w : it->second) {
            if ((welded[static_cast<std::size_t>(w)] - raw[i]).norm() <= tol) {
              found = w;
              break;
            }
          }
        }
      }
    }
    if (found < 0) {
      found = static_cast<int>(welded.size());
      welded.push_back(raw[i]);
      grid[hash(c.x(), c.y(), c.z())].push_back(found);
    }
    remap[i] = found;
  }
  return remap;
}

/// The mesh of the welded points that `tris` (raw indices, mapped through `remap`) uses, in
/// the file's vertex order; points no triangle uses (e.g. stray points in the file) dropped.
TriMesh used_mesh(const std::vector<Eigen::Vector3d>& welded, const std::vector<int>& remap,
                  std::vector<std::array<int, 3>> tris) {
  std::vector<int> used(welded.size(), -1);
  for (auto& t : tris) {
    for (int& i : t) {
      i = remap[static_cast<std::size_t>(i)];
      used[static_cast<std::size_t>(i)] = 1;
    }
  }
  int nv = 0;  // keep the file's vertex order
  for (int& u : used) u = u > 0 ? nv++ : -1;
  TriMesh m;
  m.vertices.resize(3, nv);
  for (std::size_t i = 0; i < welded.size(); ++i) {
    if (used[i] >= 0) m.vertices.col(used[i]) = welded[i];
  }
  m.triangles.resize(3, static_cast<Eigen::Index>(tris.size()));
  for (std::size_t t = 0; t < tris.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      m.triangles(k, static_cast<Eigen::Index>(t)) =
          used[static_cast<std::size_t>(tris[t][static_cast<std::size_t>(k)])];
    }
  }
  return m;
}

TriMesh mesh_from_scene(const aiScene* scene, const std::string& path, const LoadOptions& options) {
  if (!std::isfinite(options.scale) || options.scale <= 0.0) {
    throw MeshError(path + ": the scale must be a finite number > 0");
  }
  std::vector<Eigen::Vector3d> raw;
  std::vector<std::array<int, 3>> tris;
  scene_soup(scene, path, options.scale, raw, tris);
  if (tris.empty()) throw MeshError(path + ": the file contains no triangles");
  std::vector<Eigen::Vector3d> welded;
  const std::vector<int> remap = weld(raw, options.weld_tolerance, welded);
  TriMesh m = used_mesh(welded, remap, std::move(tris));
  if (options.fix_inward_orientation && enclosed_volume(m) < 0.0) {
    m.triangles.row(1).swap(m.triangles.row(2));
  }
  try {
    build_adjacency(m);
    validate_closed_manifold(m);
  } catch (const MeshError& e) {
    throw MeshError(path + ": " + e.what() + " (indices after welding duplicate vertices)");
  }
  return m;
}

}  // namespace

void save_obj(const TriMesh& m, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw MeshError(path + ": cannot open for writing");
  out.precision(17);
  for (int i = 0; i < m.vertex_count(); ++i) {
    out << "v " << m.vertices(0, i) << " " << m.vertices(1, i) << " " << m.vertices(2, i) << "\n";
  }
  for (int t = 0; t < m.triangle_count(); ++t) {
    out << "f " << m.triangles(0, t) + 1 << " " << m.triangles(1, t) + 1 << " "
        << m.triangles(2, t) + 1 << "\n";
  }
  if (!out) throw MeshError(path + ": write failed");
}

}  // namespace teleop::mesh

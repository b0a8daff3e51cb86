// Mesh tables (paper Fig. 3), icosphere invariants and the assimp loader's checks.
#include "common/mesh/tri_mesh.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <unistd.h>

namespace {

using teleop::mesh::MeshError;
using teleop::mesh::TriMesh;

std::filesystem::path temp_dir() {
  auto d =
      std::filesystem::temp_directory_path() / ("teleop_mesh_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(d);
  return d;
}

// Expects `fn` to throw MeshError whose message contains `needle`.
template <typename Fn>
void expect_mesh_error(Fn fn, const std::string& needle) {
  try {
    fn();
    ADD_FAILURE() << "no MeshError; expected one mentioning '" << needle << "'";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
        << "message: " << e.what() << "\nexpected to contain: " << needle;
  }
}

class IcosphereLevels : public ::testing::TestWithParam<int> {};

TEST_P(IcosphereLevels, CountsEulerValenceAndOrientation) {
  const int level = GetParam();
  const double r = 0.25;
  const Eigen::Vector3d c(0.1, -0.2, 0.3);
  const TriMesh m = teleop::mesh::make_icosphere(level, r, c);
  const long long f = 20LL << (2 * level);
  EXPECT_EQ(m.triangle_count(), f);
  EXPECT_EQ(m.vertex_count(), f / 2 + 2);
  EXPECT_EQ(m.edge_count(), f * 3 / 2);
  EXPECT_EQ(m.euler_characteristic(), 2);
  int valence5 = 0;
  for (int i = 0; i < m.vertex_count(); ++i) {
    const int val = m.face_count_of(i);
    ASSERT_TRUE(val == 5 || val == 6) << "vertex " << i << " valence " << val;
    EXPECT_EQ(m.neighbour_count_of(i), val);
    valence5 += val == 5;
    EXPECT_NEAR((m.vertices.col(i) - c).norm(), r, 1e-12);
  }
  EXPECT_EQ(valence5, 12);  // the icosahedron's corners
  // every triangle faces outward
  for (int t = 0; t < m.triangle_count(); ++t) {
    const Eigen::Vector3d a = m.vertices.col(m.triangles(0, t)) - c;
    const Eigen::Vector3d b = m.vertices.col(m.triangles(1, t)) - c;
    const Eigen::Vector3d d = m.vertices.col(m.triangles(2, t)) - c;
    ASSERT_GT((b - a).cross(d - a).dot(a + b + d), 0.0) << "triangle " << t;
  }
  EXPECT_NO_THROW(teleop::mesh::validate_closed_manifold(m));
  // volume converges to the ball's from below
  const double ball = 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_LT(teleop::mesh::enclosed_volume(m), ball);
  EXPECT_GT(teleop::mesh::enclosed_volume(m), (level >= 3 ? 0.97 : 0.5) * ball);
}

INSTANTIATE_TEST_SUITE_P(Levels, IcosphereLevels, ::testing::Values(0, 1, 2, 3, 4, 5));

TEST(Icosphere, Level6HasPaperCountsTimes16) {
  const TriMesh m = teleop::mesh::make_icosphere(6, 1.0, Eigen::Vector3d::Zero());
  EXPECT_EQ(m.vertex_count(), 40962);
  EXPECT_EQ(m.triangle_count(), 81920);
  EXPECT_EQ(m.euler_characteristic(), 2);
}

TEST(Icosphere, PaperLevel4Counts) {
  const TriMesh m = teleop::mesh::make_icosphere(4, 0.25, Eigen::Vector3d(0, 0, 0.25));
  EXPECT_EQ(m.triangle_count(), 5120);
  EXPECT_EQ(m.vertex_count(), 2562);
  EXPECT_EQ(m.edge_count(), 7680);
  // the redundant point list of the paper: 3 per triangle
  EXPECT_EQ(static_cast<int>(m.vertex_faces.size()), 15360);
  EXPECT_EQ(teleop::mesh::icosphere_vertex_count(4), 2562);
  EXPECT_EQ(teleop::mesh::icosphere_triangle_count(4), 5120);
}

// Vertices 0-11 are the icosahedron's corners at every level (the benchmarks pull vertex 5 at
// every level and compare); the others are ordered so that neighbours are close in memory:
// at level 4 the mean |i - j| over the edges is below 100 (creation order: 674) and at level 5
// below 200 (creation order: 2632).
TEST(Icosphere, CornersFirstThenNeighboursCloseInMemory) {
  const TriMesh base = teleop::mesh::make_icosphere(0, 1.0, Eigen::Vector3d::Zero());
  for (int level = 1; level <= 5; ++level) {
    const TriMesh m = teleop::mesh::make_icosphere(level, 1.0, Eigen::Vector3d::Zero());
    for (int k = 0; k < 12; ++k) {
      EXPECT_LT((m.vertices.col(k) - base.vertices.col(k)).norm(), 1e-12)
          << "level " << level << " vertex " << k;
      EXPECT_EQ(m.face_count_of(k), 5) << "level " << level << " vertex " << k;
    }
    double sum = 0.0;
    for (int e = 0; e < m.edge_count(); ++e) sum += m.edges(1, e) - m.edges(0, e);
    const double mean = sum / m.edge_count();
    std::printf("level %d: mean |i - j| over the edges %.1f\n", level, mean);
    if (level == 4) {
      EXPECT_LT(mean, 100.0);
    } else if (level == 5) {
      EXPECT_LT(mean, 200.0);
    }
  }
  // deterministic: the same mesh twice
  const TriMesh a = teleop::mesh::make_icosphere(3, 1.0, Eigen::Vector3d::Zero());
  const TriMesh b = teleop::mesh::make_icosphere(3, 1.0, Eigen::Vector3d::Zero());
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.triangles, b.triangles);
}

TEST(Icosphere, RejectsBadArguments) {
  expect_mesh_error([] { teleop::mesh::make_icosphere(7, 1.0, Eigen::Vector3d::Zero()); },
                    "level 7");
  expect_mesh_error([] { teleop::mesh::make_icosphere(-1, 1.0, Eigen::Vector3d::Zero()); },
                    "level -1");
  expect_mesh_error([] { teleop::mesh::make_icosphere(2, 0.0, Eigen::Vector3d::Zero()); },
                    "radius");
}

// The worked example of the paper's Fig. 3 (an open patch, 1-based vertex numbers).
TEST(Adjacency, PaperFigure3Tables) {
  TriMesh m;
  m.vertices = Eigen::Matrix3Xd::Zero(3, 16);  // vertex 0 unused: paper numbers from 1
  const int tri[16][3] = {{1, 2, 6},    {2, 7, 6},    {2, 3, 7},    {3, 8, 7},
                          {3, 4, 8},    {4, 9, 8},    {4, 5, 9},    {6, 7, 10},
                          {7, 11, 10},  {7, 8, 11},   {8, 12, 11},  {8, 9, 12},
                          {10, 11, 13}, {11, 14, 13}, {11, 12, 14}, {13, 14, 15}};
  m.triangles.resize(3, 16);
  for (int t = 0; t < 16; ++t) m.triangles.col(t) << tri[t][0], tri[t][1], tri[t][2];
  teleop::mesh::build_adjacency(m);
  auto faces_of = [&](int v) {
    std::string s;
    for (int k = m.vertex_face_offsets[v]; k < m.vertex_face_offsets[v + 1]; ++k) {
      s += static_cast<char>('A' + m.vertex_faces[k]);
    }
    return s;
  };
  auto neighbours_of = [&](int v) {
    return std::vector<int>(m.vertex_neighbours.begin() + m.vertex_neighbour_offsets[v],
                            m.vertex_neighbours.begin() + m.vertex_neighbour_offsets[v + 1]);
  };
  EXPECT_EQ(faces_of(7), "BCDHIJ");
  EXPECT_EQ(faces_of(8), "DEFJKL");
  EXPECT_EQ(faces_of(11), "IJKMNO");
  EXPECT_EQ(faces_of(1), "A");
  EXPECT_EQ(faces_of(15), "P");
  EXPECT_EQ(neighbours_of(1), (std::vector<int>{2, 6}));
  EXPECT_EQ(neighbours_of(11), (std::vector<int>{7, 8, 10, 12, 13, 14}));
  // an open patch is not a closed surface
  expect_mesh_error([&] { teleop::mesh::validate_closed_manifold(m); }, "");
}

void write_obj(const TriMesh& m, const std::filesystem::path& p) {
  teleop::mesh::save_obj(m, p.string());
}

// ASCII STL: three vertices per facet, so the loader must weld.
void write_stl(const TriMesh& m, const std::filesystem::path& p) {
  std::ofstream out(p);
  out.precision(17);
  out << "solid test\n";
  for (int t = 0; t < m.triangle_count(); ++t) {
    const Eigen::Vector3d a = m.vertices.col(m.triangles(0, t));
    const Eigen::Vector3d b = m.vertices.col(m.triangles(1, t));
    const Eigen::Vector3d c = m.vertices.col(m.triangles(2, t));
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    out << "facet normal " << n.x() << " " << n.y() << " " << n.z() << "\n outer loop\n";
    for (const auto& v : {a, b, c})
      out << "  vertex " << v.x() << " " << v.y() << " " << v.z() << "\n";
    out << " endloop\nendfacet\n";
  }
  out << "endsolid test\n";
}

void write_ply(const TriMesh& m, const std::filesystem::path& p) {
  std::ofstream out(p);
  out.precision(17);
  out << "ply\nformat ascii 1.0\nelement vertex " << m.vertex_count()
      << "\nproperty float x\nproperty float y\nproperty float z\nelement face "
      << m.triangle_count() << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < m.vertex_count(); ++i) {
    out << m.vertices(0, i) << " " << m.vertices(1, i) << " " << m.vertices(2, i) << "\n";
  }
  for (int t = 0; t < m.triangle_count(); ++t) {
    out << "3 " << m.triangles(0, t) << " " << m.triangles(1, t) << " " << m.triangles(2, t)
        << "\n";
  }
}

TEST(Loader, ReadsObjStlPlyIntoTheSameTables) {
  const auto dir = temp_dir();
  const TriMesh ref = teleop::mesh::make_icosphere(2, 0.5, Eigen::Vector3d(0, 0, 1));
  write_obj(ref, dir / "s.obj");
  write_stl(ref, dir / "s.stl");
  write_ply(ref, dir / "s.ply");
  for (const char* name : {"s.obj", "s.stl", "s.ply"}) {
    SCOPED_TRACE(name);
    const TriMesh m = teleop::mesh::load_mesh((dir / name).string());
    EXPECT_EQ(m.vertex_count(), ref.vertex_count());
    EXPECT_EQ(m.triangle_count(), ref.triangle_count());
    EXPECT_EQ(m.edge_count(), ref.edge_count());
    EXPECT_EQ(m.euler_characteristic(), 2);
    EXPECT_NEAR(teleop::mesh::enclosed_volume(m), teleop::mesh::enclosed_volume(ref), 1e-5);
    for (int i = 0; i < m.vertex_count(); ++i) {
      EXPECT_NEAR((m.vertices.col(i) - Eigen::Vector3d(0, 0, 1)).norm(), 0.5, 1e-6);
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(Loader, FlipsAnInwardSurface) {
  const auto dir = temp_dir();
  TriMesh ref = teleop::mesh::make_icosphere(1, 1.0, Eigen::Vector3d::Zero());
  ref.triangles.row(1).swap(ref.triangles.row(2));
  write_obj(ref, dir / "inward.obj");
  const TriMesh m = teleop::mesh::load_mesh((dir / "inward.obj").string());
  EXPECT_GT(teleop::mesh::enclosed_volume(m), 0.0);
  teleop::mesh::LoadOptions keep;
  keep.fix_inward_orientation = false;
  expect_mesh_error([&] { teleop::mesh::load_mesh((dir / "inward.obj").string(), keep); },
                    "oriented inward");
  std::filesystem::remove_all(dir);
}

TEST(Loader, RefusesOpenMeshNamingTheEdge) {
  const auto dir = temp_dir();
  TriMesh m = teleop::mesh::make_icosphere(1, 1.0, Eigen::Vector3d::Zero());
  Eigen::Matrix3Xi t = m.triangles.leftCols(m.triangle_count() - 1);
  m.triangles = t;
  write_obj(m, dir / "open.obj");
  expect_mesh_error([&] { teleop::mesh::load_mesh((dir / "open.obj").string()); },
                    "open surface: edge (");
  expect_mesh_error([&] { teleop::mesh::load_mesh((dir / "open.obj").string()); }, "open.obj");
  std::filesystem::remove_all(dir);
}

// Two tetrahedra sharing one edge: that edge has four triangles.
TEST(Loader, RefusesNonManifoldEdge) {
  const auto dir = temp_dir();
  std::ofstream out(dir / "nm_edge.obj");
  out << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0 -1 0\nv 0 0 -1\n"
      << "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"   // tetra (1,2,3,4)
      << "f 1 2 5\nf 1 6 2\nf 1 5 6\nf 2 6 5\n";  // tetra (1,2,5,6) shares edge 1-2
  out.close();
  expect_mesh_error([&] { teleop::mesh::load_mesh((dir / "nm_edge.obj").string()); },
                    "is shared by 4 triangles");
  std::filesystem::remove_all(dir);
}

// Two tetrahedra touching at one vertex: every edge is fine, the vertex is not.
TEST(Loader, RefusesNonManifoldVertex) {
  const auto dir = temp_dir();
  std::ofstream out(dir / "nm_vertex.obj");
  out << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv -1 0 0\nv 0 -1 0\nv 0 0 -1\n"
      << "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
      << "f 1 5 6\nf 1 6 7\nf 1 7 5\nf 5 7 6\n";
  out.close();
  expect_mesh_error([&] { teleop::mesh::load_mesh((dir / "nm_vertex.obj").string()); },
                    "non-manifold vertex 0");
  std::filesystem::remove_all(dir);
}

TEST(Loader, RefusesDegenerateTriangle) {
  const auto dir = temp_dir();
  TriMesh m = teleop::mesh::make_icosphere(1, 1.0, Eigen::Vector3d::Zero());
  // put the third corner of triangle 5 on the midpoint of its first edge: zero area
  const int a = m.triangles(0, 5), b = m.triangles(1, 5), c = m.triangles(2, 5);
  m.vertices.col(c) = 0.5 * (m.vertices.col(a) + m.vertices.col(b));
  write_obj(m, dir / "flat.obj");
  expect_mesh_error([&] { teleop::mesh::load_mesh((dir / "flat.obj").string()); },
                    "degenerate triangle");
  // two corners at the same place weld into a repeated vertex
  TriMesh w = teleop::mesh::make_icosphere(1, 1.0, Eigen::Vector3d::Zero());
  w.vertices.col(w.triangles(1, 0)) = w.vertices.col(w.triangles(0, 0));
  write_obj(w, dir / "weld.obj");
  expect_mesh_error([&] { teleop::mesh::load_mesh((dir / "weld.obj").string()); },
                    "degenerate triangle");
  std::filesystem::remove_all(dir);
}

TEST(Loader, RefusesInconsistentOrientation) {
  TriMesh m = teleop::mesh::make_icosphere(1, 1.0, Eigen::Vector3d::Zero());
  std::swap(m.triangles(1, 3), m.triangles(2, 3));
  expect_mesh_error([&] { teleop::mesh::make_mesh(m.vertices, m.triangles); },
                    "inconsistent orientation");
}

TEST(Loader, RefusesMissingAndNonMeshFiles) {
  const auto dir = temp_dir();
  expect_mesh_error([&] { teleop::mesh::load_mesh((dir / "missing.obj").string()); },
                    "missing.obj");
  std::ofstream(dir / "garbage.stl") << "this is not a mesh";
  expect_mesh_error([&] { teleop::mesh::load_mesh((dir / "garbage.stl").string()); },
                    "garbage.stl");
  std::filesystem::remove_all(dir);
}

TEST(Adjacency, RejectsOutOfRangeIndex) {
  TriMesh m = teleop::mesh::make_icosphere(0, 1.0, Eigen::Vector3d::Zero());
  m.triangles(2, 7) = 99;
  expect_mesh_error([&] { teleop::mesh::build_adjacency(m); }, "vertex 99");
}

}  // namespace

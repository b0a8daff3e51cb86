// Tetrahedral meshes: tables, boundary, the MSH reader's errors, the shipped balls.
#include "common/mesh/tet_mesh.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace msh = teleop::mesh;

namespace {

// The unit cube split into 6 tetrahedra around its diagonal (0,0,0)-(1,1,1), plus a centre
// node inside (unused, so dropped).
msh::TetMesh cube() {
  Eigen::Matrix3Xd v(3, 9);
  v << 0, 1, 1, 0, 0, 1, 1, 0, 0.5,  //
      0, 0, 1, 1, 0, 0, 1, 1, 0.5,   //
      0, 0, 0, 0, 1, 1, 1, 1, 0.5;
  Eigen::Matrix4Xi t(4, 6);
  t << 0, 0, 0, 0, 0, 0,  //
      1, 2, 3, 7, 4, 5,   //
      2, 3, 7, 4, 5, 1,   //
      6, 6, 6, 6, 6, 6;
  return msh::make_tet_mesh(v, t);
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST(TetMesh, CubeHasAClosedBoundaryWithItsNodesFirst) {
  const msh::TetMesh m = cube();
  EXPECT_EQ(m.node_count(), 8);  // the unused centre node is dropped
  EXPECT_EQ(m.tet_count(), 6);
  EXPECT_EQ(m.surface_vertex_count, 8);
  EXPECT_EQ(m.surface.triangle_count(), 12);
  EXPECT_NEAR(msh::total_volume(m), 1.0, 1e-12);
  EXPECT_NEAR(msh::enclosed_volume(m.surface), 1.0, 1e-12);  // outward orientation
  for (int t = 0; t < m.tet_count(); ++t) EXPECT_GT(msh::tet_volume(m, t), 0.0);
}

TEST(TetMesh, NegativeTetrahedraAreFlippedDegenerateOnesRefused) {
  Eigen::Matrix3Xd v(3, 4);
  v << 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1;
  Eigen::Matrix4Xi t(4, 1);
  t << 0, 2, 1, 3;  // negative
  const msh::TetMesh m = msh::make_tet_mesh(v, t);
  EXPECT_NEAR(msh::tet_volume(m, 0), 1.0 / 6.0, 1e-15);
  v(2, 3) = 0.0;  // flat
  EXPECT_THROW(
      {
        try {
          msh::make_tet_mesh(v, t);
        } catch (const msh::MeshError& e) {
          EXPECT_NE(std::string(e.what()).find("degenerate tetrahedron 0"), std::string::npos);
          throw;
        }
      },
      msh::MeshError);
  t(3, 0) = 7;
  EXPECT_THROW(msh::make_tet_mesh(v, t), msh::MeshError);
}

TEST(TetMesh, MshReaderNamesFileLineAndProblem) {
  const std::string good =
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
      "$EndNodes\n$Elements\n2\n1 15 2 0 1 1\n2 4 2 0 1 1 2 3 4\n$EndElements\n";
  const msh::TetMesh m =
      msh::load_tet_mesh(write_file("teleop_ok.msh", good), 2.0, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(m.tet_count(), 1);
  EXPECT_NEAR(msh::total_volume(m), 8.0 / 6.0, 1e-12);
  EXPECT_NEAR(m.vertices.row(2).minCoeff(), 1.0, 1e-12);
  auto message = [](const std::string& path) {
    try {
      msh::load_tet_mesh(path);
    } catch (const msh::MeshError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string v4 = good;
  v4.replace(v4.find("2.2 0 8"), 7, "4.1 0 8");
  EXPECT_NE(message(write_file("teleop_v4.msh", v4)).find("MSH version"), std::string::npos);
  std::string bad_node = good;
  bad_node.replace(bad_node.find("2 3 4\n"), 6, "2 3 9\n");
  EXPECT_NE(message(write_file("teleop_bad_node.msh", bad_node)).find("node id 9"),
            std::string::npos);
  std::string cut = good.substr(0, good.find("$Elements"));
  EXPECT_NE(message(write_file("teleop_cut.msh", cut)).find("missing"), std::string::npos);
  EXPECT_NE(message("/nonexistent.msh").find("no such"), std::string::npos);
}

TEST(TetMesh, ShippedBallsAreClosedFillTheSphereAndAreFinestAtThePoles) {
  int previous_tets = 0;
  for (int level = 1; level <= msh::kMaxBallTetLevel; ++level) {
    SCOPED_TRACE(level);
    const msh::TetMesh m = msh::ball_tet_mesh(level, 0.25, Eigen::Vector3d(0, 0, 0.25));
    EXPECT_GT(m.tet_count(), previous_tets);
    previous_tets = m.tet_count();
    const double sphere = 4.0 / 3.0 * M_PI * std::pow(0.25, 3);
    EXPECT_NEAR(msh::total_volume(m), sphere, 0.05 * sphere);  // inscribed facets
    EXPECT_NEAR(msh::total_volume(m), msh::enclosed_volume(m.surface), 1e-9);
    EXPECT_EQ(m.surface.euler_characteristic(), 2);
    // boundary nodes on the sphere, interior nodes inside it
    for (int i = 0; i < m.node_count(); ++i) {
      const double r = (m.vertices.col(i) - Eigen::Vector3d(0, 0, 0.25)).norm();
      if (i < m.surface_vertex_count) {
        EXPECT_NEAR(r, 0.25, 1e-6);
      } else {
        EXPECT_LT(r, 0.25 - 1e-6);
      }
    }
    // surface edges near the top pole are shorter than at the equator
    double pole = 1e9, equator = 0.0;
    for (int e = 0; e < m.surface.edge_count(); ++e) {
      const Eigen::Vector3d a = m.vertices.col(m.surface.edges(0, e));
      const Eigen::Vector3d b = m.vertices.col(m.surface.edges(1, e));
      const double len = (a - b).norm();
      const double z = 0.5 * (a.z() + b.z()) - 0.25;
      if (z > 0.24) pole = std::min(pole, len);
      if (std::fabs(z) < 0.02) equator = std::max(equator, len);
    }
    EXPECT_LT(pole * 2.0, equator);
  }
  EXPECT_THROW(msh::ball_tet_mesh(0, 0.25, Eigen::Vector3d::Zero()), msh::MeshError);
}

TEST(TetMesh, GmshFillsAClosedSurfaceKeepingItsTriangles) {
  if (std::system("command -v gmsh > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "gmsh is not installed (deploy/setup.sh installs it)";
  }
  const msh::TriMesh surface = msh::make_icosphere(2, 0.1, Eigen::Vector3d(0, 0, 0.1));
  const msh::TetMesh m =
      msh::tetrahedralize(surface, 0.03, std::filesystem::temp_directory_path().string());
  EXPECT_EQ(m.surface_vertex_count, surface.vertex_count());
  EXPECT_EQ(m.surface.triangle_count(), surface.triangle_count());
  EXPECT_GT(m.node_count(), m.surface_vertex_count);  // interior nodes were added
  EXPECT_NEAR(msh::total_volume(m), msh::enclosed_volume(surface), 1e-9);
  for (int t = 0; t < m.tet_count(); ++t) EXPECT_GT(msh::tet_volume(m, t), 0.0);
  // an open surface is refused with gmsh's reason
  msh::TriMesh open = surface;
  open.triangles.conservativeResize(3, open.triangles.cols() - 1);
  EXPECT_THROW(msh::tetrahedralize(open, 0.03, std::filesystem::temp_directory_path().string()),
               msh::MeshError);
}

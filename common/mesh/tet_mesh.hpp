#pragma once
// Tetrahedral meshes of solid bodies: what the volumetric FEM steps, and the boundary surface
// that collision, the viewer and the DDS mesh topics see.
//
// Sources:
//   - the shipped meshes of a ball refined at both poles (deploy/data/tet/ball_L<level>.msh,
//     made offline by deploy/data/tet/make_ball_meshes.sh with gmsh): ball_tet_mesh();
//   - any gmsh MSH 2.2 ASCII file: load_tet_mesh();
//   - any closed surface (OBJ/STL/PLY through load_mesh): tetrahedralize(), which runs Debian's
//     gmsh as a separate program (GPL: run, never linked) and reads its output back.
// Every source ends in make_tet_mesh(), which checks the tables and puts the boundary vertices
// first, so that vertex i of the surface is node i of the solid.
#include <Eigen/Core>
#include <string>

#include "common/mesh/tri_mesh.hpp"

namespace teleop::mesh {

/// A tetrahedral mesh with its boundary surface.
struct TetMesh {
  Eigen::Matrix3Xd vertices;  ///< column per node [m]; boundary nodes first
  Eigen::Matrix4Xi
      tets;  ///< column per tetrahedron, positive volume (det(x1-x0, x2-x0, x3-x0) > 0)
  int surface_vertex_count = 0;  ///< nodes 0 .. surface_vertex_count - 1 lie on the boundary
  /// The boundary: vertices are the first surface_vertex_count nodes, triangles counter-clockwise
  /// seen from outside; a closed manifold (validate_closed_manifold passed).
  TriMesh surface;
  int node_count() const { return static_cast<int>(vertices.cols()); }
  int tet_count() const { return static_cast<int>(tets.cols()); }
};

/// Builds a TetMesh from raw tables: checks indices and finiteness, orients every tetrahedron
/// positively, refuses degenerate ones (|volume| <= 1e-12 of the bounding box's), drops unused
/// nodes, extracts the boundary (faces used by one tetrahedron), checks it is a closed manifold,
/// and renumbers the nodes boundary first (each group in its old order).
/// @throws MeshError naming what is wrong and where.
TetMesh make_tet_mesh(const Eigen::Matrix3Xd& vertices, const Eigen::Matrix4Xi& tets);

/// Reads a gmsh MSH 2.2 ASCII file (the 4-node tetrahedra, element type 4; other elements are
/// ignored), scales the coordinates and adds `offset_m`. @throws MeshError naming the file, the
/// line and what is wrong (other MSH versions, binary files, missing sections, bad numbers).
TetMesh load_tet_mesh(const std::string& path, double scale = 1.0,
                      const Eigen::Vector3d& offset_m = Eigen::Vector3d::Zero());

/// Most resolution levels of the shipped ball meshes (1 coarsest .. kMaxBallTetLevel finest).
constexpr int kMaxBallTetLevel = 4;
/// Path of the shipped unit-ball mesh of `level` (1 .. kMaxBallTetLevel).
std::string ball_tet_mesh_path(int level);
/// The shipped ball of `level`, scaled to radius_m and centred at centre_m. @throws MeshError.
TetMesh ball_tet_mesh(int level, double radius_m, const Eigen::Vector3d& centre_m);

/// Fills the closed surface with tetrahedra of edge length up to max_edge_m [m] by running gmsh
/// (the surface's own triangles are kept as the boundary). work_dir: an existing folder for the
/// temporary files (removed afterwards). @throws MeshError when gmsh is missing (saying which
/// package brings it), fails, or returns a mesh whose boundary is not the input's.
TetMesh tetrahedralize(const TriMesh& surface, double max_edge_m, const std::string& work_dir);

/// Volume of tetrahedron t [m^3] (positive for the orientation make_tet_mesh enforces).
double tet_volume(const TetMesh& mesh, int t);
/// Sum of the tetrahedra's volumes [m^3].
double total_volume(const TetMesh& mesh);

}  // namespace teleop::mesh

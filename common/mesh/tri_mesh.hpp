#pragma once
// Closed triangle meshes and their adjacency tables (the paper's Fig. 3).
//
// A TriMesh holds vertex positions, triangles (counter-clockwise seen from outside), the unique
// undirected edges and two compressed (CSR) adjacency tables: the faces around each vertex
// ("Faces" column of Fig. 3) and the first neighbours of each vertex. The deformable models
// (server/deformable/) and the collision code read these tables; nothing here allocates after
// construction.
//
//   teleop::mesh::TriMesh m = teleop::mesh::make_icosphere(4, 0.25, {0, 0, 0.25});
//   // m.vertex_count() == 2562, m.triangle_count() == 5120, m.edge_count() == 7680
//   for (int k = m.vertex_neighbour_offsets[i]; k < m.vertex_neighbour_offsets[i + 1]; ++k)
//     use(m.vertex_neighbours[k]);
#include <Eigen/Core>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace teleop::mesh {

/// A mesh that is not a usable closed surface. what() says what is wrong and where (which
/// file, edge, vertex or triangle).
class MeshError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A triangle surface mesh with its adjacency tables.
struct TriMesh {
  Eigen::Matrix3Xd vertices;   ///< column per vertex [m]
  Eigen::Matrix3Xi triangles;  ///< column per triangle, counter-clockwise seen from outside
  Eigen::Matrix2Xi edges;      ///< unique undirected edges, (a, b) with a < b, sorted
  /// CSR: faces of vertex i are vertex_faces[vertex_face_offsets[i] .. offsets[i+1]), ascending.
  std::vector<int> vertex_face_offsets, vertex_faces;
  /// CSR: first neighbours of vertex i, ascending; same layout as vertex_faces.
  std::vector<int> vertex_neighbour_offsets, vertex_neighbours;

  int vertex_count() const { return static_cast<int>(vertices.cols()); }
  int triangle_count() const { return static_cast<int>(triangles.cols()); }
  int edge_count() const { return static_cast<int>(edges.cols()); }
  /// Number of triangles that contain vertex i (its valence in a closed mesh).
  int face_count_of(int i) const { return vertex_face_offsets[i + 1] - vertex_face_offsets[i]; }
  /// Number of first neighbours of vertex i.
  int neighbour_count_of(int i) const {
    return vertex_neighbour_offsets[i + 1] - vertex_neighbour_offsets[i];
  }
  /// Euler characteristic V - E + F (2 for a closed surface of genus 0).
  int euler_characteristic() const { return vertex_count() - edge_count() + triangle_count(); }
};

/// Number of vertices of an icosphere of subdivision `level`: 10 * 4^level + 2.
int icosphere_vertex_count(int level);
/// Number of triangles of an icosphere of subdivision `level`: 20 * 4^level.
int icosphere_triangle_count(int level);

/// An icosahedron subdivided `level` times (each triangle into four, new points moved onto
/// the sphere), scaled to `radius_m` and centred at `centre_m`; adjacency built.
/// level 0: 12 vertices, 20 triangles; level 4 (the paper's sphere): 2562 / 5120 / 7680 edges;
/// level 6: 40962 vertices. Vertices 0-11 are the icosahedron's corners (the same points at every
/// level), the others in reverse Cuthill-McKee order (neighbours close in memory); triangles
/// sorted by their smallest vertex. @throws MeshError if level is outside [0, 6] or radius <= 0.
TriMesh make_icosphere(int level, double radius_m, const Eigen::Vector3d& centre_m);

/// Options for load_mesh.
struct LoadOptions {
  double scale = 1.0;  ///< multiplies file coordinates to get metres
  /// Vertices closer than weld_tolerance * (bounding-box diagonal) are merged.
  double weld_tolerance = 1e-9;
  /// Flip every triangle if the closed surface is oriented inward (negative volume).
  bool fix_inward_orientation = true;
};

/// Largest mesh file load_mesh() reads [bytes] and most vertices it accepts.
constexpr std::uintmax_t kMaxMeshFileBytes = std::uintmax_t{512} << 20;
constexpr int kMaxMeshVertices = 1 << 24;

/// Refuses a format other than OBJ, STL and PLY (`extension` with or without the dot, any case):
/// Debian's assimp 5.2.5 aborts the process (ai_assert in TriangulateProcess) on some malformed
/// OFF files (found by tests/fuzz/fuzz_mesh.cpp), so only the importers we test are used.
/// @throws MeshError.
void check_mesh_format(const std::string& extension);

/// Refuses what is not a readable mesh file before assimp sees it: an empty name, a missing
/// file, a directory, a device or pipe, a format check_mesh_format() refuses, an empty file, a
/// file larger than kMaxMeshFileBytes.
/// @throws MeshError naming the path and the reason.
void check_mesh_file(const std::string& path);

/// Loads a closed triangle mesh (OBJ, STL or PLY: check_mesh_file()): polygons are
/// triangulated, all sub-meshes are merged, duplicate vertices welded, unused vertices dropped,
/// an inward-facing surface flipped, adjacency built, then validate_closed_manifold() runs.
/// @throws MeshError naming the file and the defect (unreadable, no triangles, open edge,
/// non-manifold edge or vertex, degenerate triangle, inconsistent orientation).
TriMesh load_mesh(const std::string& path, const LoadOptions& options = {});

/// load_mesh() from bytes in memory (`format_hint`: the file extension, e.g. "obj", "stl",
/// "ply"; `name` is used in messages). The same checks and the same errors.
TriMesh load_mesh_from_memory(const void* data, std::size_t size, const std::string& format_hint,
                              const std::string& name, const LoadOptions& options = {});

/// Builds a mesh from raw tables (welding nothing): computes edges and adjacency and validates.
/// @throws MeshError as load_mesh.
TriMesh make_mesh(Eigen::Matrix3Xd vertices, Eigen::Matrix3Xi triangles);

/// Fills edges and the CSR tables from vertices and triangles. @throws MeshError if a triangle
/// refers to a vertex that does not exist.
void build_adjacency(TriMesh& mesh);

/// Checks that the mesh is a closed, edge- and vertex-manifold, consistently and outward
/// oriented surface without degenerate triangles or unused vertices. Needs build_adjacency().
/// @throws MeshError saying what is wrong and where (edge (a, b), vertex i, triangle t).
void validate_closed_manifold(const TriMesh& mesh);

/// Signed volume enclosed by the surface [m^3] (positive when oriented outward).
double enclosed_volume(const TriMesh& mesh);

/// Writes the mesh as Wavefront OBJ (for tests and inspection). @throws MeshError on I/O error.
void save_obj(const TriMesh& mesh, const std::string& path);

}  // namespace teleop::mesh

// libFuzzer target: the mesh loader (common/mesh: assimp import, triangulation, welding, the
// closed-manifold checks) and the deformable model built from what it accepts (the path of a
// scene's `mesh_file`). The first byte picks the format (OBJ, STL, PLY: skipped, see below; OFF:
// refused by check_mesh_format), the rest is the file. A mesh::MeshError or config::ConfigError is
// the answer to bad input; anything else that escapes (another exception, a crash, a sanitizer
// report) is a bug.
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/mesh/tri_mesh.hpp"
#include "server/deformable/deformable.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const char* const kFormats[] = {"obj", "stl", "ply", "off"};
  if (size < 1) return 0;
  const std::string format = kFormats[data[0] % 4];
  // Debian's assimp 5.2.5 never returns from some malformed PLY headers (an infinite loop in
  // its PLY parser, not in our code: tests/fuzz/known_issues/mesh_ply_hang_assimp_5.2.5, which
  // hangs a plain `Assimp::Importer::ReadFile` too). Until that is fixed upstream or we read
  // PLY ourselves, PLY inputs are skipped so the short runs stay meaningful for the rest.
  if (format == "ply") return 0;
  namespace dm = teleop::sim::deformable;
  try {
    const teleop::mesh::TriMesh mesh =
        teleop::mesh::load_mesh_from_memory(data + 1, size - 1, format, "fuzz." + format);
    // a mesh the loader accepts is a closed, outward surface: a body can be built on it
    if (mesh.triangle_count() < 4 || !(teleop::mesh::enclosed_volume(mesh) > 0.0)) {
      __builtin_trap();
    }
    if (mesh.vertex_count() <= 2000) {
      dm::DeformableParams p;
      p.mesh_file = "fuzz." + format;
      (void)dm::make_model(mesh, p);
    }
  } catch (const teleop::mesh::MeshError&) {
  } catch (const teleop::config::ConfigError&) {
  }
  return 0;
}

// The mesh loader refuses what is not a mesh file before assimp sees it, and loads from memory
// with the same checks (the path of tests/fuzz/fuzz_mesh.cpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "common/mesh/tri_mesh.hpp"

namespace teleop::mesh {
namespace {

std::string mesh_error(const std::string& path) {
  try {
    load_mesh(path);
  } catch (const MeshError& e) {
    return e.what();
  }
  return "";
}

const std::string kTet = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

TEST(MeshFileChecks, MissingDirectoryDeviceAndEmptyFilesAreNamed) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("teleop_meshchk_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir / "a_dir.obj");
  std::ofstream(dir / "empty.obj").close();
  EXPECT_NE(mesh_error((dir / "none.obj").string()).find("none.obj: no such file"),
            std::string::npos);
  EXPECT_NE(mesh_error((dir / "a_dir.obj").string()).find("is a directory"), std::string::npos);
  EXPECT_NE(mesh_error((dir / "empty.obj").string()).find("the file is empty"), std::string::npos);
  EXPECT_NE(mesh_error("/dev/zero").find("not a regular file"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(MeshFileChecks, FromMemoryLoadsAndRefusesLikeTheFileLoader) {
  const TriMesh m = load_mesh_from_memory(kTet.data(), kTet.size(), "obj", "tet.obj");
  EXPECT_EQ(m.vertex_count(), 4);
  EXPECT_EQ(m.triangle_count(), 4);
  EXPECT_GT(enclosed_volume(m), 0.0);
  const std::string open = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  EXPECT_THROW(load_mesh_from_memory(open.data(), open.size(), "obj", "open.obj"), MeshError);
  const std::string nan =
      "v nan 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  try {
    load_mesh_from_memory(nan.data(), nan.size(), "obj", "nan.obj");
  } catch (const MeshError& e) {
    SUCCEED() << e.what();  // refused (assimp may refuse the text itself first)
    return;
  }
  ADD_FAILURE() << "a mesh with a NaN coordinate was accepted";
}

}  // namespace
}  // namespace teleop::mesh

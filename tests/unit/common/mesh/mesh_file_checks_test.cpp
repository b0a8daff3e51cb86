// The mesh loader refuses what is not a mesh file before assimp sees it, and loads from memory
// with the same checks (the path of tests/fuzz/fuzz_mesh.cpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
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

TEST(MeshFileChecks, PlyHeadersOutsideTheGrammarAreRefusedBeforeAssimp) {
  // the input that hangs Debian's assimp 5.2.5 (tests/fuzz/known_issues): refused at its
  // malformed 'format' line, naming the line, before assimp sees it
  std::ifstream f(
      std::string(TELEOP_SOURCE_DIR) + "/tests/fuzz/known_issues/mesh_ply_hang_assimp_5.2.5",
      std::ios::binary);
  ASSERT_TRUE(f.good());
  const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 1u);
  try {
    load_mesh_from_memory(bytes.data() + 1, bytes.size() - 1, "ply", "hang.ply");
    ADD_FAILURE() << "the hanging PLY header was accepted";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("hang.ply: PLY header line 2"), std::string::npos)
        << e.what();
  }
  // a well-formed header still loads (a tetrahedron)
  const std::string tet =
      "ply\nformat ascii 1.0\ncomment a tetrahedron\nelement vertex 4\nproperty float x\n"
      "property float y\nproperty float z\nelement face 4\nproperty list uchar int "
      "vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n"
      "3 1 2 3\n";
  const TriMesh m = load_mesh_from_memory(tet.data(), tet.size(), "ply", "tet.ply");
  EXPECT_EQ(m.triangle_count(), 4);
  // no end_header, an unknown keyword, a property before any element
  for (const std::string& bad :
       {std::string("ply\nformat ascii 1.0\nelement vertex 4\n"),
        std::string("ply\nformat ascii 1.0\nelemant vertex 4\nend_header\n"),
        std::string("ply\nformat ascii 1.0\nproperty float x\nend_header\n")}) {
    EXPECT_THROW(load_mesh_from_memory(bad.data(), bad.size(), "ply", "bad.ply"), MeshError) << bad;
  }
}

}  // namespace
}  // namespace teleop::mesh

// A scene that cannot run is refused at load: every bad case below throws a
// ConfigError whose message names the scene file, the field and the value (and says why), and
// the shipped scenes still load. Table-driven: each case is a scene file written to a temporary
// folder (with the mesh and include files it refers to) and loaded with load_world_model().
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "server/world/world_model.hpp"
#include "tests/support/config_error.hpp"

namespace teleop::sim {
namespace {

namespace fs = std::filesystem;

const std::string kRobotFile = std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/robot_puma560.yaml";

/// A folder of its own for this test process, removed at the end.
class SceneDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("teleop_refuse_" + std::to_string(getpid()));
    fs::create_directories(dir_);
    write("open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const char garbage[] = "\x7f\x01garbage\x00\xff not a mesh";
    write("garbage.obj", std::string(garbage, sizeof garbage - 1));
    write("empty.obj", "");
    fs::create_directories(dir_ / "meshdir.obj");
    fs::create_directories(dir_ / "incdir.yaml");
    write("norobot.yaml", "name: x\n");
    write("broken.yaml", "robot: [1, 2\n");
    write("blank.yaml", "# nothing here\n");
    write("robot_ok.yaml", "robot:\n  include: " + kRobotFile + "\n");
    // a closed tetrahedron, counter-clockwise seen from outside
    write("tet.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

std::string load_error(const std::string& file) {
  return test::config_error_of([&] { load_world_model(file); });
}

/// A tool scene with a floor and one sphere (level 1) of radius `radius` at `centre`; `extra`
/// is appended to the sphere's body mapping, `tail` to the file.
std::string tool_scene(const std::string& body_extra = "", const std::string& tail = "",
                       const std::string& centre = "[0.6, 0, 0.25]",
                       const std::string& radius = "0.25") {
  return "kind: tool\n"
         "planes:\n"
         "  - {name: floor, normal: [0, 0, 1], offset_m: 0}\n"
         "deformables:\n"
         "  - id: 10\n"
         "    body: {level: 1, radius_m: " +
         radius + ", centre_m: " + centre + body_extra + "}\n" + tail;
}

struct Case {
  std::string name;                   ///< also the scene file's name
  std::string yaml;                   ///< the scene file's text
  std::vector<std::string> expected;  ///< each must be in the message (besides the file)
};

/// Bad YAML documents: empty, what yaml-cpp lets pass, null and malformed sections.
std::vector<Case> bad_document_cases() {
  return {
      // empty documents
      {"empty", "", {"the scene is empty"}},
      {"comments_only", "# a scene\n# with nothing in it\n", {"the scene is empty"}},
      {"a_list", "- 1\n- 2\n", {"'<root>'", "not a scene"}},
      // YAML that yaml-cpp lets pass
      {"dup_top", "kind: tool\nkind: robot\n", {"'kind'", "given twice", "'tool'", "'robot'"}},
      {"dup_nested",
       "physics:\n  rate_hz: 1000\n  rate_hz: 10\n",
       {"'physics.rate_hz'", "given twice", "lines 2 and 3", "'1000'", "'10'"}},
      {"dup_in_list",
       "planes:\n  - {normal: [0, 0, 1], offset_m: 0, offset_m: 1}\n",
       {"'planes[0].offset_m'", "given twice"}},
      {"two_documents", "kind: tool\n---\nkind: robot\n", {"2 YAML documents"}},
      {"complex_key", "[a, b]: 1\n", {"'<root>'", "'[a, b]'", "not a plain name"}},
      // the explicit '?' key, anchors and aliases never reach yaml-cpp (config.cpp)
      {"complex_key_explicit", "? [a, b]\n: 1\n", {"line 1 (byte 0)", "complex key"}},
      {"self_alias", "physics: &a [*a]\n", {"line 1 (byte 9)", "anchor, alias"}},
      // null and malformed sections
      {"null_physics", "physics: ~\n", {"'physics'", "empty (null)"}},
      {"null_robot", "kind: robot\nrobot: ~\n", {"'robot'", "empty (null)"}},
      {"null_tool", "tool:\n", {"'tool'", "empty (null)"}},
      {"null_planes", "planes: ~\n", {"'planes'", "empty (null)"}},
      {"null_deformables", "deformables: ~\n", {"'deformables'", "empty (null)"}},
      {"null_field", "tool: {mass_kg: ~}\n", {"'tool.mass_kg'", "empty (null)"}},
      {"scalar_section", "physics: 5\n", {"'physics'", "'5'", "must be a mapping"}},
      {"unknown_key", "tool: {mass: 1}\n", {"'tool.mass'", "unknown field"}},
      {"unknown_world_key", "world: {size: 1}\n", {"'world.size'", "unknown field"}},
  };
}

/// Bad worlds: repeated ids and names, objects outside the world, rates the scene cannot run
/// at.
std::vector<Case> bad_world_cases() {
  return {
      // ids and names
      {"dup_ids",
       tool_scene("", "  - id: 10\n    body: {level: 1, radius_m: 0.1, centre_m: [0, 0.5, 0.1]}\n"),
       {"'deformables[1].id'", "'10'", "already the id of deformables[0]"}},
      {"dup_auto_id",
       tool_scene("",
                  "  - body: {level: 1, radius_m: 0.1, centre_m: [0, 0.5, 0.1]}\n"
                  "  - id: 11\n    body: {level: 1, radius_m: 0.1, centre_m: [0, -0.5, 0.1]}\n"),
       {"'deformables[2].id'", "'11'", "already the id of deformables[1]"}},
      {"dup_plane_names",
       "planes:\n  - {name: floor, normal: [0, 0, 1]}\n  - {name: floor, normal: [1, 0, 0]}\n",
       {"'planes[1].name'", "'floor'", "unique"}},
      // objects outside the world
      {"sphere_9km",
       tool_scene("", "", "[9000, 0, 0.25]"),
       {"'deformables[0].body.centre_m'", "'[9000, 0, 0.25]'", "outside the world box"}},
      {"radius_100",
       tool_scene("", "", "[0.6, 0, 0.25]", "100"),
       {"'deformables[0].body.radius_m'", "'100'", "does not fit"}},
      {"sphere_in_floor",
       tool_scene("", "", "[0.6, 0, 0.1]"),
       {"'deformables[0].body.centre_m'", "'[0.6, 0, 0.1]'", "behind plane 'floor'"}},
      {"tool_in_floor",
       "planes:\n  - {name: floor, normal: [0, 0, 1]}\ntool: {start_position_m: [0, 0, 0.01]}\n",
       {"'tool.start_position_m'", "[0, 0, 0.01]", "behind plane 'floor'"}},
      {"workspace_outside_world",
       "world: {min_m: [-1, -1, -1], max_m: [1, 1, 1]}\n",
       {"'command.workspace_min_m'", "[-1.5, -1.5, -0.1]", "outside the world box"}},
      {"world_inverted", "world: {min_m: [0, 0, 0], max_m: [0, 1, 1]}\n", {"'world.min_m'"}},
      // a fem body keeps the tip out itself: of a contact block only the friction applies
      {"fem_contact_stiffness",
       tool_scene(", model: fem", "    contact: {friction_static: 0.3, stiffness_n_per_m: 300}\n"),
       {"'deformables[0].contact.stiffness_n_per_m'", "model fem",
        "allowed here: friction_static, friction_kinetic"}},
      // rates the scene cannot run at
      {"robot_rate_10",
       "kind: robot\nphysics: {rate_hz: 10}\nrobot: {include: " + kRobotFile + "}\n",
       {"'physics.rate_hz'", "'10'", "robot.ik.gain_per_s", "at least 29 Hz"}},
      {"tool_rate_10", "physics: {rate_hz: 10}\n", {"'physics.rate_hz'", "'10'", "tool slave"}},
      {"tool_too_stiff",
       "tool: {kp_n_per_m: 1000000, mass_kg: 0.01}\n",
       {"'physics.rate_hz'", "'1000' (the default)", "tool.kp_n_per_m"}},
      {"body_max_substeps",
       tool_scene(", edge_stiffness_n_per_m: 200000, max_substeps: 2"),
       {"'physics.rate_hz'", "deformables[0] (id 10)", "largest stable step", "max_substeps 2",
        "at level 1"}},
      {"explicit_undamped",
       tool_scene(", integrator: explicit_euler, stiffness_damping_s: 0, radial_damping_s: 0"),
       {"'deformables[0].body.integrator'", "'explicit_euler'", "unstable at any step"}},
  };
}

/// Bad files a scene refers to: meshes (the scene file and the field that referenced the mesh)
/// and includes (the including file and the field).
std::vector<Case> bad_file_cases() {
  return {
      // meshes: the scene file and the field that referenced the mesh
      {"mesh_missing",
       tool_scene(", mesh_file: nothere.obj"),
       {"'deformables[0].body.mesh_file'", "'nothere.obj'", "no such file"}},
      {"mesh_garbage",
       tool_scene(", mesh_file: garbage.obj"),
       {"'deformables[0].body.mesh_file'", "'garbage.obj'"}},
      {"mesh_open",
       tool_scene(", mesh_file: open.obj"),
       {"'deformables[0].body.mesh_file'", "'open.obj'", "a closed surface needs"}},
      {"mesh_empty",
       tool_scene(", mesh_file: empty.obj"),
       {"'deformables[0].body.mesh_file'", "'empty.obj'", "empty"}},
      {"mesh_dir",
       tool_scene(", mesh_file: meshdir.obj"),
       {"'deformables[0].body.mesh_file'", "'meshdir.obj'", "is a directory"}},
      // includes: the including file and the field
      {"include_missing",
       "kind: robot\nrobot: {include: nothere.yaml}\n",
       {"'robot.include'", "'nothere.yaml'", "does not exist"}},
      {"include_dir",
       "kind: robot\nrobot: {include: incdir.yaml}\n",
       {"'robot.include'", "'incdir.yaml'", "is a directory"}},
      {"include_no_robot",
       "kind: robot\nrobot: {include: norobot.yaml}\n",
       {"'robot.include'", "'norobot.yaml'", "'robot': is required but missing"}},
      {"include_broken",
       "kind: robot\nrobot: {include: broken.yaml}\n",
       {"'robot.include'", "'broken.yaml'", "line 2", "not closed"}},
      {"include_blank",
       "kind: robot\nrobot: {include: blank.yaml}\n",
       {"'robot.include'", "'blank.yaml'", "empty"}},
      {"include_nested",
       "kind: robot\nrobot: {include: robot_ok.yaml}\n",
       {"'robot.include'", "'robot_ok.yaml'", "robot.include"}},
  };
}

TEST_F(SceneDir, EveryBadSceneIsRefusedNamingFileFieldAndValue) {
  std::vector<Case> cases = bad_document_cases();
  const std::vector<Case> worlds = bad_world_cases(), files = bad_file_cases();
  cases.insert(cases.end(), worlds.begin(), worlds.end());
  cases.insert(cases.end(), files.begin(), files.end());
  for (const Case& c : cases) {
    const std::string file = write(c.name + ".yaml", c.yaml);
    const std::string msg = load_error(file);
    ASSERT_FALSE(msg.empty()) << c.name << ": accepted\n" << c.yaml;
    EXPECT_NE(msg.find(file), std::string::npos) << c.name << ": " << msg;
    for (const std::string& e : c.expected) {
      EXPECT_NE(msg.find(e), std::string::npos) << c.name << ": '" << e << "' not in: " << msg;
    }
  }
}

TEST_F(SceneDir, SpecialFilesAreRefused) {
  std::string msg = load_error("/dev/null");
  EXPECT_NE(msg.find("/dev/null: the scene is empty"), std::string::npos) << msg;
  msg = load_error(dir_.string());
  EXPECT_NE(msg.find(dir_.string() + ": is a directory"), std::string::npos) << msg;
  msg = load_error(path("missing.yaml"));
  EXPECT_NE(msg.find(path("missing.yaml") + ": cannot open"), std::string::npos) << msg;
}

TEST_F(SceneDir, ParsedTextNamesItsFileToo) {
  const std::string msg = test::config_error_of([] {
    parse_world_model(config::Node::parse("physics: {rate_hz: 10, rate_hz: 20}", "s.yaml"));
  });
  EXPECT_NE(msg.find("s.yaml: field 'physics.rate_hz' is given twice"), std::string::npos) << msg;
}

TEST_F(SceneDir, RobotLinkMeshErrorsNameTheIncludingSceneAndTheIncludedField) {
  // a robot file whose first link takes its box from a missing mesh
  std::ifstream in(kRobotFile);
  std::string robot((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t at = robot.find("      dh:");
  ASSERT_NE(at, std::string::npos);
  robot.insert(at, "      mesh: {file: nothere.stl}\n");
  write("robot_mesh.yaml", robot);
  const std::string scene =
      write("with_mesh.yaml", "kind: robot\nrobot: {include: robot_mesh.yaml}\n");
  const std::string msg = load_error(scene);
  EXPECT_NE(msg.find(scene + ": field 'robot.include'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("robot.links[0].mesh.file"), std::string::npos) << msg;
  EXPECT_NE(msg.find("nothere.stl"), std::string::npos) << msg;
}

TEST_F(SceneDir, StiffBodyThatSubStepsLoadsAndSaysSo) {
  // stiffer than the default: its stable step falls below 1 ms, the automatic step sub-steps
  const std::string file = write("stiff.yaml", tool_scene(", edge_stiffness_n_per_m: 50000"));
  const WorldModel m = load_world_model(file);
  ASSERT_EQ(m.bodies.size(), 1u);
  const int n = m.bodies[0].body.substeps_for(1e-3);
  EXPECT_GT(n, 1);
  const auto notes = physics_rate_notes(m, m.physics_rate_hz);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("deformables[0] (id 10)"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("largest stable step"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find(std::to_string(n) + " sub-steps"), std::string::npos) << notes[0];
  // a rate high enough is accepted, one too low (more sub-steps than max_substeps) refused
  EXPECT_TRUE(physics_rate_problem(m, 1000.0).empty());
  EXPECT_TRUE(physics_rate_problem(m, min_physics_rate_hz(m) * 1.01).empty());
  EXPECT_FALSE(physics_rate_problem(m, 10.0).empty());
}

TEST_F(SceneDir, MeshBodiesLoadRelativeToTheSceneFile) {
  const std::string file =
      write("tet_scene.yaml",
            "planes:\n  - {name: floor, normal: [0, 0, 1]}\ndeformables:\n"
            "  - body: {mesh_file: tet.obj, mesh_scale: 0.2, centre_m: [0.5, 0, 0], "
            "integrator: implicit_euler}\n");
  const WorldModel m = load_world_model(file);
  ASSERT_EQ(m.bodies.size(), 1u);
  EXPECT_EQ(m.bodies[0].body.mesh.vertex_count(), 4);
}

TEST(SceneRefuse, ShippedScenesLoadAsBefore) {
  const std::string dir = std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/";
  const WorldModel d = load_world_model(dir + "default.yaml");
  EXPECT_TRUE(d.has_robot());
  EXPECT_EQ(d.physics_rate_hz, 1000.0);
  ASSERT_EQ(d.bodies.size(), 1u);
  EXPECT_EQ(d.bodies[0].body.substeps_for(1e-3), 1);  // the default sphere does not sub-step
  EXPECT_TRUE(physics_rate_notes(d, 1000.0).empty());
  EXPECT_LT(min_physics_rate_hz(d), 400.0);  // 319 Hz: the node penalty of the tip on the sphere
  const WorldModel t = load_world_model(dir + "tool_only.yaml");
  EXPECT_FALSE(t.has_robot());
  EXPECT_EQ(t.planes.size(), 5u);
  EXPECT_LT(min_physics_rate_hz(t), 1000.0);
}

}  // namespace
}  // namespace teleop::sim

// Automatic model selection (server/deformable/model_select.hpp): table -> choice, the
// tolerance and budget edges, refusals at load, and the accuracy sub-steps it relies on.
#include "server/deformable/model_select.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "server/world/world_model.hpp"
#include "tests/unit/server/deformable/test_helpers.hpp"

namespace teleop::sim::deformable {
namespace {

// A small table in the format teleop_bench deformable writes (errors in metres).
const char* kTable =
    "model,integrator,level,dt_s,step_us_median,step_us_p99,error,kernel\n"
    "mass_spring,symplectic_euler,2,0.001,5,6,0.00012,scalar\n"
    "mass_spring,symplectic_euler,2,0.001,2.5,3,0.00012,simd\n"
    "mass_spring,symplectic_euler,2,0.00025,5,6,0.00003,scalar\n"
    "mass_spring,symplectic_euler,4,0.001,60,90,0.00011,scalar\n"
    "mass_spring,symplectic_euler,4,0.001,25,40,0.00011,simd\n"
    "mass_spring,symplectic_euler,4,0.00025,60,90,0.000027,scalar\n"
    "mass_spring,explicit_euler,4,0.001,100,120,inf,scalar\n"
    "mass_spring,explicit_euler,1,0.001,1,1,inf,scalar\n"
    "mass_spring,implicit_euler,4,0.001,700,800,0.00008,scalar\n"
    "navier_linear,symplectic_euler,1,0.001,1.2,2,0.0014,scalar\n"
    "navier_linear,symplectic_euler,5,0.00025,360,400,0.000016,scalar\n"
    "navier_linear,symplectic_euler,3,0.0003,20,30,0.00001,scalar\n";

ModelTable table() { return parse_model_table(kTable, "test.csv"); }

ModelRequest all_auto(double tol_mm, double budget_us, double dt = 1e-3) {
  ModelRequest r;
  r.tolerance_mm = tol_mm;
  r.budget_us = budget_us;
  r.physics_dt_s = dt;
  return r;
}

TEST(ModelTable, ParsesTheBenchFormatWithAndWithoutKernel) {
  const ModelTable t = table();
  ASSERT_EQ(t.entries.size(), 12u);
  EXPECT_EQ(t.entries[1].kernel, KernelKind::kSimd);
  EXPECT_TRUE(std::isinf(t.entries[6].error_m));
  EXPECT_EQ(t.entries[10].model, ModelKind::kNavierLinear);
  EXPECT_EQ(t.entries[10].level, 5);
  // the older CSV without the kernel column
  const ModelTable old = parse_model_table(
      "model,integrator,level,dt_s,step_us_median,step_us_p99,error\n"
      "mass_spring,symplectic_euler,4,0.001,88,115,0.000119\n",
      "old.csv");
  ASSERT_EQ(old.entries.size(), 1u);
  EXPECT_EQ(old.entries[0].kernel, KernelKind::kScalar);
}

TEST(ModelTable, RefusesMalformedTablesNamingFileAndLine) {
  try {
    parse_model_table("model,level\nmass_spring,4\n", "bad.csv");
    FAIL();
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.csv: line 1"), std::string::npos) << e.what();
  }
  try {
    parse_model_table(
        "model,integrator,level,dt_s,step_us_median,step_us_p99,error\n"
        "mass_spring,symplectic_euler,4,0.001,fast,115,0.000119\n",
        "bad.csv");
    FAIL();
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("fast"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_model_table("model,integrator,level,dt_s,step_us_median,step_us_p99,error\n",
                                 "empty.csv"),
               config::ConfigError);
  EXPECT_THROW(load_model_table("/nonexistent/deformable_table.csv"), config::ConfigError);
}

TEST(SelectModel, PicksTheCheapestEntryWithinToleranceAndBudget) {
  // 0.2 mm: everything finite but Navier level 1 qualifies; cheapest: level 2 simd, 2.5 us
  SelectResult r = select_model(table(), all_auto(0.2, 100));
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.entry.level, 2);
  EXPECT_EQ(r.choice.entry.kernel, KernelKind::kSimd);
  EXPECT_EQ(r.choice.substeps, 1);
  EXPECT_DOUBLE_EQ(r.choice.cost_us_median, 2.5);
  EXPECT_NEAR(r.choice.error_mm, 0.12, 1e-12);
  // 2 mm: Navier level 1 (1.2 us) is cheaper and now within tolerance
  r = select_model(table(), all_auto(2.0, 100));
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.entry.model, ModelKind::kNavierLinear);
  EXPECT_EQ(r.choice.entry.level, 1);
}

TEST(SelectModel, TighterToleranceBuysAccuracySubSteps) {
  // 0.05 mm: only the 0.25 ms entries (4 sub-steps per 1 ms) and Navier at 0.3 ms (does not
  // divide 1 ms: not a candidate) qualify; level 2 at 4 x 5 us = 20 us
  const SelectResult r = select_model(table(), all_auto(0.05, 1000));
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.entry.level, 2);
  EXPECT_EQ(r.choice.substeps, 4);
  EXPECT_DOUBLE_EQ(r.choice.cost_us_median, 20.0);
  EXPECT_DOUBLE_EQ(r.choice.cost_us_p99, 24.0);
  // at a 4 kHz world the same entry is a single step
  const SelectResult q = select_model(table(), all_auto(0.05, 1000, 2.5e-4));
  ASSERT_EQ(q.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(q.choice.substeps, 1);
  EXPECT_DOUBLE_EQ(q.choice.cost_us_median, 5.0);
}

TEST(SelectModel, EdgesAreInclusive) {
  // error == tolerance and cost == budget are accepted
  SelectResult r = select_model(table(), all_auto(0.12, 2.5));
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_DOUBLE_EQ(r.choice.cost_us_median, 2.5);
  // just below the cheapest cost: refused as a budget problem naming the cheapest accurate entry
  r = select_model(table(), all_auto(0.12, 2.4999));
  EXPECT_EQ(r.outcome, SelectOutcome::kBudget);
  EXPECT_DOUBLE_EQ(r.cheapest_accurate.cost_us_median, 2.5);
  // just below the smallest error at 1 ms: a tolerance problem naming the most accurate entry
  r = select_model(table(), all_auto(0.0159, 1e6));
  EXPECT_EQ(r.outcome, SelectOutcome::kTolerance);
  EXPECT_NEAR(r.most_accurate.error_mm, 0.016, 1e-12);
  EXPECT_EQ(r.most_accurate.substeps, 4);
}

TEST(SelectModel, BlownUpAndMismatchedEntriesAreNeverChosen) {
  ModelRequest req = all_auto(1e3, 1e6);
  req.model = ModelKind::kMassSpring;
  req.integrator = IntegratorKind::kExplicitEuler;
  EXPECT_EQ(select_model(table(), req).outcome, SelectOutcome::kNoEntry);  // both blew up
  req.integrator = IntegratorKind::kImplicitEuler;
  SelectResult r = select_model(table(), req);
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.entry.integrator, IntegratorKind::kImplicitEuler);
  EXPECT_EQ(r.matching, 1);
  // fixed level and kernel
  req = all_auto(1.0, 1e6);
  req.level = 4;
  req.kernel = KernelKind::kScalar;
  r = select_model(table(), req);
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.entry.level, 4);
  EXPECT_EQ(r.choice.entry.kernel, KernelKind::kScalar);
  EXPECT_DOUBLE_EQ(r.choice.cost_us_median, 60.0);
  // a world step the entry's step does not divide (and one shorter than the entry's)
  req = all_auto(1.0, 1e6, 0.7e-3);
  EXPECT_EQ(select_model(table(), req).outcome, SelectOutcome::kNoEntry);
  req = all_auto(1.0, 1e6, 0.6e-3);  // 0.3 ms divides it: Navier level 3, 2 sub-steps
  r = select_model(table(), req);
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.substeps, 2);
}

// ---- loading through the scene's deformable mapping ----

class AutoBodyYaml : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("teleop_model_select_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    std::ofstream(dir_ / "table.csv") << kTable;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  AutoBody load(const std::string& yaml, double dt = 1e-3) {
    const std::string file = (dir_ / "scene.yaml").string();
    std::ofstream(file) << yaml;
    const config::Node n = config::Node::load_file(file);
    return load_deformable_body(n.at("body"), dt, {});
  }
  std::string error_of(const std::string& yaml) {
    try {
      load(yaml);
    } catch (const config::ConfigError& e) {
      return e.what();
    }
    return "";
  }
  std::filesystem::path dir_;
};

TEST(ShapeError, IsTheIcosahedronsSagAtLevelZeroAndShrinksFourfoldPerLevel) {
  // regular icosahedron: inradius / circumradius = 0.7946544723
  EXPECT_NEAR(icosphere_shape_error_m(0, 1.0), 1.0 - 0.7946544723, 1e-9);
  double prev = icosphere_shape_error_m(0, 0.25);
  EXPECT_NEAR(prev, 0.25 * (1.0 - 0.7946544723), 1e-9);  // scales with the radius
  for (int l = 1; l <= 5; ++l) {
    const double e = icosphere_shape_error_m(l, 0.25);
    RecordProperty("shape_error_mm_level_" + std::to_string(l), std::to_string(e * 1e3));
    EXPECT_GT(prev / e, 3.0) << l;
    EXPECT_LT(prev / e, 5.5) << l;
    prev = e;
  }
  EXPECT_GT(icosphere_shape_error_m(4, 0.25), 0.25e-3);  // 0.28 mm at the paper's sphere
  EXPECT_LT(icosphere_shape_error_m(4, 0.25), 0.32e-3);
}

TEST(SelectModel, ShapeErrorRulesOutCoarseMeshes) {
  ModelRequest r = all_auto(0.2, 1000);
  r.shape_error_mm = {50, 10, 2.4, 0.6, 0.15, 0.04, 0.01};
  const SelectResult c = select_model(table(), r);
  ASSERT_EQ(c.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(c.choice.entry.level, 4);  // level 2 is 2.4 mm off the sphere whatever its motion
  EXPECT_EQ(c.choice.substeps, 4);     // level 4 at 1 ms: 0.11 + 0.15 > 0.2
  EXPECT_NEAR(c.choice.error_mm, 0.027 + 0.15, 1e-9);
  EXPECT_NEAR(c.choice.dynamic_error_mm, 0.027, 1e-12);
  EXPECT_NEAR(c.choice.shape_error_mm, 0.15, 1e-12);
}

TEST_F(AutoBodyYaml, BuildsTheChosenBodyAndSaysWhy) {
  // radius 0.25 m: level 2 is 4.4 mm off the sphere, level 4 0.28 mm; 0.35 mm needs level 4 at
  // 0.25 ms (0.027 + 0.28), 4 sub-steps of the 60 us scalar entry
  const AutoBody b = load(
      "body: {model: auto, integrator: auto, level: auto, tolerance_mm: 0.35, budget_us: 1000,\n"
      "       model_table: table.csv, centre_m: [0, 0, 0]}\n");
  ASSERT_TRUE(b.choice.has_value());
  EXPECT_EQ(b.model.params.level, 4);
  EXPECT_EQ(b.model.params.model, ModelKind::kMassSpring);
  EXPECT_EQ(b.model.params.integrator, IntegratorKind::kSymplecticEuler);
  EXPECT_EQ(b.model.params.kernel, KernelKind::kScalar);
  EXPECT_EQ(b.model.params.min_substeps, 4);
  EXPECT_EQ(b.model.substeps_for(1e-3), 4);
  EXPECT_EQ(b.model.node_count, 2562);
  EXPECT_EQ(b.stability_substeps, 1);
  EXPECT_TRUE(b.differs_from_table.empty());
  EXPECT_NEAR(b.choice->shape_error_mm, 1e3 * icosphere_shape_error_m(4, 0.25), 1e-12);
  const std::string s = b.summary();
  EXPECT_LT(s.size(), 128u);
  EXPECT_NE(s.find("mass_spring symplectic_euler scalar level 4, 4 x 0.25 ms"), std::string::npos)
      << s;
  EXPECT_NE(s.find("predicted 240.0 us"), std::string::npos) << s;
  EXPECT_NE(b.report().find("tolerance 0.35 mm"), std::string::npos) << b.report();
  EXPECT_NE(b.report().find("shape"), std::string::npos) << b.report();
}

TEST_F(AutoBodyYaml, FixedFieldsStayAndOtherMaterialIsFlagged) {
  // a larger tolerance: level 4 at 1 ms (0.11 + 0.28 mm), the scalar kernel as fixed
  const AutoBody b = load(
      "body: {model: mass_spring, level: auto, kernel: scalar, tolerance_mm: 0.45,\n"
      "       budget_us: 1000, model_table: table.csv, edge_stiffness_n_per_m: 200}\n");
  ASSERT_TRUE(b.choice.has_value());
  EXPECT_EQ(b.model.params.kernel, KernelKind::kScalar);
  EXPECT_EQ(b.model.params.level, 4);
  EXPECT_EQ(b.model.params.min_substeps, 1);
  EXPECT_DOUBLE_EQ(b.model.params.edge_stiffness_n_per_m, 200.0);
  ASSERT_EQ(b.differs_from_table.size(), 1u);
  EXPECT_EQ(b.differs_from_table[0], "edge_stiffness_n_per_m");
  EXPECT_NE(b.summary().find("other material"), std::string::npos);
}

TEST_F(AutoBodyYaml, WithoutAutoItIsTheExplicitBody) {
  const AutoBody b = load("body: {model: mass_spring, level: 2, centre_m: [0, 0, 0]}\n");
  EXPECT_FALSE(b.choice.has_value());
  EXPECT_TRUE(b.summary().empty());
  DeformableParams p =
      testing::small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 2);
  p.gravity_mps2 = DeformableParams{}.gravity_mps2;
  p.sleep_time_s = DeformableParams{}.sleep_time_s;
  const DeformableModel m = make_model(make_mesh_for(p), p);
  EXPECT_EQ(b.model.params.min_substeps, 1);
  EXPECT_EQ(b.model.node_count, m.node_count);
  EXPECT_EQ(b.model.stable_step_s, m.stable_step_s);
  EXPECT_TRUE(b.model.mass_kg == m.mass_kg);
}

TEST_F(AutoBodyYaml, BadValuesAreRefusedNamingFieldValueAndRange) {
  const std::string head = "body: {level: auto, model_table: table.csv, ";
  std::string e = error_of(head + "tolerance_mm: 0, budget_us: 100}\n");
  EXPECT_NE(e.find("scene.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("body.tolerance_mm"), std::string::npos) << e;
  EXPECT_NE(e.find("value 0 "), std::string::npos) << e;
  EXPECT_NE(e.find("(0, 1000]"), std::string::npos) << e;
  e = error_of(head + "tolerance_mm: -1, budget_us: 100}\n");
  EXPECT_NE(e.find("body.tolerance_mm"), std::string::npos) << e;
  // budget below every entry within tolerance: names the cheapest one and its cost
  e = error_of(head + "tolerance_mm: 0.45, budget_us: 1}\n");
  EXPECT_NE(e.find("body.budget_us"), std::string::npos) << e;
  EXPECT_NE(e.find("value 1 "), std::string::npos) << e;
  EXPECT_NE(e.find("mass_spring symplectic_euler simd level 4, 1 x 1 ms: 25.0 us"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("allowed range [25.0, 1e+06]"), std::string::npos) << e;
  // a tolerance no entry meets: names the smallest error (level 4 at 0.25 ms, shape included)
  e = error_of(head + "tolerance_mm: 0.001, budget_us: 1000}\n");
  EXPECT_NE(e.find("body.tolerance_mm"), std::string::npos) << e;
  EXPECT_NE(e.find("level 4, 4 x 0.25 ms"), std::string::npos) << e;
  // missing fields, fields without auto, auto with a mesh file, unknown values
  e = error_of(head + "budget_us: 100}\n");
  EXPECT_NE(e.find("body.tolerance_mm': is required"), std::string::npos) << e;
  e = error_of("body: {level: 3, tolerance_mm: 0.1}\n");
  EXPECT_NE(e.find("body.tolerance_mm': is used only when"), std::string::npos) << e;
  e = error_of(head + "tolerance_mm: 0.2, budget_us: 100, mesh_file: x.obj}\n");
  EXPECT_NE(e.find("body.mesh_file"), std::string::npos) << e;
  e = error_of(
      "body: {model: auto, integrator: leapfrog, tolerance_mm: 1, budget_us: 100,"
      " model_table: table.csv}\n");
  EXPECT_NE(e.find("body.integrator"), std::string::npos) << e;
  e = error_of("body: {level: auto, tolerance_mm: 1, budget_us: 100, model_table: nope.csv}\n");
  EXPECT_NE(e.find("nope.csv"), std::string::npos) << e;
  EXPECT_NE(e.find("teleop_bench deformable"), std::string::npos) << e;
}

TEST_F(AutoBodyYaml, StifferMaterialCountsItsStabilitySubSteps) {
  // x10 stiffness: the level-2 body needs stability sub-steps at 1 ms; with a small budget the
  // selection moves on to an entry it can afford, or refuses naming the real cost
  const AutoBody b = load(
      "body: {model: mass_spring, integrator: symplectic_euler, level: auto, kernel: scalar,\n"
      "       tolerance_mm: 0.45, budget_us: 1000, model_table: table.csv,\n"
      "       edge_stiffness_n_per_m: 1500, radial_stiffness_n_per_m3: 1.5e6,\n"
      "       youngs_modulus_pa: 60000}\n");
  ASSERT_TRUE(b.choice.has_value());
  const int stab = b.model.substeps_needed(b.choice->entry.dt_s);
  EXPECT_EQ(b.stability_substeps, stab);
  EXPECT_NE(b.report().find("differs in"), std::string::npos);
  if (stab > 1) {
    EXPECT_NE(b.report().find("stability sub-steps"), std::string::npos);
  }
}

TEST(ModelTable, TheShippedTableLoadsAndServesTheDefaultRequest) {
  const std::string file = default_model_table_file();
  if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " not present";
  const ModelTable t = load_model_table(file);
  EXPECT_GT(t.entries.size(), 50u);
  const SelectResult r = select_model(t, all_auto(0.5, 1000));
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_LE(r.choice.error_mm, 0.5);
  EXPECT_LE(r.choice.cost_us_median, 1000.0);
}

TEST(ModelTable, TheAutoSceneLoadsThroughTheWorldLoader) {
  if (!std::filesystem::exists(default_model_table_file())) GTEST_SKIP() << "no shipped table";
  const WorldModel w =
      load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/sphere_auto.yaml");
  ASSERT_EQ(w.bodies.size(), 1u);
  EXPECT_NE(w.bodies[0].auto_summary.find("auto: "), std::string::npos);
  EXPECT_NE(w.bodies[0].auto_report.find("predicted cost"), std::string::npos);
  EXPECT_GT(w.bodies[0].body.node_count, 0);
  // the default scene fixes its model: no selection, the body it always had
  const WorldModel d =
      load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/default.yaml");
  EXPECT_TRUE(d.bodies[0].auto_summary.empty());
  EXPECT_EQ(d.bodies[0].body.params.min_substeps, 1);
  // no `kernel` in it: the default kernel (simd where the CPU has AVX2 and FMA)
  EXPECT_EQ(d.bodies[0].body.params.kernel,
            default_kernel(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler));
  EXPECT_EQ(d.bodies[0].body.node_count, 2562);
}

// ---- the accuracy sub-steps the selection relies on ----

TEST(MinSubsteps, SplitsTheStepExactlyLikeShorterSingleSteps) {
  DeformableParams p =
      testing::small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 2);
  p.min_substeps = 4;
  const DeformableModel m4 = make_model(make_mesh_for(p), p);
  p.min_substeps = 1;
  const DeformableModel m1 = make_model(make_mesh_for(p), p);
  EXPECT_EQ(m4.substeps_for(1e-3), 4);
  EXPECT_EQ(m1.substeps_for(1e-3), 1);
  EXPECT_EQ(m4.substeps_for(-1.0), m1.substeps_for(-1.0));  // bad dt: unchanged
  DeformableState a = make_state(m4), b = make_state(m1);
  a.x.col(3) += Eigen::Vector3d(0.004, 0, 0);
  b.x = a.x;
  EventQueue ev;
  for (int k = 0; k < 50; ++k) {
    ASSERT_EQ(step(m4, a, 1e-3, &ev), StepStatus::kOk);
    for (int j = 0; j < 4; ++j) ASSERT_EQ(step(m1, b, 0.25e-3, nullptr), StepStatus::kOk);
  }
  EXPECT_EQ((a.x - b.x).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(a.last_substeps, 4);
  SimEvent e;
  ASSERT_TRUE(ev.pop(e));
  EXPECT_NE(std::string(e.message).find("min_substeps"), std::string::npos) << e.message;
}

}  // namespace
}  // namespace teleop::sim::deformable

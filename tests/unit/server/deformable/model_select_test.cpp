// Automatic model selection (server/deformable/model_select.hpp): the table's physical-error
// columns, table -> choice (the volumetric model for a tight tolerance, a cheap surface for a
// loose one), the tolerance and budget edges, refusals at load, and the accuracy sub-steps it
// relies on.
#include "server/deformable/model_select.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "server/deformable/material.hpp"
#include "server/world/world_model.hpp"
#include "tests/unit/server/deformable/test_helpers.hpp"

namespace teleop::sim::deformable {
namespace {

// A small table in the format teleop_bench deformable writes (errors in %, against physics);
// the Bullet rows are the peer's, for the chart.
const char* kTable =
    "model,integrator,kernel,level,nodes,elements,dt_s,substeps,step_us_median,step_us_p99,"
    "cost_steps,lamb_s2_pct,lamb_t2_pct,lamb_s0_pct,press_5mm_pct,error_pct\n"
    "mass_spring,symplectic_euler,scalar,2,162,642,0.001,1,5,6,900,0.5,-1,-10,-30,30\n"
    "mass_spring,symplectic_euler,simd,2,162,642,0.001,1,2.5,3,900,0.5,-1,-10,-30,30\n"
    "mass_spring,symplectic_euler,scalar,4,2562,10242,0.001,1,60,90,900,1,-0.5,-10,-20,20\n"
    "mass_spring,symplectic_euler,simd,4,2562,10242,0.001,1,25,40,900,1,-0.5,-10,-20,20\n"
    "mass_spring,explicit_euler,scalar,4,2562,10242,0.001,2,100,120,900,nan,nan,nan,-20,inf\n"
    "mass_spring,explicit_euler,scalar,2,162,642,0.001,2,1,1,900,nan,nan,nan,-30,inf\n"
    "mass_spring,implicit_euler,scalar,4,2562,10242,0.001,1,700,800,900,1,-1,-10,-18,18\n"
    "navier_linear,symplectic_euler,scalar,2,162,480,0.001,1,1.2,2,900,-51,-18,-63,-40,63\n"
    "navier_linear,symplectic_euler,scalar,3,642,1920,0.0005,1,20,30,900,-51,-18,-63,-40,63\n"
    "fem,symplectic_euler,scalar,1,445,1735,0.001,4,300,400,900,-1,-3,-5,9,9\n"
    "fem,symplectic_euler,scalar,2,887,3835,0.001,4,900,1000,900,-0.2,-2,-3,2,3\n"
    "fem,implicit_euler,scalar,2,887,3835,0.001,1,3500,3700,900,-1,-2,-4,3,4\n"
    "bullet_fem,implicit,scalar,1,445,1735,0.001,1,800,1300,3000,nan,nan,nan,nan,inf\n"
    "bullet_fem,explicit,scalar,1,445,1735,0.001,1,18000,20000,3000,10,70,nan,nan,inf\n";

ModelTable table() { return parse_model_table(kTable, "test.csv"); }

ModelRequest all_auto(double tol_pct, double budget_us, double dt = 1e-3) {
  ModelRequest r;
  r.tolerance_pct = tol_pct;
  r.budget_us = budget_us;
  r.physics_dt_s = dt;
  return r;
}

std::string parse_error(const std::string& text) {
  try {
    parse_model_table(text, "bad.csv");
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ModelTable, ReadsThePhysicalErrorColumnsAndSkipsThePeers) {
  const ModelTable t = table();
  ASSERT_EQ(t.entries.size(), 12u);  // the two bullet_fem rows are not candidates
  EXPECT_EQ(t.entries[1].kernel, KernelKind::kSimd);
  EXPECT_DOUBLE_EQ(t.entries[2].error_pct, 20.0);
  EXPECT_DOUBLE_EQ(t.entries[2].s2_pct, 1.0);
  EXPECT_DOUBLE_EQ(t.entries[2].t2_pct, -0.5);
  EXPECT_DOUBLE_EQ(t.entries[2].s0_pct, -10.0);
  EXPECT_DOUBLE_EQ(t.entries[2].press_pct, -20.0);
  EXPECT_TRUE(std::isinf(t.entries[4].error_pct));
  EXPECT_TRUE(std::isnan(t.entries[4].s2_pct));
  EXPECT_EQ(t.entries[4].substeps, 2);
  EXPECT_EQ(t.entries[9].model, ModelKind::kFem);
  EXPECT_EQ(t.entries[9].level, 1);
  EXPECT_EQ(t.entries[9].substeps, 4);
  EXPECT_DOUBLE_EQ(t.entries[8].dt_s, 0.0005);
  // the required columns alone: kernel scalar, 1 sub-step, the quantities unknown
  const ModelTable small = parse_model_table(
      "model,integrator,level,dt_s,step_us_median,step_us_p99,error_pct\n"
      "mass_spring,symplectic_euler,4,0.001,88,115,21.5\n",
      "small.csv");
  ASSERT_EQ(small.entries.size(), 1u);
  EXPECT_EQ(small.entries[0].kernel, KernelKind::kScalar);
  EXPECT_EQ(small.entries[0].substeps, 1);
  EXPECT_DOUBLE_EQ(small.entries[0].error_pct, 21.5);
  EXPECT_TRUE(std::isnan(small.entries[0].press_pct));
}

TEST(ModelTable, RefusesMalformedTablesNamingFileAndLine) {
  // the former table (error in metres against the same model at level 6): refused, saying why
  std::string e = parse_error(
      "model,integrator,level,dt_s,step_us_median,step_us_p99,error,kernel\n"
      "mass_spring,symplectic_euler,4,0.001,88,115,0.000119,scalar\n");
  EXPECT_NE(e.find("bad.csv: line 1"), std::string::npos) << e;
  EXPECT_NE(e.find("error_pct"), std::string::npos) << e;
  EXPECT_NE(e.find("teleop_bench deformable"), std::string::npos) << e;
  e = parse_error("model,level\nmass_spring,4\n");
  EXPECT_NE(e.find("bad.csv: line 1"), std::string::npos) << e;
  const std::string head = "model,integrator,level,dt_s,step_us_median,step_us_p99,error_pct";
  e = parse_error(head + "\nmass_spring,symplectic_euler,4,0.001,fast,115,12\n");
  EXPECT_NE(e.find("line 2"), std::string::npos) << e;
  EXPECT_NE(e.find("fast"), std::string::npos) << e;
  e = parse_error(head + "\n# a comment\nmass_spring,symplectic_euler,4,0.001,88,115,-3\n");
  EXPECT_NE(e.find("line 3"), std::string::npos) << e;
  EXPECT_NE(e.find("error_pct >= 0"), std::string::npos) << e;
  e = parse_error(head + ",substeps\nmass_spring,symplectic_euler,4,0.001,88,115,3,2.5\n");
  EXPECT_NE(e.find("substeps an integer"), std::string::npos) << e;
  e = parse_error(head + "\nrubber_band,symplectic_euler,4,0.001,88,115,3\n");
  EXPECT_NE(e.find("line 2"), std::string::npos) << e;
  EXPECT_NE(e.find("rubber_band"), std::string::npos) << e;
  e = parse_error(head + "\nmass_spring,symplectic_euler,9,0.001,88,115,3\n");
  EXPECT_NE(e.find("level 9"), std::string::npos) << e;
  EXPECT_NE(parse_error(head + "\n").find("no entries"), std::string::npos);
  EXPECT_THROW(load_model_table("/nonexistent/deformable_table.csv"), config::ConfigError);
}

TEST(SelectModel, PicksTheCheapestEntryWithinToleranceAndBudget) {
  // 35 %: every finite surface entry but Navier qualifies; cheapest: level 2 simd, 2.5 us
  SelectResult r = select_model(table(), all_auto(35, 100));
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.entry.model, ModelKind::kMassSpring);
  EXPECT_EQ(r.choice.entry.level, 2);
  EXPECT_EQ(r.choice.entry.kernel, KernelKind::kSimd);
  EXPECT_EQ(r.choice.substeps, 1);
  EXPECT_DOUBLE_EQ(r.choice.cost_us_median, 2.5);
  EXPECT_DOUBLE_EQ(r.choice.error_pct, 30.0);
  // 70 %: Navier level 2 (1.2 us, 63 %) is cheaper and now within tolerance
  r = select_model(table(), all_auto(70, 100));
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.entry.model, ModelKind::kNavierLinear);
  EXPECT_EQ(r.choice.entry.level, 2);
  // 25 %: the finer mass-spring, simd
  r = select_model(table(), all_auto(25, 100));
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.entry.level, 4);
  EXPECT_EQ(r.choice.entry.kernel, KernelKind::kSimd);
}

TEST(SelectModel, ATightToleranceTakesTheVolumetricModelALooseOneACheapSurface) {
  // below what every surface entry achieves (18 % at best): only fem qualifies
  SelectResult r = select_model(table(), all_auto(10, 1e4));
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.entry.model, ModelKind::kFem);
  EXPECT_EQ(r.choice.entry.level, 1);
  EXPECT_DOUBLE_EQ(r.choice.cost_us_median, 300.0);
  r = select_model(table(), all_auto(5, 1e4));  // level 1 is 9 % off: level 2
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.entry.model, ModelKind::kFem);
  EXPECT_EQ(r.choice.entry.level, 2);
  EXPECT_EQ(r.choice.entry.integrator, IntegratorKind::kSymplecticEuler);  // cheaper than implicit
  // loose: the cheapest body of all, whatever its physics
  r = select_model(table(), all_auto(500, 1e4));
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_NE(r.choice.entry.model, ModelKind::kFem);
  EXPECT_DOUBLE_EQ(r.choice.cost_us_median, 1.2);
  // fem within tolerance but over budget: a budget problem naming the cheapest fem entry
  r = select_model(table(), all_auto(10, 100));
  EXPECT_EQ(r.outcome, SelectOutcome::kBudget);
  EXPECT_EQ(r.cheapest_accurate.entry.model, ModelKind::kFem);
}

TEST(SelectModel, ALongerWorldStepRunsAccuracySubSteps) {
  // a 2 ms world: the 1 ms entries take 2 sub-steps, the 0.5 ms one 4
  const SelectResult r = select_model(table(), all_auto(70, 1e4, 2e-3));
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.entry.model, ModelKind::kNavierLinear);
  EXPECT_EQ(r.choice.substeps, 2);
  EXPECT_DOUBLE_EQ(r.choice.cost_us_median, 2.4);
  EXPECT_DOUBLE_EQ(r.choice.cost_us_p99, 4.0);
  ModelRequest req = all_auto(70, 1e4, 2e-3);
  req.level = 3;
  const SelectResult q = select_model(table(), req);
  ASSERT_EQ(q.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(q.choice.substeps, 4);
  EXPECT_DOUBLE_EQ(q.choice.cost_us_median, 80.0);
}

TEST(SelectModel, EdgesAreInclusive) {
  // error == tolerance and cost == budget are accepted
  SelectResult r = select_model(table(), all_auto(30, 2.5));
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_DOUBLE_EQ(r.choice.cost_us_median, 2.5);
  // just below the cheapest cost: refused as a budget problem naming the cheapest accurate entry
  r = select_model(table(), all_auto(30, 2.4999));
  EXPECT_EQ(r.outcome, SelectOutcome::kBudget);
  EXPECT_DOUBLE_EQ(r.cheapest_accurate.cost_us_median, 2.5);
  // just below the smallest error: a tolerance problem naming the most accurate entry
  r = select_model(table(), all_auto(2.999, 1e6));
  EXPECT_EQ(r.outcome, SelectOutcome::kTolerance);
  EXPECT_DOUBLE_EQ(r.most_accurate.error_pct, 3.0);
  EXPECT_EQ(r.most_accurate.entry.model, ModelKind::kFem);
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
  req = all_auto(100, 1e6);
  req.level = 4;
  req.kernel = KernelKind::kScalar;
  r = select_model(table(), req);
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_EQ(r.choice.entry.level, 4);
  EXPECT_EQ(r.choice.entry.kernel, KernelKind::kScalar);
  EXPECT_DOUBLE_EQ(r.choice.cost_us_median, 60.0);
  // a world step the entries' steps do not divide, and one shorter than every entry's
  EXPECT_EQ(select_model(table(), all_auto(100, 1e6, 0.7e-3)).outcome, SelectOutcome::kNoEntry);
  EXPECT_EQ(select_model(table(), all_auto(100, 1e6, 0.25e-3)).outcome, SelectOutcome::kNoEntry);
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

TEST_F(AutoBodyYaml, BuildsTheChosenBodyAndSaysWhy) {
  // 25 %: the level-4 mass-spring ball, simd (25 us), springs from the default material
  const AutoBody b = load(
      "body: {model: auto, integrator: auto, level: auto, tolerance_pct: 25, budget_us: 1000,\n"
      "       model_table: table.csv, centre_m: [0, 0, 0]}\n");
  ASSERT_TRUE(b.choice.has_value());
  EXPECT_EQ(b.model.params.level, 4);
  EXPECT_EQ(b.model.params.model, ModelKind::kMassSpring);
  EXPECT_EQ(b.model.params.integrator, IntegratorKind::kSymplecticEuler);
  EXPECT_EQ(b.model.params.kernel, KernelKind::kSimd);
  EXPECT_EQ(b.model.params.min_substeps, 1);
  EXPECT_EQ(b.model.node_count, 2562);
  EXPECT_TRUE(b.model.params.springs_from_material);
  const MassSpringStiffness k = mass_spring_from_material(6000.0, 0.3, 0.25, 0.3);
  EXPECT_DOUBLE_EQ(b.model.params.edge_stiffness_n_per_m, k.edge_n_per_m);
  EXPECT_DOUBLE_EQ(b.model.params.radial_stiffness_n_per_m3, k.radial_n_per_m3);
  EXPECT_TRUE(b.differs_from_table.empty()) << b.differs_from_table[0];
  const std::string s = b.summary();
  EXPECT_LT(s.size(), 128u);
  EXPECT_NE(s.find("mass_spring symplectic_euler simd level 4, 1 x 1 ms"), std::string::npos) << s;
  EXPECT_NE(s.find("error 20 %"), std::string::npos) << s;
  const std::string rep = b.report();
  EXPECT_NE(rep.find("tolerance 25 %"), std::string::npos) << rep;
  EXPECT_NE(rep.find("physical error 20 %"), std::string::npos) << rep;
  EXPECT_NE(rep.find("Lamb S2 +1.0 %, T2 -0.5 %, S0 -10.0 %"), std::string::npos) << rep;
  EXPECT_NE(rep.find("CalculiX -20.0 %"), std::string::npos) << rep;
  EXPECT_NE(rep.find("predicted cost"), std::string::npos) << rep;
}

TEST_F(AutoBodyYaml, ATightToleranceBuildsTheFemBall) {
  const AutoBody b = load(
      "body: {model: auto, integrator: auto, level: auto, tolerance_pct: 5, budget_us: 1e5,\n"
      "       model_table: table.csv, centre_m: [0, 0, 0.25]}\n");
  ASSERT_TRUE(b.choice.has_value());
  EXPECT_EQ(b.model.params.model, ModelKind::kFem);
  EXPECT_EQ(b.model.params.level, 2);
  EXPECT_GT(b.model.fem.tet_count, 1000);
  EXPECT_GE(b.stability_factor, 1.0);
  EXPECT_TRUE(b.differs_from_table.empty()) << b.differs_from_table[0];
}

TEST_F(AutoBodyYaml, FixedFieldsStayAndOtherMaterialIsFlagged) {
  // a stiffer material: its springs derived from it, and the prediction flagged
  AutoBody b = load(
      "body: {model: mass_spring, level: auto, kernel: scalar, tolerance_pct: 25,\n"
      "       budget_us: 1000, model_table: table.csv, youngs_modulus_pa: 8000}\n");
  ASSERT_TRUE(b.choice.has_value());
  EXPECT_EQ(b.model.params.kernel, KernelKind::kScalar);
  EXPECT_EQ(b.model.params.level, 4);
  EXPECT_DOUBLE_EQ(b.model.params.edge_stiffness_n_per_m,
                   mass_spring_from_material(8000.0, 0.3, 0.25, 0.3).edge_n_per_m);
  ASSERT_EQ(b.differs_from_table.size(), 1u);
  EXPECT_EQ(b.differs_from_table[0], "youngs_modulus_pa");
  EXPECT_NE(b.summary().find("other material"), std::string::npos);
  // springs given instead of a material: kept, and flagged
  b = load(
      "body: {model: mass_spring, level: auto, kernel: scalar, tolerance_pct: 25,\n"
      "       budget_us: 1000, model_table: table.csv, edge_stiffness_n_per_m: 200}\n");
  EXPECT_FALSE(b.model.params.springs_from_material);
  EXPECT_DOUBLE_EQ(b.model.params.edge_stiffness_n_per_m, 200.0);
  ASSERT_GE(b.differs_from_table.size(), 1u);
  EXPECT_EQ(b.differs_from_table[0], "edge_stiffness_n_per_m");
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
  std::string e = error_of(head + "tolerance_pct: 0, budget_us: 100}\n");
  EXPECT_NE(e.find("scene.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("body.tolerance_pct"), std::string::npos) << e;
  EXPECT_NE(e.find("value '0' "), std::string::npos) << e;
  EXPECT_NE(e.find("(0, 1000]"), std::string::npos) << e;
  e = error_of(head + "tolerance_pct: -1, budget_us: 100}\n");
  EXPECT_NE(e.find("body.tolerance_pct"), std::string::npos) << e;
  // the former field: refused, naming what replaced it and its range
  e = error_of(head + "tolerance_mm: 0.5, budget_us: 100}\n");
  EXPECT_NE(e.find("body.tolerance_mm"), std::string::npos) << e;
  EXPECT_NE(e.find("replaced by tolerance_pct"), std::string::npos) << e;
  EXPECT_NE(e.find("(0, 1000]"), std::string::npos) << e;
  // budget below every entry within tolerance: names the cheapest one and its cost
  e = error_of(head + "tolerance_pct: 35, budget_us: 1}\n");
  EXPECT_NE(e.find("body.budget_us"), std::string::npos) << e;
  EXPECT_NE(e.find("value 1 "), std::string::npos) << e;
  EXPECT_NE(e.find("mass_spring symplectic_euler simd level 2, 1 x 1 ms: 2.5 us"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("allowed range [2.5, 1e6]"), std::string::npos) << e;
  // a tolerance no entry meets: names the smallest error (mass-spring, the default model, and
  // the integrator's default: symplectic, 20 %)
  e = error_of(head + "tolerance_pct: 0.001, budget_us: 1000}\n");
  EXPECT_NE(e.find("body.tolerance_pct"), std::string::npos) << e;
  EXPECT_NE(e.find("(20 %: mass_spring symplectic_euler"), std::string::npos) << e;
  e = error_of(
      "body: {model: auto, integrator: auto, level: auto, model_table: table.csv, "
      "tolerance_pct: 0.001, budget_us: 1000}\n");
  EXPECT_NE(e.find("(3 %: fem symplectic_euler scalar level 2"), std::string::npos) << e;
  // missing fields, fields without auto, auto with a mesh file, unknown values
  e = error_of(head + "budget_us: 100}\n");
  EXPECT_NE(e.find("body.tolerance_pct': is required"), std::string::npos) << e;
  e = error_of("body: {level: 3, tolerance_pct: 10}\n");
  EXPECT_NE(e.find("body.tolerance_pct': is used only when"), std::string::npos) << e;
  e = error_of(head + "tolerance_pct: 20, budget_us: 100, mesh_file: x.obj}\n");
  EXPECT_NE(e.find("body.mesh_file"), std::string::npos) << e;
  e = error_of(head + "tolerance_pct: 20, budget_us: 100, tet_mesh_file: x.msh}\n");
  EXPECT_NE(e.find("body.tet_mesh_file"), std::string::npos) << e;
  e = error_of(
      "body: {model: auto, integrator: leapfrog, tolerance_pct: 1, budget_us: 100,"
      " model_table: table.csv}\n");
  EXPECT_NE(e.find("body.integrator"), std::string::npos) << e;
  e = error_of("body: {level: auto, tolerance_pct: 1, budget_us: 100, model_table: nope.csv}\n");
  EXPECT_NE(e.find("nope.csv"), std::string::npos) << e;
  EXPECT_NE(e.find("teleop_bench deformable"), std::string::npos) << e;
}

TEST_F(AutoBodyYaml, StifferMaterialCountsItsStabilitySubSteps) {
  // x100 stiffness: the body needs more stability sub-steps at 1 ms than the table's; with the
  // budget the selection keeps an entry it can afford, or refuses naming the real cost
  const AutoBody b = load(
      "body: {model: mass_spring, integrator: symplectic_euler, level: auto, kernel: scalar,\n"
      "       tolerance_pct: 35, budget_us: 1000, model_table: table.csv,\n"
      "       youngs_modulus_pa: 600000}\n");
  ASSERT_TRUE(b.choice.has_value());
  const int needed = b.model.substeps_needed(b.choice->entry.dt_s);
  EXPECT_GT(needed, 1);
  EXPECT_DOUBLE_EQ(b.stability_factor,
                   std::max(1.0, static_cast<double>(needed) / b.choice->entry.substeps));
  EXPECT_LE(b.choice->cost_us_median * b.stability_factor, 1000.0);
  EXPECT_NE(b.report().find("differs in youngs_modulus_pa"), std::string::npos) << b.report();
  EXPECT_NE(b.report().find("stability sub-steps"), std::string::npos) << b.report();
}

TEST(ModelTable, TheShippedTableLoadsAndServesTheDefaultRequest) {
  const std::string file = default_model_table_file();
  if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " not present";
  const ModelTable t = load_model_table(file);
  EXPECT_GT(t.entries.size(), 40u);
  ModelRequest req = all_auto(100, 1e5);
  req.model.reset();
  req.integrator.reset();
  const SelectResult r = select_model(t, req);
  ASSERT_EQ(r.outcome, SelectOutcome::kChosen);
  EXPECT_LE(r.choice.error_pct, 100.0);
  // the volumetric model is in it, and is the most accurate
  EXPECT_EQ(r.most_accurate.entry.model, ModelKind::kFem);
  EXPECT_LT(r.most_accurate.error_pct, 15.0);
}

TEST(ModelTable, TheAutoSceneLoadsThroughTheWorldLoader) {
  if (!std::filesystem::exists(default_model_table_file())) GTEST_SKIP() << "no shipped table";
  const WorldModel w =
      load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/sphere_auto.yaml");
  ASSERT_EQ(w.bodies.size(), 1u);
  EXPECT_NE(w.bodies[0].auto_summary.find("auto: "), std::string::npos);
  EXPECT_NE(w.bodies[0].auto_report.find("predicted cost"), std::string::npos);
  EXPECT_GT(w.bodies[0].body.node_count, 0);
  // the default and the paper's scenes fix their models: no selection, the bodies they name
  const WorldModel d =
      load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/default.yaml");
  EXPECT_TRUE(d.bodies[0].auto_summary.empty());
  EXPECT_EQ(d.bodies[0].body.params.model, ModelKind::kFem);
  EXPECT_EQ(d.bodies[0].body.params.min_substeps, 1);
  EXPECT_EQ(d.bodies[0].body.node_count, 477);      // its surface
  EXPECT_EQ(d.bodies[0].body.fem.node_count, 885);  // all its nodes
  const WorldModel paper =
      load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/paper_sphere.yaml");
  EXPECT_TRUE(paper.bodies[0].auto_summary.empty());
  EXPECT_EQ(paper.bodies[0].body.params.min_substeps, 1);
  // no `kernel` in it: the default kernel (simd where the CPU has AVX2 and FMA)
  EXPECT_EQ(paper.bodies[0].body.params.kernel,
            default_kernel(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler));
  EXPECT_EQ(paper.bodies[0].body.node_count, 2562);
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

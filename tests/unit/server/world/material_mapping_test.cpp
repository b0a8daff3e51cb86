// A material stated once: every model derives its parameters from it, the same way on the scene
// path (load_deformable_params + make_model) and on the validation path (ball_params, used by
// `teleop_experiment validate` and `teleop_bench deformable`); the mass-spring mapping
// (server/deformable/material.hpp) checked against physics: its ball's lowest free vibrations
// against Lamb's.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/config/config.hpp"
#include "server/deformable/material.hpp"
#include "server/world/physics_validation.hpp"

namespace df = teleop::sim::deformable;
namespace va = teleop::sim::validation;

namespace {

df::DeformableModel from_scene(const std::string& yaml) {
  const teleop::config::Node root = teleop::config::Node::parse(yaml, "scene.yaml");
  return df::make_model(df::load_deformable_params(root.at("body")));
}

std::string scene_body(const std::string& model, int level, const va::Material& m) {
  return "body: {model: " + model + ", level: " + std::to_string(level) +
         ", radius_m: 0.25, youngs_modulus_pa: " + std::to_string(m.youngs_modulus_pa) +
         ", poisson_ratio: " + std::to_string(m.poisson_ratio) +
         ", density_kg_per_m3: " + std::to_string(m.density_kg_per_m3) + "}\n";
}

}  // namespace

TEST(MaterialOnce, SceneAndValidationDeriveTheSameBodyForEveryModel) {
  for (const va::Material& mat : {va::foam(), va::silicone()}) {
    for (auto model : {df::ModelKind::kMassSpring, df::ModelKind::kNavierLinear,
                       df::ModelKind::kNavierCorotational, df::ModelKind::kFem}) {
      const int level = model == df::ModelKind::kFem ? 1 : 2;
      const df::DeformableModel scene = from_scene(scene_body(df::to_string(model), level, mat));
      const df::DeformableModel valid =
          df::make_model(va::ball_params(model, df::IntegratorKind::kSymplecticEuler, level, mat));
      SCOPED_TRACE(std::string(df::to_string(model)) + " " + mat.name);
      EXPECT_DOUBLE_EQ(scene.lame_mu_pa, valid.lame_mu_pa);
      EXPECT_DOUBLE_EQ(scene.lame_lambda_pa, valid.lame_lambda_pa);
      // the scene gives a density (mass = density x the mesh's volume), validation the mass of
      // the sphere: equal within the mesh's volume deficit
      EXPECT_NEAR(scene.total_mass_kg, valid.total_mass_kg, 0.05 * valid.total_mass_kg);
      EXPECT_EQ(scene.state_node_count(), valid.state_node_count());
      if (model == df::ModelKind::kMassSpring) {
        EXPECT_TRUE(scene.params.springs_from_material);
        EXPECT_TRUE(valid.params.springs_from_material);
        EXPECT_DOUBLE_EQ(scene.params.edge_stiffness_n_per_m, valid.params.edge_stiffness_n_per_m);
        EXPECT_DOUBLE_EQ(scene.params.radial_stiffness_n_per_m3,
                         valid.params.radial_stiffness_n_per_m3);
        EXPECT_TRUE(scene.edge_k_iso == valid.edge_k_iso);
        EXPECT_TRUE(scene.radial_k == valid.radial_k);
        const df::MassSpringStiffness k =
            df::mass_spring_from_material(mat.youngs_modulus_pa, mat.poisson_ratio, 0.25,
                                          df::DeformableParams{}.centre_mass_fraction);
        EXPECT_DOUBLE_EQ(scene.params.edge_stiffness_n_per_m, k.edge_n_per_m);
      }
      if (model == df::ModelKind::kNavierLinear || model == df::ModelKind::kNavierCorotational) {
        EXPECT_EQ(scene.params.radial_stiffness_n_per_m3, 0.0);
        EXPECT_EQ(valid.params.radial_stiffness_n_per_m3, 0.0);
      }
      if (model == df::ModelKind::kFem) {
        EXPECT_EQ(scene.fem.tet_count, valid.fem.tet_count);
        EXPECT_DOUBLE_EQ(scene.params.stiffness_damping_s, valid.params.stiffness_damping_s);
        EXPECT_DOUBLE_EQ(scene.params.mass_damping_per_s, valid.params.mass_damping_per_s);
      }
    }
  }
}

TEST(MaterialOnce, AMassSpringBodyGivesEitherItsMaterialOrItsSprings) {
  // without a material the springs are the scene's (the default scene's body is unchanged)
  const df::DeformableModel legacy = from_scene("body: {model: mass_spring, level: 2}\n");
  EXPECT_FALSE(legacy.params.springs_from_material);
  EXPECT_EQ(legacy.params.edge_stiffness_n_per_m, df::DeformableParams{}.edge_stiffness_n_per_m);
  // both: refused naming the field and both ways
  try {
    from_scene(
        "body: {model: mass_spring, youngs_modulus_pa: 6000, edge_stiffness_n_per_m: 150}\n");
    FAIL();
  } catch (const teleop::config::ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("scene.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find("body.edge_stiffness_n_per_m"), std::string::npos) << what;
    EXPECT_NE(what.find("youngs_modulus_pa, poisson_ratio"), std::string::npos) << what;
  }
}

TEST(MaterialOnce, TheMassSpringMappingScalesAsAMaterialAndIgnoresTheLevel) {
  const df::MassSpringStiffness a = df::mass_spring_from_material(6000.0, 0.3, 0.25, 0.3);
  // k = (1 - f_c) eta_T2^2 mu R / (3 sqrt 3), by hand: 0.7 x 2.5011^2 x 2307.7 x 0.25 / 5.196
  EXPECT_NEAR(a.edge_n_per_m, 486.0, 1.0);
  const df::MassSpringStiffness twice_e = df::mass_spring_from_material(12000.0, 0.3, 0.25, 0.3);
  EXPECT_NEAR(twice_e.edge_n_per_m, 2.0 * a.edge_n_per_m, 1e-9 * a.edge_n_per_m);
  EXPECT_NEAR(twice_e.radial_n_per_m3, 2.0 * a.radial_n_per_m3, 1e-9 * a.radial_n_per_m3);
  const df::MassSpringStiffness twice_r = df::mass_spring_from_material(6000.0, 0.3, 0.5, 0.3);
  EXPECT_NEAR(twice_r.edge_n_per_m, 2.0 * a.edge_n_per_m, 1e-9 * a.edge_n_per_m);
  EXPECT_NEAR(twice_r.radial_n_per_m3, 0.5 * a.radial_n_per_m3, 1e-9 * a.radial_n_per_m3);
  EXPECT_THROW(df::mass_spring_from_material(6000.0, 0.6, 0.25, 0.3), teleop::config::ConfigError);
  EXPECT_THROW(df::mass_spring_from_material(0.0, 0.3, 0.25, 0.3), teleop::config::ConfigError);
  // the level does not enter: two levels of the same body have the same springs
  df::DeformableParams p = va::ball_params(df::ModelKind::kMassSpring,
                                           df::IntegratorKind::kSymplecticEuler, 2, va::foam());
  const df::DeformableModel l2 = df::make_model(p);
  p.level = 3;
  const df::DeformableModel l3 = df::make_model(p);
  EXPECT_EQ(l2.params.edge_stiffness_n_per_m, l3.params.edge_stiffness_n_per_m);
  EXPECT_EQ(l2.params.radial_stiffness_n_per_m3, l3.params.radial_stiffness_n_per_m3);
}

TEST(MaterialOnce, TheMassSpringBallHasLambsTwoLowestFrequencies) {
  // against physics (Lamb's analytic frequencies of the elastic sphere), for two materials: the
  // mapping fixes T2 and S2 in the membrane limit; the level-3 lattice is within a few %
  for (const va::Material& mat : {va::foam(), va::silicone()}) {
    const df::DeformableParams p =
        va::ball_params(df::ModelKind::kMassSpring, df::IntegratorKind::kSymplecticEuler, 3, mat);
    for (auto mode : {va::LambMode::kT2, va::LambMode::kS2}) {
      const double lamb = va::lamb_frequency_hz(mode, mat, va::kBallRadiusM);
      std::uint64_t faults = 0;
      const double f = va::free_vibration_hz(p, mode, 1.0, lamb, nullptr, &faults);
      EXPECT_EQ(faults, 0u);
      RecordProperty(mat.name + "_" + va::to_string(mode) + "_error_pct",
                     std::to_string(100.0 * (f / lamb - 1.0)));
      EXPECT_NEAR(f / lamb, 1.0, 0.08)
          << mat.name << " " << va::to_string(mode) << ": " << f << " Hz against Lamb's " << lamb;
    }
  }
}

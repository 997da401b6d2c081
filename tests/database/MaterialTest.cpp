#include "brittle/database/Material.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

using testing::makeGlassMaterial;

struct FieldCase {
  const char* field;  // the snake_case name the message must contain
  std::function<void(Material&, double)> set;
  std::vector<double> badValues;
};

std::vector<FieldCase> fieldCases() {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  return {
      {"youngs_modulus_pa", [](Material& m, double v) { m.youngsModulusPa = v; }, {0.0, -1e9, nan, inf}},
      {"poisson_ratio", [](Material& m, double v) { m.poissonRatio = v; }, {0.5, 0.7, -1.0, -2.0, nan}},
      {"density_kg_per_m3", [](Material& m, double v) { m.densityKgPerM3 = v; }, {0.0, -1.0, nan, -inf}},
      {"tensile_strength_pa", [](Material& m, double v) { m.tensileStrengthPa = v; }, {0.0, -5.0, nan}},
      {"fracture_energy_j_per_m2", [](Material& m, double v) { m.fractureEnergyJPerM2 = v; }, {0.0, -1.0, nan}},
      {"rayleigh_alpha_per_s", [](Material& m, double v) { m.rayleighAlphaPerS = v; }, {-1e-3, nan, inf}},
      {"rayleigh_beta_s", [](Material& m, double v) { m.rayleighBetaS = v; }, {-1e-9, nan}},
      {"restitution", [](Material& m, double v) { m.restitution = v; }, {-0.1, 1.1, nan}},
  };
}

TEST(Material, PhysicalMaterialIsValid) { EXPECT_TRUE(validateMaterial(makeGlassMaterial()).ok()); }

TEST(Material, EachNonsenseFieldIsRejectedByName) {
  for (const FieldCase& c : fieldCases()) {
    for (double bad : c.badValues) {
      Material m = makeGlassMaterial();
      c.set(m, bad);
      const Status s = validateMaterial(m);
      ASSERT_FALSE(s.ok()) << c.field << " = " << bad;
      EXPECT_EQ(s.error().code, ErrorCode::InvalidMaterial) << c.field << " = " << bad;
      EXPECT_NE(s.error().message.find(c.field), std::string::npos)
          << "message '" << s.error().message << "' does not name " << c.field;
      EXPECT_NE(s.error().message.find("glass"), std::string::npos) << s.error().message;
    }
  }
}

TEST(Material, NanIsReportedAsNotFinite) {
  Material m = makeGlassMaterial();
  m.densityKgPerM3 = std::numeric_limits<double>::quiet_NaN();
  const Status s = validateMaterial(m);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("not finite"), std::string::npos) << s.error().message;
}

TEST(Material, IncompressibleLimitIsRejected) {
  // ν = 0.5 makes the bulk modulus infinite (λ = Eν/((1+ν)(1−2ν))); ν just below is legal.
  Material m = makeGlassMaterial();
  m.poissonRatio = 0.5;
  EXPECT_EQ(validateMaterial(m).error().code, ErrorCode::InvalidMaterial);
  m.poissonRatio = std::nextafter(0.5, 0.0);
  EXPECT_TRUE(validateMaterial(m).ok());
}

TEST(Material, BoundaryValuesAreAccepted) {
  Material m = makeGlassMaterial();
  m.rayleighAlphaPerS = 0.0;
  m.rayleighBetaS = 0.0;
  m.restitution = 0.0;
  EXPECT_TRUE(validateMaterial(m).ok());
  m.restitution = 1.0;
  m.poissonRatio = -0.99;
  EXPECT_TRUE(validateMaterial(m).ok());
}

TEST(Material, EmptyNameIsRejected) {
  Material m = makeGlassMaterial();
  m.name.clear();
  const Status s = validateMaterial(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::InvalidMaterial);
  EXPECT_NE(s.error().message.find("name"), std::string::npos);
}

TEST(Material, FractureEnergyFromToughnessMatchesPlaneStrainFormula) {
  // Glass: K_Ic = 0.75 MPa·√m, E = 70 GPa, ν = 0.22 ⇒ G_c = K²(1−ν²)/E = 5.35275e11 / 7e10.
  EXPECT_NEAR(fractureEnergyFromToughness(0.75e6, 70e9, 0.22), 7.646785714285714, 1e-12);
  // ν = 0 reduces to the plane-stress value K²/E.
  EXPECT_NEAR(fractureEnergyFromToughness(1e6, 100e9, 0.0), 10.0, 1e-12);
  // G_c is quadratic in K_Ic.
  EXPECT_NEAR(fractureEnergyFromToughness(2e6, 70e9, 0.22) / fractureEnergyFromToughness(1e6, 70e9, 0.22), 4.0, 1e-12);
}

TEST(Material, RayleighDampingRatio) {
  Material m = makeGlassMaterial();
  m.rayleighAlphaPerS = 2.0;
  m.rayleighBetaS = 1e-5;
  // ζ = (α/ω + βω)/2 = (0.002 + 0.01)/2 at ω = 1000 rad/s.
  EXPECT_NEAR(rayleighDampingRatio(m, 1000.0), 0.006, 1e-15);
  // Its minimum is at ω = √(α/β), where ζ = √(αβ).
  const double omegaMin = std::sqrt(m.rayleighAlphaPerS / m.rayleighBetaS);
  const double zetaMin = std::sqrt(m.rayleighAlphaPerS * m.rayleighBetaS);
  EXPECT_NEAR(rayleighDampingRatio(m, omegaMin), zetaMin, 1e-15);
  EXPECT_GT(rayleighDampingRatio(m, 0.9 * omegaMin), zetaMin);
  EXPECT_GT(rayleighDampingRatio(m, 1.1 * omegaMin), zetaMin);
  // Pure stiffness-proportional damping grows linearly with ω.
  m.rayleighAlphaPerS = 0.0;
  EXPECT_NEAR(rayleighDampingRatio(m, 2000.0), 2.0 * rayleighDampingRatio(m, 1000.0), 1e-15);
}

}  // namespace
}  // namespace brittle

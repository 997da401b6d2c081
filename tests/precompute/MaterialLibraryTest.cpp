#include "brittle/precompute/MaterialLibrary.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

// A material file as (key, raw JSON value) pairs, so a test can inject text that is not a valid
// double (a string, 1e999) exactly as a user might write it.
using Fields = std::vector<std::pair<std::string, std::string>>;

Fields validFields() {
  return {
      {"name", "\"my-glass\""},
      {"youngs_modulus_pa", "7.2e10"},
      {"poisson_ratio", "0.22"},
      {"density_kg_per_m3", "2500"},
      {"tensile_strength_pa", "5e7"},
      {"fracture_energy_j_per_m2", "7.4"},
      {"rayleigh_alpha_per_s", "0"},
      {"rayleigh_beta_s", "1.6e-7"},
      {"restitution", "0.5"},
      {"source", "\"test values\""},
  };
}

Fields withField(Fields fields, const std::string& key, const std::string& value) {
  for (auto& [k, v] : fields) {
    if (k == key) {
      v = value;
      return fields;
    }
  }
  fields.emplace_back(key, value);
  return fields;
}

Fields withoutField(Fields fields, const std::string& key) {
  std::erase_if(fields, [&](const auto& kv) { return kv.first == key; });
  return fields;
}

std::filesystem::path writeText(const std::string& text, const std::string& fileName = "material.json") {
  const auto path = testing::makeTempDir("materials") / fileName;
  std::ofstream(path) << text;
  return path;
}

std::filesystem::path writeFields(const Fields& fields) {
  std::string text = "{\n";
  for (size_t i = 0; i < fields.size(); ++i) {
    text += "  \"" + fields[i].first + "\": " + fields[i].second + (i + 1 < fields.size() ? ",\n" : "\n");
  }
  return writeText(text + "}\n");
}

void expectError(const Result<Material>& result, ErrorCode code, const std::string& mention) {
  ASSERT_FALSE(result.ok()) << "expected " << errorCodeName(code);
  EXPECT_EQ(result.error().code, code) << result.error().message;
  EXPECT_NE(result.error().message.find(mention), std::string::npos)
      << "message should mention '" << mention << "': " << result.error().message;
}

TEST(MaterialPresets, NamesAreSortedAndIncludeTheDocumentedPresets) {
  const auto names = materialPresetNames();
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  EXPECT_EQ(std::adjacent_find(names.begin(), names.end()), names.end()) << "duplicate preset name";
  for (const char* expected : {"ceramic", "concrete", "glass", "porcelain", "steel", "stone"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  }
}

TEST(MaterialPresets, EveryPresetIsValidAndCitesASource) {
  for (const auto& name : materialPresetNames()) {
    SCOPED_TRACE(name);
    const auto m = materialPreset(name);
    ASSERT_TRUE(m.ok()) << m.error().message;
    EXPECT_EQ(m.value().name, name);
    const Status valid = validateMaterial(m.value());
    EXPECT_TRUE(valid.ok()) << (valid.ok() ? "" : valid.error().message);
    EXPECT_FALSE(m.value().source.empty());
  }
}

TEST(MaterialPresets, GlassIsSodaLimeGlass) {
  const auto glass = materialPreset("glass");
  ASSERT_TRUE(glass.ok());
  const Material& m = glass.value();
  EXPECT_GE(m.youngsModulusPa, 65e9);
  EXPECT_LE(m.youngsModulusPa, 75e9);
  EXPECT_GE(m.poissonRatio, 0.18);
  EXPECT_LE(m.poissonRatio, 0.25);
  EXPECT_GE(m.densityKgPerM3, 2400.0);
  EXPECT_LE(m.densityKgPerM3, 2600.0);
  EXPECT_GE(m.tensileStrengthPa, 20e6);
  EXPECT_LE(m.tensileStrengthPa, 100e6);
  // K_Ic of soda-lime glass is 0.7–0.8 MPa·√m, i.e. G_c of roughly 6–9 J/m².
  EXPECT_GE(m.fractureEnergyJPerM2, 6.0);
  EXPECT_LE(m.fractureEnergyJPerM2, 9.0);
}

TEST(MaterialPresets, DampingIsHalfTheLossFactorAtOneKilohertz) {
  // Glass uses η = 1e-3 put entirely on β at f_ref = 1 kHz, so ζ(1 kHz) = η/2.
  const auto glass = materialPreset("glass");
  ASSERT_TRUE(glass.ok());
  EXPECT_EQ(glass.value().rayleighAlphaPerS, 0.0);
  EXPECT_NEAR(rayleighDampingRatio(glass.value(), 2.0 * std::numbers::pi * 1000.0), 0.5e-3, 1e-12);
}

TEST(MaterialPresets, GlassFractureEnergyComesFromItsToughness) {
  const auto glass = materialPreset("glass");
  ASSERT_TRUE(glass.ok());
  const Material& m = glass.value();
  const double kIc = 0.75e6;
  EXPECT_NEAR(m.fractureEnergyJPerM2, kIc * kIc * (1.0 - m.poissonRatio * m.poissonRatio) / m.youngsModulusPa,
              1e-9);
}

TEST(MaterialPresets, ToughnessConversionMatchesTheFormula) {
  // G_c = K²(1−ν²)/E: 1 MPa·√m, ν = 0.3, E = 100 GPa gives 1e12 · 0.91 / 1e11 = 9.1 J/m².
  EXPECT_NEAR(fractureEnergyFromToughness(1.0e6, 100.0e9, 0.3), 9.1, 1e-12);
}

TEST(MaterialPresets, UnknownNameIsATypedErrorListingThePresets) {
  expectError(materialPreset("unobtainium"), ErrorCode::UnknownMaterial, "glass");
  expectError(resolveMaterial("unobtainium"), ErrorCode::UnknownMaterial, "unobtainium");
}

TEST(MaterialFile, RoundTripsACustomMaterial) {
  const auto path = writeFields(validFields());
  const auto loaded = loadMaterialFile(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  const Material& m = loaded.value();
  EXPECT_EQ(m.name, "my-glass");
  EXPECT_EQ(m.youngsModulusPa, 7.2e10);
  EXPECT_EQ(m.poissonRatio, 0.22);
  EXPECT_EQ(m.densityKgPerM3, 2500.0);
  EXPECT_EQ(m.tensileStrengthPa, 5e7);
  EXPECT_EQ(m.fractureEnergyJPerM2, 7.4);
  EXPECT_EQ(m.rayleighAlphaPerS, 0.0);
  EXPECT_EQ(m.rayleighBetaS, 1.6e-7);
  EXPECT_EQ(m.restitution, 0.5);
  EXPECT_EQ(m.source, "test values");

  // resolveMaterial reads anything ending in .json as a file.
  const auto resolved = resolveMaterial(path.string());
  ASSERT_TRUE(resolved.ok()) << resolved.error().message;
  EXPECT_EQ(resolved.value().name, "my-glass");
}

TEST(MaterialFile, ToughnessIsConvertedToFractureEnergy) {
  auto fields = withoutField(validFields(), "fracture_energy_j_per_m2");
  fields.emplace_back("fracture_toughness_pa_sqrt_m", "7.5e5");
  const auto loaded = loadMaterialFile(writeFields(fields));
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  EXPECT_NEAR(loaded.value().fractureEnergyJPerM2, 7.5e5 * 7.5e5 * (1.0 - 0.22 * 0.22) / 7.2e10, 1e-12);
}

TEST(MaterialFile, ResolvesPresetNames) {
  const auto m = resolveMaterial("porcelain");
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m.value().name, "porcelain");
}

TEST(MaterialFile, MissingFileIsFileNotFound) {
  const auto path = testing::makeTempDir("materials") / "absent.json";
  expectError(loadMaterialFile(path), ErrorCode::FileNotFound, "absent.json");
  expectError(resolveMaterial(path.string()), ErrorCode::FileNotFound, "absent.json");
}

TEST(MaterialFile, MalformedJsonIsParseError) {
  expectError(loadMaterialFile(writeText("{ \"name\": \"x\", ")), ErrorCode::ParseError, "material.json");
  expectError(loadMaterialFile(writeText("")), ErrorCode::ParseError, "material.json");
}

TEST(MaterialFile, TopLevelMustBeAnObject) {
  expectError(loadMaterialFile(writeText("[1, 2, 3]")), ErrorCode::ParseError, "object");
}

TEST(MaterialFile, MissingKeyIsParseErrorNamingTheKey) {
  expectError(loadMaterialFile(writeFields(withoutField(validFields(), "density_kg_per_m3"))), ErrorCode::ParseError,
              "density_kg_per_m3");
  expectError(loadMaterialFile(writeFields(withoutField(validFields(), "name"))), ErrorCode::ParseError, "name");
}

TEST(MaterialFile, UnknownKeyIsParseErrorNamingTheKey) {
  // A typo must not silently drop a value.
  auto fields = withoutField(validFields(), "poisson_ratio");
  fields.emplace_back("poisson_ration", "0.22");
  expectError(loadMaterialFile(writeFields(fields)), ErrorCode::ParseError, "poisson_ration");
}

TEST(MaterialFile, NegativeModulusIsInvalidMaterial) {
  expectError(loadMaterialFile(writeFields(withField(validFields(), "youngs_modulus_pa", "-7.2e10"))),
              ErrorCode::InvalidMaterial, "youngs_modulus_pa");
}

TEST(MaterialFile, IncompressiblePoissonRatioIsInvalidMaterial) {
  expectError(loadMaterialFile(writeFields(withField(validFields(), "poisson_ratio", "0.5"))),
              ErrorCode::InvalidMaterial, "poisson_ratio");
  expectError(loadMaterialFile(writeFields(withField(validFields(), "poisson_ratio", "0.7"))),
              ErrorCode::InvalidMaterial, "poisson_ratio");
}

TEST(MaterialFile, NonNumericValueIsParseError) {
  // JSON has no NaN literal; a string "NaN" is the way a user would try to write one.
  expectError(loadMaterialFile(writeFields(withField(validFields(), "density_kg_per_m3", "\"NaN\""))),
              ErrorCode::ParseError, "density_kg_per_m3");
  expectError(loadMaterialFile(writeFields(withField(validFields(), "restitution", "true"))), ErrorCode::ParseError,
              "restitution");
  expectError(loadMaterialFile(writeFields(withField(validFields(), "name", "42"))), ErrorCode::ParseError, "name");
}

TEST(MaterialFile, OverflowingNumberIsParseError) {
  // The parser rejects 1e999 itself, so an infinity never reaches validateMaterial.
  expectError(loadMaterialFile(writeFields(withField(validFields(), "tensile_strength_pa", "1e999"))),
              ErrorCode::ParseError, "1e999");
}

TEST(MaterialFile, EnergyAndToughnessAreExclusive) {
  auto both = validFields();
  both.emplace_back("fracture_toughness_pa_sqrt_m", "7.5e5");
  expectError(loadMaterialFile(writeFields(both)), ErrorCode::ParseError, "fracture_toughness_pa_sqrt_m");
  expectError(loadMaterialFile(writeFields(withoutField(validFields(), "fracture_energy_j_per_m2"))),
              ErrorCode::ParseError, "fracture_energy_j_per_m2");
}

TEST(MaterialFile, NegativeToughnessIsInvalidMaterial) {
  // K enters squared; without its own check −K would pass as a positive G_c.
  auto fields = withoutField(validFields(), "fracture_energy_j_per_m2");
  fields.emplace_back("fracture_toughness_pa_sqrt_m", "-7.5e5");
  expectError(loadMaterialFile(writeFields(fields)), ErrorCode::InvalidMaterial, "fracture_toughness_pa_sqrt_m");
}

TEST(MaterialFile, RepositoryExamplesLoadAsDocumented) {
  const auto dir = testing::sourceDir() / "assets" / "materials";
  const auto good = loadMaterialFile(dir / "example-custom-glass.json");
  ASSERT_TRUE(good.ok()) << good.error().message;
  EXPECT_FALSE(good.value().source.empty());
  expectError(loadMaterialFile(dir / "invalid-negative-modulus.json"), ErrorCode::InvalidMaterial,
              "youngs_modulus_pa");
}

}  // namespace
}  // namespace brittle

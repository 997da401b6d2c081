#include "brittle/precompute/Calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <numbers>
#include <random>

#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

// A bar with an oblong section: its lowest modes mix bending in two planes, torsion and
// stretching, so the frequency ratios pin ν.
TetMesh bar() { return testing::makeBoxTetMesh(0.40, 0.10, 0.06, 8, 2, 2); }

double volume(double sx, double sy, double sz) { return sx * sy * sz; }

// The "real" material the measurements come from, and the nominal one the user starts from.
Material truth() {
  Material m = materialPreset("glass").value();
  m.name = "measured-glass";
  m.youngsModulusPa = 52e9;
  m.poissonRatio = 0.27;
  m.densityKgPerM3 = 2300.0;
  m.rayleighAlphaPerS = 30.0;
  m.rayleighBetaS = 2e-7;
  return m;
}

// Standard normal deviates from the portable mt19937_64 stream (Box-Muller), so the noise is the
// same on every standard library.
std::vector<double> normals(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto uniform = [&] { return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53; };
  std::vector<double> out;
  while (out.size() < n) {
    const double r = std::sqrt(-2.0 * std::log(uniform())), t = 2.0 * std::numbers::pi * uniform();
    out.push_back(r * std::cos(t));
    out.push_back(r * std::sin(t));
  }
  out.resize(n);
  return out;
}

// Exact tap-test measurements of `m`: frequencies, decay rates (α + βω²)/2 and the mass.
CalibrationMeasurements measure(const TetMesh& mesh, const Material& m, int count) {
  CalibrationMeasurements out;
  out.frequenciesHz = naturalFrequenciesHz(mesh, m, count).value();
  for (double f : out.frequenciesHz) {
    const double omega = 2.0 * std::numbers::pi * f;
    out.decayRatesPerS.push_back(0.5 * (m.rayleighAlphaPerS + m.rayleighBetaS * omega * omega));
  }
  out.massKg = m.densityKgPerM3 * volume(0.40, 0.10, 0.06);
  return out;
}

// Relative Gaussian noise on each frequency and decay rate; frequencies re-sorted.
CalibrationMeasurements addNoise(CalibrationMeasurements m, double frequencyNoise, double rateNoise, uint64_t seed) {
  const size_t n = m.frequenciesHz.size();
  const std::vector<double> noise = normals(2 * n, seed);
  for (size_t i = 0; i < n; ++i) {
    m.frequenciesHz[i] *= 1.0 + frequencyNoise * noise[i];
    m.decayRatesPerS[i] *= 1.0 + rateNoise * noise[n + i];
  }
  std::sort(m.frequenciesHz.begin(), m.frequenciesHz.end());
  return m;
}

TEST(Calibration, ExactMeasurementsGiveTheTrueMaterialBack) {
  const TetMesh mesh = bar();
  const CalibrationMeasurements measured = measure(mesh, truth(), 8);
  const auto fit = calibrateMaterial(mesh, materialPreset("glass").value(), measured, CalibrationSettings{});
  ASSERT_TRUE(fit.ok()) << fit.error().message;
  const CalibrationResult& r = fit.value();
  EXPECT_NEAR(r.material.densityKgPerM3, 2300.0, 1e-9);
  EXPECT_NEAR(r.material.youngsModulusPa / 52e9, 1.0, 1e-7);
  EXPECT_NEAR(r.material.poissonRatio, 0.27, 1e-7);
  EXPECT_NEAR(r.material.rayleighAlphaPerS, 30.0, 1e-6);
  EXPECT_NEAR(r.material.rayleighBetaS / 2e-7, 1.0, 1e-8);
  EXPECT_LT(r.rmsFrequencyError, 1e-9);
  EXPECT_LT(r.rmsDecayRateError, 1e-9);
  EXPECT_FALSE(r.poissonAtBound);
  ASSERT_EQ(r.modelFrequenciesHz.size(), 8u);
  // What is not measured stays the base material's.
  EXPECT_EQ(r.material.tensileStrengthPa, materialPreset("glass").value().tensileStrengthPa);
  EXPECT_EQ(r.material.fractureEnergyJPerM2, materialPreset("glass").value().fractureEnergyJPerM2);
  EXPECT_LE(r.modalSolves, 25);
  EXPECT_EQ(validateMaterial(r.material).ok(), true);
}

// A P2 object is fitted with P2 tets. A thin plate's P1 tets lock in bending: their frequencies
// are far above the P2 ones on the same mesh, so a P1 fit of a P2 plate's measurements returns an
// E that is far too low, the locking absorbed into the material.
TEST(Calibration, AQuadraticObjectIsFittedWithItsOwnElements) {
  const TetMesh plate = testing::makeBoxTetMesh(0.20, 0.20, 0.01, 6, 6, 1);
  CalibrationMeasurements measured;
  measured.frequenciesHz = naturalFrequenciesHz(plate, truth(), 4, 1, ElementOrder::P2).value();
  const std::vector<double> linearHz = naturalFrequenciesHz(plate, truth(), 4, 1, ElementOrder::P1).value();
  EXPECT_GT(linearHz[0], 1.3 * measured.frequenciesHz[0]);  // the locking this test is about
  CalibrationSettings settings;
  settings.fitPoissonRatio = false;
  Material base = materialPreset("glass").value();
  base.poissonRatio = 0.27;
  base.densityKgPerM3 = 2300.0;

  settings.elementOrder = ElementOrder::P2;
  const auto quadratic = calibrateMaterial(plate, base, measured, settings);
  ASSERT_TRUE(quadratic.ok()) << quadratic.error().message;
  EXPECT_NEAR(quadratic.value().material.youngsModulusPa / 52e9, 1.0, 1e-7);
  EXPECT_LT(quadratic.value().rmsFrequencyError, 1e-9);

  settings.elementOrder = ElementOrder::P1;
  const auto linear = calibrateMaterial(plate, base, measured, settings);
  ASSERT_TRUE(linear.ok()) << linear.error().message;
  EXPECT_LT(linear.value().material.youngsModulusPa, 0.6 * 52e9);
}

TEST(Calibration, NoisyMeasurementsLandWithinTheirReportedUncertainty) {
  // 0.5 % frequency noise and 5 % decay-rate noise, as a careful tap test gives. Over several
  // noise draws the truth must lie within 4 reported σ, and σ must be honest (not huge).
  const TetMesh mesh = bar();
  const CalibrationMeasurements exact = measure(mesh, truth(), 8);
  for (uint64_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    const CalibrationMeasurements noisy = addNoise(exact, 0.005, 0.05, seed);
    const auto fit = calibrateMaterial(mesh, materialPreset("porcelain").value(), noisy, CalibrationSettings{});
    ASSERT_TRUE(fit.ok()) << fit.error().message;
    const CalibrationResult& r = fit.value();
    EXPECT_GT(r.youngsModulusStdPa, 0.0);
    EXPECT_LT(r.youngsModulusStdPa / 52e9, 0.03);
    EXPECT_LT(std::abs(r.material.youngsModulusPa - 52e9), 4.0 * r.youngsModulusStdPa);
    EXPECT_LT(std::abs(r.material.youngsModulusPa / 52e9 - 1.0), 0.03);
    EXPECT_GT(r.poissonRatioStd, 0.0);
    EXPECT_LT(std::abs(r.material.poissonRatio - 0.27), std::max(4.0 * r.poissonRatioStd, 1e-3));
    EXPECT_LT(std::abs(r.material.poissonRatio - 0.27), 0.05);
    EXPECT_LT(std::abs(r.material.rayleighBetaS / 2e-7 - 1.0), 0.15);
    EXPECT_LT(std::abs(r.material.rayleighBetaS - 2e-7), 4.0 * r.betaStdS);
    EXPECT_LT(r.rmsFrequencyError, 0.01);
  }
}

TEST(Calibration, FixedPoissonRatioNeedsOneFrequency) {
  const TetMesh mesh = bar();
  Material nominal = materialPreset("glass").value();
  nominal.poissonRatio = 0.27;
  CalibrationMeasurements measured = measure(mesh, truth(), 1);
  measured.decayRatesPerS.clear();
  measured.massKg = 0.0;  // density not measured: the base's is kept, so E/ρ is what is fitted
  CalibrationSettings settings;
  settings.fitPoissonRatio = false;
  const auto fit = calibrateMaterial(mesh, nominal, measured, settings);
  ASSERT_TRUE(fit.ok()) << fit.error().message;
  EXPECT_EQ(fit.value().material.poissonRatio, 0.27);
  EXPECT_EQ(fit.value().material.densityKgPerM3, nominal.densityKgPerM3);
  EXPECT_NEAR(fit.value().material.youngsModulusPa / (52e9 * nominal.densityKgPerM3 / 2300.0), 1.0, 1e-8);
  EXPECT_TRUE(std::isnan(fit.value().youngsModulusStdPa));  // one measurement, one unknown
  EXPECT_EQ(fit.value().material.rayleighAlphaPerS, nominal.rayleighAlphaPerS);
}

TEST(Calibration, OneDecayRateFitsStiffnessDampingAlone) {
  const TetMesh mesh = bar();
  Material stiffOnly = truth();
  stiffOnly.rayleighAlphaPerS = 0.0;
  CalibrationMeasurements measured = measure(mesh, stiffOnly, 1);
  CalibrationSettings settings;
  settings.fitPoissonRatio = false;
  Material nominal = materialPreset("glass").value();
  nominal.poissonRatio = 0.27;
  const auto fit = calibrateMaterial(mesh, nominal, measured, settings);
  ASSERT_TRUE(fit.ok()) << fit.error().message;
  EXPECT_EQ(fit.value().material.rayleighAlphaPerS, 0.0);
  EXPECT_NEAR(fit.value().material.rayleighBetaS / 2e-7, 1.0, 1e-8);
}

TEST(Calibration, PoissonRatioBeyondTheBoundsEndsOnTheBoundAndSaysSo) {
  const TetMesh mesh = bar();
  Material rubbery = truth();
  rubbery.poissonRatio = 0.42;
  CalibrationMeasurements measured = measure(mesh, rubbery, 8);
  CalibrationSettings settings;
  settings.poissonMax = 0.35;
  const auto fit = calibrateMaterial(mesh, materialPreset("glass").value(), measured, settings);
  ASSERT_TRUE(fit.ok()) << fit.error().message;
  EXPECT_TRUE(fit.value().poissonAtBound);
  EXPECT_NEAR(fit.value().material.poissonRatio, 0.35, 1e-9);
  EXPECT_GT(fit.value().rmsFrequencyError, 1e-4);  // the data cannot be met inside the bounds
}

TEST(Calibration, BadMeasurementsGiveTypedErrors) {
  const TetMesh mesh = bar();
  const Material glass = materialPreset("glass").value();
  const CalibrationMeasurements good = measure(mesh, truth(), 4);
  auto expectInvalid = [&](CalibrationMeasurements m, CalibrationSettings s, const std::string& text) {
    const auto r = calibrateMaterial(mesh, glass, m, s);
    ASSERT_FALSE(r.ok()) << text;
    EXPECT_EQ(r.error().code, ErrorCode::InvalidArgument) << r.error().message;
    EXPECT_NE(r.error().message.find(text), std::string::npos) << r.error().message;
  };
  CalibrationMeasurements m = good;
  m.frequenciesHz.resize(1);
  m.decayRatesPerS.resize(1);
  expectInvalid(m, {}, "at least 2");
  m = good;
  std::swap(m.frequenciesHz[0], m.frequenciesHz[1]);
  expectInvalid(m, {}, "ascending");
  m = good;
  m.frequenciesHz[2] = std::nan("");
  expectInvalid(m, {}, "frequency 2");
  m = good;
  m.decayRatesPerS.pop_back();
  expectInvalid(m, {}, "3 decay rates for 4");
  m = good;
  m.decayRatesPerS[0] = -1.0;
  expectInvalid(m, {}, "decay rate 0");
  m = good;
  m.massKg = -2.0;
  expectInvalid(m, {}, "mass");
  CalibrationSettings s;
  s.poissonMin = 0.3;
  s.poissonMax = 0.2;
  expectInvalid(good, s, "bounds");
  s = {};
  s.poissonMin = 0.25;
  expectInvalid(good, s, "outside the bounds");  // glass ν = 0.2
  s = {};
  s.modeCount = 2;
  expectInvalid(good, s, "modeCount");
  Material broken = glass;
  broken.youngsModulusPa = -1.0;
  EXPECT_EQ(calibrateMaterial(mesh, broken, good, {}).error().code, ErrorCode::InvalidMaterial);
}

TEST(Calibration, CancelledFromTheProgressSink) {
  struct Cancel final : ProgressSink {
    void report(std::string_view, double) override {}
    bool wasInterrupted() override { return true; }
  } cancel;
  const TetMesh mesh = bar();
  const auto r = calibrateMaterial(mesh, materialPreset("glass").value(), measure(mesh, truth(), 4), {}, &cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::Cancelled);
}

TEST(Calibration, CalibratedMaterialFileReadsBackEqual) {
  const auto dir = testing::makeTempDir("calibration");
  Material m = truth();
  m.youngsModulusPa = 5.123456789012345e10;
  m.source = "calibrated \"quoted\" source";
  ASSERT_TRUE(saveMaterialFile(m, dir / "m.json").ok());
  const auto back = loadMaterialFile(dir / "m.json");
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back.value(), m);
  Material bad = m;
  bad.poissonRatio = 0.7;
  EXPECT_EQ(saveMaterialFile(bad, dir / "bad.json").error().code, ErrorCode::InvalidMaterial);
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.json"));
  EXPECT_EQ(saveMaterialFile(m, dir / "missing" / "m.json").error().code, ErrorCode::PackIoError);
}

}  // namespace
}  // namespace brittle

#include "brittle/database/Material.h"

#include <cmath>

namespace brittle {
namespace {

Status checkField(const Material& m, const char* field, double value, bool ok, const char* rule) {
  if (!std::isfinite(value)) {
    return makeError(ErrorCode::InvalidMaterial,
                     "material '" + m.name + "': " + field + " is not finite");
  }
  if (!ok) {
    return makeError(ErrorCode::InvalidMaterial, "material '" + m.name + "': " + field + " = " +
                                                     std::to_string(value) + " (must be " + rule + ")");
  }
  return Ok{};
}

}  // namespace

Status validateMaterial(const Material& m) {
  if (m.name.empty()) return makeError(ErrorCode::InvalidMaterial, "material has an empty name");
  const struct {
    const char* field;
    double value;
    bool ok;
    const char* rule;
  } checks[] = {
      {"youngs_modulus_pa", m.youngsModulusPa, m.youngsModulusPa > 0.0, "> 0"},
      {"poisson_ratio", m.poissonRatio, m.poissonRatio > -1.0 && m.poissonRatio < 0.5,
       "in (-1, 0.5)"},
      {"density_kg_per_m3", m.densityKgPerM3, m.densityKgPerM3 > 0.0, "> 0"},
      {"tensile_strength_pa", m.tensileStrengthPa, m.tensileStrengthPa > 0.0, "> 0"},
      {"fracture_energy_j_per_m2", m.fractureEnergyJPerM2, m.fractureEnergyJPerM2 > 0.0, "> 0"},
      {"rayleigh_alpha_per_s", m.rayleighAlphaPerS, m.rayleighAlphaPerS >= 0.0, ">= 0"},
      {"rayleigh_beta_s", m.rayleighBetaS, m.rayleighBetaS >= 0.0, ">= 0"},
      {"restitution", m.restitution, m.restitution >= 0.0 && m.restitution <= 1.0, "in [0, 1]"},
  };
  for (const auto& c : checks) {
    Status s = checkField(m, c.field, c.value, c.ok, c.rule);
    if (!s) return s;
  }
  return Ok{};
}

double fractureEnergyFromToughness(double toughnessPaSqrtM, double youngsModulusPa,
                                   double poissonRatio) {
  return toughnessPaSqrtM * toughnessPaSqrtM * (1.0 - poissonRatio * poissonRatio) / youngsModulusPa;
}

double rayleighDampingRatio(const Material& m, double omegaRadPerS) {
  return 0.5 * (m.rayleighAlphaPerS / omegaRadPerS + m.rayleighBetaS * omegaRadPerS);
}

Eigen::Matrix<double, 6, 6> isotropicElasticity(double youngsModulusPa, double poissonRatio) {
  const double e = youngsModulusPa, nu = poissonRatio;
  const double lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  const double mu = e / (2.0 * (1.0 + nu));
  Eigen::Matrix<double, 6, 6> c = Eigen::Matrix<double, 6, 6>::Zero();
  c.topLeftCorner<3, 3>().setConstant(lambda);
  c.topLeftCorner<3, 3>().diagonal().array() += 2.0 * mu;
  c.bottomRightCorner<3, 3>().diagonal().setConstant(mu);
  return c;
}

}  // namespace brittle

// Material.h — an isotropic brittle material, in SI units, as stored in a pack.
#pragma once

#include <Eigen/Core>
#include <string>

#include "brittle/core/Result.h"

namespace brittle {

struct Material {
  std::string name;
  double youngsModulusPa = 0.0;        ///< E
  double poissonRatio = 0.0;           ///< ν, in (−1, 0.5)
  double densityKgPerM3 = 0.0;         ///< ρ
  double tensileStrengthPa = 0.0;      ///< σ_t, the Rankine threshold
  double fractureEnergyJPerM2 = 0.0;   ///< G_c (= K_Ic²(1−ν²)/E in plane strain)
  double rayleighAlphaPerS = 0.0;      ///< mass-proportional damping α (1/s)
  double rayleighBetaS = 0.0;          ///< stiffness-proportional damping β (s)
  double restitution = 0.0;            ///< coefficient of restitution in [0, 1]
  std::string source;                  ///< citation for the values

  bool operator==(const Material&) const = default;
};

/// Checks every value is finite and physical: E > 0, −1 < ν < 0.5, ρ > 0, σ_t > 0, G_c > 0,
/// α ≥ 0, β ≥ 0, 0 ≤ restitution ≤ 1, non-empty name. Error: InvalidMaterial naming the field.
Status validateMaterial(const Material& material);

/// G_c from a plane-strain fracture toughness K_Ic (Pa·√m): G_c = K_Ic²(1−ν²)/E.
double fractureEnergyFromToughness(double toughnessPaSqrtM, double youngsModulusPa,
                                   double poissonRatio);

/// 6 by 6 isotropic elasticity matrix C (Pa) in Voigt order (xx, yy, zz, yz, xz, xy) for
/// engineering shear strains: σ = C ε.
Eigen::Matrix<double, 6, 6> isotropicElasticity(double youngsModulusPa, double poissonRatio);

/// Modal damping ratio of Rayleigh damping at angular frequency ω: ζ = (α/ω + βω)/2.
double rayleighDampingRatio(const Material& material, double omegaRadPerS);

}  // namespace brittle

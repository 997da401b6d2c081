// HertzContact.h — the contact between an impactor and a body, after Hertz: effective mass,
// radius and modulus, contact duration, peak force, and the force pulse the modal response is
// driven by.
//
//   1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂            effective modulus (Pa)
//   1/R* = 1/R₁ + 1/R₂                            effective radius (m); a flat body has R₂ = ∞
//   1/m* = 1/m₁ + 1/M + (r × n)ᵀ I⁻¹ (r × n)       effective mass (kg): the body's mass M and its
//                                                  rotational inertia I (world axes, about the
//                                                  centre of mass) seen at the contact point r
//   δ_max = (15 m* v² / (16 E* √R*))^(2/5)         largest indentation (m)
//   F_max = 4/3 E* √R* δ_max^(3/2)                 peak force (N)
//   t_c   = 2.87 (m*² / (R* E*² v))^(1/5)          contact duration (s)
//   a     = √(R* δ_max)                            contact patch radius (m)
// (K. L. Johnson, Contact Mechanics, 1985, §11.4.) The indentation is close to a half sine, so
// the pulse is F(t) = F₀ sin^(3/2)(π t / t_c) on [0, t_c]. Its amplitude F₀ is set so that the
// impulse ∫F dt equals the host's impulse: (1 + e) m* v by default (e the restitution), which for
// e = 1 puts F₀ within 2.3 % of Hertz's F_max.
#pragma once

#include <Eigen/Core>
#include <limits>

#include "brittle/core/Result.h"

namespace brittle {

struct HertzInput {
  double impactorMassKg = 1.0;          ///< > 0; +∞ for an immovable impactor (the ground)
  double impactorRadiusM = 0.01;        ///< > 0; +∞ for a flat impactor
  double impactorYoungsModulusPa = 210e9;
  double impactorPoissonRatio = 0.3;
  double bodyMassKg = 1.0;
  Eigen::Matrix3d bodyInertiaKgM2 = Eigen::Matrix3d::Identity();  ///< world axes, about the centre of mass
  Eigen::Vector3d contactOffsetM = Eigen::Vector3d::Zero();       ///< contact point − centre of mass (world)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();              ///< unit, the body's outward normal
  double bodyRadiusM = std::numeric_limits<double>::infinity();   ///< local radius of curvature; ∞: flat
  double bodyYoungsModulusPa = 70e9;
  double bodyPoissonRatio = 0.2;
  double speedMps = 1.0;                ///< normal approach speed, > 0
  /// The impulse the host resolved (N·s); ≤ 0: (1 + restitution) m* v.
  double impulseNs = 0.0;
  double restitution = 1.0;             ///< in [0, 1], used when impulseNs ≤ 0
};

struct HertzContact {
  double effectiveMassKg = 0.0;
  double effectiveRadiusM = 0.0;
  double effectiveModulusPa = 0.0;
  double maxIndentationM = 0.0;
  double hertzPeakForceN = 0.0;   ///< F_max of Hertz theory (elastic)
  double durationS = 0.0;         ///< t_c
  double patchRadiusM = 0.0;      ///< a
  double impulseNs = 0.0;         ///< ∫F dt of the pulse (= the host's impulse)
  double pulseAmplitudeN = 0.0;   ///< F₀: the pulse's peak
};

/// Hertz contact of one impact. Errors: InvalidArgument naming the field (non-finite or
/// non-positive masses, radii, moduli, speed; Poisson ratios outside (−1, 0.5); a non-unit normal;
/// a flat body hit by a flat impactor; restitution outside [0, 1]).
Result<HertzContact> computeHertzContact(const HertzInput& input);

/// The pulse F(t) = F₀ sin^(3/2)(π t / t_c) for t in [0, t_c], 0 outside (N).
double hertzPulseForceN(const HertzContact& contact, double timeS);

/// ∫₀^π sin^(3/2)(x) dx / π: the pulse's impulse is this × F₀ × t_c.
inline constexpr double kHertzPulseShapeIntegral = 0.5564178944;

}  // namespace brittle

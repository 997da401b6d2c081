#include "brittle/runtime/HertzContact.h"

#include <Eigen/Geometry>
#include <Eigen/Dense>
#include <cmath>
#include <numbers>

namespace brittle {
namespace {

Error badImpact(const std::string& field, const std::string& why) {
  return makeError(ErrorCode::InvalidArgument, "impact: " + field + " " + why);
}

bool positiveOrInfinite(double x) { return x > 0.0 && !std::isnan(x); }
bool positiveFinite(double x) { return x > 0.0 && std::isfinite(x); }

}  // namespace

Result<HertzContact> computeHertzContact(const HertzInput& in) {
  if (!positiveOrInfinite(in.impactorMassKg)) return badImpact("impactor mass", "must be > 0 (or +inf)");
  if (!positiveOrInfinite(in.impactorRadiusM)) return badImpact("impactor radius", "must be > 0 (or +inf)");
  if (!positiveOrInfinite(in.bodyRadiusM)) return badImpact("body radius of curvature", "must be > 0 (or +inf)");
  if (std::isinf(in.impactorRadiusM) && std::isinf(in.bodyRadiusM)) {
    return badImpact("radii", "are both infinite: a flat body hit by a flat impactor has no Hertz contact");
  }
  if (!positiveFinite(in.impactorYoungsModulusPa)) return badImpact("impactor Young's modulus", "must be finite and > 0");
  if (!positiveFinite(in.bodyYoungsModulusPa)) return badImpact("body Young's modulus", "must be finite and > 0");
  for (double nu : {in.impactorPoissonRatio, in.bodyPoissonRatio}) {
    if (!(nu > -1.0 && nu < 0.5)) return badImpact("Poisson ratio", "must be in (-1, 0.5)");
  }
  if (!positiveFinite(in.bodyMassKg)) return badImpact("body mass", "must be finite and > 0");
  if (!in.bodyInertiaKgM2.allFinite()) return badImpact("body inertia", "is not finite");
  if (!in.contactOffsetM.allFinite()) return badImpact("contact point", "is not finite");
  if (!in.normal.allFinite() || std::abs(in.normal.norm() - 1.0) > 1e-6) return badImpact("normal", "must be a unit vector");
  if (!positiveFinite(in.speedMps)) return badImpact("speed", "must be finite and > 0");
  if (!std::isfinite(in.impulseNs)) return badImpact("impulse", "is not finite");
  if (!(in.restitution >= 0.0 && in.restitution <= 1.0)) return badImpact("restitution", "must be in [0, 1]");

  HertzContact c;
  c.effectiveModulusPa = 1.0 / ((1.0 - in.impactorPoissonRatio * in.impactorPoissonRatio) / in.impactorYoungsModulusPa +
                                (1.0 - in.bodyPoissonRatio * in.bodyPoissonRatio) / in.bodyYoungsModulusPa);
  c.effectiveRadiusM = 1.0 / (1.0 / in.impactorRadiusM + 1.0 / in.bodyRadiusM);  // 1/∞ = 0
  // The body's effective mass at the point along the normal: a unit impulse n at r changes the
  // point's normal velocity by 1/M + (r × n)ᵀ I⁻¹ (r × n).
  const Eigen::Vector3d rn = in.contactOffsetM.cross(in.normal);
  const Eigen::LDLT<Eigen::Matrix3d> inertia(in.bodyInertiaKgM2);
  double bodyCompliance = 1.0 / in.bodyMassKg;
  if (rn.squaredNorm() > 0.0) {
    if (inertia.info() != Eigen::Success || !inertia.isPositive()) return badImpact("body inertia", "is not positive definite");
    bodyCompliance += rn.dot(inertia.solve(rn));
  }
  c.effectiveMassKg = 1.0 / (1.0 / in.impactorMassKg + bodyCompliance);

  const double v = in.speedMps, m = c.effectiveMassKg, r = c.effectiveRadiusM, e = c.effectiveModulusPa;
  c.maxIndentationM = std::pow(15.0 * m * v * v / (16.0 * e * std::sqrt(r)), 0.4);
  c.hertzPeakForceN = 4.0 / 3.0 * e * std::sqrt(r) * std::pow(c.maxIndentationM, 1.5);
  c.durationS = 2.87 * std::pow(m * m / (r * e * e * v), 0.2);
  c.patchRadiusM = std::sqrt(r * c.maxIndentationM);
  c.impulseNs = in.impulseNs > 0.0 ? in.impulseNs : (1.0 + in.restitution) * m * v;
  c.pulseAmplitudeN = c.impulseNs / (kHertzPulseShapeIntegral * c.durationS);
  if (!std::isfinite(c.durationS) || !std::isfinite(c.pulseAmplitudeN) || !(c.durationS > 0.0)) {
    return badImpact("values", "give a non-finite contact (extreme masses, radii or speed)");
  }
  return c;
}

double hertzPulseForceN(const HertzContact& c, double t) {
  if (!(t > 0.0) || !(t < c.durationS)) return 0.0;
  const double s = std::sin(std::numbers::pi * t / c.durationS);
  return c.pulseAmplitudeN * s * std::sqrt(s);
}

}  // namespace brittle

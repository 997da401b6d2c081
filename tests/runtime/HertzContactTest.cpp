#include "brittle/runtime/HertzContact.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace brittle {
namespace {

// A steel ball (20 mm radius, 0.1 kg) at 5 m/s on a large, heavy glass block.
HertzInput ballOnBlock() {
  HertzInput in;
  in.impactorMassKg = 0.1;
  in.impactorRadiusM = 0.02;
  in.bodyMassKg = 1e9;
  in.bodyInertiaKgM2 = 1e9 * Eigen::Matrix3d::Identity();
  in.bodyYoungsModulusPa = 70e9;
  in.bodyPoissonRatio = 0.2;
  in.speedMps = 5.0;
  in.restitution = 1.0;
  return in;
}

TEST(HertzContact, SphereOnAFlatHeavyBodyMatchesTheAnalyticFormulas) {
  const HertzInput in = ballOnBlock();
  auto c = computeHertzContact(in);
  ASSERT_TRUE(c) << c.error().message;
  const double eStar = 1.0 / ((1 - 0.09) / 210e9 + (1 - 0.04) / 70e9);
  EXPECT_NEAR(c.value().effectiveModulusPa, eStar, 1e-9 * eStar);
  EXPECT_NEAR(c.value().effectiveRadiusM, 0.02, 1e-15);
  EXPECT_NEAR(c.value().effectiveMassKg, 0.1, 1e-9);  // the block weighs 1e9 kg: 1e-10 relative
  // Johnson (1985) §11.4 in closed form for these numbers.
  const double m = c.value().effectiveMassKg, r = 0.02, v = 5.0;
  const double delta = std::pow(15.0 * m * v * v / (16.0 * eStar * std::sqrt(r)), 0.4);
  const double fMax = 4.0 / 3.0 * eStar * std::sqrt(r) * std::pow(delta, 1.5);
  const double tc = 2.87 * std::pow(m * m / (r * eStar * eStar * v), 0.2);
  EXPECT_NEAR(c.value().maxIndentationM, delta, 1e-12 * delta);
  EXPECT_NEAR(c.value().hertzPeakForceN, fMax, 1e-9 * fMax);
  EXPECT_NEAR(c.value().durationS, tc, 1e-12 * tc);
  EXPECT_NEAR(c.value().patchRadiusM, std::sqrt(r * delta), 1e-12);
  // Orders of magnitude a reader can check: ~90 µs, 0.16 mm.
  EXPECT_GT(tc, 60e-6);
  EXPECT_LT(tc, 120e-6);
  // Elastic: the pulse carries 2 m v, and its peak is within 2.5 % of Hertz's F_max.
  EXPECT_NEAR(c.value().impulseNs, 2.0 * m * v, 1e-12);
  EXPECT_NEAR(m, 0.1, 1e-9);
  EXPECT_NEAR(c.value().pulseAmplitudeN / fMax, 1.0, 0.025);
}

TEST(HertzContact, PulseIntegratesToTheHostImpulse) {
  HertzInput in = ballOnBlock();
  in.restitution = 0.4;
  auto c = computeHertzContact(in);
  ASSERT_TRUE(c);
  const int n = 20000;
  double impulse = 0.0;
  for (int i = 0; i < n; ++i) impulse += hertzPulseForceN(c.value(), (i + 0.5) * c.value().durationS / n) * c.value().durationS / n;
  EXPECT_NEAR(impulse, 1.4 * 0.1 * 5.0, 1e-5);
  EXPECT_EQ(hertzPulseForceN(c.value(), -1e-9), 0.0);
  EXPECT_EQ(hertzPulseForceN(c.value(), c.value().durationS * 1.01), 0.0);
  in.impulseNs = 0.3;  // the host's own impulse wins
  auto h = computeHertzContact(in);
  ASSERT_TRUE(h);
  EXPECT_NEAR(h.value().pulseAmplitudeN * kHertzPulseShapeIntegral * h.value().durationS, 0.3, 1e-12);
}

TEST(HertzContact, EffectiveMassIncludesRotationalInertiaAtThePoint) {
  // A free rod of mass M, length L hit at its end, perpendicular: 1/m_b = 1/M + (L/2)²/(M L²/12) = 4/M.
  HertzInput in = ballOnBlock();
  const double mass = 2.0, length = 1.0;
  in.impactorMassKg = std::numeric_limits<double>::infinity();
  in.bodyMassKg = mass;
  in.bodyInertiaKgM2 = Eigen::Vector3d(mass * length * length / 12, mass * length * length / 12, 1e-3).asDiagonal();
  in.contactOffsetM = Eigen::Vector3d(0, 0, length / 2);
  in.normal = Eigen::Vector3d::UnitX();
  auto end = computeHertzContact(in);
  ASSERT_TRUE(end);
  EXPECT_NEAR(end.value().effectiveMassKg, mass / 4.0, 1e-12);
  in.contactOffsetM.setZero();  // at the centre: the whole mass
  auto centre = computeHertzContact(in);
  ASSERT_TRUE(centre);
  EXPECT_NEAR(centre.value().effectiveMassKg, mass, 1e-12);
  EXPECT_GT(end.value().durationS, 0.0);
  EXPECT_LT(end.value().durationS, centre.value().durationS);  // a lighter effective mass rebounds sooner
}

TEST(HertzContact, ScalingWithSpeedFollowsTheory) {
  HertzInput in = ballOnBlock();
  auto slow = computeHertzContact(in);
  in.speedMps *= 32.0;
  auto fast = computeHertzContact(in);
  ASSERT_TRUE(slow && fast);
  EXPECT_NEAR(slow.value().durationS / fast.value().durationS, 2.0, 1e-12);             // t_c ∝ v^(−1/5)
  EXPECT_NEAR(fast.value().hertzPeakForceN / slow.value().hertzPeakForceN, 64.0, 1e-9);  // F ∝ v^(6/5)
}

TEST(HertzContact, BadInputsGiveTypedErrors) {
  auto expectBad = [](HertzInput in, const char* what) {
    auto c = computeHertzContact(in);
    ASSERT_FALSE(c) << what;
    EXPECT_EQ(c.error().code, ErrorCode::InvalidArgument) << what;
  };
  HertzInput in = ballOnBlock();
  in.speedMps = std::nan("");
  expectBad(in, "NaN speed");
  in = ballOnBlock();
  in.speedMps = 0.0;
  expectBad(in, "zero speed");
  in = ballOnBlock();
  in.impactorRadiusM = std::numeric_limits<double>::infinity();
  expectBad(in, "flat on flat");
  in = ballOnBlock();
  in.normal = Eigen::Vector3d(0, 0, 2);
  expectBad(in, "non-unit normal");
  in = ballOnBlock();
  in.bodyPoissonRatio = 0.5;
  expectBad(in, "incompressible");
  in = ballOnBlock();
  in.restitution = 1.5;
  expectBad(in, "restitution");
  in = ballOnBlock();
  in.impactorMassKg = -1;
  expectBad(in, "negative mass");
}

}  // namespace
}  // namespace brittle

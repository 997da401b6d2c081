#include "brittle/descriptors/MomentDescriptor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "DescriptorTestShapes.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

int component(int p, int q, int r, int maxOrder = 4) {
  const auto layout = momentDescriptorLayout(maxOrder);
  return static_cast<int>(std::find(layout.begin(), layout.end(), std::array{p, q, r}) - layout.begin());
}

Descriptor primaryDescriptor(const TriangleMesh& mesh, const MomentDescriptorSettings& settings = {}) {
  const auto frames = computeCanonicalFrames(mesh);
  EXPECT_TRUE(frames.ok());
  const auto d = computeMomentDescriptor(mesh, frames.value().candidates.front(), settings);
  EXPECT_TRUE(d.ok());
  return d.value();
}

TEST(MomentDescriptor, LayoutSkipsTheFixedMoments) {
  EXPECT_EQ(momentDescriptorSize(2), 3);
  EXPECT_EQ(momentDescriptorSize(4), 28);
  EXPECT_EQ(static_cast<int>(momentDescriptorLayout(5).size()), momentDescriptorSize(5));
  EXPECT_EQ(component(2, 0, 0), 0);
  EXPECT_EQ(component(3, 0, 0), 3);
  EXPECT_EQ(component(0, 0, 4), 27);
}

TEST(MomentDescriptor, BoxAndCubeMatchClosedForm) {
  // Unit-volume box with sides a' ≤ b' ≤ c' (a'b'c' = 1) centred on the origin:
  // m200 = a'²/12, m400 = a'⁴/80, m220 = a'²b'²/144, every odd moment 0.
  for (const Eigen::Vector3d& sides : {Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(3.0, 0.5, 1.4)}) {
    const auto d = primaryDescriptor(testing::makeBoxSurface(sides.x(), sides.y(), sides.z()));
    Eigen::Vector3d c = sides / std::cbrt(sides.prod());
    std::sort(c.data(), c.data() + 3);
    EXPECT_NEAR(d[component(2, 0, 0)], c[0] * c[0] / 12, 1e-6);
    EXPECT_NEAR(d[component(0, 2, 0)], c[1] * c[1] / 12, 1e-6);
    EXPECT_NEAR(d[component(0, 0, 2)], c[2] * c[2] / 12, 1e-6);
    EXPECT_NEAR(d[component(4, 0, 0)], std::pow(c[0], 4) / 80, 1e-6);
    EXPECT_NEAR(d[component(0, 4, 0)], std::pow(c[1], 4) / 80, 1e-6);
    EXPECT_NEAR(d[component(0, 0, 4)], std::pow(c[2], 4) / 80, 1e-6);
    EXPECT_NEAR(d[component(2, 2, 0)], c[0] * c[0] * c[1] * c[1] / 144, 1e-6);
    EXPECT_NEAR(d[component(0, 2, 2)], c[1] * c[1] * c[2] * c[2] / 144, 1e-6);
    EXPECT_NEAR(d[component(3, 0, 0)], 0.0, 1e-6);
    EXPECT_NEAR(d[component(1, 1, 1)], 0.0, 1e-6);
    EXPECT_NEAR(d[component(3, 1, 0)], 0.0, 1e-6);
  }
}

TEST(MomentDescriptor, SphereMatchesClosedFormWithinFaceting) {
  // Unit-volume ball, R = (3/4π)^{1/3}: m200 = 4πR⁵/15, m400 = 4πR⁷/35, m220 = 4πR⁷/105.
  const double pi = std::numbers::pi, r = std::cbrt(3.0 / (4.0 * pi));
  const auto d = primaryDescriptor(testing::makeIcosphere(1.0, 4));
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(d[a] / (4 * pi * std::pow(r, 5) / 15), 1.0, 3e-3);
  EXPECT_NEAR(d[component(4, 0, 0)] / (4 * pi * std::pow(r, 7) / 35), 1.0, 5e-3);
  EXPECT_NEAR(d[component(0, 2, 2)] / (4 * pi * std::pow(r, 7) / 105), 1.0, 5e-3);
  EXPECT_NEAR(d[component(2, 1, 0)], 0.0, 1e-6);
}

TEST(MomentDescriptor, InvariantToSimilarityAndRemeshing) {
  // Float32 output: invariance holds to ~1e-6 absolute on values of order 0.1.
  const auto solid = testing::makeIrregularSolid();
  MomentDescriptorSettings settings;
  settings.maxOrder = 6;
  const auto reference = primaryDescriptor(solid, settings);
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const auto d = primaryDescriptor(testing::transformed(solid, testing::randomSimilarity(seed)), settings);
    EXPECT_LT(momentDistance(d, reference), 1e-5f) << seed;
  }
  const auto fine = primaryDescriptor(subdivideMidpoints(subdivideMidpoints(solid)), settings);
  EXPECT_LT(momentDistance(fine, reference), 1e-6f);
  // A different solid is far away by comparison.
  const auto other = primaryDescriptor(testing::makeBoxSurface(1.0, 2.0, 3.0), settings);
  EXPECT_GT(momentDistance(other, reference), 1e-2f);
}

TEST(MomentDescriptor, CandidateMatrixRowsMatchSingleFrames) {
  const auto prism = testing::makeBoxSurface(1.0, 1.0, 2.0);
  const auto frames = computeCanonicalFrames(prism);
  ASSERT_TRUE(frames.ok());
  const auto all = computeMomentDescriptors(prism, frames.value());
  ASSERT_TRUE(all.ok());
  ASSERT_EQ(all.value().rows(), static_cast<Eigen::Index>(frames.value().candidates.size()));
  for (Eigen::Index c = 0; c < all.value().rows(); ++c) {
    const auto one = computeMomentDescriptor(prism, frames.value().candidates[c]);
    ASSERT_TRUE(one.ok());
    EXPECT_LT((all.value().row(c).transpose() - one.value()).norm(), 1e-6f);
  }
}

TEST(MomentDescriptor, FromFramesEqualsMeshPass) {
  const auto solid = testing::makeIrregularSolid();
  const auto frames = computeCanonicalFrames(solid);
  ASSERT_TRUE(frames.ok());
  const auto stored = momentDescriptorsFromFrames(frames.value());
  const auto direct = computeMomentDescriptors(solid, frames.value());
  ASSERT_TRUE(stored.ok() && direct.ok());
  EXPECT_LT((stored.value() - direct.value()).cwiseAbs().maxCoeff(), 1e-6f);
  MomentDescriptorSettings high;
  high.maxOrder = 5;
  EXPECT_EQ(momentDescriptorsFromFrames(frames.value(), high).error().code, ErrorCode::InvalidArgument);
}

TEST(MomentDescriptor, OrderWeightsScaleComponents) {
  const auto solid = testing::makeIrregularSolid();
  const auto plain = primaryDescriptor(solid);
  MomentDescriptorSettings weighted;
  weighted.orderWeights = {0.0, 0.0, 1.0, 4.0, 0.0};
  const auto d = primaryDescriptor(solid, weighted);
  EXPECT_FLOAT_EQ(d[component(2, 0, 0)], plain[component(2, 0, 0)]);
  EXPECT_FLOAT_EQ(d[component(2, 1, 0)], 2.0f * plain[component(2, 1, 0)]);
  EXPECT_EQ(d[component(2, 2, 0)], 0.0f);
}

TEST(MomentDescriptor, TypedErrors) {
  const auto box = testing::makeBoxSurface(1, 2, 3);
  const auto frame = computeCanonicalFrames(box).value().candidates.front();
  MomentDescriptorSettings s;
  s.maxOrder = 1;
  EXPECT_EQ(computeMomentDescriptor(box, frame, s).error().code, ErrorCode::InvalidArgument);
  s.maxOrder = 4;
  s.orderWeights = {1.0, 1.0};
  EXPECT_EQ(computeMomentDescriptor(box, frame, s).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(computeMomentDescriptor(TriangleMesh{}, frame).error().code, ErrorCode::EmptyMesh);
  auto nan = box;
  nan.vertices(3, 2) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(computeMomentDescriptor(nan, frame).error().code, ErrorCode::NonFiniteValue);
  auto open = box;
  open.faces.conservativeResize(11, 3);
  EXPECT_EQ(computeMomentDescriptor(open, frame).error().code, ErrorCode::OpenMesh);
  CanonicalFrame broken = frame;
  broken.scalePerM = 0.0;
  EXPECT_EQ(computeMomentDescriptor(box, broken).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(computeMomentDescriptors(box, CanonicalFrames{}).error().code, ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace brittle

#include "brittle/descriptors/CanonicalFrame.h"

#include <gtest/gtest.h>

#include <cmath>

#include "DescriptorTestShapes.h"
#include "brittle/descriptors/MomentDescriptor.h"
#include "brittle/descriptors/VolumeMoments.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

VolumeMoments canonicalMoments(const TriangleMesh& mesh, const CanonicalFrame& frame, int order) {
  auto raw = computeVolumeMoments(mesh, order, frame.translationM);
  EXPECT_TRUE(raw.ok());
  return transformVolumeMoments(raw.value(), frame.scalePerM * frame.rotation);
}

// Smallest moment-descriptor distance between any candidate of `query` and the first frame of
// `reference` — what a search over candidates sees.
double bestCandidateDistance(const TriangleMesh& reference, const TriangleMesh& query) {
  const auto ref = computeCanonicalFrames(reference);
  const auto qry = computeCanonicalFrames(query);
  EXPECT_TRUE(ref.ok() && qry.ok());
  const auto r = computeMomentDescriptor(reference, ref.value().candidates.front());
  const auto q = computeMomentDescriptors(query, qry.value());
  EXPECT_TRUE(r.ok() && q.ok());
  double best = 1e30;
  for (Eigen::Index c = 0; c < q.value().rows(); ++c) {
    best = std::min(best, static_cast<double>(momentDistance(q.value().row(c).transpose(), r.value())));
  }
  return best;
}

TEST(CanonicalFrame, FrameIsNormalisedPrincipalAndRightHanded) {
  const auto solid = testing::makeIrregularSolid();
  const auto frames = computeCanonicalFrames(solid);
  ASSERT_TRUE(frames.ok()) << frames.error().message;
  ASSERT_EQ(frames.value().candidates.size(), 1u);
  EXPECT_FALSE(frames.value().ambiguous());
  const auto& f = frames.value().candidates.front();
  EXPECT_NEAR(f.rotation.determinant(), 1.0, 1e-12);
  EXPECT_TRUE((f.rotation * f.rotation.transpose()).isIdentity(1e-12));
  const auto m = canonicalMoments(solid, f, 3);
  EXPECT_NEAR(m(0, 0, 0), 1.0, 1e-12);
  for (auto [p, q, r] : {std::array{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {1, 0, 1}, {0, 1, 1}}) {
    EXPECT_NEAR(m(p, q, r), 0.0, 1e-12);
  }
  EXPECT_LT(m(2, 0, 0), m(0, 2, 0));
  EXPECT_LT(m(0, 2, 0), m(0, 0, 2));
  EXPECT_NEAR(m(2, 0, 0), frames.value().principalSecondMoments[0], 1e-12);
  // Two signs are set by skewness, the third by handedness; all three are confidently non-zero.
  EXPECT_GT(m(3, 0, 0), 0.0);
  EXPECT_GT(m(0, 3, 0), 0.0);
  EXPECT_GT(std::abs(m(0, 0, 3)), 0.0);
}

TEST(CanonicalFrame, FramesFromGivenMomentsEqualThePassOverTheSurface) {
  // What the runtime does: moments summed elsewhere (here about an arbitrary origin, order 5),
  // moved to the surface's box centre. Same candidates up to rounding; too low an order is refused.
  // (Only for a shape whose frame is well defined: where a symmetry leaves an axis or its sign to
  // rounding, a box say, the two forms may keep different but equivalent candidates.)
  const TriangleMesh solid = testing::makeIrregularSolid();
  const auto fromSurface = computeCanonicalFrames(solid);
  ASSERT_TRUE(fromSurface.ok()) << fromSurface.error().message;
  const Eigen::Vector3d origin(0.3, -1.2, 0.7);
  const auto moments = computeVolumeMoments(solid, 5, origin);
  ASSERT_TRUE(moments.ok());
  const auto fromMoments = computeCanonicalFrames(solid, moments.value(), origin);
  ASSERT_TRUE(fromMoments.ok()) << fromMoments.error().message;
  ASSERT_EQ(fromMoments.value().candidates.size(), fromSurface.value().candidates.size());
  for (size_t c = 0; c < fromSurface.value().candidates.size(); ++c) {
    const CanonicalFrame &a = fromMoments.value().candidates[c], &b = fromSurface.value().candidates[c];
    EXPECT_LT((a.rotation - b.rotation).norm(), 1e-9) << c;
    EXPECT_LT((a.translationM - b.translationM).norm(), 1e-12) << c;
    EXPECT_NEAR(a.scalePerM, b.scalePerM, 1e-12 * b.scalePerM) << c;
  }
  EXPECT_LT((fromMoments.value().centralMoments.values - fromSurface.value().centralMoments.values).norm(),
            1e-12 * fromSurface.value().centralMoments.values.norm());
  const auto low = computeVolumeMoments(solid, 3, origin);
  EXPECT_EQ(computeCanonicalFrames(solid, low.value(), origin).error().code, ErrorCode::InvalidArgument);
}

TEST(CanonicalFrame, InvariantToSimilarityAndRemeshing) {
  const auto solid = testing::makeIrregularSolid();
  const auto base = computeCanonicalFrames(solid);
  ASSERT_TRUE(base.ok());
  const Points reference = base.value().candidates.front().pointsToCanonical(solid.vertices);
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const auto s = testing::randomSimilarity(seed);
    const auto moved = testing::transformed(solid, s);
    const auto frames = computeCanonicalFrames(moved);
    ASSERT_TRUE(frames.ok());
    ASSERT_EQ(frames.value().candidates.size(), 1u) << seed;
    // Vertex i lands on the same canonical point whatever the pose: the frame moved with the solid.
    const Points canonical = frames.value().candidates.front().pointsToCanonical(moved.vertices);
    EXPECT_LT((canonical - reference).cwiseAbs().maxCoeff(), 1e-9) << seed;
    EXPECT_NEAR(frames.value().volumeM3, base.value().volumeM3 * std::pow(s.scale, 3), 1e-10 * frames.value().volumeM3);
  }
  const auto fine = subdivideMidpoints(subdivideMidpoints(solid));
  const auto frames = computeCanonicalFrames(fine);
  ASSERT_TRUE(frames.ok());
  const Points canonical = frames.value().candidates.front().pointsToCanonical(Points(fine.vertices.topRows(8)));
  EXPECT_LT((canonical - reference).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(CanonicalFrame, IsoscelesWedgePointsTowardsItsApexWithHandCheckedSkewness) {
  // Cross-section: triangle (0,−h), (w,0), (0,h), extruded over z ∈ [−d, d]. Mirror-symmetric in y
  // and z, so those skewnesses vanish; along x the section width 2h(1 − x/w) is a triangular
  // distribution on [0, w] with its mode at 0. For w = 1: mean 1/3, variance 1/18, third central
  // moment E[x³] − E[x²] + E[x]/3 − 1/27 = 1/10 − 1/6 + 1/9 − 1/27 = 1/135, so the standardised
  // skewness is (1/135)·18^{3/2} = 2√2/5 ≈ 0.566 > 0: the +x canonical axis must point from the
  // base towards the apex.
  const double w = 3.0, h = 0.5, d = 0.8;
  Eigen::Matrix<double, Eigen::Dynamic, 2> section(3, 2);
  section << 0.0, -h, w, 0.0, 0.0, h;
  const auto wedge = testing::makePrism(section, -d, d);
  const auto frames = computeCanonicalFrames(wedge);
  ASSERT_TRUE(frames.ok()) << frames.error().message;
  const double expected = 2.0 * std::sqrt(2.0) / 5.0;
  // Var along x = w²/18 = 0.5 is the largest (y: h²/6, z: d²/3), so x is canonical axis 2.
  for (const auto& f : frames.value().candidates) {
    EXPECT_NEAR(f.rotation.row(2).dot(Eigen::Vector3d::UnitX()), 1.0, 1e-12);
  }
  EXPECT_NEAR(frames.value().skewness[2], expected, 1e-12);
  EXPECT_NEAR(frames.value().skewness[0], 0.0, 1e-12);
  EXPECT_NEAR(frames.value().skewness[1], 0.0, 1e-12);
  // y and z signs are free; handedness leaves two of the four patterns, both kept (the wedge's
  // mirror symmetries make them equal, so they collapse unless duplicates are kept).
  CanonicalFrameSettings keepAll;
  keepAll.duplicateTolerance = 0.0;
  const auto all = computeCanonicalFrames(wedge, keepAll);
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all.value().candidates.size(), 2u);
}

TEST(CanonicalFrame, CubeGivesSeveralCandidatesAndOneMatchesAnyPose) {
  const auto cube = testing::makeBoxSurface(2.0, 2.0, 2.0);
  const auto frames = computeCanonicalFrames(cube);
  ASSERT_TRUE(frames.ok());
  EXPECT_TRUE(frames.value().degenerateLowerPair && frames.value().degenerateUpperPair);
  EXPECT_GE(frames.value().candidates.size(), 2u);
  EXPECT_LE(frames.value().candidates.size(), 24u);
  for (const auto& f : frames.value().candidates) EXPECT_NEAR(f.rotation.determinant(), 1.0, 1e-12);
  for (unsigned seed = 1; seed <= 10; ++seed) {
    EXPECT_LT(bestCandidateDistance(cube, testing::transformed(cube, testing::randomSimilarity(seed))), 1e-6) << seed;
  }
}

TEST(CanonicalFrame, SquarePrismAndCylinderAreHandled) {
  const auto prism = testing::makeBoxSurface(1.0, 1.0, 2.5);
  const auto cylinder = testing::makeCylinder(0.5, 2.5, 48);
  for (const auto* mesh : {&prism, &cylinder}) {
    const auto frames = computeCanonicalFrames(*mesh);
    ASSERT_TRUE(frames.ok());
    EXPECT_TRUE(frames.value().degenerateLowerPair);
    EXPECT_FALSE(frames.value().degenerateUpperPair);
    CanonicalFrameSettings keepAll;
    keepAll.duplicateTolerance = 0.0;
    EXPECT_GE(computeCanonicalFrames(*mesh, keepAll).value().candidates.size(), 4u);
    for (unsigned seed = 1; seed <= 10; ++seed) {
      EXPECT_LT(bestCandidateDistance(*mesh, testing::transformed(*mesh, testing::randomSimilarity(seed))), 1e-6);
    }
  }
}

TEST(CanonicalFrame, SphereHasManyEquivalentFrames) {
  const auto sphere = testing::makeIcosphere(1.0, 3);
  CanonicalFrameSettings keepAll;
  keepAll.duplicateTolerance = 0.0;
  const auto all = computeCanonicalFrames(sphere, keepAll);
  ASSERT_TRUE(all.ok());
  EXPECT_TRUE(all.value().degenerateLowerPair && all.value().degenerateUpperPair);
  EXPECT_GE(all.value().candidates.size(), 4u);
  for (unsigned seed = 1; seed <= 5; ++seed) {
    EXPECT_LT(bestCandidateDistance(sphere, testing::transformed(sphere, testing::randomSimilarity(seed))), 1e-6);
  }
  // Remeshing changes the polyhedron itself; the level-3 and level-4 spheres differ by faceting.
  EXPECT_LT(bestCandidateDistance(testing::makeIcosphere(1.0, 4), sphere), 5e-3);
}

TEST(CanonicalFrame, RegularTetrahedronUsesThirdOrderMoments) {
  // Isotropic second moments, but ∫(u·x)³ peaks at the four vertex directions.
  const auto tet = testing::makeTetrahedron({1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1});
  const auto frames = computeCanonicalFrames(tet);
  ASSERT_TRUE(frames.ok());
  EXPECT_TRUE(frames.value().degenerateLowerPair && frames.value().degenerateUpperPair);
  for (unsigned seed = 1; seed <= 10; ++seed) {
    EXPECT_LT(bestCandidateDistance(tet, testing::transformed(tet, testing::randomSimilarity(seed))), 1e-6) << seed;
  }
}

TEST(CanonicalFrame, TypedErrors) {
  EXPECT_EQ(computeCanonicalFrames(TriangleMesh{}).error().code, ErrorCode::EmptyMesh);
  auto box = testing::makeBoxSurface(1, 2, 3);
  auto nan = box;
  nan.vertices(0, 0) = std::nan("");
  EXPECT_EQ(computeCanonicalFrames(nan).error().code, ErrorCode::NonFiniteValue);
  auto open = box;
  open.faces.conservativeResize(10, 3);
  EXPECT_EQ(computeCanonicalFrames(open).error().code, ErrorCode::OpenMesh);
  auto inward = box;
  inward.faces.col(1).swap(inward.faces.col(2));
  const auto inwardResult = computeCanonicalFrames(inward);
  ASSERT_FALSE(inwardResult.ok());
  EXPECT_EQ(inwardResult.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(inwardResult.error().message.find("negative volume"), std::string::npos);
  auto flat = box;
  flat.vertices.col(2).setZero();
  const auto flatResult = computeCanonicalFrames(flat);
  ASSERT_FALSE(flatResult.ok());
  EXPECT_EQ(flatResult.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(flatResult.error().message.find("zero volume"), std::string::npos);
  CanonicalFrameSettings bad;
  bad.eigenGapTolerance = std::nan("");
  EXPECT_EQ(computeCanonicalFrames(box, bad).error().code, ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace brittle

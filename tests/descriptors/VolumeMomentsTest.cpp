#include "brittle/descriptors/VolumeMoments.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <utility>
#include <numbers>
#include <random>
#include <vector>

#include "DescriptorTestShapes.h"
#include "MonomialTables.h"
#include "brittle/descriptors/MassProperties.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

double factorial(int n) { return n <= 1 ? 1.0 : n * factorial(n - 1); }

TEST(VolumeMoments, MonomialIndexRoundTrips) {
  EXPECT_EQ(monomialIndex(0, 0, 0), 0);
  EXPECT_EQ(monomialIndex(1, 0, 0), 1);
  EXPECT_EQ(monomialIndex(0, 0, 1), 3);
  EXPECT_EQ(monomialIndex(2, 0, 0), 4);
  EXPECT_EQ(monomialIndex(0, 0, 2), 9);
  for (int i = 0; i < monomialCount(kMaxMomentOrder); ++i) {
    const auto [p, q, r] = monomialExponents(i);
    EXPECT_EQ(monomialIndex(p, q, r), i);
  }
}

TEST(VolumeMoments, BoxMatchesClosedForm) {
  // ∫_box x^p y^q z^r = a^(p+1) b^(q+1) c^(r+1) / ((p+1)(q+1)(r+1)) for [0,a]×[0,b]×[0,c].
  const double a = 2.0, b = 0.7, c = 1.3;
  const auto m = computeVolumeMoments(testing::makeBoxSurface(a, b, c), 6, Eigen::Vector3d(0.4, -0.2, 0.9));
  ASSERT_TRUE(m.ok()) << m.error().message;
  // Moments about a shifted origin, brought back to x: y = x − o ⇒ x = I (y − (−o)).
  const auto x = transformVolumeMoments(m.value(), Eigen::Matrix3d::Identity(), -Eigen::Vector3d(0.4, -0.2, 0.9));
  for (int i = 0; i < monomialCount(6); ++i) {
    const auto [p, q, r] = monomialExponents(i);
    const double expected = std::pow(a, p + 1) * std::pow(b, q + 1) * std::pow(c, r + 1) / ((p + 1) * (q + 1) * (r + 1));
    EXPECT_NEAR(x.values[i], expected, 1e-12 * std::abs(expected) + 1e-13) << p << q << r;
  }
}

TEST(VolumeMoments, RightTetrahedronMatchesDirichletIntegral) {
  // T = (0, a e1, b e2, c e3): ∫ x^p y^q z^r = a^(p+1) b^(q+1) c^(r+1) p! q! r! / (p+q+r+3)!.
  const double a = 1.5, b = 0.8, c = 2.1;
  const auto tet = testing::makeTetrahedron({0, 0, 0}, {a, 0, 0}, {0, b, 0}, {0, 0, c});
  const auto m = computeVolumeMoments(tet, 5, Eigen::Vector3d::Zero());
  ASSERT_TRUE(m.ok());
  for (int i = 0; i < monomialCount(5); ++i) {
    const auto [p, q, r] = monomialExponents(i);
    const double expected = std::pow(a, p + 1) * std::pow(b, q + 1) * std::pow(c, r + 1) * factorial(p) *
                            factorial(q) * factorial(r) / factorial(p + q + r + 3);
    EXPECT_NEAR(m.value().values[i], expected, 1e-13 * std::abs(expected)) << p << q << r;
  }
}

TEST(VolumeMoments, TetMomentsEqualThoseOfItsSurface) {
  // A general tetrahedron off the origin: the four-vertex kernel (order 4 unrolled, order 6
  // generic) against the pass over its four faces, and its sign under a swap of two vertices.
  const Eigen::Vector3d a(0.31, -0.12, 0.05), b(1.4, 0.2, -0.3), c(0.2, 1.1, 0.4), d(0.5, 0.3, 1.7);
  const auto tet = testing::makeTetrahedron(a, b, c, d);
  for (int order : {4, 6}) {
    const auto fromFaces = computeVolumeMoments(tet, order, Eigen::Vector3d::Zero());
    ASSERT_TRUE(fromFaces.ok()) << fromFaces.error().message;
    std::vector<double> fromTet(monomialCount(order), 0.0), swapped(monomialCount(order), 0.0);
    addTetVolumeMoments(a, b, c, d, order, fromTet.data());
    addTetVolumeMoments(b, a, c, d, order, swapped.data());
    for (int m = 0; m < monomialCount(order); ++m) {
      const double expected = fromFaces.value().values[m];
      EXPECT_NEAR(fromTet[m], expected, 1e-13 * (1.0 + std::abs(expected))) << "order " << order << ", monomial " << m;
      EXPECT_NEAR(swapped[m], -fromTet[m], 1e-14 * (1.0 + std::abs(expected))) << m;
    }
  }
}

TEST(VolumeMoments, RightTetrahedronCentralThirdMomentIsHandChecked) {
  // Central third moment along x of T = (0, a e1, b e2, c e3), with x̄ = a/4:
  //   μ₃ = m300 − 3x̄ m200 + 3x̄² m100 − x̄³ V = a⁴bc (1/120 − 1/80 + 1/128 − 1/384) = a⁴bc/960 > 0:
  // the solid is thick at x = 0 and tapers towards the vertex a e1, so it skews towards +x.
  const double a = 1.5, b = 0.8, c = 2.1;
  const auto tet = testing::makeTetrahedron({0, 0, 0}, {a, 0, 0}, {0, b, 0}, {0, 0, c});
  const auto m = computeVolumeMoments(tet, 3, Eigen::Vector3d(a / 4, b / 4, c / 4));
  ASSERT_TRUE(m.ok());
  EXPECT_NEAR(m.value()(1, 0, 0), 0.0, 1e-15);
  EXPECT_NEAR(m.value()(3, 0, 0), std::pow(a, 4) * b * c / 960.0, 1e-15);
  EXPECT_NEAR(m.value().directional(Eigen::Vector3d::UnitX(), 3), std::pow(a, 4) * b * c / 960.0, 1e-15);
}

TEST(VolumeMoments, SphereMatchesClosedFormWithinFaceting) {
  // Ball of radius R: m200 = 4πR⁵/15, m400 = 4πR⁷/35, m220 = 4πR⁷/105; odd moments vanish.
  const double r = 0.7;
  const auto m = computeVolumeMoments(testing::makeIcosphere(r, 5), 4, Eigen::Vector3d::Zero());
  ASSERT_TRUE(m.ok());
  const double pi = std::numbers::pi;
  const auto& v = m.value();
  EXPECT_NEAR(v(0, 0, 0) / (4.0 / 3.0 * pi * std::pow(r, 3)), 1.0, 2e-3);
  for (auto [p, q, rr] : {std::array{2, 0, 0}, {0, 2, 0}, {0, 0, 2}}) {
    EXPECT_NEAR(v(p, q, rr) / (4 * pi * std::pow(r, 5) / 15), 1.0, 4e-3);
  }
  for (auto [p, q, rr] : {std::array{4, 0, 0}, {0, 4, 0}, {0, 0, 4}}) {
    EXPECT_NEAR(v(p, q, rr) / (4 * pi * std::pow(r, 7) / 35), 1.0, 6e-3);
  }
  EXPECT_NEAR(v(2, 2, 0) / (4 * pi * std::pow(r, 7) / 105), 1.0, 6e-3);
  for (auto [p, q, rr] : {std::array{3, 0, 0}, {1, 2, 0}, {1, 1, 1}, {2, 1, 0}}) EXPECT_NEAR(v(p, q, rr), 0.0, 1e-12);
}

TEST(VolumeMoments, AgreesWithMassProperties) {
  const auto solid = testing::makeIrregularSolid();
  const auto mp = computeSurfaceMassProperties(solid, 1.0);
  const auto m = computeVolumeMoments(solid, 2, mp.centerOfMassM);
  ASSERT_TRUE(m.ok());
  EXPECT_NEAR(m.value()(0, 0, 0), mp.volumeM3, 1e-14);
  EXPECT_NEAR(m.value()(1, 0, 0), 0.0, 1e-14);
  EXPECT_NEAR(m.value()(2, 0, 0), mp.secondMomentM5(0, 0), 1e-14);
  EXPECT_NEAR(m.value()(1, 1, 0), mp.secondMomentM5(0, 1), 1e-14);
  EXPECT_NEAR(m.value()(0, 1, 1), mp.secondMomentM5(1, 2), 1e-14);
}

TEST(VolumeMoments, TransformEqualsMomentsOfTransformedMesh) {
  const auto solid = testing::makeIrregularSolid();
  const auto s = testing::randomSimilarity(7);
  const auto m = computeVolumeMoments(solid, 4, Eigen::Vector3d::Zero());
  const auto direct = computeVolumeMoments(testing::transformed(solid, s), 4, s.translation);
  ASSERT_TRUE(m.ok() && direct.ok());
  const auto mapped = transformVolumeMoments(m.value(), s.scale * s.rotation);
  for (int i = 0; i < monomialCount(4); ++i) {
    const double scale = std::pow(s.scale, 3 + monomialExponents(i)[0] + monomialExponents(i)[1] + monomialExponents(i)[2]);
    EXPECT_NEAR(mapped.values[i], direct.value().values[i], 1e-11 * scale) << i;
  }
}

TEST(VolumeMoments, SubdivisionChangesNothing) {
  const auto solid = testing::makeIrregularSolid();
  const auto a = computeVolumeMoments(solid, 4, Eigen::Vector3d::Zero());
  const auto b = computeVolumeMoments(subdivideMidpoints(subdivideMidpoints(solid)), 4, Eigen::Vector3d::Zero());
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_LT((a.value().values - b.value().values).cwiseAbs().maxCoeff(), 1e-13);
}

TEST(VolumeMoments, OrderFourIsTheGeneralPassBitForBit) {
  // Order 4 takes two faces a time (one per SSE2 lane); every other order the general loop, whose
  // first 35 sums are the same operations. So order 5's first 35 values are order 4's exactly:
  // on an irregular solid about a point off its box's centre, and on a box whose corner is the
  // origin (coordinates exactly 0 there, where a product's zero could change sign).
  const std::pair<TriangleMesh, Eigen::Vector3d> cases[] = {
      {subdivideMidpoints(testing::makeIrregularSolid()), Eigen::Vector3d(0.013, -0.021, 0.034)},
      {testing::makeBoxSurface(0.3, 0.2, 0.1), Eigen::Vector3d::Zero()}};
  for (const auto& [solid, origin] : cases) {
    const auto four = computeVolumeMoments(solid, 4, origin), five = computeVolumeMoments(solid, 5, origin);
    ASSERT_TRUE(four.ok() && five.ok());
    ASSERT_EQ(four.value().values.size(), monomialCount(4));
    EXPECT_EQ(std::memcmp(four.value().values.data(), five.value().values.data(), sizeof(double) * monomialCount(4)), 0)
        << "largest difference " << (four.value().values - five.value().values.head(monomialCount(4))).cwiseAbs().maxCoeff();
  }
}

// The lanes this machine can run: both forms where it has AVX, else the SSE2 one alone.
std::vector<Lanes> runnableLanes() {
  std::vector<Lanes> lanes{Lanes::Narrow};
  if (widestLanes() == Lanes::Wide) lanes.push_back(Lanes::Wide);
  return lanes;
}

TEST(VolumeMoments, OrderFourPassIsTheSameBitsInEitherLanes) {
  // Two faces to an SSE2 register or four to an AVX one, each face's terms added in face order: the
  // two forms' sums are the same bits (and computeVolumeMoments, which takes the widest, equals the
  // general loop: OrderFourIsTheGeneralPassBitForBit). The faces are cut to a multiple of four so
  // that both forms do them all; the cut mesh is open, which the pass itself does not check.
  TriangleMesh solid = subdivideMidpoints(testing::makeIrregularSolid());
  solid.faces.conservativeResize(4 * (solid.faces.rows() / 4), 3);
  const Eigen::Vector3d origin(0.013, -0.021, 0.034);
  std::vector<double> narrow(monomialCount(4), 0.0);
  ASSERT_EQ(detail::surfaceMomentsOrder4(solid, origin, narrow.data(), Lanes::Narrow), solid.faces.rows());
  EXPECT_NE(narrow[monomialIndex(4, 0, 0)], 0.0);
  if (widestLanes() != Lanes::Wide) GTEST_SKIP() << "this CPU has no AVX: the SSE2 form alone runs here";
  std::vector<double> wide(monomialCount(4), 0.0);
  ASSERT_EQ(detail::surfaceMomentsOrder4(solid, origin, wide.data(), Lanes::Wide), solid.faces.rows());
  EXPECT_EQ(std::memcmp(narrow.data(), wide.data(), sizeof(double) * narrow.size()), 0);
}

TEST(VolumeMoments, HighOrderPassIsTheGeneralLoopBitForBitInEitherLanes) {
  // Order 10 (the polynomial modes') goes two or four faces at a time from run-time tables. Its
  // low monomials are the general loop's bits (order 3 takes that loop alone), the two lanes agree
  // bit for bit, and a box's moments are the analytic ∫x^p y^q z^r (to rounding).
  const TriangleMesh solid = subdivideMidpoints(testing::makeIrregularSolid());
  const Eigen::Vector3d origin(0.013, -0.021, 0.034);
  const auto three = computeVolumeMoments(solid, 3, origin), ten = computeVolumeMoments(solid, 10, origin);
  ASSERT_TRUE(three.ok() && ten.ok());
  EXPECT_EQ(std::memcmp(three.value().values.data(), ten.value().values.data(), sizeof(double) * monomialCount(3)), 0);
  TriangleMesh whole = solid;
  whole.faces.conservativeResize(4 * (whole.faces.rows() / 4), 3);
  std::vector<double> narrow(monomialCount(10), 0.0);
  ASSERT_EQ(detail::surfaceMoments(whole, origin, 10, narrow.data(), Lanes::Narrow), whole.faces.rows());
  if (widestLanes() == Lanes::Wide) {
    std::vector<double> wide(monomialCount(10), 0.0);
    ASSERT_EQ(detail::surfaceMoments(whole, origin, 10, wide.data(), Lanes::Wide), whole.faces.rows());
    EXPECT_EQ(std::memcmp(narrow.data(), wide.data(), sizeof(double) * narrow.size()), 0);
  }
  const double a = 0.15, b = 0.1, c = 0.05;  // the box's half sides
  const auto box = computeVolumeMoments(testing::makeBoxSurface(2 * a, 2 * b, 2 * c), 10, Eigen::Vector3d(a, b, c));  // about its centre
  ASSERT_TRUE(box.ok());
  auto even = [](double h, int k) { return k % 2 ? 0.0 : 2.0 * std::pow(h, k + 1) / (k + 1); };  // ∫_{−h}^{h} t^k dt
  for (int m = 0; m < monomialCount(10); ++m) {
    const auto [p, q, r] = monomialExponents(m);
    const double expected = even(a, p) * even(b, q) * even(c, r);
    EXPECT_NEAR(box.value().values[m], expected, 1e-13 * even(a, 0) * even(b, 0) * even(c, 0)) << p << " " << q << " " << r;
  }
}

TEST(VolumeMoments, DirectionalInLanesIsTheScalarBitForBit) {
  // Directional moments of many directions at once (the canonical frames' samples) are the scalar
  // call's bits in either lanes, for every order, and for counts that are not whole registers.
  const auto moments = computeVolumeMoments(subdivideMidpoints(testing::makeIrregularSolid()), 4,
                                            Eigen::Vector3d(0.013, -0.021, 0.034));
  ASSERT_TRUE(moments.ok());
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Eigen::Vector3d> u(37);
  for (auto& d : u) d = Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  u[3] = Eigen::Vector3d(0.0, -0.0, 1.0);  // signed zeros in a lane
  for (Lanes lanes : runnableLanes()) {
    for (int order = 0; order <= 4; ++order) {
      for (size_t count : {size_t{0}, size_t{1}, size_t{3}, size_t{4}, size_t{37}}) {
        std::vector<double> batch(count, -1.0);
        detail::directional(moments.value(), u.data(), count, order, batch.data(), lanes);
        for (size_t k = 0; k < count; ++k) {
          const double one = moments.value().directional(u[k], order);
          EXPECT_EQ(std::memcmp(&batch[k], &one, sizeof one), 0) << "order " << order << ", direction " << k;
        }
      }
    }
  }
}

TEST(VolumeMoments, TypedErrors) {
  const Eigen::Vector3d o = Eigen::Vector3d::Zero();
  EXPECT_EQ(computeVolumeMoments(TriangleMesh{}, 4, o).error().code, ErrorCode::EmptyMesh);
  auto box = testing::makeBoxSurface(1, 1, 1);
  EXPECT_EQ(computeVolumeMoments(box, kMaxMomentOrder + 1, o).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(computeVolumeMoments(box, -1, o).error().code, ErrorCode::InvalidArgument);

  auto nan = box;
  nan.vertices(5, 1) = std::nan("");
  const auto nanResult = computeVolumeMoments(nan, 4, o);
  ASSERT_FALSE(nanResult.ok());
  EXPECT_EQ(nanResult.error().code, ErrorCode::NonFiniteValue);
  EXPECT_NE(nanResult.error().message.find("vertex 5"), std::string::npos);

  auto open = box;
  open.faces.conservativeResize(11, 3);
  EXPECT_EQ(computeVolumeMoments(open, 4, o).error().code, ErrorCode::OpenMesh);

  auto flipped = box;  // one face turned over: its edges no longer cancel
  std::swap(flipped.faces(3, 1), flipped.faces(3, 2));
  EXPECT_EQ(computeVolumeMoments(flipped, 4, o).error().code, ErrorCode::OpenMesh);

  auto badIndex = box;
  badIndex.faces(2, 0) = 8;
  EXPECT_EQ(computeVolumeMoments(badIndex, 4, o).error().code, ErrorCode::InvalidArgument);
}

TEST(VolumeMoments, TetsInLanesAreOneAtATimeBitForBit) {
  // The runtime's corner cells add six sub-tets at a time: in either lanes, and for counts that are
  // not whole registers, the sums are the bits of one addTetVolumeMoments call after another
  // (both signs of orientation, a flat tet, and a coordinate of −0.0 among them).
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal(0.0, 0.3);
  std::vector<std::array<Eigen::Vector3d, 4>> tets(23);
  for (auto& t : tets)
    for (auto& p : t) p = Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  tets[5][3] = tets[5][0] + 0.5 * (tets[5][1] - tets[5][0]);  // flat: det 0 within rounding
  tets[7][2] = Eigen::Vector3d(-0.0, 0.1, -0.0);
  for (Lanes lanes : runnableLanes()) {
    for (int count : {0, 1, 2, 3, 5, 6, 23}) {
      std::vector<double> one(monomialCount(4), 0.25), batch(monomialCount(4), 0.25);  // onto nonzero sums
      for (int i = 0; i < count; ++i) {
        const auto& t = tets[static_cast<size_t>(i)];
        addTetVolumeMoments(t[0], t[1], t[2], t[3], 4, one.data());
      }
      detail::tetMomentsOrder4(tets.data(), count, batch.data(), lanes);
      EXPECT_EQ(std::memcmp(one.data(), batch.data(), sizeof(double) * one.size()), 0)
          << count << " tets, " << (lanes == Lanes::Wide ? "AVX" : "SSE2");
      if (count == 23) {
        EXPECT_NE(batch[monomialIndex(2, 1, 1)], 0.25);
      }
    }
  }
  std::vector<double> viaPublic(monomialCount(4), 0.0), narrow(monomialCount(4), 0.0);
  addTetVolumeMomentsOrder4(tets.data(), 23, viaPublic.data());
  detail::tetMomentsOrder4(tets.data(), 23, narrow.data(), Lanes::Narrow);
  EXPECT_EQ(std::memcmp(viaPublic.data(), narrow.data(), sizeof(double) * narrow.size()), 0);
}

}  // namespace
}  // namespace brittle

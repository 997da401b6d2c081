#include "brittle/descriptors/VoxelDescriptor.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "DescriptorTestShapes.h"
#include "TriangleDistances.h"
#include "brittle/core/TriangleGeometry.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

CanonicalFrame primaryFrame(const TriangleMesh& mesh) {
  const auto frames = computeCanonicalFrames(mesh);
  EXPECT_TRUE(frames.ok());
  return frames.value().candidates.front();
}

Descriptor occupancy(const TriangleMesh& mesh, const VoxelDescriptorSettings& s = {}) {
  const auto d = computeVoxelDescriptor(mesh, primaryFrame(mesh), s);
  EXPECT_TRUE(d.ok()) << (d.ok() ? "" : d.error().message);
  return d.ok() ? d.value() : Descriptor();
}

Descriptor clampedDistance(const TriangleMesh& mesh, const CanonicalFrame& frame) {
  const auto d = computeImprovedVoxelDescriptor(mesh, frame);
  EXPECT_TRUE(d.ok()) << (d.ok() ? "" : d.error().message);
  return d.ok() ? d.value() : Descriptor();
}

// Smallest distance between any candidate of `query` and the first frame of `reference`.
template <typename Compute, typename Distance>
float bestCandidate(const TriangleMesh& reference, const TriangleMesh& query, Compute compute, Distance distance) {
  const auto ref = compute(reference, computeCanonicalFrames(reference).value());
  const auto qry = compute(query, computeCanonicalFrames(query).value());
  EXPECT_TRUE(ref.ok() && qry.ok());
  float best = 1e30f;
  for (Eigen::Index c = 0; c < qry.value().rows(); ++c) {
    best = std::min(best, distance(qry.value().row(c).transpose(), ref.value().row(0).transpose()));
  }
  return best;
}

// The winding number of a closed surface at p (van Oosterom–Strackee solid angles): 1 inside,
// 0 outside. Independent of the parity fill under test.
double windingNumber(const Points& v, const Triangles& f, const Eigen::Vector3d& p) {
  double total = 0.0;
  for (Eigen::Index t = 0; t < f.rows(); ++t) {
    const Eigen::Vector3d a = v.row(f(t, 0)).transpose() - p, b = v.row(f(t, 1)).transpose() - p,
                          c = v.row(f(t, 2)).transpose() - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    total += 2.0 * std::atan2(a.dot(b.cross(c)), la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb);
  }
  return total / (4.0 * std::numbers::pi);
}

// Occupancy against the winding number at every voxel centre, in a given frame.
void expectOccupancyIsTheWindingNumber(const TriangleMesh& mesh, const CanonicalFrame& frame, int resolution) {
  VoxelDescriptorSettings s;
  s.resolution = resolution;
  const auto d = computeVoxelDescriptor(mesh, frame, s);
  ASSERT_TRUE(d.ok()) << d.error().message;
  const Points canonical = frame.pointsToCanonical(mesh.vertices);
  const double h = 2.0 * s.halfExtent / resolution;
  int mismatches = 0, inside = 0;
  for (int i = 0; i < resolution; ++i) {
    for (int j = 0; j < resolution; ++j) {
      for (int l = 0; l < resolution; ++l) {
        const Eigen::Vector3d p(-s.halfExtent + (i + 0.5) * h, -s.halfExtent + (j + 0.5) * h, -s.halfExtent + (l + 0.5) * h);
        const double w = windingNumber(canonical, mesh.faces, p);
        ASSERT_TRUE(std::abs(w) < 1e-6 || std::abs(w - 1.0) < 1e-6) << "a centre on the surface: pick another shape";
        const float expected = w > 0.5 ? 1.0f : 0.0f;
        inside += expected == 1.0f;
        mismatches += d.value()[(i * resolution + j) * resolution + l] != expected;
      }
    }
  }
  EXPECT_EQ(mismatches, 0) << "of " << resolution * resolution * resolution << " centres, " << inside << " inside";
  EXPECT_GT(inside, 0);
}

TEST(VoxelDescriptor, OccupancyIsTheWindingNumberAtEveryCentre) {
  // A ball, in its canonical frame and turned.
  const TriangleMesh ball = testing::makeIcosphere(1.0, 3);
  expectOccupancyIsTheWindingNumber(ball, primaryFrame(ball), 16);
  CanonicalFrame turned;
  turned.rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  turned.scalePerM = 0.8;
  expectOccupancyIsTheWindingNumber(ball, turned, 16);
  // A box whose faces' diagonals run exactly through columns of centres (x = ±y), so that the
  // column's line meets the top and bottom faces on an edge shared by two triangles: the tie rule
  // must count one crossing there, not zero or two.
  const double h = 3.0 / 16.0;
  const TriangleMesh box = testing::makeBoxSurface(2.0 * (2.5 * h), 2.0 * (2.5 * h), 1.3);
  expectOccupancyIsTheWindingNumber(box, CanonicalFrame{}, 16);
  // A bent, non-convex solid: the box with one corner pushed in (a fold seen from some columns).
  TriangleMesh dented = testing::makeBoxSurface(1.2, 0.9, 0.7);
  dented.vertices.row(0) *= 0.2;
  expectOccupancyIsTheWindingNumber(dented, CanonicalFrame{}, 24);
}

TEST(VoxelDescriptor, CubeOccupiesTheExpectedVoxels) {
  // Unit cube [-½, ½]³ on the default grid (h = 3/16, centres at −1.5 + (i + ½)h): the centres
  // with |x| ≤ ½ are i = 5..10, so exactly 6³ voxels are occupied.
  const auto d = occupancy(testing::makeBoxSurface(2.0, 2.0, 2.0));
  ASSERT_EQ(d.size(), 16 * 16 * 16);
  EXPECT_EQ(d.sum(), 216.0f);
  EXPECT_EQ(d[(5 * 16 + 5) * 16 + 5], 1.0f);
  EXPECT_EQ(d[(4 * 16 + 7) * 16 + 7], 0.0f);
  EXPECT_EQ(d[(11 * 16 + 7) * 16 + 7], 0.0f);
}

TEST(VoxelDescriptor, SphereVolumeFromOccupancy) {
  VoxelDescriptorSettings s;
  s.resolution = 32;
  const auto d = occupancy(testing::makeIcosphere(3.0, 4), s);
  const double h = 3.0 / 32;
  EXPECT_NEAR(d.sum() * h * h * h, 1.0, 0.05);
}

// Distance from p to a triangle, independently of the descriptor's Voronoi regions: the plane's
// foot point where it falls inside the triangle (barycentric coordinates), else the nearest of
// the three edges.
double distanceToTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const auto toSegment = [&](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
    const Eigen::Vector3d e = v - u;
    const double t = std::clamp(e.dot(p - u) / e.squaredNorm(), 0.0, 1.0);
    return (p - (u + t * e)).norm();
  };
  const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
  const Eigen::Vector3d foot = p - n.dot(p - a) * n;
  const double area = (b - a).cross(c - a).dot(n);
  const double alpha = (b - foot).cross(c - foot).dot(n) / area, beta = (c - foot).cross(a - foot).dot(n) / area;
  if (alpha >= 0.0 && beta >= 0.0 && alpha + beta <= 1.0) return std::abs(n.dot(p - a));
  return std::min({toSegment(a, b), toSegment(b, c), toSegment(c, a)});
}

// The clamped signed distance against every triangle at every centre, signed by the winding
// number: the descriptor's values to float rounding.
void expectClampedDistanceIsBruteForce(const TriangleMesh& mesh, const CanonicalFrame& frame,
                                       const ImprovedVoxelDescriptorSettings& s = {}) {
  const auto d = computeImprovedVoxelDescriptor(mesh, frame, s);
  ASSERT_TRUE(d.ok()) << d.error().message;
  const Points v = frame.pointsToCanonical(mesh.vertices);
  const double h = 2.0 * s.halfExtent / s.resolution, reach = s.clampVoxels * h;
  int within = 0;
  double worst = 0.0;
  for (int i = 0; i < s.resolution; ++i) {
    for (int j = 0; j < s.resolution; ++j) {
      for (int l = 0; l < s.resolution; ++l) {
        const Eigen::Vector3d p(-s.halfExtent + (i + 0.5) * h, -s.halfExtent + (j + 0.5) * h, -s.halfExtent + (l + 0.5) * h);
        double nearest = std::numeric_limits<double>::infinity();
        for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
          nearest = std::min(nearest, distanceToTriangle(p, v.row(mesh.faces(f, 0)).transpose(), v.row(mesh.faces(f, 1)).transpose(),
                                                         v.row(mesh.faces(f, 2)).transpose()));
        }
        const double sign = windingNumber(v, mesh.faces, p) > 0.5 ? -1.0 : 1.0;
        const float got = d.value()[(i * s.resolution + j) * s.resolution + l];
        if (nearest >= reach) {
          EXPECT_EQ(got, static_cast<float>(sign)) << "clamped, exactly, at " << p.transpose();
        } else {
          ++within;
          worst = std::max(worst, std::abs(got - sign * nearest / reach));
        }
      }
    }
  }
  EXPECT_LT(worst, 1e-6) << "the largest difference from brute force, over " << within << " centres within the clamp";
  EXPECT_GT(within, 100);
}

TEST(VoxelDescriptor, ImprovedIsTheBruteForceClampedDistance) {
  const auto solid = testing::makeIrregularSolid();
  expectClampedDistanceIsBruteForce(solid, primaryFrame(solid));
  CanonicalFrame turned = primaryFrame(solid);
  turned.rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()) * turned.rotation;
  expectClampedDistanceIsBruteForce(solid, turned);
  const auto ball = testing::makeIcosphere(1.0, 2);
  expectClampedDistanceIsBruteForce(ball, primaryFrame(ball));
  // Large triangles (a box of 12): each triangle's columns reach across the grid.
  TriangleMesh dented = testing::makeBoxSurface(1.2, 0.9, 0.7);
  dented.vertices.row(0) *= 0.2;
  expectClampedDistanceIsBruteForce(dented, CanonicalFrame{});
  // On a finer grid with a wider clamp, turned: a large triangle's slab holds many more centres
  // (the visit's buffers are sized by it).
  CanonicalFrame tilted;
  tilted.rotation = Eigen::AngleAxisd(0.4, Eigen::Vector3d(2, -1, 1).normalized()).toRotationMatrix();
  ImprovedVoxelDescriptorSettings fine;
  fine.resolution = 40;
  fine.clampVoxels = 3.5;
  expectClampedDistanceIsBruteForce(dented, tilted, fine);
}

TEST(VoxelDescriptor, TriangleDistancesInLanesAreTheScalarBits) {
  // The clamped distances measure a triangle's centres two or four to a register: each value must be
  // closestOnTriangle's squared distance bit for bit, in every Voronoi region (counted), on slivers,
  // on triangles without area (the scalar fallback) and for counts that leave a register part full.
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto point = [&] { return Eigen::Vector3d(unit(random), unit(random), unit(random)); };
  std::vector<std::array<Eigen::Vector3d, 3>> triangles;
  for (int i = 0; i < 40; ++i) triangles.push_back({0.4 * point(), 0.4 * point(), 0.4 * point()});
  const Eigen::Vector3d o(0.1, -0.2, 0.05), e(0.3, 0.1, -0.2);
  triangles.push_back({o, o + e, o + e * (1.0 + 1e-9) + Eigen::Vector3d(0, 1e-12, 0)});  // a sliver
  triangles.push_back({o, o + e, o + 2.5 * e});                                          // on a line
  triangles.push_back({o, o, o + e});                                                    // two corners equal
  triangles.push_back({o, o, o});                                                        // one point
  std::array<int, 7> regions{};  // a, b, c, the three edges, the face: counted from the weights
  size_t values = 0;
  for (const auto& t : triangles) {
    for (const size_t count : {size_t{1}, size_t{3}, size_t{4}, size_t{37}}) {
      std::vector<double> x(count), y(count), z(count);
      for (size_t i = 0; i < count; ++i) {
        Eigen::Vector3d p = point();
        if (i % 5 == 0) p = (t[0] + t[1] + t[2]) / 3.0 + 0.01 * p;  // near the face
        if (i % 7 == 0) p = t[i % 3];                                  // on a corner
        x[i] = p.x(), y[i] = p.y(), z[i] = p.z();
      }
      for (const Lanes lanes : {Lanes::Narrow, Lanes::Wide}) {
        if (lanes == Lanes::Wide && widestLanes() != Lanes::Wide) continue;
        std::vector<double> out(count, -1.0);
        detail::squaredDistancesToTriangle(x.data(), y.data(), z.data(), count, t[0], t[1], t[2], out.data(), lanes);
        for (size_t i = 0; i < count; ++i) {
          const Eigen::Vector3d p(x[i], y[i], z[i]);
          Eigen::Vector3d bary;
          const double want = (closestOnTriangle(p, t[0], t[1], t[2], bary) - p).squaredNorm();
          ASSERT_EQ(std::memcmp(&want, &out[i], sizeof(double)), 0) << want << " " << out[i] << " at " << p.transpose();
          const int zeros = (bary.array() == 0.0).count();
          regions[zeros == 2 ? (bary[0] == 1.0 ? 0 : bary[1] == 1.0 ? 1 : 2) : zeros == 1 ? 3 + (bary[0] == 0.0 ? 1 : bary[1] == 0.0 ? 2 : 0) : 6]++;
          ++values;
        }
      }
    }
  }
  EXPECT_GT(values, 3000u);
  for (size_t r = 0; r < regions.size(); ++r) EXPECT_GT(regions[r], 20) << "region " << r;
}

TEST(VoxelDescriptor, ImprovedIsAClampedSignedDistance) {
  const auto cube = testing::makeBoxSurface(1.0, 1.0, 1.0);
  const auto d = clampedDistance(cube, primaryFrame(cube));
  EXPECT_GE(d.minCoeff(), -1.0f);
  EXPECT_LE(d.maxCoeff(), 1.0f);
  const double wh = 2.0 * 3.0 / 16;  // clamp distance w·h
  // Centre (0.46875, −0.09375, −0.09375): 0.03125 inside the face x = ½.
  EXPECT_NEAR(d[(10 * 16 + 7) * 16 + 7], -0.03125 / wh, 1e-5);
  // Centre (0.65625, …): 0.15625 outside.
  EXPECT_NEAR(d[(11 * 16 + 7) * 16 + 7], 0.15625 / wh, 1e-5);
  EXPECT_EQ(d[(7 * 16 + 7) * 16 + 7], -1.0f);  // deep inside: clamped
  EXPECT_EQ(d[0], 1.0f);                      // far corner: clamped
}

TEST(VoxelDescriptor, InvariantToSimilarityAndRemeshing) {
  const auto solid = testing::makeIrregularSolid();
  const auto occRef = occupancy(solid);
  const auto sdfRef = clampedDistance(solid, primaryFrame(solid));
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const auto moved = testing::transformed(solid, testing::randomSimilarity(seed));
    EXPECT_EQ(voxelHammingDistance(occupancy(moved), occRef), 0.0f) << seed;
    EXPECT_LT((clampedDistance(moved, primaryFrame(moved)) - sdfRef).cwiseAbs().maxCoeff(), 1e-4f) << seed;
  }
  // Same polyhedron, 16× the triangles: the same solid, so the same exact distances, but for the
  // frame's rounding (OpenVDB's narrow band, until stop 80, moved them by up to 0.023 of the clamp
  // distance, from the triangles its dilation reached).
  const auto fine = subdivideMidpoints(subdivideMidpoints(solid));
  EXPECT_EQ(voxelHammingDistance(occupancy(fine), occRef), 0.0f);
  const Descriptor fineSdf = clampedDistance(fine, primaryFrame(fine));
  EXPECT_LT((fineSdf - sdfRef).cwiseAbs().maxCoeff(), 1e-4f);

  // Different faceting of the same sphere: a few boundary voxels may flip.
  const auto coarse = testing::makeIcosphere(1.0, 3), finer = testing::makeIcosphere(1.0, 4);
  const auto descriptorsOf = [](const TriangleMesh& m, const CanonicalFrames& f) { return computeVoxelDescriptors(m, f); };
  EXPECT_LT(bestCandidate(coarse, finer, descriptorsOf, voxelHammingDistance), 0.01f);
  const auto improvedOf = [](const TriangleMesh& m, const CanonicalFrames& f) { return computeImprovedVoxelDescriptors(m, f); };
  const auto maxAbs = [](const Descriptor& a, const Descriptor& b) { return (a - b).cwiseAbs().maxCoeff(); };
  EXPECT_LT(bestCandidate(coarse, finer, improvedOf, maxAbs), 0.1f);
}

TEST(VoxelDescriptor, ImprovedGrowsSmoothlyWithMisalignment) {
  // Rotating the frame by δ moves the clamped distance by at most δ·|x|/(w·h) per voxel, so the
  // distance grows gradually from zero; occupancy stays put until a voxel centre crosses the
  // surface, then jumps by whole voxels.
  const auto solid = testing::makeIrregularSolid();
  const CanonicalFrame frame = primaryFrame(solid);
  const auto reference = clampedDistance(solid, frame);
  float previous = 0.0f;
  for (double degrees : {0.1, 0.5, 1.0, 2.0, 4.0}) {
    CanonicalFrame tilted = frame;
    tilted.rotation = Eigen::AngleAxisd(degrees * std::numbers::pi / 180, Eigen::Vector3d(1, 2, 3).normalized()) * frame.rotation;
    const auto d = clampedDistance(solid, tilted);
    const float change = (d - reference).cwiseAbs().maxCoeff();
    const double bound = degrees * std::numbers::pi / 180 * 1.5 * std::sqrt(3.0) / (2.0 * 3.0 / 16);
    EXPECT_GT(change, previous);
    EXPECT_LT(change, bound + 1e-4);
    previous = change;
  }
}

TEST(VoxelDescriptor, AmbiguousShapesMatchSomeCandidate) {
  const auto descriptorsOf = [](const TriangleMesh& m, const CanonicalFrames& f) { return computeVoxelDescriptors(m, f); };
  const auto improvedOf = [](const TriangleMesh& m, const CanonicalFrames& f) { return computeImprovedVoxelDescriptors(m, f); };
  const auto cube = testing::makeBoxSurface(1.0, 1.0, 1.0);
  const auto cylinder = testing::makeCylinder(0.5, 1.6, 48);
  const auto sphere = testing::makeIcosphere(1.0, 3);
  for (unsigned seed = 1; seed <= 4; ++seed) {
    const auto s = testing::randomSimilarity(seed);
    EXPECT_EQ(bestCandidate(cube, testing::transformed(cube, s), descriptorsOf, voxelHammingDistance), 0.0f);
    EXPECT_LT(bestCandidate(cylinder, testing::transformed(cylinder, s), descriptorsOf, voxelHammingDistance), 0.02f);
    EXPECT_LT(bestCandidate(sphere, testing::transformed(sphere, s), descriptorsOf, voxelHammingDistance), 0.01f);
    EXPECT_LT(bestCandidate(cylinder, testing::transformed(cylinder, s), improvedOf, voxelL2Distance), 1.0f);
  }
}

TEST(VoxelDescriptor, TypedErrors) {
  const auto box = testing::makeBoxSurface(1, 2, 3);
  const auto frame = primaryFrame(box);
  EXPECT_EQ(computeVoxelDescriptor(TriangleMesh{}, frame).error().code, ErrorCode::EmptyMesh);
  auto nan = box;
  nan.vertices(1, 1) = std::nan("");
  EXPECT_EQ(computeVoxelDescriptor(nan, frame).error().code, ErrorCode::NonFiniteValue);
  auto open = box;
  open.faces.conservativeResize(11, 3);
  EXPECT_EQ(computeImprovedVoxelDescriptor(open, frame).error().code, ErrorCode::OpenMesh);
  VoxelDescriptorSettings bad;
  bad.resolution = 1;
  EXPECT_EQ(computeVoxelDescriptor(box, frame, bad).error().code, ErrorCode::InvalidArgument);
  ImprovedVoxelDescriptorSettings badClamp;
  badClamp.clampVoxels = 0.0;
  EXPECT_EQ(computeImprovedVoxelDescriptor(box, frame, badClamp).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(computeVoxelDescriptors(box, CanonicalFrames{}).error().code, ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace brittle

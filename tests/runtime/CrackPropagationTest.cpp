// CrackPropagation.h: the pruned stress scan against the full one, crack growth and its Griffith
// energy stop on a bar in uniform tension, crumb merging (against the one-merge-at-a-time
// definition and on hand-made cuts), and typed errors.
#include "brittle/runtime/CrackPropagation.h"

#include <Eigen/SVD>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <tuple>
#include <cstring>

#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

// A random hit on `points` stress points, drawn from g in this order: the modal coordinates q
// (instants by modes), the static correction's stress per newton (left empty without it), and the
// force at each instant.
struct RandomHit {
  Eigen::MatrixXd q;
  Eigen::VectorXd staticStress;
  std::vector<double> force;
};
RandomHit randomHit(std::mt19937_64& rng, std::normal_distribution<double>& g, Eigen::Index points, int modes,
                    int instants, bool correction) {
  RandomHit hit;
  hit.q.resize(instants, modes);
  for (Eigen::Index i = 0; i < hit.q.size(); ++i) hit.q.data()[i] = g(rng);
  if (correction) {
    hit.staticStress.resize(6 * points);
    for (Eigen::Index i = 0; i < hit.staticStress.size(); ++i) hit.staticStress[i] = 1e3 * g(rng);
  }
  hit.force.resize(static_cast<size_t>(instants));
  for (double& f : hit.force) f = 100.0 * std::abs(g(rng));
  return hit;
}

// Stress-mode blocks (6 by modes) in groups of 1–maxSize around shared centres, as the corners of
// the elements at one node are: each block its centre (1e6 g) plus spread · 1e6 g, until there
// are at least `count`; keyOf(group) gives each block's key as it is made.
template <class KeyOf>
void groupedBlocks(std::mt19937_64& rng, std::normal_distribution<double>& g, int modes, size_t count, int maxSize,
                   double spread, KeyOf keyOf, std::vector<Eigen::MatrixXd>& blocks, std::vector<int32_t>& keys) {
  for (int32_t group = 0; keys.size() < count; ++group) {
    Eigen::MatrixXd centre(6, modes);
    for (Eigen::Index i = 0; i < centre.size(); ++i) centre.data()[i] = 1e6 * g(rng);
    const int size = 1 + static_cast<int>(rng() % static_cast<uint64_t>(maxSize));
    for (int m = 0; m < size; ++m) {
      Eigen::MatrixXd block = centre;
      for (Eigen::Index i = 0; i < block.size(); ++i) block.data()[i] += spread * 1e6 * g(rng);
      blocks.push_back(block);
      keys.push_back(keyOf(group));
    }
  }
}

// The blocks as stress modes in a shuffled order (a group's points are not next to each other in
// the rows, as a node's corners are not), with each point's key.
void shuffledPoints(std::mt19937_64& rng, int modes, const std::vector<Eigen::MatrixXd>& blocks, const std::vector<int32_t>& keys,
                    MatrixXdRow& stressModes, std::vector<int32_t>& pointKeys) {
  std::vector<size_t> order(keys.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::shuffle(order.begin(), order.end(), rng);
  const auto points = static_cast<Eigen::Index>(keys.size());
  stressModes.resize(6 * points, modes);
  pointKeys.resize(keys.size());
  for (Eigen::Index e = 0; e < points; ++e) {
    stressModes.middleRows(6 * e, 6) = blocks[order[static_cast<size_t>(e)]];
    pointKeys[static_cast<size_t>(e)] = keys[order[static_cast<size_t>(e)]];
  }
}

// The definition, as it was first written: relabel the whole mesh after every merge.
int mergeCrumbsByRelabelling(const TetTopology& topo, int minNodes, Eigen::VectorXd& edgeCuts, Eigen::VectorXi& labels,
                             int& fragmentCount) {
  int merged = 0;
  while (fragmentCount > 1) {
    std::vector<int> size(static_cast<size_t>(fragmentCount), 0);
    for (Eigen::Index i = 0; i < labels.size(); ++i) ++size[static_cast<size_t>(labels[i])];
    int crumb = -1;
    for (int l = 0; l < fragmentCount; ++l) {
      if (size[static_cast<size_t>(l)] < minNodes && (crumb < 0 || size[static_cast<size_t>(l)] < size[static_cast<size_t>(crumb)])) crumb = l;
    }
    if (crumb < 0) break;
    std::vector<int> shared(static_cast<size_t>(fragmentCount), 0);
    for (Eigen::Index e = 0; e < topo.edges.rows(); ++e) {
      const int a = labels[topo.edges(e, 0)], b = labels[topo.edges(e, 1)];
      if (a == crumb && b != crumb) ++shared[static_cast<size_t>(b)];
      if (b == crumb && a != crumb) ++shared[static_cast<size_t>(a)];
    }
    const int into = static_cast<int>(std::max_element(shared.begin(), shared.end()) - shared.begin());
    for (Eigen::Index e = 0; e < topo.edges.rows(); ++e) {
      const int a = labels[topo.edges(e, 0)], b = labels[topo.edges(e, 1)];
      if ((a == crumb && b == into) || (a == into && b == crumb)) edgeCuts[e] = std::numeric_limits<double>::quiet_NaN();
    }
    fragmentCount = labelFragments(topo, edgeCuts, labels.size(), labels);
    ++merged;
  }
  return merged;
}

TEST(CrackPropagation, CrumbMergingEqualsRelabellingAfterEveryMerge) {
  const TetMesh box = testing::makeBoxTetMesh(0.1, 0.1, 0.05, 6, 6, 3);
  auto topo = buildTetTopology(box);
  ASSERT_TRUE(topo) << topo.error().message;
  const TetTopology& t = topo.value();
  std::mt19937_64 rng(7);
  int totalMerges = 0;
  for (int trial = 0; trial < 40; ++trial) {
    // Random planes cut every edge they cross: many fragments, many of them crumbs.
    Eigen::VectorXd cuts = Eigen::VectorXd::Constant(t.edges.rows(), std::numeric_limits<double>::quiet_NaN());
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const int planes = 1 + trial % 6;
    for (int p = 0; p < planes; ++p) {
      const Eigen::Vector3d n = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
      const double d = n.dot(Eigen::Vector3d(0.05, 0.05, 0.025)) + 0.02 * u(rng);
      for (Eigen::Index e = 0; e < t.edges.rows(); ++e) {
        const double a = n.dot(box.nodes.row(t.edges(e, 0)).transpose()) - d;
        const double b = n.dot(box.nodes.row(t.edges(e, 1)).transpose()) - d;
        if ((a < 0) != (b < 0)) cuts[e] = a / (a - b);
      }
    }
    Eigen::VectorXi labels;
    const int count = labelFragments(t, cuts, box.nodes.rows(), labels);
    const int minNodes = 2 + trial % 25;
    Eigen::VectorXd fastCuts = cuts, slowCuts = cuts;
    Eigen::VectorXi fastLabels = labels, slowLabels = labels;
    int fastCount = count, slowCount = count;
    const int fast = mergeCrumbs(t, minNodes, fastCuts, fastLabels, fastCount);
    const int slow = mergeCrumbsByRelabelling(t, minNodes, slowCuts, slowLabels, slowCount);
    ASSERT_EQ(fast, slow) << "trial " << trial;
    ASSERT_EQ(fastCount, slowCount) << "trial " << trial;
    ASSERT_EQ(fastLabels, slowLabels) << "trial " << trial;
    for (Eigen::Index e = 0; e < cuts.size(); ++e) ASSERT_EQ(std::isnan(fastCuts[e]), std::isnan(slowCuts[e])) << e;
    totalMerges += fast;
    // Every fragment left is at least minNodes big, unless it is the only one.
    std::vector<int> size(static_cast<size_t>(fastCount), 0);
    for (Eigen::Index i = 0; i < fastLabels.size(); ++i) ++size[static_cast<size_t>(fastLabels[i])];
    if (fastCount > 1) {
      EXPECT_GE(*std::min_element(size.begin(), size.end()), minNodes) << "trial " << trial;
    }
  }
  EXPECT_GT(totalMerges, 40);  // the trials exercised merging
}

// The element stress sums each row in four running sums (mode j to sum j mod 4): the same bits in
// SSE2 pairs and AVX quads, for every mode count (tails of 0–3 modes), and within rounding of
// Eigen's product, which sums in another order.
TEST(CrackPropagation, ElementStressIsTheSameBitsInEitherLanesAndNearEigensProduct) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (Eigen::Index r : {1, 2, 3, 4, 5, 7, 8, 13, 40, 41}) {
    MatrixXdRow S(6 * 9, r + 3);  // a stride wider than the modes read
    for (Eigen::Index i = 0; i < S.size(); ++i) S.data()[i] = normal(rng) * 1e6;
    Eigen::VectorXd q(r);
    for (Eigen::Index j = 0; j < r; ++j) q[j] = normal(rng) * 1e-6;
    for (Eigen::Index p = 0; p < 9; ++p) {
      const Voigt narrow = detail::elementStress(S, p, q.data(), r, Lanes::Narrow);
      const Voigt eigen = S.block(6 * p, 0, 6, r) * q;
      const double scale = (S.block(6 * p, 0, 6, r).cwiseAbs() * q.cwiseAbs()).maxCoeff();
      EXPECT_LE((narrow - eigen).cwiseAbs().maxCoeff(), 1e-15 * r * scale) << r << " modes, point " << p;
      if (widestLanes() == Lanes::Wide) {
        const Voigt wide = detail::elementStress(S, p, q.data(), r, Lanes::Wide);
        EXPECT_EQ(std::memcmp(wide.data(), narrow.data(), sizeof(double) * 6), 0) << r << " modes, point " << p;
      }
    }
  }
}

TEST(CrackPropagation, PrunedScanEqualsTheFullScanOnRandomFields) {
  // Several generator seeds; fields with and without the static correction; thresholds from below
  // the typical peak (many seeds) to above every σ₁ (none).
  int withSeeds = 0, withoutSeeds = 0, firstSeedCheaper = 0;
  for (uint64_t rngSeed : {11u, 12u, 13u, 14u}) {
    std::mt19937_64 rng(rngSeed);
    std::normal_distribution<double> g(0.0, 1.0);
    for (int trial = 0; trial < 6; ++trial) {
      SCOPED_TRACE(::testing::Message() << "seed " << rngSeed << ", trial " << trial);
      const int elements = 200, modes = 8, instants = 30;
      MatrixXdRow stressModes(6 * elements, modes);
      for (Eigen::Index i = 0; i < stressModes.size(); ++i) stressModes.data()[i] = 1e6 * g(rng);
      const bool correction = trial % 2 == 0;
      const auto [q, staticStress, force] = randomHit(rng, g, elements, modes, instants, correction);
      // Unit weights, or 1/ω-like ones (the World's), under which the spectral bound is the tighter.
      const Eigen::VectorXd scales =
          trial % 3 == 0 ? Eigen::VectorXd() : Eigen::VectorXd(Eigen::VectorXd::LinSpaced(modes, 1, modes).cwiseInverse());
      const StressBounds bounds = stressModeBounds(stressModes, modes, scales);
      const double threshold = trial == 5 ? 1e9 : 2.5e6 + 4e5 * trial;
      const StressScan full = scanStresses(stressModes, bounds, q, staticStress, force, threshold, false);
      const StressScan pruned = scanStresses(stressModes, bounds, q, staticStress, force, threshold, true);
      EXPECT_EQ(pruned.peakPrincipalPa, full.peakPrincipalPa);
      EXPECT_EQ(pruned.peakElement, full.peakElement);
      EXPECT_EQ(pruned.peakInstant, full.peakInstant);
      EXPECT_EQ(full.evaluations, int64_t{elements} * instants + elements);  // every pair, then every seed candidate
      // The full scan's peak is the definition: σ₁ of that element at that instant, the largest.
      StressField field{&stressModes, q.row(full.peakInstant).transpose(), correction ? &staticStress : nullptr,
                        force[static_cast<size_t>(full.peakInstant)]};
      // The pruned scan's seeds, made one by one as they are taken, are the full scan's list.
      EXPECT_TRUE(pruned.seeds.empty());
      EXPECT_EQ(orderedSeeds(pruned, field), full.seeds);
      EXPECT_EQ(pruned.hasSeeds(), !full.seeds.empty());
      EXPECT_LE(pruned.evaluations, full.evaluations);
      if (!full.seeds.empty()) {  // the first seed evaluates at most every candidate, usually fewer
        SeedOrderWorkspace workspace;
        SeedOrder order(pruned, field, workspace);
        int32_t first = -1;
        ASSERT_TRUE(order.next(first));
        EXPECT_EQ(first, full.seeds.front());
        EXPECT_LE(order.evaluations(), static_cast<int64_t>(pruned.seedCandidates.size()));
        if (order.evaluations() < static_cast<int64_t>(pruned.seedCandidates.size())) ++firstSeedCheaper;
      }
      // (Within rounding: the scan and StressField::at may sum the product in different orders.)
      const double peak = full.peakPrincipalPa;
      EXPECT_NEAR(maxPrincipalStress(field.at(full.peakElement)), peak, 1e-12 * peak);
      for (size_t i = 0; i < full.seeds.size(); ++i) {
        const double s1 = maxPrincipalStress(field.at(full.seeds[i]));
        EXPECT_GE(s1, threshold * (1 - 1e-12));
        EXPECT_LE(s1, peak * (1 + 1e-12));
        if (i > 0) {
          EXPECT_LE(s1, maxPrincipalStress(field.at(full.seeds[i - 1])) * (1 + 1e-12));
        }
      }
      (full.seeds.empty() ? withoutSeeds : withSeeds) += 1;
    }
  }
  EXPECT_GT(withSeeds, 0);
  EXPECT_GT(withoutSeeds, 0);
  EXPECT_GT(firstSeedCheaper, 0);  // lazily made seeds save evaluations on these fields
}

TEST(CrackPropagation, GroupedScanEqualsTheFullScanAndItsGroupBoundsHold) {
  // Points in groups of 1–12 around shared centres (as the corners of the elements at one node
  // are), each a centre plus a perturbation of 2 % (tight groups) or 100 % (loose ones), and
  // groups by random keys (any grouping must give true bounds). With and without the static
  // correction. The grouped scan finds the full scan's peak, element, instant and seeds; every
  // group bound it made holds at every point and instant of the group; tight groups leave few of
  // them to visit.
  int tightLive = 0, tightGroups = 0, checked = 0;
  for (uint64_t rngSeed : {21u, 22u, 23u}) {
    std::mt19937_64 rng(rngSeed);
    std::normal_distribution<double> g(0.0, 1.0);
    for (int trial = 0; trial < 6; ++trial) {
      SCOPED_TRACE(::testing::Message() << "seed " << rngSeed << ", trial " << trial);
      // Odd counts: the group bounds take instants four, eight or sixteen at a time (29 leaves two
      // blocks of eight in the last sixteen, 37 one).
      const int modes = 8, instants = rngSeed == 23u ? 37 : 29;
      const double spread = trial < 2 ? 0.02 : 1.0;
      std::vector<int32_t> keys;
      std::vector<Eigen::MatrixXd> blocks;
      groupedBlocks(rng, g, modes, 240, 12, spread,
                    [&](int32_t group) { return trial == 5 ? static_cast<int32_t>(rng() % 17) : group; }, blocks, keys);
      // The points of a group are not next to each other in the stress modes' rows.
      MatrixXdRow stressModes;
      std::vector<int32_t> pointKeys;
      shuffledPoints(rng, modes, blocks, keys, stressModes, pointKeys);
      const auto points = static_cast<Eigen::Index>(keys.size());
      const bool correction = trial % 2 == 0;
      const auto [q, staticStress, force] = randomHit(rng, g, points, modes, instants, correction);
      const Eigen::VectorXd scales = Eigen::VectorXd::LinSpaced(modes, 1, modes).cwiseInverse();
      const StressBounds bounds = stressModeBounds(stressModes, modes, scales, pointKeys);
      ASSERT_EQ(bounds.groupPoints.size(), keys.size());
      const double threshold = 2.5e6 + 4e5 * trial;
      const StressScan full = scanStresses(stressModes, bounds, q, staticStress, force, threshold, false);
      StressScanWorkspace workspace;
      StressScan grouped;
      scanStresses(stressModes, bounds, q, staticStress, force, threshold, true, workspace, grouped);
      EXPECT_EQ(grouped.peakPrincipalPa, full.peakPrincipalPa);
      EXPECT_EQ(grouped.peakElement, full.peakElement);
      EXPECT_EQ(grouped.peakInstant, full.peakInstant);
      StressField field{&stressModes, q.row(full.peakInstant).transpose(), correction ? &staticStress : nullptr,
                        force[static_cast<size_t>(full.peakInstant)]};
      EXPECT_EQ(orderedSeeds(grouped, field), full.seeds);
      // The group bounds in SSE2 registers, four instants to one, are the same bits as the widest
      // lanes' (eight to an AVX register where the CPU has it), and so is the whole scan.
      StressScanWorkspace narrowWorkspace;
      narrowWorkspace.lanes = Lanes::Narrow;
      StressScan narrow;
      scanStresses(stressModes, bounds, q, staticStress, force, threshold, true, narrowWorkspace, narrow);
      EXPECT_EQ(narrow.peakPrincipalPa, grouped.peakPrincipalPa);
      EXPECT_EQ(narrow.evaluations, grouped.evaluations);
      EXPECT_EQ(narrow.seeds, grouped.seeds);
      ASSERT_EQ(narrowWorkspace.groupBoundAt.size(), workspace.groupBoundAt.size());
      EXPECT_EQ(std::memcmp(narrowWorkspace.groupBoundAt.data(), workspace.groupBoundAt.data(),
                            sizeof(double) * workspace.groupBoundAt.size()),
                0);
      const auto groups = static_cast<Eigen::Index>(bounds.groupStart.size()) - 1;
      ASSERT_EQ(workspace.groupBound.size(), groups);
      int live = 0;
      for (Eigen::Index group = 0; group < groups; ++group) {
        // Groups whose bounds the scan did not need (too few points left in them, or none) keep NaN.
        if (std::isnan(workspace.groupBound[group])) continue;
        ++checked;
        live += workspace.groupBound[group] >= full.peakPrincipalPa;
        for (int32_t i = bounds.groupStart[static_cast<size_t>(group)]; i < bounds.groupStart[static_cast<size_t>(group) + 1]; ++i) {
          const int32_t e = bounds.groupPoints[static_cast<size_t>(i)];
          for (Eigen::Index k = 0; k < instants; ++k) {
            StressField at{&stressModes, q.row(k).transpose(), correction ? &staticStress : nullptr, force[static_cast<size_t>(k)]};
            EXPECT_LE(maxPrincipalStress(at.atPoint(e)), workspace.groupBoundAt[static_cast<size_t>(group * instants + k)])
                << "group " << group << ", point " << e << ", instant " << k;
          }
        }
      }
      if (trial < 2) {
        tightLive += live;
        tightGroups += static_cast<int>(groups);
      }
    }
  }
  EXPECT_GT(checked, 100);
  // Tight groups: a group's bound is near its best point's σ₁, so few reach the peak.
  EXPECT_LT(tightLive, tightGroups / 4) << tightLive << " of " << tightGroups;
}

TEST(CrackPropagation, PrunedSearchInRoundsIsTheSameOnAnyThreadCountAndTiesGoToTheLowestPoint) {
  // The pruned search runs in rounds: each of its fixed ranges takes a few groups (points) from its
  // heap, then every range goes on from the best of all so far. A range that adopted another's best
  // must still report the full scan's answer, ties included, and the counts must not depend on how
  // many threads ran the ranges. 1 200 points (75 a range), in node-like groups or one by one; the
  // full scan's peak point copied, rows and static correction, to a point in another range, so that
  // two points tie at the peak and the lower one is the answer.
  for (uint64_t rngSeed : {31u, 32u, 33u}) {
    std::mt19937_64 rng(rngSeed);
    std::normal_distribution<double> g(0.0, 1.0);
    for (int trial = 0; trial < 4; ++trial) {
      SCOPED_TRACE(::testing::Message() << "seed " << rngSeed << ", trial " << trial);
      const int modes = 8, instants = 21;
      const bool grouped = trial % 2 == 0, correction = trial < 2;
      std::vector<int32_t> keys;
      std::vector<Eigen::MatrixXd> blocks;
      groupedBlocks(rng, g, modes, 1200, grouped ? 6 : 1, 0.3, [](int32_t group) { return group; }, blocks, keys);
      MatrixXdRow stressModes;
      std::vector<int32_t> pointKeys;
      shuffledPoints(rng, modes, blocks, keys, stressModes, pointKeys);
      const auto points = static_cast<Eigen::Index>(keys.size());
      auto [q, staticStress, force] = randomHit(rng, g, points, modes, instants, correction);
      const Eigen::VectorXd scales = Eigen::VectorXd::LinSpaced(modes, 1, modes).cwiseInverse();
      const double threshold = 3e6;
      Eigen::Index from = -1, to = -1;
      double peakBefore = 0.0;
      if (!grouped) {  // a tie at the peak, in another range than the peak's
        const StressBounds first = stressModeBounds(stressModes, modes, scales);
        const StressScan before = scanStresses(stressModes, first, q, staticStress, force, threshold, false);
        from = before.peakElement, to = (from + points / 2) % points;
        peakBefore = before.peakPrincipalPa;
        stressModes.middleRows(6 * to, 6) = stressModes.middleRows(6 * from, 6);
        if (correction) staticStress.segment<6>(6 * to) = staticStress.segment<6>(6 * from);
      }
      const StressBounds bounds = grouped ? stressModeBounds(stressModes, modes, scales, pointKeys) : stressModeBounds(stressModes, modes, scales);
      const StressScan full = scanStresses(stressModes, bounds, q, staticStress, force, threshold, false);
      if (!grouped) {  // the copy ties with the peak (the same value), and the lower of the two is the answer
        EXPECT_EQ(full.peakPrincipalPa, peakBefore);
        EXPECT_EQ(full.peakElement, std::min(from, to));
      }
      std::vector<StressScan> scans;
      for (int threads : {1, 2, 4}) {
        tbb::task_arena arena(threads);
        StressScanWorkspace workspace;
        StressScan scan;
        arena.execute([&] { scanStresses(stressModes, bounds, q, staticStress, force, threshold, true, workspace, scan); });
        EXPECT_EQ(scan.peakPrincipalPa, full.peakPrincipalPa) << threads << " threads";
        EXPECT_EQ(scan.peakElement, full.peakElement) << threads << " threads";
        EXPECT_EQ(scan.peakInstant, full.peakInstant) << threads << " threads";
        EXPECT_LT(scan.evaluations, full.evaluations / 4) << threads << " threads";
        scans.push_back(scan);
      }
      for (size_t i = 1; i < scans.size(); ++i) {
        EXPECT_EQ(scans[i].evaluations, scans[0].evaluations);
        EXPECT_EQ(scans[i].seedCandidates, scans[0].seedCandidates);
      }
    }
  }
}

TEST(CrackPropagation, GroupsOfEqualPointsAreSearchedByTheirLowestPointWithTheFullScansAnswer) {
  // P2 corners read as nodal means (CornerStressMeans) make every point of a node's group the same
  // rows, bit for bit, and the static correction too: the peak search then evaluates each such
  // group's lowest point only, and its preparation, per-point bounds and seed candidates take each
  // group's once. Its peak, element, instant and seeds are the full scan's and those of the same
  // search told the groups differ; it evaluates fewer. A static correction that differs on a
  // group's points keeps that group searched point by point.
  for (uint64_t rngSeed : {31u, 32u, 33u}) {
    SCOPED_TRACE(::testing::Message() << "seed " << rngSeed);
    std::mt19937_64 rng(rngSeed);
    std::normal_distribution<double> g(0.0, 1.0);
    const int modes = 8, instants = 29;
    std::vector<int32_t> keys;
    std::vector<Eigen::MatrixXd> blocks;
    groupedBlocks(rng, g, modes, 240, 12, 0.0, [](int32_t group) { return group; }, blocks, keys);
    MatrixXdRow stressModes;
    std::vector<int32_t> pointKeys;
    shuffledPoints(rng, modes, blocks, keys, stressModes, pointKeys);
    const auto points = static_cast<Eigen::Index>(keys.size());
    auto [q, staticStress, force] = randomHit(rng, g, points, modes, instants, true);
    std::map<int32_t, Eigen::Index> firstOf;  // the static correction equal on each group's points
    for (Eigen::Index e = 0; e < points; ++e) {
      const auto [it, fresh] = firstOf.emplace(pointKeys[static_cast<size_t>(e)], e);
      if (!fresh) staticStress.segment<6>(6 * e) = staticStress.segment<6>(6 * it->second);
    }
    const Eigen::VectorXd scales = Eigen::VectorXd::LinSpaced(modes, 1, modes).cwiseInverse();
    const StressBounds bounds = stressModeBounds(stressModes, modes, scales, pointKeys);
    EXPECT_TRUE(std::all_of(bounds.groupUniform.begin(), bounds.groupUniform.end(), [](char u) { return u == 1; }));
    StressBounds told = bounds;
    std::fill(told.groupUniform.begin(), told.groupUniform.end(), 0);
    const double threshold = 2.0e6;
    const StressScan full = scanStresses(stressModes, bounds, q, staticStress, force, threshold, false);
    StressScanWorkspace wa, wb;
    StressScan same, apart;
    scanStresses(stressModes, bounds, q, staticStress, force, threshold, true, wa, same);
    scanStresses(stressModes, told, q, staticStress, force, threshold, true, wb, apart);
    for (const StressScan* s : {&same, &apart}) {
      EXPECT_EQ(s->peakPrincipalPa, full.peakPrincipalPa);
      EXPECT_EQ(s->peakElement, full.peakElement);
      EXPECT_EQ(s->peakInstant, full.peakInstant);
      StressField field{&stressModes, q.row(full.peakInstant).transpose(), &staticStress, force[static_cast<size_t>(full.peakInstant)]};
      EXPECT_EQ(orderedSeeds(*s, field), full.seeds);
    }
    EXPECT_LT(same.evaluations, apart.evaluations);
    // What the scan prepares, and the seed candidates, are the same bits whether each uniform
    // group's terms and seed bound are computed once, at its first point, or at every point.
    EXPECT_TRUE(wa.modalPressure == wb.modalPressure);
    EXPECT_TRUE(wa.modalDeviator == wb.modalDeviator);
    EXPECT_TRUE(wa.elementBound == wb.elementBound);
    EXPECT_TRUE(wa.pressureScale == wb.pressureScale);
    EXPECT_TRUE(wa.staticNorm == wb.staticNorm);
    EXPECT_TRUE(wa.staticPressure == wb.staticPressure);
    EXPECT_TRUE(wa.staticDeviator == wb.staticDeviator);
    EXPECT_FALSE(same.seedCandidates.empty());
    EXPECT_EQ(same.seedCandidates, apart.seedCandidates);
    // One point's static correction moved: its group is searched point by point again.
    Eigen::VectorXd moved = staticStress;
    moved[6 * full.peakElement] *= 1.5;
    StressScan movedScan;
    scanStresses(stressModes, bounds, q, moved, force, threshold, true, wa, movedScan);
    const StressScan movedFull = scanStresses(stressModes, bounds, q, moved, force, threshold, false);
    EXPECT_EQ(movedScan.peakPrincipalPa, movedFull.peakPrincipalPa);
    EXPECT_EQ(movedScan.peakElement, movedFull.peakElement);
    EXPECT_EQ(movedScan.peakInstant, movedFull.peakInstant);
  }
}

TEST(CrackPropagation, ANodeMemoGivesTheSameStressesAsComputingEveryPoint) {
  // StressField::nodeMemo: P2 corners whose rows are their node's (as nodal means make them)
  // computed once per node are the same bits as computed every time.
  std::mt19937_64 rng(41);
  std::normal_distribution<double> g(0.0, 1.0);
  const int modes = 12, nodes = 60, elements = 200;
  Tetrahedra corners(elements, 4);
  for (Eigen::Index i = 0; i < corners.size(); ++i) corners.data()[i] = static_cast<int32_t>(rng() % nodes);
  MatrixXdRow nodeRows(6 * nodes, modes);
  for (Eigen::Index i = 0; i < nodeRows.size(); ++i) nodeRows.data()[i] = 1e6 * g(rng);
  Eigen::VectorXd nodeStatic(6 * nodes);
  for (Eigen::Index i = 0; i < nodeStatic.size(); ++i) nodeStatic[i] = 1e3 * g(rng);
  MatrixXdRow stressModes(24 * elements, modes);
  Eigen::VectorXd staticStress(24 * elements);
  for (Eigen::Index e = 0; e < elements; ++e) {
    for (int c = 0; c < 4; ++c) {
      stressModes.middleRows(6 * (4 * e + c), 6) = nodeRows.middleRows(6 * corners(e, c), 6);
      staticStress.segment<6>(6 * (4 * e + c)) = nodeStatic.segment<6>(6 * corners(e, c));
    }
  }
  Eigen::VectorXd q(modes);
  for (Eigen::Index j = 0; j < modes; ++j) q[j] = g(rng);
  StressField plain{&stressModes, q, &staticStress, 250.0};
  plain.pointsPerElement = 4;
  NodeStressMemo memo;
  memo.reset(nodes);
  StressField memoised = plain;
  memoised.corners = &corners;
  memoised.nodeMemo = &memo;
  std::vector<Voigt> got(static_cast<size_t>(elements));
  for (int i = 0; i < 2 * elements; ++i) {  // every element twice: the second read from the memo
    const Voigt s = memoised.at(i % elements);
    if (i >= elements) got[static_cast<size_t>(i - elements)] = s;
  }
  for (int32_t e = 0; e < elements; ++e) {
    const Voigt expected = plain.at(e);
    EXPECT_EQ(std::memcmp(got[static_cast<size_t>(e)].data(), expected.data(), sizeof(Voigt)), 0) << e;
  }
  std::vector<char> referenced(static_cast<size_t>(nodes), 0);
  for (Eigen::Index i = 0; i < corners.size(); ++i) referenced[static_cast<size_t>(corners.data()[i])] = 1;
  for (int v = 0; v < nodes; ++v) {  // each node the elements read was computed once and kept
    EXPECT_EQ(memo.known[static_cast<size_t>(v)], referenced[static_cast<size_t>(v)] ? 1 : 0) << v;
    if (referenced[static_cast<size_t>(v)]) {
      const Voigt direct = plain.atPoint(std::distance(corners.data(), std::find(corners.data(), corners.data() + corners.size(), v)));  // point 4e + c
      EXPECT_EQ(std::memcmp(memo.stress[static_cast<size_t>(v)].data(), direct.data(), sizeof(Voigt)), 0) << v;
    }
  }
}

TEST(CrackPropagation, OnePreparationServesBothScansOfAnImpactWithScanStressesBits) {
  // The impact prepares a scan (prepareStressScan) beside the static correction, then scans twice
  // when the uncorrected peak is reported: the truncated modes alone, then with the correction.
  // Here the workspace first serves another hit (stale buffers), is prepared for this one, scans
  // without and then with the correction; the second scan must be scanStresses' own, bit for bit,
  // in its group bounds too. Groups of points around shared centres, as at a mesh node.
  std::mt19937_64 rng(31);
  std::normal_distribution<double> g(0.0, 1.0);
  const int modes = 12, instants = 37;
  std::vector<int32_t> keys;
  std::vector<Eigen::MatrixXd> blocks;
  groupedBlocks(rng, g, modes, 300, 10, 0.05, [](int32_t group) { return group; }, blocks, keys);
  const auto points = static_cast<Eigen::Index>(keys.size());
  MatrixXdRow stressModes(6 * points, modes);
  for (Eigen::Index e = 0; e < points; ++e) stressModes.middleRows(6 * e, 6) = blocks[static_cast<size_t>(e)];
  const Eigen::VectorXd scales = Eigen::VectorXd::LinSpaced(modes, 1, modes).cwiseInverse();
  const StressBounds bounds = stressModeBounds(stressModes, modes, scales, keys);
  ASSERT_GE(bounds.groupStart.size(), 30u);
  const auto other = randomHit(rng, g, points, modes, instants + 5, true);
  const auto [q, staticStress, force] = randomHit(rng, g, points, modes, instants, true);
  const double threshold = 3e6;
  static const Eigen::VectorXd kNoStatic;

  StressScanWorkspace reference;
  StressScan expected;
  scanStresses(stressModes, bounds, q, staticStress, force, threshold, true, reference, expected);
  StressScan expectedUncorrected;
  StressScanWorkspace uncorrectedWorkspace;
  scanStresses(stressModes, bounds, q, kNoStatic, force, std::numeric_limits<double>::infinity(), true,
               uncorrectedWorkspace, expectedUncorrected);

  StressScanWorkspace workspace;
  StressScan scan;
  scanStresses(stressModes, bounds, other.q, other.staticStress, other.force, threshold, true, workspace, scan);
  prepareStressScan(bounds, q, true, workspace);
  scanPreparedStresses(stressModes, bounds, q, kNoStatic, force, std::numeric_limits<double>::infinity(), true, workspace,
                       scan);
  EXPECT_EQ(scan.peakPrincipalPa, expectedUncorrected.peakPrincipalPa);
  EXPECT_EQ(scan.evaluations, expectedUncorrected.evaluations);
  // A scan equal to scanStresses' own: its peak, where and when, its evaluations and its seeds.
  auto expectExpected = [&](const StressScan& got) {
    EXPECT_EQ(got.peakPrincipalPa, expected.peakPrincipalPa);
    EXPECT_EQ(got.peakElement, expected.peakElement);
    EXPECT_EQ(got.peakInstant, expected.peakInstant);
    EXPECT_EQ(got.evaluations, expected.evaluations);
    EXPECT_EQ(got.seedCandidates, expected.seedCandidates);
  };
  scanPreparedStresses(stressModes, bounds, q, staticStress, force, threshold, true, workspace, scan);
  expectExpected(scan);
  EXPECT_FALSE(expected.seedCandidates.empty());
  ASSERT_EQ(workspace.elementBound.size(), reference.elementBound.size());
  EXPECT_EQ(std::memcmp(workspace.elementBound.data(), reference.elementBound.data(),
                        sizeof(double) * static_cast<size_t>(reference.elementBound.size())),
            0);
  ASSERT_EQ(workspace.groupBoundAt.size(), reference.groupBoundAt.size());
  // The groups the two searches bounded, at every instant (the others were never written, in
  // either: compared only where the reference's are finite).
  const auto groups = static_cast<Eigen::Index>(bounds.groupStart.size()) - 1;
  int bounded = 0;
  for (Eigen::Index group = 0; group < groups; ++group) {
    if (std::isnan(reference.groupBound[group])) continue;
    ++bounded;
    EXPECT_EQ(workspace.groupBound[group], reference.groupBound[group]) << "group " << group;
    EXPECT_EQ(std::memcmp(workspace.groupBoundAt.data() + group * instants, reference.groupBoundAt.data() + group * instants,
                          sizeof(double) * instants),
              0)
        << "group " << group;
  }
  EXPECT_GT(bounded, 0);
  // A workspace never prepared is prepared by the scan itself (nothing read past its buffers).
  StressScanWorkspace unprepared;
  StressScan direct;
  scanPreparedStresses(stressModes, bounds, q, staticStress, force, threshold, true, unprepared, direct);
  expectExpected(direct);
}

TEST(CrackPropagation, SpectralBoundIsANormBoundWithinSixPercent) {
  // ‖D S_e W‖₂ from the trace of the 16th power of the Gram matrix: never below the exact norm
  // (an SVD), at most 6^(1/32) above it, for any number of the first modes, and so a bound on
  // ‖D S_e q‖ / ‖W⁻¹ q‖. Blocks of rank 1 to 6, and an all-zero one.
  std::mt19937_64 rng(31);
  std::normal_distribution<double> g(0.0, 1.0);
  const int points = 60, modes = 40;
  MatrixXdRow stressModes = MatrixXdRow::Zero(6 * points, modes);
  for (int e = 1; e < points; ++e) {
    const int rank = 1 + e % 6;
    Eigen::MatrixXd left(6, rank), right(rank, modes);
    for (Eigen::Index i = 0; i < left.size(); ++i) left.data()[i] = 1e6 * g(rng);
    for (Eigen::Index i = 0; i < right.size(); ++i) right.data()[i] = g(rng);
    stressModes.block(6 * e, 0, 6, modes) = left * right;
  }
  const Eigen::VectorXd scales = Eigen::VectorXd::LinSpaced(modes, 1, modes).cwiseInverse();
  const StressBounds bounds = stressModeBounds(stressModes, modes, scales);
  const Eigen::Matrix<double, 6, 1> d = (Eigen::Matrix<double, 6, 1>() << 1, 1, 1, std::sqrt(2.0), std::sqrt(2.0), std::sqrt(2.0)).finished();
  EXPECT_EQ(bounds.spectralNorms[0], 0.0);
  double worst = 1.0;
  for (int e = 1; e < points; ++e) {
    const Eigen::MatrixXd a = d.asDiagonal() * stressModes.block(6 * e, 0, 6, modes) * scales.asDiagonal();
    const double exact = Eigen::JacobiSVD<Eigen::MatrixXd>(a).singularValues()[0];
    EXPECT_GE(bounds.spectralNorms[e], exact) << "point " << e;
    EXPECT_LE(bounds.spectralNorms[e], std::pow(6.0, 1.0 / 32.0) * exact * (1 + 1e-12)) << "point " << e;
    worst = std::max(worst, bounds.spectralNorms[e] / exact);
    for (int r : {1, 7, modes}) {  // any first r modes: ‖D S_e q‖ ≤ bound · ‖W⁻¹ q‖
      Eigen::VectorXd q(r);
      for (Eigen::Index i = 0; i < r; ++i) q[i] = g(rng);
      const double stress = (d.asDiagonal() * stressModes.block(6 * e, 0, 6, r) * q).norm();
      EXPECT_LE(stress, bounds.spectralNorms[e] * (scales.head(r).cwiseInverse().asDiagonal() * q).norm()) << e << ", " << r;
    }
  }
  EXPECT_GT(worst, 1.0);  // the bound is not the exact norm by accident
  // The split: each mode's mean normal stress and its deviator's norm; the deviator's spectral
  // norm bounded as the whole block's.
  ASSERT_EQ(bounds.pressureModes.rows(), points);
  const Eigen::Matrix<double, 6, 1> mode = stressModes.block(30, 3, 6, 1);
  const double pressure = (mode[0] + mode[1] + mode[2]) / 3.0;
  EXPECT_NEAR(bounds.pressureModes(5, 3), pressure, 1e-9 * std::abs(pressure));
  Eigen::Matrix<double, 6, 1> deviator = d.asDiagonal() * mode;
  deviator.head<3>().array() -= pressure;
  EXPECT_NEAR(bounds.deviatorNorms(5, 3), deviator.norm(), 1e-9 * deviator.norm());
  EXPECT_EQ(bounds.deviatorSpectralNorms[0], 0.0);
  for (int e = 1; e < points; ++e) {
    Eigen::MatrixXd a = d.asDiagonal() * stressModes.block(6 * e, 0, 6, modes);
    const Eigen::RowVectorXd p = a.topRows(3).colwise().sum() / 3.0;
    a.topRows(3).rowwise() -= p;
    a = a * scales.asDiagonal();
    const double exact = Eigen::JacobiSVD<Eigen::MatrixXd>(a).singularValues()[0];
    EXPECT_GE(bounds.deviatorSpectralNorms[e], exact) << "point " << e;
    EXPECT_LE(bounds.deviatorSpectralNorms[e], std::pow(6.0, 1.0 / 32.0) * exact * (1 + 1e-9)) << "point " << e;
  }
}

TEST(CrackPropagation, P1PointsGroupByNodeClustersAndP2PointsByCorner) {
  // P1: a key (a cluster's first node) is the lowest node of its cluster, each element's lowest
  // node is its key or shares a tet with it, a key's own elements are in its cluster, a cluster
  // holds at most 16 elements (or its first node's own, if more), and there are far fewer groups
  // than lowest nodes (grouping by lowest node alone fails that). P2: each corner's own node.
  for (const auto& [nx, ny, nz] : {std::tuple{8, 8, 2}, std::tuple{5, 3, 4}}) {
    const TetMesh mesh = testing::makeBoxTetMesh(0.2, 0.2, 0.05, nx, ny, nz);
    const Eigen::Index t = mesh.tets.rows(), n = mesh.nodes.rows();
    SCOPED_TRACE(::testing::Message() << t << " tets");
    std::vector<std::vector<bool>> adjacent(static_cast<size_t>(n), std::vector<bool>(static_cast<size_t>(n), false));
    for (Eigen::Index e = 0; e < t; ++e) {
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) adjacent[static_cast<size_t>(mesh.tets(e, a))][static_cast<size_t>(mesh.tets(e, b))] = true;
      }
    }
    const std::vector<int32_t> keys = stressPointNodes(mesh.tets, 1);
    ASSERT_EQ(keys.size(), static_cast<size_t>(t));
    std::vector<bool> isKey(static_cast<size_t>(n), false), isLowest(static_cast<size_t>(n), false);
    for (Eigen::Index e = 0; e < t; ++e) {
      const int32_t key = keys[static_cast<size_t>(e)], lowest = mesh.tets.row(e).minCoeff();
      ASSERT_GE(key, 0);
      ASSERT_LT(key, n);
      EXPECT_LE(key, lowest) << "element " << e;
      EXPECT_TRUE(adjacent[static_cast<size_t>(key)][static_cast<size_t>(lowest)]) << "element " << e;
      isKey[static_cast<size_t>(key)] = true;
      isLowest[static_cast<size_t>(lowest)] = true;
    }
    for (Eigen::Index e = 0; e < t; ++e) {  // a key's own elements are in its cluster
      const int32_t lowest = mesh.tets.row(e).minCoeff();
      if (isKey[static_cast<size_t>(lowest)]) {
        EXPECT_EQ(keys[static_cast<size_t>(e)], lowest) << "element " << e;
      }
    }
    std::vector<int> clusterSize(static_cast<size_t>(n), 0), ownSize(static_cast<size_t>(n), 0);
    for (Eigen::Index e = 0; e < t; ++e) {
      ++clusterSize[static_cast<size_t>(keys[static_cast<size_t>(e)])];
      ++ownSize[static_cast<size_t>(mesh.tets.row(e).minCoeff())];
    }
    int keyCount = 0, lowestCount = 0;
    for (Eigen::Index u = 0; u < n; ++u) {
      keyCount += isKey[static_cast<size_t>(u)];
      lowestCount += isLowest[static_cast<size_t>(u)];
      EXPECT_LE(clusterSize[static_cast<size_t>(u)], std::max(16, ownSize[static_cast<size_t>(u)])) << "cluster " << u;
    }
    EXPECT_LT(3 * keyCount, 2 * lowestCount) << keyCount << " groups";
    EXPECT_EQ(stressPointNodes(mesh.tets, 1), keys);  // the same on every call
    const std::vector<int32_t> corners = stressPointNodes(mesh.tets, 4);
    ASSERT_EQ(corners.size(), static_cast<size_t>(4 * t));
    for (Eigen::Index e = 0; e < t; ++e) {
      for (int c = 0; c < 4; ++c) EXPECT_EQ(corners[static_cast<size_t>(4 * e + c)], mesh.tets(e, c));
    }
  }
}

TEST(CrackPropagation, ScanOfFourPointsPerElementNamesEachElementOnceByItsStrongestPoint) {
  // P2 stress modes (the 4 corners of each element): pruned equals full, the peak is the largest
  // σ₁ over every element's points, and the seeds are exactly the elements whose strongest point
  // reaches σ_t at the peak instant, each once, strongest first.
  constexpr int kPoints = 4;
  for (uint64_t rngSeed : {21u, 22u, 23u}) {
    SCOPED_TRACE(::testing::Message() << "seed " << rngSeed);
    std::mt19937_64 rng(rngSeed);
    std::normal_distribution<double> g(0.0, 1.0);
    const int elements = 120, modes = 6, instants = 20;
    MatrixXdRow stressModes(6 * kPoints * elements, modes);
    for (Eigen::Index i = 0; i < stressModes.size(); ++i) stressModes.data()[i] = 1e6 * g(rng);
    Eigen::MatrixXd q(instants, modes);
    for (Eigen::Index i = 0; i < q.size(); ++i) q.data()[i] = g(rng);
    Eigen::VectorXd staticStress(6 * kPoints * elements);
    for (Eigen::Index i = 0; i < staticStress.size(); ++i) staticStress[i] = 1e3 * g(rng);
    std::vector<double> force(instants);
    for (double& f : force) f = 100.0 * std::abs(g(rng));
    const StressBounds bounds = stressModeBounds(stressModes, modes);
    ASSERT_EQ(bounds.pressureModes.rows(), kPoints * elements);
    const double threshold = 3e6;
    const StressScan full = scanStresses(stressModes, bounds, q, staticStress, force, threshold, false, kPoints);
    const StressScan pruned = scanStresses(stressModes, bounds, q, staticStress, force, threshold, true, kPoints);
    EXPECT_EQ(pruned.peakPrincipalPa, full.peakPrincipalPa);
    EXPECT_EQ(pruned.peakElement, full.peakElement);
    EXPECT_EQ(pruned.peakInstant, full.peakInstant);
    ASSERT_GE(full.peakElement, 0);
    ASSERT_LT(full.peakElement, elements);

    StressField field{&stressModes, q.row(full.peakInstant).transpose(), &staticStress,
                      force[static_cast<size_t>(full.peakInstant)], kPoints};
    auto strongest = [&](int e) {  // the definition: the largest σ₁ over the element's points
      double best = -std::numeric_limits<double>::infinity();
      for (int c = 0; c < kPoints; ++c) best = std::max(best, maxPrincipalStress(field.atPoint(kPoints * e + c)));
      return best;
    };
    const double peak = full.peakPrincipalPa;
    EXPECT_NEAR(strongest(full.peakElement), peak, 1e-12 * peak);
    EXPECT_NEAR(maxPrincipalStress(field.at(full.peakElement)), peak, 1e-12 * peak);
    std::vector<int32_t> expected;
    for (int e = 0; e < elements; ++e)
      if (strongest(e) >= threshold) expected.push_back(e);
    EXPECT_EQ(orderedSeeds(pruned, field), full.seeds);  // each element once, as in the full scan
    std::vector<int32_t> seeds = full.seeds;
    ASSERT_FALSE(seeds.empty());
    for (size_t i = 1; i < seeds.size(); ++i) EXPECT_LE(strongest(seeds[i]), strongest(seeds[i - 1]) * (1 + 1e-12));
    std::sort(seeds.begin(), seeds.end());
    EXPECT_EQ(std::adjacent_find(seeds.begin(), seeds.end()), seeds.end()) << "an element seeded twice";
    EXPECT_EQ(seeds, expected);
  }
}

TEST(CrackPropagation, AnElementsStressIsItsStrongestPointTheFirstOfEquals) {
  // StressField::at solves its points' eigenproblems in order of their split bounds and leaves out
  // those that cannot win: the answer must be the point that solving every one in order gives,
  // bit for bit. Random corners, then ties and uniaxial stresses (where the split bound is tight).
  constexpr int kPoints = 4;
  auto firstStrongest = [](const StressField& field, int e) {
    Voigt best = field.atPoint(kPoints * e);
    double bestS1 = maxPrincipalStress(best);
    for (int c = 1; c < kPoints; ++c) {
      const Voigt s = field.atPoint(kPoints * e + c);
      if (const double s1 = maxPrincipalStress(s); s1 > bestS1) {
        best = s;
        bestS1 = s1;
      }
    }
    return best;
  };
  std::mt19937_64 rng(31);
  std::normal_distribution<double> g(0.0, 1.0);
  const int random = 300, crafted = 8, elements = random + crafted, modes = 3;
  MatrixXdRow stressModes(6 * kPoints * elements, modes);
  for (Eigen::Index i = 0; i < stressModes.size(); ++i) stressModes.data()[i] = 1e6 * g(rng);
  auto setPoint = [&](int e, int c, const Voigt& s) {  // σ = s at q = (1, 0, 0)
    stressModes.block(6 * (kPoints * e + c), 0, 6, modes).setZero();
    stressModes.block<6, 1>(6 * (kPoints * e + c), 0) = s;
  };
  const Voigt uniaxial = (Voigt() << 7e6, 0, 0, 0, 0, 0).finished();
  const Voigt alongY = (Voigt() << 0, 7e6, 0, 0, 0, 0).finished(), alongZ = (Voigt() << 0, 0, 7e6, 0, 0, 0).finished();
  const Voigt shear = (Voigt() << 0, 0, 0, 7e6, 0, 0).finished();
  const Voigt weaker = (Voigt() << 1e6, -2e6, 0.5e6, 0, 0.1e6, 0).finished();
  const Voigt pattern[crafted][kPoints] = {
      {uniaxial, uniaxial, uniaxial, uniaxial},  // all equal: the first
      {weaker, uniaxial, weaker, uniaxial},      // two equal strongest: the first of them
      {weaker, weaker, weaker, uniaxial},        // the last alone
      {shear, uniaxial, shear, weaker},          // σ₁ equal, split bounds not
      {uniaxial * (1.0 - 1e-15), uniaxial, uniaxial * (1.0 - 1e-15), weaker},
      {weaker, weaker, weaker, weaker},
      {alongY, uniaxial, alongZ, weaker},        // the same σ₁ in other directions: the first
      {weaker, alongZ, weaker, alongY},
  };
  for (int k = 0; k < crafted; ++k) {
    for (int c = 0; c < kPoints; ++c) setPoint(random + k, c, pattern[k][c]);
  }
  ASSERT_EQ(maxPrincipalStress(alongY), maxPrincipalStress(uniaxial));  // ties that the choice sees
  ASSERT_EQ(maxPrincipalStress(alongZ), maxPrincipalStress(uniaxial));
  for (const Eigen::Vector3d& qValues : {Eigen::Vector3d(1.0, 0.0, 0.0), Eigen::Vector3d(0.3, -1.2, 0.8)}) {
    const StressField field{&stressModes, qValues, nullptr, 0.0, kPoints};
    for (int e = 0; e < elements; ++e) {
      SCOPED_TRACE(::testing::Message() << "element " << e << ", q " << qValues.transpose());
      const Voigt expected = firstStrongest(field, e), got = field.at(e);
      EXPECT_EQ(std::memcmp(expected.data(), got.data(), sizeof(double) * 6), 0);
    }
  }
}

// A uniform tension σ_xx along a box of 8 × 2 × 2 cells (0.05 m each): every element is a seed
// and the principal direction is x everywhere, so one crack (maxCracks = 1, no noise) grows along
// the plane x = 0.0375 through the centroid of element 0 and costs G_c × 0.1 × 0.1 m² to cross the
// bar.
struct UniformTension {
  static constexpr double kTensionPa = 60e6, kStrengthPa = 45e6, kGcJPerM2 = 8.0, kCrossSectionM2 = 0.1 * 0.1;
  static constexpr double kCellSectionM2 = 0.05 * 0.05;  // bounds the section of one tet
  static constexpr double kPlaneX = 0.75 * 0.05;
  TetMesh mesh = testing::makeBoxTetMesh(0.4, 0.1, 0.1, 8, 2, 2);
  TetTopology topo = buildTetTopology(mesh).value();
  MatrixXdRow stressModes = MatrixXdRow::Zero(6 * mesh.tets.rows(), 1);
  Eigen::MatrixXd q = Eigen::MatrixXd::Constant(1, 1, kTensionPa);
  StressScan scan;
  StressField field;
  CrackSettings settings;

  UniformTension() {
    for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) stressModes(6 * e, 0) = 1.0;  // σ_xx per unit q
    scan = scanStresses(stressModes, stressModeBounds(stressModes, 1), q, Eigen::VectorXd(), {0.0}, kStrengthPa, true);
    field.stressModes = &stressModes;
    field.q = q.row(0).transpose();
    settings.maxCracks = 1;
    settings.noiseRad = 0.0;
    settings.minFragmentNodes = 1;
  }
  Result<FractureState> grow(double budgetJ) const {
    return propagateCracks(mesh, topo, scan, field, kStrengthPa, kGcJPerM2, budgetJ, settings);
  }
};

TEST(CrackPropagation, EnoughEnergyRunsTheCrackThroughTheBar) {
  const UniformTension c;
  const std::vector<int32_t> seeds = orderedSeeds(c.scan, c.field);
  ASSERT_EQ(seeds.size(), static_cast<size_t>(c.mesh.tets.rows()));
  ASSERT_EQ(seeds.front(), 0);
  auto r = c.grow(1.0);  // 12 times what crossing the bar costs
  ASSERT_TRUE(r) << r.error().message;
  const FractureState& s = r.value();
  EXPECT_FALSE(s.arrestedByEnergy);
  EXPECT_EQ(s.crackCount, 1);
  EXPECT_EQ(s.energyBudgetJ, 1.0);
  EXPECT_NEAR(s.crackAreaM2, UniformTension::kCrossSectionM2, 1e-12 * UniformTension::kCrossSectionM2);
  EXPECT_NEAR(s.energySpentJ, UniformTension::kGcJPerM2 * s.crackAreaM2, 1e-12 * s.energySpentJ);
  // Two pieces, split at the plane: the nodes at x = 0 and the rest.
  ASSERT_EQ(s.fragmentCount, 2);
  for (Eigen::Index i = 0; i < c.mesh.nodes.rows(); ++i) {
    EXPECT_EQ(s.nodeLabels[i], c.mesh.nodes(i, 0) < UniformTension::kPlaneX ? 0 : 1) << "node " << i;
  }
  // Every cut edge crosses the plane, at the point where it does.
  for (Eigen::Index e = 0; e < c.topo.edges.rows(); ++e) {
    const double a = c.mesh.nodes(c.topo.edges(e, 0), 0) - UniformTension::kPlaneX;
    const double b = c.mesh.nodes(c.topo.edges(e, 1), 0) - UniformTension::kPlaneX;
    if ((a < 0) == (b < 0)) {
      EXPECT_TRUE(std::isnan(s.edgeCuts[e])) << "edge " << e;
    } else {
      EXPECT_NEAR(s.edgeCuts[e], a / (a - b), 1e-12) << "edge " << e;
    }
  }
}

TEST(CrackPropagation, GriffithStopSpendsNoMoreThanTheBudget) {
  const UniformTension c;
  const double full = UniformTension::kGcJPerM2 * UniformTension::kCrossSectionM2;
  const double oneCut = UniformTension::kGcJPerM2 * UniformTension::kCellSectionM2;  // > any one element's cost
  const FractureState through = c.grow(2.0 * full).value();
  ASSERT_FALSE(through.arrestedByEnergy);
  double lastArea = -1.0, lastBudget = 0.0;
  bool lastArrested = true;
  for (double fraction : {0.0, 0.05, 0.3, 0.6, 0.9, 0.999, 1.5}) {
    SCOPED_TRACE(fraction);
    const double budget = fraction * full;
    auto r = c.grow(budget);
    ASSERT_TRUE(r) << r.error().message;
    const FractureState& s = r.value();
    EXPECT_LE(s.energySpentJ, budget);
    EXPECT_NEAR(s.energySpentJ, UniformTension::kGcJPerM2 * s.crackAreaM2, 1e-12 * full);
    if (fraction < 1.0) {
      // Stopped by the energy, by the cut that would have overspent it: less than one element's
      // cost is left.
      EXPECT_TRUE(s.arrestedByEnergy);
      EXPECT_LT(budget - s.energySpentJ, oneCut);
      EXPECT_LT(s.crackAreaM2, UniformTension::kCrossSectionM2);
      if (fraction <= 0.6) {
        EXPECT_EQ(s.fragmentCount, 1) << "a crack stopped halfway leaves the bar whole";
      }
    } else {
      EXPECT_FALSE(s.arrestedByEnergy);
      EXPECT_NEAR(s.crackAreaM2, UniformTension::kCrossSectionM2, 1e-12 * UniformTension::kCrossSectionM2);
      EXPECT_EQ(s.fragmentCount, 2);
    }
    if (fraction == 0.0) {
      EXPECT_EQ(s.crackAreaM2, 0.0);
      EXPECT_EQ(s.crackCount, 0);
      EXPECT_TRUE(s.cutElements.empty());
      EXPECT_TRUE(s.edgeCuts.array().isNaN().all());
    }
    // More energy, more crack: once the budget has grown by more than any one element costs, an
    // arrested crack gets at least one more element. The crack grows in the same order whatever
    // the budget: a smaller one's cuts come first.
    if (lastArrested && budget - lastBudget >= oneCut) {
      EXPECT_GT(s.crackAreaM2, lastArea);
    } else {
      EXPECT_GE(s.crackAreaM2, lastArea);
    }
    lastArea = s.crackAreaM2;
    lastBudget = budget;
    lastArrested = s.arrestedByEnergy;
    ASSERT_LE(s.cutElements.size(), through.cutElements.size());
    EXPECT_TRUE(std::equal(s.cutElements.begin(), s.cutElements.end(), through.cutElements.begin()));
  }
}

TEST(CrackPropagation, CrumbsACrackCutsOffAreMergedBack) {
  // The crack through the bar cuts off the 3 × 3 nodes at x = 0: a fragment of 9 nodes.
  UniformTension c;
  c.settings.minFragmentNodes = 9;
  const FractureState kept = c.grow(1.0).value();
  EXPECT_EQ(kept.fragmentCount, 2);
  EXPECT_EQ(kept.mergedCrumbs, 0);
  c.settings.minFragmentNodes = 10;
  const FractureState merged = c.grow(1.0).value();
  EXPECT_EQ(merged.fragmentCount, 1);
  EXPECT_EQ(merged.mergedCrumbs, 1);
  EXPECT_TRUE(merged.edgeCuts.array().isNaN().all()) << "the edges between them are whole again";
  EXPECT_TRUE((merged.nodeLabels.array() == 0).all());
  EXPECT_EQ(merged.crackAreaM2, kept.crackAreaM2);  // the energy was spent all the same
}

// Two straight cracks in a plate of 8 × 8 × 1 cells: one started by σ_xx at (0.13, 0.05) (the
// plane x = its seed's centroid x), one by σ_yy at (0.33, 0.23) (y = its centroid y), and a weak
// tension elsewhere, so that both run until the plate's edges (no noise, no turn towards the local
// direction). Crossing, they cut the plate into four; where cracks end at cracks, the one that
// reaches the other's sheet second ends on it, a T-junction, and makes three. Either way one
// plane runs whole: no label spans it.
TEST(CrackPropagation, CracksEndingAtCracksMakeJunctionsWhereCrossingCracksMakeFourPieces) {
  const TetMesh mesh = testing::makeBoxTetMesh(0.4, 0.4, 0.05, 8, 8, 1);
  const TetTopology topo = buildTetTopology(mesh).value();
  const Eigen::Index t = mesh.tets.rows();
  auto centroid = [&](Eigen::Index e) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int i = 0; i < 4; ++i) c += 0.25 * mesh.nodes.row(mesh.tets(e, i)).transpose();
    return c;
  };
  auto nearest = [&](const Eigen::Vector3d& p) {
    Eigen::Index best = 0;
    for (Eigen::Index e = 1; e < t; ++e) {
      if ((centroid(e) - p).norm() < (centroid(best) - p).norm()) best = e;
    }
    return best;
  };
  const Eigen::Index a = nearest({0.13, 0.05, 0.025}), b = nearest({0.33, 0.23, 0.025});
  const double planeX = centroid(a).x(), planeY = centroid(b).y();
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) {  // no node on either plane
    ASSERT_GT(std::abs(mesh.nodes(i, 0) - planeX), 1e-6);
    ASSERT_GT(std::abs(mesh.nodes(i, 1) - planeY), 1e-6);
  }
  MatrixXdRow stressModes = MatrixXdRow::Zero(6 * t, 1);
  for (Eigen::Index e = 0; e < t; ++e) stressModes.block(6 * e, 0, 3, 1).setConstant(1e6);  // 1 MPa, isotropic
  stressModes(6 * a, 0) = 60e6;      // σ_xx
  stressModes(6 * b + 1, 0) = 50e6;  // σ_yy
  const Eigen::MatrixXd q = Eigen::MatrixXd::Ones(1, 1);
  const double strengthPa = 45e6;
  const StressScan scan = scanStresses(stressModes, stressModeBounds(stressModes, 1), q, Eigen::VectorXd(), {0.0}, strengthPa, true);
  StressField field;
  field.stressModes = &stressModes;
  field.q = q.row(0).transpose();
  CrackSettings settings;
  settings.maxCracks = 2;
  settings.noiseRad = 0.0;
  settings.directionBlend = 1.0;
  settings.minFragmentNodes = 1;
  // The side of each plane every fragment's nodes are on: {label: sides seen}, 1 below, 2 above.
  auto sides = [&](const FractureState& s, int axis, double plane) {
    std::map<int, int> seen;
    for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) seen[s.nodeLabels[i]] |= mesh.nodes(i, axis) < plane ? 1 : 2;
    return seen;
  };
  auto spans = [](const std::map<int, int>& seen) {
    return std::count_if(seen.begin(), seen.end(), [](const auto& kv) { return kv.second == 3; });
  };
  const FractureState crossing = propagateCracks(mesh, topo, scan, field, strengthPa, 8.0, 1e6, settings).value();
  ASSERT_EQ(crossing.crackCount, 2);
  EXPECT_EQ(crossing.fragmentCount, 4);
  EXPECT_EQ(spans(sides(crossing, 0, planeX)), 0);
  EXPECT_EQ(spans(sides(crossing, 1, planeY)), 0);
  settings.endAtCracks = true;
  CrackWorkspace workspace;
  FractureState ending;
  ASSERT_TRUE(propagateCracks(mesh, topo, scan, field, strengthPa, 8.0, 1e6, settings, workspace, ending));
  ASSERT_EQ(ending.crackCount, 2);
  // The crack that ends cuts the elements where it meets the other's sheet, so the two join
  // without a gap: some elements are cut by both (cutBy: cracks × #T).
  ASSERT_EQ(workspace.cutBy.size(), 2 * static_cast<size_t>(t));
  int both = 0;
  for (Eigen::Index e = 0; e < t; ++e) both += workspace.cutBy[static_cast<size_t>(e)] && workspace.cutBy[static_cast<size_t>(t + e)];
  EXPECT_GT(both, 0);
  EXPECT_EQ(ending.fragmentCount, 3);
  const auto spansX = spans(sides(ending, 0, planeX)), spansY = spans(sides(ending, 1, planeY));
  EXPECT_EQ(std::min(spansX, spansY), 0) << "one sheet runs whole";
  EXPECT_EQ(std::max(spansX, spansY), 1) << "the other ends on it: one piece lies on both of its sides";
  EXPECT_FALSE(ending.arrestedByEnergy);
  EXPECT_LT(ending.crackAreaM2, crossing.crackAreaM2);
  EXPECT_LT(ending.cutElements.size(), crossing.cutElements.size());
  // Every cut element of the junction's result is one the crossing cracks cut too, and the
  // junction keeps its seeds' elements.
  const auto cut = [](const FractureState& s, Eigen::Index e) {
    return std::find(s.cutElements.begin(), s.cutElements.end(), static_cast<int32_t>(e)) != s.cutElements.end();
  };
  for (int32_t e : ending.cutElements) EXPECT_TRUE(cut(crossing, e)) << e;
  EXPECT_TRUE(cut(ending, a));
  EXPECT_TRUE(cut(ending, b));
}

TEST(CrackPropagation, ACrumbJoinsTheFragmentItWasCutFrom) {
  // A 0.4 × 0.2 × 0.2 m box of 4 × 2 × 2 cells (node (i, j, k) = i + 5 (j + 3 k)) cut by the plane
  // x = 0.25 into 27 and 18 nodes, and its corner node 44 = (0.4, 0.2, 0.2) chipped off alone.
  const TetMesh box = testing::makeBoxTetMesh(0.4, 0.2, 0.2, 4, 2, 2);
  const TetTopology topo = buildTetTopology(box).value();
  Eigen::VectorXd cuts = Eigen::VectorXd::Constant(topo.edges.rows(), std::numeric_limits<double>::quiet_NaN());
  int planeCuts = 0;
  for (Eigen::Index e = 0; e < topo.edges.rows(); ++e) {
    const int32_t a = topo.edges(e, 0), b = topo.edges(e, 1);
    if ((box.nodes(a, 0) < 0.25) != (box.nodes(b, 0) < 0.25)) {
      cuts[e] = 0.5;
      ++planeCuts;
    } else if (a == 44 || b == 44) {
      cuts[e] = 0.5;
    }
  }
  Eigen::VectorXi labels;
  int count = labelFragments(topo, cuts, box.nodes.rows(), labels);
  ASSERT_EQ(count, 3);
  EXPECT_EQ(labels[0], 0);
  EXPECT_EQ(labels[3], 1);  // the lowest node right of the plane
  EXPECT_EQ(labels[44], 2);
  // Below 8 nodes: the chip goes back to the right part, the only one it touches.
  Eigen::VectorXd chipped = cuts;
  EXPECT_EQ(mergeCrumbs(topo, 8, chipped, labels, count), 1);
  ASSERT_EQ(count, 2);
  EXPECT_EQ(labels[44], labels[3]);
  EXPECT_EQ((labels.array() == 0).count(), 27);
  EXPECT_EQ((labels.array() == 1).count(), 18);
  EXPECT_EQ(chipped.size() - chipped.array().isNaN().count(), planeCuts) << "only the plane's cuts are left";
  // Below 20 nodes the right part is a crumb as well, and joins the left one.
  EXPECT_EQ(mergeCrumbs(topo, 20, chipped, labels, count), 1);
  EXPECT_EQ(count, 1);
  EXPECT_TRUE((labels.array() == 0).all());
  EXPECT_TRUE(chipped.array().isNaN().all());
  // A mesh that is a single fragment has nothing to merge, however large minNodes is.
  EXPECT_EQ(mergeCrumbs(topo, 1000, chipped, labels, count), 0);
  EXPECT_EQ(count, 1);
}

// Growth runs on the caller's thread whatever its arena holds (a helper that computed stresses
// ahead on a second thread was removed: it no longer paid), so the fracture is the same bits in an
// arena of one, two or four threads: on a random field of quadratic-element corners, several noisy
// cracks.
TEST(CrackPropagation, GrowthIsTheSameBitsInAnArenaOfAnySize) {
  const TetMesh mesh = testing::makeBoxTetMesh(0.4, 0.2, 0.2, 10, 5, 5);
  const TetTopology topo = buildTetTopology(mesh).value();
  constexpr int kPoints = 4, kModes = 8;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  MatrixXdRow stressModes(6 * kPoints * mesh.tets.rows(), kModes);
  for (Eigen::Index i = 0; i < stressModes.size(); ++i) stressModes.data()[i] = g(rng);
  Eigen::MatrixXd q(1, kModes);
  for (int j = 0; j < kModes; ++j) q(0, j) = 20e6 * (1.0 + 0.2 * g(rng));
  const double strengthPa = 40e6;
  const StressScan scan = scanStresses(stressModes, stressModeBounds(stressModes, kModes), q, Eigen::VectorXd(), {0.0},
                                       strengthPa, true, kPoints);
  ASSERT_TRUE(scan.hasSeeds());
  StressField field;
  field.stressModes = &stressModes;
  field.pointsPerElement = kPoints;
  field.q = q.row(0).transpose();
  CrackSettings settings;
  settings.maxCracks = 4;
  settings.seed = 5;
  auto growOn = [&](int threads) {
    FractureState state;
    CrackWorkspace workspace;
    tbb::task_arena arena(threads);
    Status status = Ok{};
    arena.execute([&] { status = propagateCracks(mesh, topo, scan, field, strengthPa, 8.0, 5.0, settings, workspace, state); });
    EXPECT_TRUE(status) << status.error().message;
    return state;
  };
  const FractureState one = growOn(1);
  ASSERT_GT(one.cutElements.size(), 100u) << "the cracks should run far";
  ASSERT_GE(one.fragmentCount, 2);
  for (int threads : {2, 4}) {
    SCOPED_TRACE(threads);
    const FractureState other = growOn(threads);
    EXPECT_EQ(other.cutElements, one.cutElements);
    ASSERT_EQ(other.edgeCuts.size(), one.edgeCuts.size());
    EXPECT_EQ(std::memcmp(other.edgeCuts.data(), one.edgeCuts.data(), sizeof(double) * static_cast<size_t>(one.edgeCuts.size())), 0);
    EXPECT_EQ(other.nodeLabels, one.nodeLabels);
    EXPECT_EQ(other.fragmentCount, one.fragmentCount);
    EXPECT_EQ(other.crackCount, one.crackCount);
    EXPECT_EQ(other.energySpentJ, one.energySpentJ);
    EXPECT_EQ(other.crackAreaM2, one.crackAreaM2);
  }
}

// A result's fracture arrays handed back to the workspace (CrackWorkspace::recycle, as the World
// does with a reused result) are the next growth's storage: the same fracture, in the same memory,
// and the state left empty in between, as clear() leaves it.
TEST(CrackPropagation, ARecycledStateGrowsInItsOldStorage) {
  const TetMesh mesh = testing::makeBoxTetMesh(0.4, 0.2, 0.2, 8, 4, 4);
  const TetTopology topo = buildTetTopology(mesh).value();
  constexpr int kModes = 6;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  MatrixXdRow stressModes(6 * mesh.tets.rows(), kModes);
  for (Eigen::Index i = 0; i < stressModes.size(); ++i) stressModes.data()[i] = g(rng);
  Eigen::MatrixXd q(1, kModes);
  for (int j = 0; j < kModes; ++j) q(0, j) = 20e6 * (1.0 + 0.2 * g(rng));
  const double strengthPa = 30e6;
  const StressScan scan = scanStresses(stressModes, stressModeBounds(stressModes, kModes), q, Eigen::VectorXd(), {0.0},
                                       strengthPa, true, 1);
  ASSERT_TRUE(scan.hasSeeds());
  StressField field;
  field.stressModes = &stressModes;
  field.q = q.row(0).transpose();
  CrackSettings settings;
  settings.maxCracks = 3;
  CrackWorkspace workspace;
  FractureState state;
  ASSERT_TRUE(propagateCracks(mesh, topo, scan, field, strengthPa, 8.0, 5.0, settings, workspace, state));
  ASSERT_GE(state.fragmentCount, 2);
  const FractureState first = state;
  const double* cuts = state.edgeCuts.data();
  const int* labels = state.nodeLabels.data();
  workspace.recycle(state);
  EXPECT_EQ(state.edgeCuts.size(), 0);
  EXPECT_EQ(state.nodeLabels.size(), 0);
  // The spares hold the storage meanwhile, so it cannot be freed and handed out again by malloc:
  // the pointers below are equal only if growth took the spares.
  EXPECT_EQ(workspace.spareEdgeCuts.data(), cuts);
  EXPECT_EQ(workspace.spareNodeLabels.data(), labels);
  ASSERT_TRUE(propagateCracks(mesh, topo, scan, field, strengthPa, 8.0, 5.0, settings, workspace, state));
  EXPECT_EQ(workspace.spareEdgeCuts.size(), 0) << "growth left the spares where they were";
  EXPECT_EQ(state.edgeCuts.data(), cuts) << "the edge cuts were allocated again";
  EXPECT_EQ(state.nodeLabels.data(), labels) << "the node labels were allocated again";
  ASSERT_EQ(state.edgeCuts.size(), first.edgeCuts.size());
  EXPECT_EQ(std::memcmp(state.edgeCuts.data(), first.edgeCuts.data(), sizeof(double) * static_cast<size_t>(first.edgeCuts.size())), 0);
  EXPECT_EQ(state.nodeLabels, first.nodeLabels);
  EXPECT_EQ(state.cutElements, first.cutElements);
  EXPECT_EQ(state.fragmentCount, first.fragmentCount);
}

TEST(CrackPropagation, BadSettingsAndMaterialValuesGiveTypedErrors) {
  const UniformTension c;
  // True when the growth is refused with InvalidArgument.
  auto refused = [&](double strengthPa, double gc, double budget, const CrackSettings& settings) {
    auto r = propagateCracks(c.mesh, c.topo, c.scan, c.field, strengthPa, gc, budget, settings);
    return !r && r.error().code == ErrorCode::InvalidArgument;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const double s = UniformTension::kStrengthPa, gc = UniformTension::kGcJPerM2;
  EXPECT_FALSE(refused(s, gc, 1.0, c.settings));
  EXPECT_TRUE(refused(0.0, gc, 1.0, c.settings));
  EXPECT_TRUE(refused(nan, gc, 1.0, c.settings));
  EXPECT_TRUE(refused(s, 0.0, 1.0, c.settings));
  EXPECT_TRUE(refused(s, -gc, 1.0, c.settings));
  EXPECT_TRUE(refused(s, gc, inf, c.settings));
  EXPECT_TRUE(refused(s, gc, nan, c.settings));
  for (auto broken : std::initializer_list<void (*)(CrackSettings&)>{
           [](CrackSettings& x) { x.maxCracks = -1; }, [](CrackSettings& x) { x.directionBlend = 1.5; },
           [](CrackSettings& x) { x.directionBlend = -0.1; }, [](CrackSettings& x) { x.noiseRad = -0.1; },
           [](CrackSettings& x) { x.propagationStressRatio = std::numeric_limits<double>::quiet_NaN(); }}) {
    CrackSettings bad = c.settings;
    broken(bad);
    EXPECT_TRUE(refused(s, gc, 1.0, bad));
  }
}

}  // namespace
}  // namespace brittle

// Crack propagation's building blocks: crumb merging against the one-merge-at-a-time definition,
// and the pruned stress scan against the full one.
#include "brittle/runtime/CrackPropagation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

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

TEST(CrackPropagation, PrunedScanEqualsTheFullScanOnRandomFields) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const int elements = 200, modes = 8, instants = 30;
    MatrixXdRow stressModes(6 * elements, modes);
    for (Eigen::Index i = 0; i < stressModes.size(); ++i) stressModes.data()[i] = 1e6 * g(rng);
    Eigen::MatrixXd q(instants, modes);
    for (Eigen::Index i = 0; i < q.size(); ++i) q.data()[i] = g(rng);
    Eigen::VectorXd staticStress(6 * elements);
    for (Eigen::Index i = 0; i < staticStress.size(); ++i) staticStress[i] = 1e3 * g(rng);
    std::vector<double> force(instants);
    for (double& f : force) f = 100.0 * std::abs(g(rng));
    const Eigen::MatrixXd bounds = stressModeBounds(stressModes, modes);
    const double threshold = 2.5e6 + 1e5 * trial;
    const StressScan full = scanStresses(stressModes, bounds, q, staticStress, force, threshold, false);
    const StressScan pruned = scanStresses(stressModes, bounds, q, staticStress, force, threshold, true);
    EXPECT_EQ(pruned.peakPrincipalPa, full.peakPrincipalPa);
    EXPECT_EQ(pruned.peakElement, full.peakElement);
    EXPECT_EQ(pruned.peakInstant, full.peakInstant);
    EXPECT_EQ(pruned.seeds, full.seeds);
    EXPECT_LE(pruned.evaluations, full.evaluations);
  }
}

}  // namespace
}  // namespace brittle

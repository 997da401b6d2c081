// The exact path for fragments (FragmentModes.h): sub-meshes of whole tets, and the fragment's own
// modes against the bake's ARPACK solve, against Eigen's dense solver, and against beam theory.
#include "brittle/runtime/FragmentModes.h"

#include <gtest/gtest.h>

#include <array>

#include "brittle/precompute/ModalAnalysis.h"
#include "brittle/descriptors/MassProperties.h"
#include "brittle/runtime/FemAssembly.h"
#include "brittle/runtime/FragmentSurfaces.h"
#include "brittle/runtime/PolynomialModes.h"
#include "brittle/runtime/TetTopology.h"
#include "brittle/testing/BakeFixtures.h"

namespace brittle {
namespace {

using testing::presetGlass;

// The sub-mesh of `label`, with every crossed edge cut at `cut`.
Result<FragmentSubMesh> subMesh(const TetMesh& mesh, const Eigen::VectorXi& labels, int label, double cut = 0.5) {
  const TetTopology topology = buildTetTopology(mesh).value();
  return fragmentSubMesh(mesh, topology, labels, Eigen::VectorXd::Constant(topology.edges.rows(), cut), label);
}

double meshVolume(const TetMesh& mesh) {
  double v = 0.0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    const Eigen::Vector3d a = mesh.nodes.row(mesh.tets(t, 0));
    v += (Eigen::Vector3d(mesh.nodes.row(mesh.tets(t, 1))) - a)
             .dot((Eigen::Vector3d(mesh.nodes.row(mesh.tets(t, 2))) - a).cross(Eigen::Vector3d(mesh.nodes.row(mesh.tets(t, 3))) - a)) /
         6.0;
  }
  return v;
}

// Two 4 × 3 × 3-cell blocks of 1 cm cells joined by a neck of one cell: a piece that hangs on a thin
// neck, as runtime fragments do. The unused nodes of the grid are dropped.
FragmentSubMesh dumbbell() {
  const TetMesh grid = testing::makeBoxTetMesh(0.09, 0.03, 0.03, 9, 3, 3);
  std::vector<Eigen::Index> kept;
  for (Eigen::Index t = 0; t < grid.tets.rows(); ++t) {
    const Eigen::Index cell = t / 6, i = cell % 9, j = (cell / 9) % 3, k = cell / 27;
    if (i != 4 || (j == 1 && k == 1)) kept.push_back(t);
  }
  std::vector<int> index(static_cast<size_t>(grid.nodes.rows()), -1);
  FragmentSubMesh sub;
  sub.mesh.tets.resize(static_cast<Eigen::Index>(kept.size()), 4);
  std::vector<Eigen::Index> nodes;
  for (size_t t = 0; t < kept.size(); ++t)
    for (int c = 0; c < 4; ++c) {
      const int n = grid.tets(kept[t], c);
      if (index[static_cast<size_t>(n)] < 0) {
        index[static_cast<size_t>(n)] = static_cast<int>(nodes.size());
        nodes.push_back(n);
      }
      sub.mesh.tets(static_cast<Eigen::Index>(t), c) = index[static_cast<size_t>(n)];
    }
  sub.mesh.nodes.resize(static_cast<Eigen::Index>(nodes.size()), 3);
  for (size_t n = 0; n < nodes.size(); ++n) sub.mesh.nodes.row(static_cast<Eigen::Index>(n)) = grid.nodes.row(nodes[n]);
  sub.wholeTets = sub.mesh.tets.rows();
  return sub;
}

// The polynomial Ritz values of a solid, its P2 frequencies on a mesh of it (the truth here), and
// the Ritz values corrected by the mesh's linear-tet ratios.
struct Corrected {
  Eigen::VectorXd ritz, truth, corrected;
  MeshFrequencyRatios ratios;
};
Corrected correct(const FragmentSubMesh& sub) {
  Corrected c;
  const TriangleMesh surface{sub.mesh.nodes, buildTetTopology(sub.mesh).value().boundaryTriangles};
  c.ritz = polynomialModes(surface, presetGlass(), 5, /*withShapes=*/false).value().frequenciesHz;
  ExactModesSettings es;
  es.modeCount = kMeshRatioModes;
  es.elementOrder = ElementOrder::P2;
  c.truth = exactFragmentAsset(sub, presetGlass(), es, "truth").value().modal.frequenciesHz;
  auto ratios = meshFrequencyRatios(sub, presetGlass(), 5, kMeshRatioModes);
  EXPECT_TRUE(ratios) << ratios.error().message;
  c.ratios = ratios.value();
  c.corrected = c.ritz;
  applyMeshRatios(c.corrected, c.ratios);
  return c;
}

// No polynomial of degree 5 swings one block about the neck, so the Ritz values are far above the
// dumbbell's own; the mesh's own linear-tet fields do, and their ratio to the polynomial fields on
// the same mesh brings the Ritz values most of the way down to the P2 truth (measured: Ritz 14.9k,
// truth 3.4k, corrected 5.2k Hz; the neck is one linear tet across, which still locks). On a
// compact block the ratios stay near 1 and the correction moves little (Ritz +1.0 %, corrected
// +0.7 %).
TEST(FragmentModes, TheMeshFindsTheHingeThePolynomialsMiss) {
  const Corrected hinge = correct(dumbbell());
  std::printf("dumbbell: Ritz %.0f %.0f %.0f, truth %.0f %.0f %.0f, ratios %.3f %.3f %.3f, corrected %.0f %.0f %.0f Hz\n",
              hinge.ritz[0], hinge.ritz[1], hinge.ritz[2], hinge.truth[0], hinge.truth[1], hinge.truth[2], hinge.ratios.ratios[0],
              hinge.ratios.ratios[1], hinge.ratios.ratios[2], hinge.corrected[0], hinge.corrected[1], hinge.corrected[2]);
  for (int k = 0; k < kMeshRatioModes; ++k) {
    EXPECT_GT(hinge.ratios.ratios[k], 0.0);
    EXPECT_LE(hinge.ratios.ratios[k], 1.0);
    EXPECT_NEAR(hinge.ratios.ratios[k], hinge.ratios.meshHz[k] / hinge.ratios.polynomialHz[k], 1e-12);
    EXPECT_GT(hinge.ritz[k], 3.0 * hinge.truth[k]) << k;
    EXPECT_LT(hinge.ratios.ratios[k], 0.5) << k;
    EXPECT_GE(hinge.corrected[k], hinge.truth[k]) << k;
    EXPECT_LT(hinge.corrected[k] - hinge.truth[k], 0.25 * (hinge.ritz[k] - hinge.truth[k])) << k;  // 4 times closer at least
  }
  const Corrected block = correct(FragmentSubMesh{testing::makeBoxTetMesh(0.06, 0.04, 0.03, 6, 4, 3), 144, 0, 0.0});
  std::printf("block: Ritz %.0f, truth %.0f, ratio %.3f, corrected %.0f Hz\n", block.ritz[0], block.truth[0], block.ratios.ratios[0],
              block.corrected[0]);
  for (int k = 0; k < kMeshRatioModes; ++k) {
    EXPECT_GT(block.ratios.ratios[k], 0.95) << k;
    EXPECT_NEAR(block.corrected[k] / block.truth[k], 1.0, 0.02) << k;
  }
}

// The check's own eigen solve takes the six rigid motions out of the Lanczos operator instead of
// computing them, and no eigenvectors: its frequencies are the exact path's on the same linear-tet
// mesh (which solves for all nine with vectors), on solids large enough for Lanczos (a block of
// 1 170 DOF and the dumbbell, above the dense solver's 240).
TEST(FragmentModes, TheChecksFrequenciesAreTheLinearMeshsOwn) {
  for (const FragmentSubMesh& sub : {FragmentSubMesh{testing::makeBoxTetMesh(0.12, 0.05, 0.04, 12, 5, 4), 0, 0, 0.0}, dumbbell()}) {
    ASSERT_GT(3 * sub.mesh.nodes.rows(), ExactModesSettings{}.denseMaxDof);
    auto ratios = meshFrequencyRatios(sub, presetGlass(), 5, kMeshRatioModes);
    ASSERT_TRUE(ratios) << ratios.error().message;
    ExactModesSettings es;
    es.modeCount = kMeshRatioModes;
    es.elementOrder = ElementOrder::P1;
    const Eigen::VectorXd own = exactFragmentAsset(sub, presetGlass(), es, "own").value().modal.frequenciesHz;
    for (int k = 0; k < kMeshRatioModes; ++k) EXPECT_NEAR(ratios.value().meshHz[k] / own[k], 1.0, 1e-9) << k;
  }
}

// In quadratic tets the check's own frequencies are the truth's here (the same P2 model on the same
// mesh), and the corrected Ritz values land within the polynomials' own error on that mesh of it:
// the hinge the linear tets still lock (5.2k Hz against 3.4k) is found.
TEST(FragmentModes, AQuadraticCheckFindsTheHingeUnlocked) {
  const FragmentSubMesh sub = dumbbell();
  const Corrected linear = correct(sub);
  auto ratios = meshFrequencyRatios(sub, presetGlass(), 5, kMeshRatioModes, ElementOrder::P2);
  ASSERT_TRUE(ratios) << ratios.error().message;
  Eigen::VectorXd corrected = linear.ritz;
  applyMeshRatios(corrected, ratios.value());
  for (int k = 0; k < kMeshRatioModes; ++k) {
    EXPECT_NEAR(ratios.value().meshHz[k] / linear.truth[k], 1.0, 1e-9) << k;
    EXPECT_NEAR(corrected[k] / linear.truth[k], 1.0, 0.05) << k;
    EXPECT_LT(std::abs(corrected[k] - linear.truth[k]), 0.2 * std::abs(linear.corrected[k] - linear.truth[k])) << k;
  }
  std::printf("dumbbell, P2 check: corrected %.0f %.0f %.0f Hz, truth %.0f %.0f %.0f\n", corrected[0], corrected[1], corrected[2],
              linear.truth[0], linear.truth[1], linear.truth[2]);
}

TEST(FragmentModes, MeshRatiosScaleTheLowestModesAndKeepThemInOrder) {
  MeshFrequencyRatios r;
  r.ratios = Eigen::Vector2d(1.0, 0.25);
  Eigen::VectorXd f(4);
  f << 100.0, 200.0, 300.0, 400.0;
  applyMeshRatios(f, r);
  EXPECT_EQ(f, Eigen::Vector4d(50.0, 100.0, 300.0, 400.0));
}

TEST(FragmentModes, OneLabelIsTheWholeMeshAndItsModesAreTheBakedOnes) {
  const TetMesh bar = testing::makeBoxTetMesh(0.2, 0.05, 0.03, 10, 3, 2);
  auto sub = subMesh(bar, Eigen::VectorXi::Zero(bar.nodes.rows()), 0);
  ASSERT_TRUE(sub) << sub.error().message;
  EXPECT_EQ(sub.value().mesh.tets.rows(), bar.tets.rows());
  EXPECT_EQ(sub.value().wholeTets, bar.tets.rows());
  EXPECT_EQ(sub.value().splitTets, 0);
  EXPECT_EQ(sub.value().mesh.nodes.rows(), bar.nodes.rows());
  EXPECT_DOUBLE_EQ(sub.value().droppedVolumeM3, 0.0);

  // The bake's path: ARPACK on the same K and M.
  const FemSystem fem = assembleFem(bar, presetGlass(), FemSettings{}).value();
  ModalSettings ms;
  ms.modeCount = 12;
  ms.shiftRad2PerS2 = defaultShift(bar.nodes, presetGlass());
  auto baked = computeModes(fem, bar.nodes, ms);
  ASSERT_TRUE(baked) << baked.error().message;

  for (int denseMaxDof : {0, 100000}) {  // Spectra, then Eigen's dense solver
    ExactModesSettings es;
    es.modeCount = 12;
    es.denseMaxDof = denseMaxDof;
    auto own = exactFragmentAsset(sub.value(), presetGlass(), es, "bar");
    ASSERT_TRUE(own) << own.error().message;
    const ModalBasis& m = own.value().modal;
    ASSERT_EQ(m.frequenciesHz.size(), 12);
    for (int j = 0; j < 12; ++j) {
      EXPECT_NEAR(m.frequenciesHz[j], baked.value().basis.frequenciesHz[j], 1e-7 * baked.value().basis.frequenciesHz[j]) << j;
    }
    EXPECT_LT(m.residuals.maxCoeff(), 1e-8);
    EXPECT_LT(m.orthonormalityError, 1e-8);
    EXPECT_EQ(own.value().stressModes.rows(), 6 * bar.tets.rows());
    EXPECT_EQ(own.value().stressModes.cols(), 12);
    EXPECT_NEAR(own.value().massProperties.volumeM3, 0.2 * 0.05 * 0.03, 1e-12);
    EXPECT_EQ(own.value().bake.factorization, denseMaxDof > 0 ? "dense" : "supernodal-ldlt");
  }
}

TEST(FragmentModes, TwoHalvesPartitionTheBarAndRingLikeHalfBeams) {
  // A slender free-free bar cut across at x = 0.195 m (the crossed edges at their middle): the
  // halves hold exactly their volumes, and the first bending frequency of the shorter beam is about
  // (0.4 / 0.195)² = 4.2× the whole's (f ∝ 1/L²; shear and rotary inertia bring a stubby part a
  // little below).
  const TetMesh bar = testing::makeBoxTetMesh(0.4, 0.02, 0.02, 40, 2, 2);
  Eigen::VectorXi labels(bar.nodes.rows());
  for (Eigen::Index i = 0; i < bar.nodes.rows(); ++i) labels[i] = bar.nodes(i, 0) < 0.19 + 1e-9 ? 0 : 1;
  auto left = subMesh(bar, labels, 0), right = subMesh(bar, labels, 1);
  ASSERT_TRUE(left && right);
  EXPECT_GT(left.value().splitTets, 0);
  EXPECT_EQ(left.value().splitTets, right.value().splitTets);
  EXPECT_EQ(left.value().wholeTets + right.value().wholeTets + left.value().splitTets, bar.tets.rows());
  EXPECT_NEAR(meshVolume(left.value().mesh), 0.195 * 0.02 * 0.02, 1e-15);
  EXPECT_NEAR(meshVolume(right.value().mesh), 0.205 * 0.02 * 0.02, 1e-15);

  ExactModesSettings es;
  es.modeCount = 4;
  auto whole = exactFragmentAsset(subMesh(bar, Eigen::VectorXi::Zero(bar.nodes.rows()), 0).value(), presetGlass(), es, "bar");
  auto half = exactFragmentAsset(left.value(), presetGlass(), es, "half");
  ASSERT_TRUE(whole && half) << (whole ? half.error().message : whole.error().message);
  const double ratio = half.value().modal.frequenciesHz[0] / whole.value().modal.frequenciesHz[0];
  EXPECT_GT(ratio, 3.4);
  EXPECT_LT(ratio, 4.3);
}

TEST(FragmentModes, SubMeshesHoldTheVolumesOfTheFragmentSurfaces) {
  // Three fragments from two slanted cuts with uneven crack parameters: each sub-mesh is conforming
  // (its boundary is closed: the topology builds) and encloses what the fragment surface encloses.
  const TetMesh box = testing::makeBoxTetMesh(0.2, 0.1, 0.08, 6, 4, 3);
  const TetTopology topology = buildTetTopology(box).value();
  Eigen::VectorXi labels(box.nodes.rows());
  for (Eigen::Index i = 0; i < box.nodes.rows(); ++i) {
    const Eigen::Vector3d x = box.nodes.row(i);
    labels[i] = x.x() + 0.4 * x.z() < 0.07 ? 0 : (x.y() - 0.3 * x.x() < 0.04 ? 1 : 2);
  }
  Eigen::VectorXd cuts(topology.edges.rows());
  for (Eigen::Index e = 0; e < cuts.size(); ++e) cuts[e] = 0.1 + 0.8 * std::fmod(0.618034 * static_cast<double>(e), 1.0);
  auto surfaces = buildFragmentSurfaces(box, topology, labels, 3, cuts);
  ASSERT_TRUE(surfaces) << surfaces.error().message;
  double total = 0.0;
  for (int label = 0; label < 3; ++label) {
    auto sub = fragmentSubMesh(box, topology, labels, cuts, label);
    ASSERT_TRUE(sub) << sub.error().message;
    EXPECT_DOUBLE_EQ(sub.value().droppedVolumeM3, 0.0);
    EXPECT_TRUE(buildTetTopology(sub.value().mesh));
    const double v = meshVolume(sub.value().mesh);
    EXPECT_NEAR(v, computeSurfaceMassProperties(surfaces.value()[static_cast<size_t>(label)], 1.0).volumeM3, 1e-14) << label;
    total += v;
    ExactModesSettings es;
    es.modeCount = 6;
    auto own = exactFragmentAsset(sub.value(), presetGlass(), es, "piece");
    ASSERT_TRUE(own) << own.error().message;
    EXPECT_LT(own.value().modal.residuals.maxCoeff(), 1e-8);
  }
  EXPECT_NEAR(total, 0.2 * 0.1 * 0.08, 1e-14);
}

// The check's cut (CutCells::Prisms): a tet one crack crosses becomes the tet or prism between the
// label's corners and the crack points. Each sub-mesh is conforming (its topology builds), the
// pieces still tile the box (their quads split alike from every side), the count before the cut is
// the sub-mesh's own, it has fewer nodes than the exact path's, and where the crack is one plane
// (its points on it, so the fans' face and tet points too) both hold the same solid.
TEST(FragmentModes, PrismCellsTileTheSolidWithFewerPoints) {
  const TetMesh box = testing::makeBoxTetMesh(0.2, 0.1, 0.08, 6, 4, 3);
  const TetTopology topology = buildTetTopology(box).value();
  const std::vector<Eigen::Vector3d> seeds = {{0.02, 0.02, 0.02}, {0.15, 0.08, 0.06}, {0.1, 0.01, 0.07}, {0.05, 0.09, 0.04},
                                              {0.18, 0.02, 0.01}};
  Eigen::VectorXd uneven(topology.edges.rows());
  for (Eigen::Index e = 0; e < uneven.size(); ++e) uneven[e] = 0.1 + 0.8 * std::fmod(0.618034 * static_cast<double>(e), 1.0);
  // The plane x + 0.2 y = 0.06, slanted between the grid's first two layers of nodes across x, so
  // that it crosses no edge within 6 % of an end (the cut's clamp, 5 %, would move a crack point
  // off it).
  const Eigen::Vector3d normal(1.0, 0.2, 0.0);
  Eigen::VectorXi planeLabels(box.nodes.rows());
  Eigen::VectorXd planeCuts(topology.edges.rows());
  auto cutAt = [&](double offset) {
    double nearest = 0.5;
    for (Eigen::Index i = 0; i < box.nodes.rows(); ++i) planeLabels[i] = normal.dot(box.nodes.row(i).transpose()) < offset ? 0 : 1;
    planeCuts.setConstant(std::nan(""));
    for (Eigen::Index e = 0; e < planeCuts.size(); ++e) {
      const double a = normal.dot(box.nodes.row(topology.edges(e, 0)).transpose()) - offset;
      const double b = normal.dot(box.nodes.row(topology.edges(e, 1)).transpose()) - offset;
      if ((a < 0.0) == (b < 0.0)) continue;
      planeCuts[e] = a / (a - b);
      nearest = std::min({nearest, planeCuts[e], 1.0 - planeCuts[e]});
    }
    return nearest;
  };
  ASSERT_GE(cutAt(0.06), 0.06);
  for (int labelling = 0; labelling < 2; ++labelling) {
    Eigen::VectorXi labels = planeLabels;
    const int count = labelling == 0 ? 2 : static_cast<int>(seeds.size());
    if (labelling == 1) {
      for (Eigen::Index i = 0; i < box.nodes.rows(); ++i) {
        const Eigen::Vector3d x = box.nodes.row(i);
        int nearest = 0;
        for (int s = 1; s < count; ++s)
          if ((x - seeds[static_cast<size_t>(s)]).norm() < (x - seeds[static_cast<size_t>(nearest)]).norm()) nearest = s;
        labels[i] = nearest;
      }
    }
    const Eigen::VectorXd& cuts = labelling == 0 ? planeCuts : uneven;
    double total = 0.0;
    for (int label = 0; label < count; ++label) {
      auto prisms = fragmentSubMesh(box, topology, labels, cuts, label, CutCells::Prisms);
      auto fans = fragmentSubMesh(box, topology, labels, cuts, label);
      ASSERT_TRUE(prisms && fans) << labelling << " " << label;
      EXPECT_DOUBLE_EQ(prisms.value().droppedVolumeM3, 0.0);
      EXPECT_TRUE(buildTetTopology(prisms.value().mesh)) << labelling << " " << label;
      EXPECT_EQ(fragmentCutDof(box, topology, labels, label, ElementOrder::P1, CutCells::Prisms), 3 * prisms.value().mesh.nodes.rows())
          << labelling << " " << label;
      EXPECT_LT(prisms.value().mesh.nodes.rows(), fans.value().mesh.nodes.rows());
      EXPECT_LT(prisms.value().mesh.tets.rows(), fans.value().mesh.tets.rows());
      const double v = meshVolume(prisms.value().mesh);
      if (labelling == 0) {
        EXPECT_NEAR(v, meshVolume(fans.value().mesh), 1e-15) << label;
      }
      total += v;
    }
    EXPECT_NEAR(total, 0.2 * 0.1 * 0.08, 1e-14) << labelling;
  }
  EXPECT_EQ(fragmentCutDof(box, topology, planeLabels, 0, ElementOrder::P2, CutCells::Prisms), 0);  // P1 only
  // The check runs on it.
  auto piece = fragmentSubMesh(box, topology, planeLabels, planeCuts, 0, CutCells::Prisms);
  auto ratios = meshFrequencyRatios(piece.value(), presetGlass(), 5, kMeshRatioModes);
  ASSERT_TRUE(ratios) << ratios.error().message;
  EXPECT_GT(ratios.value().ratios.minCoeff(), 0.5);
}

TEST(FragmentModes, TheCountBeforeTheCutIsTheSubMeshsOwn) {
  // fragmentCutDof counts, from the labels alone, the degrees of freedom that fragmentSubMesh's
  // mesh then has, in both orders: the World refuses the exact path on it before cutting. Two
  // labellings of a box, cut at uneven parameters: three slanted pieces, and five pieces around
  // seeds (every crossed tet kind: one, two and three corners in a piece).
  const TetMesh box = testing::makeBoxTetMesh(0.2, 0.1, 0.08, 6, 4, 3);
  const TetTopology topology = buildTetTopology(box).value();
  Eigen::VectorXd cuts(topology.edges.rows());
  for (Eigen::Index e = 0; e < cuts.size(); ++e) cuts[e] = 0.1 + 0.8 * std::fmod(0.618034 * static_cast<double>(e), 1.0);
  const std::vector<Eigen::Vector3d> seeds = {{0.02, 0.02, 0.02}, {0.15, 0.08, 0.06}, {0.1, 0.01, 0.07}, {0.05, 0.09, 0.04},
                                              {0.18, 0.02, 0.01}};
  for (int labelling = 0; labelling < 2; ++labelling) {
    Eigen::VectorXi labels(box.nodes.rows());
    int count = labelling == 0 ? 3 : static_cast<int>(seeds.size());
    for (Eigen::Index i = 0; i < box.nodes.rows(); ++i) {
      const Eigen::Vector3d x = box.nodes.row(i);
      if (labelling == 0) {
        labels[i] = x.x() + 0.4 * x.z() < 0.07 ? 0 : (x.y() - 0.3 * x.x() < 0.04 ? 1 : 2);
        continue;
      }
      int nearest = 0;
      for (int s = 1; s < count; ++s)
        if ((x - seeds[static_cast<size_t>(s)]).norm() < (x - seeds[static_cast<size_t>(nearest)]).norm()) nearest = s;
      labels[i] = nearest;
    }
    int64_t crossed = 0;
    std::array<bool, 4> kinds{};  // crossed tets with 1, 2, 3 corners in a piece
    for (Eigen::Index e = 0; e < box.tets.rows(); ++e)
      for (int label = 0; label < count; ++label) {
        int c = 0;
        for (int k = 0; k < 4; ++k) c += labels[box.tets(e, k)] == label ? 1 : 0;
        if (c > 0 && c < 4) kinds[static_cast<size_t>(c)] = true;
      }
    EXPECT_TRUE(kinds[1] && kinds[2] && kinds[3]) << labelling;
    for (int label = 0; label < count; ++label) {
      auto sub = fragmentSubMesh(box, topology, labels, cuts, label);
      ASSERT_TRUE(sub) << sub.error().message;
      crossed += sub.value().splitTets;
      EXPECT_DOUBLE_EQ(sub.value().droppedVolumeM3, 0.0) << labelling << " " << label;  // the count's premise
      for (ElementOrder order : {ElementOrder::P1, ElementOrder::P2}) {
        EXPECT_EQ(fragmentCutDof(box, topology, labels, label, order), 3 * femNodeCount(sub.value().mesh, order))
            << labelling << " " << label;
      }
    }
    EXPECT_GT(crossed, 0);
    EXPECT_EQ(fragmentCutDof(box, topology, labels, count, ElementOrder::P2), 0);  // no node has that label
  }
  EXPECT_EQ(fragmentCutDof(box, topology, Eigen::VectorXi::Zero(3), 0, ElementOrder::P1), 0);  // sizes
  // One label: the whole mesh, nothing cut.
  EXPECT_EQ(fragmentCutDof(box, topology, Eigen::VectorXi::Zero(box.nodes.rows()), 0, ElementOrder::P2),
            3 * femNodeCount(box, ElementOrder::P2));
}

TEST(FragmentModes, BadInputsGiveTypedErrors) {
  const TetMesh bar = testing::makeBoxTetMesh(0.1, 0.05, 0.05, 2, 1, 1);
  const TetTopology topology = buildTetTopology(bar).value();
  const Eigen::VectorXd cuts = Eigen::VectorXd::Constant(topology.edges.rows(), 0.5);
  EXPECT_EQ(fragmentSubMesh(bar, topology, Eigen::VectorXi::Zero(3), cuts, 0).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(fragmentSubMesh(bar, topology, Eigen::VectorXi::Zero(bar.nodes.rows()), Eigen::VectorXd::Zero(2), 0).error().code,
            ErrorCode::InvalidArgument);
  EXPECT_EQ(subMesh(bar, Eigen::VectorXi::Zero(bar.nodes.rows()), 1).error().code, ErrorCode::InvalidArgument);
  Eigen::VectorXi split = Eigen::VectorXi::Zero(bar.nodes.rows());
  split[0] = 1;
  EXPECT_EQ(fragmentSubMesh(bar, topology, split, Eigen::VectorXd::Constant(cuts.size(), std::nan("")), 1).error().code,
            ErrorCode::InvalidArgument);  // a crossed edge without a cut

  auto sub = subMesh(bar, Eigen::VectorXi::Zero(bar.nodes.rows()), 0).value();
  ExactModesSettings bad;
  bad.modeCount = 0;
  EXPECT_EQ(exactFragmentAsset(sub, presetGlass(), bad, "x").error().code, ErrorCode::InvalidArgument);

  // Two tets that share one node only: nine zero modes, not six.
  FragmentSubMesh hinge;
  hinge.mesh.nodes.resize(7, 3);
  hinge.mesh.nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1;
  hinge.mesh.tets.resize(2, 4);
  hinge.mesh.tets << 0, 1, 2, 3, 0, 4, 6, 5;
  ASSERT_GT(meshVolume(hinge.mesh), 0.0);
  ExactModesSettings es;
  es.modeCount = 3;
  EXPECT_EQ(exactFragmentAsset(hinge, presetGlass(), es, "hinge").error().code, ErrorCode::RigidModeMismatch);
  EXPECT_EQ(meshFrequencyRatios(hinge, presetGlass(), 5, 3).error().code, ErrorCode::RigidModeMismatch);
  EXPECT_EQ(meshFrequencyRatios(sub, presetGlass(), 0, 3).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(meshFrequencyRatios(sub, presetGlass(), kMaxPolynomialModeDegree + 1, 3).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(meshFrequencyRatios(sub, presetGlass(), 5, 0).error().code, ErrorCode::InvalidArgument);

}

TEST(FragmentModes, ALabelInTwoPiecesKeepsTheLargerConnectedOne) {
  // Label 0 at both ends of a bar, label 1 in between: the two end pieces share no face.
  const TetMesh bar = testing::makeBoxTetMesh(0.5, 0.1, 0.1, 5, 1, 1);
  Eigen::VectorXi labels(bar.nodes.rows());
  for (Eigen::Index i = 0; i < bar.nodes.rows(); ++i) {
    const double x = bar.nodes(i, 0);
    labels[i] = x < 0.25 || x > 0.45 ? 0 : 1;
  }
  auto sub = subMesh(bar, labels, 0);
  ASSERT_TRUE(sub) << sub.error().message;
  EXPECT_NEAR(sub.value().droppedVolumeM3, 0.05 * 0.1 * 0.1, 1e-15);
  EXPECT_NEAR(meshVolume(sub.value().mesh), 0.25 * 0.1 * 0.1, 1e-15);
  for (Eigen::Index i = 0; i < sub.value().mesh.nodes.rows(); ++i) EXPECT_LT(sub.value().mesh.nodes(i, 0), 0.251);
  ExactModesSettings es;
  es.modeCount = 3;
  EXPECT_TRUE(exactFragmentAsset(sub.value(), presetGlass(), es, "end"));  // one connected solid: six rigid modes
}

}  // namespace
}  // namespace brittle

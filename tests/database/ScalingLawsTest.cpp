// The scaling laws of ScalingLaws.h against direct computation on the transformed mesh.
#include "brittle/database/ScalingLaws.h"

#include <gtest/gtest.h>

#include <cstring>

#include "FragmentTestSupport.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/runtime/FemAssembly.h"
#include "brittle/precompute/MaterialLibrary.h"

namespace brittle {
namespace {

class ScalingLawsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    DatabaseBakeSettings s = testing::smallDatabaseSettings(1, true);
    s.tetMesh.targetTets = 900;
    s.modeCount = 8;
    // A box with three distinct sides, off the origin: non-degenerate modes and principal axes.
    TriangleMesh box = testing::makeBoxSurface(0.3, 0.2, 0.12);
    box.vertices.rowwise() += Eigen::RowVector3d(0.5, -0.2, 0.1);
    std::array<Descriptor, kDescriptorKindCount> descriptors;
    auto e = bakeFragmentEntry(box, "box", s, descriptors);
    ASSERT_TRUE(e) << e.error().message;
    entry = new FragmentEntry(std::move(e).value());
    reference = new Material(s.referenceMaterial);
  }
  static void TearDownTestSuite() {
    delete entry;
    delete reference;
  }

  static CanonicalFrame someFrame(double lengthM) {
    std::mt19937_64 rng(3);
    CanonicalFrame f;
    f.rotation = testing::randomRotation(rng);
    f.translationM = Eigen::Vector3d(1.5, -0.25, 3.0);
    f.scalePerM = 1.0 / lengthM;
    return f;
  }

  // Glass's Poisson ratio with steel-like stiffness and density: the laws are exact.
  static Material sameNuMaterial() {
    Material m = *reference;
    m.name = "stiff-dense";
    m.youngsModulusPa = 2.1e11;
    m.densityKgPerM3 = 7800.0;
    return m;
  }

  static ModalResult directModes(const ObjectAsset& placed, const Material& material, int modes) {
    auto system = assembleFem(placed.tetMesh, material, {});
    EXPECT_TRUE(system);
    ModalSettings ms;
    ms.modeCount = modes;
    ms.shiftRad2PerS2 = defaultShift(placed.tetMesh.nodes, material);
    auto direct = computeModes(system.value(), placed.tetMesh.nodes, ms);
    EXPECT_TRUE(direct) << direct.error().message;
    return direct.value();
  }

  static inline FragmentEntry* entry = nullptr;
  static inline Material* reference = nullptr;
};

TEST_F(ScalingLawsTest, EntryIsCanonicalAtUnitVolume) {
  EXPECT_NEAR(entry->asset.massProperties.volumeM3, 1.0, 0.01);  // tet mesh of a unit-volume box
  EXPECT_LT(entry->asset.massProperties.centerOfMassM.norm(), 1e-9);
  const Eigen::Matrix3d& s = entry->asset.massProperties.secondMomentM5;
  EXPECT_LT(std::abs(s(0, 1)) + std::abs(s(0, 2)) + std::abs(s(1, 2)), 1e-9);  // principal axes
  EXPECT_LT(s(0, 0), s(1, 1));
  EXPECT_LT(s(1, 1), s(2, 2));
}

TEST_F(ScalingLawsTest, RescaledEntryEqualsDirectModalAnalysisOfTheTransformedMesh) {
  const double length = 0.37;
  const Material target = sameNuMaterial();
  InstantiateReport report;
  auto placed = instantiateEntry(*entry, *reference, target, someFrame(length), &report);
  ASSERT_TRUE(placed) << placed.error().message;
  EXPECT_FALSE(report.poissonCorrected);
  EXPECT_DOUBLE_EQ(report.lengthScaleM, length);
  const ObjectAsset& a = placed.value();

  const ModalResult direct = directModes(a, target, 8);
  for (int i = 0; i < 8; ++i) {
    EXPECT_NEAR(a.modal.frequenciesHz(i) / direct.basis.frequenciesHz(i), 1.0, 1e-7) << "mode " << i;
  }
  // The rescaled, rotated modes are eigenvectors of the transformed K, M and mass-normalised.
  auto system = assembleFem(a.tetMesh, target, {}).value();
  const Eigen::MatrixXd phi = a.modal.modes;
  const Eigen::MatrixXd kphi = system.stiffness * phi, mphi = system.mass * phi;
  for (int i = 0; i < 8; ++i) {
    const double residual =
        (kphi.col(i) - a.modal.eigenvaluesRad2PerS2(i) * mphi.col(i)).norm() / kphi.col(i).norm();
    EXPECT_LT(residual, 1e-7) << "mode " << i;
  }
  EXPECT_LT((phi.transpose() * mphi - Eigen::MatrixXd::Identity(8, 8)).cwiseAbs().maxCoeff(), 1e-9);
  // Stress modes: the scaled, rotated ones equal C B Φ computed on the transformed mesh.
  const MatrixXdRow stress = computeStressModes(a.tetMesh, target, a.modal.modes);
  EXPECT_LT((stress - a.stressModes).cwiseAbs().maxCoeff(), 1e-9 * stress.cwiseAbs().maxCoeff());
  // Mass properties.
  const MassProperties mp = computeTetMassProperties(a.tetMesh, target.densityKgPerM3);
  EXPECT_NEAR(a.massProperties.massKg / mp.massKg, 1.0, 1e-12);
  EXPECT_LT((a.massProperties.centerOfMassM - mp.centerOfMassM).norm(), 1e-12);
  EXPECT_LT((a.massProperties.inertiaKgM2 - mp.inertiaKgM2).norm(), 1e-10 * mp.inertiaKgM2.norm());
  EXPECT_LT((a.massProperties.secondMomentM5 - mp.secondMomentM5).norm(), 1e-10 * mp.secondMomentM5.norm());
}

TEST_F(ScalingLawsTest, RescaledEntryMatchesAFreshBakeOfTheScaledSolidWithinOnePercent) {
  // A new tet mesh of the scaled, moved surface: the laws plus a different discretisation.
  const double length = 2.5;
  const CanonicalFrame frame = someFrame(length);
  const Material target = sameNuMaterial();
  TriangleMesh scaled = entry->surface;
  for (Eigen::Index v = 0; v < scaled.vertices.rows(); ++v) {
    scaled.vertices.row(v) = frame.toQuery(entry->surface.vertices.row(v).transpose()).transpose();
  }
  ObjectBakeSettings bake;
  bake.name = "scaled";
  bake.material = target;
  bake.tetMesh.targetTets = 900;
  bake.tetMesh.seed = 11;  // a different mesh from the entry's
  bake.modal.modeCount = 8;
  auto fresh = bakeSurface(scaled, bake);
  ASSERT_TRUE(fresh) << fresh.error().message;
  auto placed = instantiateEntry(*entry, *reference, target, frame);
  ASSERT_TRUE(placed);
  for (int i = 0; i < 3; ++i) {
    const double ratio = placed.value().modal.frequenciesHz(i) / fresh.value().modal.frequenciesHz(i);
    std::printf("mode %d: rescaled %.2f Hz, fresh bake %.2f Hz (%.3f%%)\n", i, placed.value().modal.frequenciesHz(i),
                fresh.value().modal.frequenciesHz(i), 100.0 * (ratio - 1.0));
    EXPECT_NEAR(ratio, 1.0, 0.01) << "mode " << i;
  }
}

TEST_F(ScalingLawsTest, OtherPoissonRatioGoesThroughRayleighRitz) {
  const Material steel = materialPreset("steel").value();
  ASSERT_NE(steel.poissonRatio, reference->poissonRatio);
  InstantiateReport report;
  auto placed = instantiateEntry(*entry, *reference, steel, someFrame(0.5), &report);
  ASSERT_TRUE(placed);
  EXPECT_TRUE(report.poissonCorrected);
  const ObjectAsset& a = placed.value();
  const ModalResult direct = directModes(a, steel, 8);
  auto system = assembleFem(a.tetMesh, steel, {}).value();
  const Eigen::MatrixXd phi = a.modal.modes;
  EXPECT_LT((phi.transpose() * (system.mass * phi) - Eigen::MatrixXd::Identity(8, 8)).cwiseAbs().maxCoeff(), 1e-9);
  // Ritz values in the stored basis: upper bounds, and close for the lowest modes.
  for (int i = 0; i < 8; ++i) {
    const double ratio = a.modal.frequenciesHz(i) / direct.basis.frequenciesHz(i);
    std::printf("mode %d: Ritz %.2f Hz, direct %.2f Hz (%+.3f%%)\n", i, a.modal.frequenciesHz(i),
                direct.basis.frequenciesHz(i), 100.0 * (ratio - 1.0));
    EXPECT_GE(ratio, 1.0 - 1e-9) << "mode " << i;
    if (i < 3) {
      EXPECT_LT(ratio, 1.02) << "mode " << i;
    }
  }
  // Stress modes are C(ν) times the Ritz strains: exact for the corrected modes.
  const MatrixXdRow stress = computeStressModes(a.tetMesh, steel, a.modal.modes);
  EXPECT_LT((stress - a.stressModes).cwiseAbs().maxCoeff(), 1e-9 * stress.cwiseAbs().maxCoeff());
}

TEST_F(ScalingLawsTest, QuadraticEntriesRescaleAndTakeAnotherPoissonRatio) {
  // A P2 entry (pieces of thin parts): its modes live on the FEM nodes (corners and mid-edges) and
  // its stress modes on four corners per tet. Rescaled at glass's ν, the placed modes are
  // eigenpairs of the transformed P2 mesh's K and M and its stress modes are C B Φ there; at
  // steel's ν the Ritz values (the P2 strain energy integrated exactly from the corner strains)
  // bound the direct P2 frequencies from above, within 2 % for the lowest three.
  DatabaseBakeSettings s = testing::smallDatabaseSettings(1, true);
  s.tetMesh.targetTets = 300;
  s.modeCount = 8;
  s.elementOrder = ElementOrder::P2;
  TriangleMesh box = testing::makeBoxSurface(0.3, 0.2, 0.12);
  std::array<Descriptor, kDescriptorKindCount> descriptors;
  auto e = bakeFragmentEntry(box, "box-p2", s, descriptors);
  ASSERT_TRUE(e) << e.error().message;
  ASSERT_EQ(e.value().asset.elementOrder, ElementOrder::P2);
  for (const Material& target : {sameNuMaterial(), materialPreset("steel").value()}) {
    SCOPED_TRACE(target.name);
    InstantiateReport report;
    auto placed = instantiateEntry(e.value(), *reference, target, someFrame(0.45), &report);
    ASSERT_TRUE(placed) << placed.error().message;
    EXPECT_EQ(report.poissonCorrected, target.poissonRatio != reference->poissonRatio);
    const ObjectAsset& a = placed.value();
    EXPECT_EQ(a.elementOrder, ElementOrder::P2);
    auto fem = makeFemMesh(a.tetMesh, ElementOrder::P2);
    ASSERT_TRUE(fem);
    auto system = assembleFem(fem.value(), target, {}).value();
    const Eigen::MatrixXd phi = a.modal.modes;
    ASSERT_EQ(phi.rows(), system.stiffness.rows());
    const Eigen::MatrixXd kphi = system.stiffness * phi, mphi = system.mass * phi;
    EXPECT_LT((phi.transpose() * mphi - Eigen::MatrixXd::Identity(8, 8)).cwiseAbs().maxCoeff(), 1e-9);
    const MatrixXdRow stress = computeStressModes(fem.value(), target, a.modal.modes);
    EXPECT_LT((stress - a.stressModes).cwiseAbs().maxCoeff(), 1e-9 * stress.cwiseAbs().maxCoeff());
    ModalSettings ms;
    ms.modeCount = 8;
    ms.shiftRad2PerS2 = defaultShift(a.tetMesh.nodes, target);
    auto direct = computeModes(system, fem.value().nodes(), ms);
    ASSERT_TRUE(direct) << direct.error().message;
    for (int i = 0; i < 8; ++i) {
      const double ratio = a.modal.frequenciesHz(i) / direct.value().basis.frequenciesHz(i);
      if (!report.poissonCorrected) {
        const double residual = (kphi.col(i) - a.modal.eigenvaluesRad2PerS2(i) * mphi.col(i)).norm() / kphi.col(i).norm();
        EXPECT_LT(residual, 1e-7) << "mode " << i;
        EXPECT_NEAR(ratio, 1.0, 1e-7) << "mode " << i;
        continue;
      }
      std::printf("P2 mode %d: Ritz %.2f Hz, direct %.2f Hz (%+.3f%%)\n", i, a.modal.frequenciesHz(i),
                  direct.value().basis.frequenciesHz(i), 100.0 * (ratio - 1.0));
      EXPECT_GE(ratio, 1.0 - 1e-9) << "mode " << i;
      if (i < 3) {
        EXPECT_LT(ratio, 1.02) << "mode " << i;
      }
    }
  }
}

// The Rayleigh–Ritz basis at another ν depends on the entry and ν alone: computed once
// (entryAtPoisson) and handed to instantiateEntry, it places the entry with the same bits as the
// correction instantiateEntry makes itself, at any size and pose. One for another ν, or of
// another entry's shape, is refused.
TEST_F(ScalingLawsTest, APoissonBasisComputedOnceGivesTheSameBits) {
  const Material steel = materialPreset("steel").value();
  ASSERT_NE(steel.poissonRatio, reference->poissonRatio);
  auto basis = entryAtPoisson(*entry, *reference, steel.poissonRatio);
  ASSERT_TRUE(basis) << basis.error().message;
  EXPECT_EQ(basis.value().poissonRatio, steel.poissonRatio);
  auto sameBits = [](const auto& a, const auto& b) {
    return a.rows() == b.rows() && a.cols() == b.cols() &&
           std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
  };
  for (double length : {0.5, 0.013}) {
    SCOPED_TRACE(length);
    InstantiateReport report;
    auto own = instantiateEntry(*entry, *reference, steel, someFrame(length));
    auto given = instantiateEntry(*entry, *reference, steel, someFrame(length), &report, &basis.value());
    ASSERT_TRUE(own && given);
    EXPECT_TRUE(report.poissonCorrected);
    EXPECT_TRUE(sameBits(given.value().modal.modes, own.value().modal.modes));
    EXPECT_TRUE(sameBits(given.value().modal.eigenvaluesRad2PerS2, own.value().modal.eigenvaluesRad2PerS2));
    EXPECT_TRUE(sameBits(given.value().modal.frequenciesHz, own.value().modal.frequenciesHz));
    EXPECT_TRUE(sameBits(given.value().stressModes, own.value().stressModes));
    EXPECT_TRUE(sameBits(given.value().tetMesh.nodes, own.value().tetMesh.nodes));
    // And it is a correction: steel's E and ρ at the reference's ν, where nothing is corrected,
    // give other modes and stresses.
    Material steelAtReferenceNu = steel;
    steelAtReferenceNu.poissonRatio = reference->poissonRatio;
    const ObjectAsset uncorrected = instantiateEntry(*entry, *reference, steelAtReferenceNu, someFrame(length)).value();
    EXPECT_FALSE(sameBits(given.value().modal.eigenvaluesRad2PerS2, uncorrected.modal.eigenvaluesRad2PerS2));
    EXPECT_FALSE(sameBits(given.value().stressModes, uncorrected.stressModes));
  }
  // At ν₀ there is nothing to correct, and a basis given is not read.
  auto atReference = instantiateEntry(*entry, *reference, sameNuMaterial(), someFrame(0.5), nullptr, &basis.value());
  ASSERT_TRUE(atReference);
  EXPECT_TRUE(sameBits(atReference.value().stressModes,
                       instantiateEntry(*entry, *reference, sameNuMaterial(), someFrame(0.5)).value().stressModes));

  Material other = steel;
  other.poissonRatio = 0.21;
  EXPECT_EQ(instantiateEntry(*entry, *reference, other, someFrame(0.5), nullptr, &basis.value()).error().code,
            ErrorCode::InvalidArgument);
  EntryAtPoisson truncated = basis.value();
  truncated.stressModes.conservativeResize(truncated.stressModes.rows() - 6, Eigen::NoChange);
  EXPECT_EQ(instantiateEntry(*entry, *reference, steel, someFrame(0.5), nullptr, &truncated).error().code,
            ErrorCode::InvalidArgument);
  EXPECT_EQ(entryAtPoisson(*entry, *reference, 0.7).error().code, ErrorCode::InvalidMaterial);
  FragmentEntry descriptorsOnly = *entry;
  descriptorsOnly.asset.tetMesh.tets.resize(0, 4);
  EXPECT_EQ(entryAtPoisson(descriptorsOnly, *reference, steel.poissonRatio).error().code, ErrorCode::InvalidArgument);
}

TEST_F(ScalingLawsTest, TypedErrors) {
  Material bad = *reference;
  bad.youngsModulusPa = -1.0;
  EXPECT_EQ(instantiateEntry(*entry, *reference, bad, someFrame(1.0)).error().code, ErrorCode::InvalidMaterial);
  CanonicalFrame frame = someFrame(1.0);
  frame.scalePerM = 0.0;
  EXPECT_EQ(instantiateEntry(*entry, *reference, *reference, frame).error().code, ErrorCode::InvalidArgument);
  FragmentEntry descriptorsOnly = *entry;
  descriptorsOnly.asset.tetMesh.tets.resize(0, 4);
  EXPECT_EQ(instantiateEntry(descriptorsOnly, *reference, *reference, someFrame(1.0)).error().code,
            ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace brittle

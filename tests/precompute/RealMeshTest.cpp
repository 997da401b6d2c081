// Real meshes nobody in this project wrote: the sample meshes of Debian's libcgal-demo package,
// fetched at test time (tests/common/fetch_cgal_meshes.sh), never committed.
#include <gtest/gtest.h>

#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/MeshIO.h"
#include "brittle/precompute/MeshValidation.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

class RealMeshTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = testing::cgalDemoMeshDir();
    ASSERT_FALSE(dir.empty()) << "could not fetch libcgal-demo meshes (apt-get download libcgal-demo)";
  }
  std::filesystem::path dir;
};

TEST_F(RealMeshTest, ValidatorNamesTheDefectsOfBrokenSamples) {
  struct Expect {
    const char* file;
    ErrorCode code;
  };
  for (const auto& e : {Expect{"elephant-with-holes.off", ErrorCode::OpenMesh},
                        Expect{"knot2.off", ErrorCode::NonManifold},  // two separate components
                        Expect{"cube-shuffled.off", ErrorCode::InconsistentOrientation},
                        Expect{"beam.off", ErrorCode::InwardFacing},
                        Expect{"camel.off", ErrorCode::SelfIntersection},
                        Expect{"degtri_sliding.off", ErrorCode::DegenerateFace}}) {
    auto mesh = readSurfaceMesh(dir / e.file);
    ASSERT_TRUE(mesh.ok()) << e.file << ": " << mesh.error().message;
    const Status s = validateSurfaceMesh(mesh.value());
    ASSERT_FALSE(s.ok()) << e.file;
    EXPECT_EQ(s.error().code, e.code) << e.file << ": " << s.error().message;
  }
}

TEST_F(RealMeshTest, BakesSeveralRealMeshes) {
  for (const char* file : {"elephant.off", "eight.off", "couplingdown.off", "fandisk.off"}) {
    ObjectBakeSettings s;
    s.meshPath = dir / file;
    s.material = materialPreset("porcelain").value();
    s.tetMesh.targetTets = 3000;
    s.modal.modeCount = 10;
    ObjectBakeReport report;
    auto asset = bakeObject(s, nullptr, &report);
    ASSERT_TRUE(asset.ok()) << file << ": " << asset.error().message;
    const auto& a = asset.value();
    EXPECT_LE(a.modal.residuals.maxCoeff(), 1e-8) << file;
    EXPECT_LE(a.modal.orthonormalityError, 1e-8) << file;
    EXPECT_GT(a.quality.minDihedralDeg, 3.0) << file;
    // Mesh_3 approximates the surface within facet_distance: the volume moves a little.
    EXPECT_NEAR(report.tetVolumeRelativeError, 0.0, 0.05) << file;
    EXPECT_NEAR(static_cast<double>(a.tetMesh.tets.rows()) / 3000.0, 1.0, 0.5) << file;
  }
}

}  // namespace
}  // namespace brittle

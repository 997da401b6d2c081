#include "brittle/precompute/BakePipeline.h"

#include <gtest/gtest.h>

#include <fstream>

#include "brittle/precompute/BakeManifest.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/testing/AssetChecks.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

class BakePipelineTest : public ::testing::Test {
 protected:
  std::filesystem::path dir = testing::makeTempDir("bake");

  ObjectBakeSettings boxSettings() {
    testing::writeOff(testing::makeBoxSurface(0.2, 0.1, 0.05), dir / "box.off");
    ObjectBakeSettings s;
    s.meshPath = dir / "box.off";
    s.material = materialPreset("glass").value();
    s.tetMesh.targetTets = 1500;
    s.modal.modeCount = 12;
    return s;
  }
};

TEST_F(BakePipelineTest, BoxAssetIsCheckedAndPhysical) {
  ObjectBakeReport report;
  auto asset = bakeObject(boxSettings(), nullptr, &report);
  ASSERT_TRUE(asset.ok()) << asset.error().message;
  const ObjectAsset& a = asset.value();
  EXPECT_EQ(a.name, "box");
  EXPECT_EQ(a.materialName, "glass");
  const double volume = 0.2 * 0.1 * 0.05, mass = volume * 2500.0;
  EXPECT_NEAR(a.massProperties.volumeM3, volume, 1e-12);
  EXPECT_NEAR(a.massProperties.massKg, mass, 1e-9);
  EXPECT_NEAR(a.massProperties.inertiaKgM2(2, 2), mass * (0.04 + 0.01) / 12.0, 1e-9 * mass);
  EXPECT_NEAR(report.tetVolumeRelativeError, 0.0, 1e-10);
  EXPECT_EQ(a.modal.frequenciesHz.size(), 12);
  EXPECT_LE(a.modal.residuals.maxCoeff(), 1e-8);
  EXPECT_LE(a.modal.orthonormalityError, 1e-8);
  EXPECT_EQ(a.stressModes.rows(), 6 * a.tetMesh.tets.rows());
  EXPECT_EQ(a.stressModes.cols(), 12);
  EXPECT_EQ(a.modal.modes.rows(), 3 * a.tetMesh.nodes.rows());
  EXPECT_EQ(a.surfaceFaces.rows(), a.quality.surfaceFaceCount);
  EXPECT_LT(a.bake.shift, 0.0);
  EXPECT_EQ(a.bake.factorization, "cholmod");
  EXPECT_GT(a.bake.totalS, 0.0);
}

TEST_F(BakePipelineTest, SameInputsSameDatasets) {
  const auto s = boxSettings();
  auto a = bakePack({s});
  auto b = bakePack({s});
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_TRUE(writePack(a.value(), dir / "a.h5").ok());
  ASSERT_TRUE(writePack(b.value(), dir / "b.h5").ok());
  auto ra = readPack(dir / "a.h5");
  auto rb = readPack(dir / "b.h5");
  ASSERT_TRUE(ra.ok() && rb.ok());
  const ObjectAsset& x = ra.value().objects.at(0);
  const ObjectAsset& y = rb.value().objects.at(0);
  testing::expectSameBakedData(x, y);  // everything but the wall-clock timings
}

TEST_F(BakePipelineTest, BadInputsGiveTheirOwnTypedErrors) {
  auto s = boxSettings();
  auto expectCode = [&](const TriangleMesh& mesh, ErrorCode code) {
    testing::writeOff(mesh, dir / "bad.off");
    s.meshPath = dir / "bad.off";
    auto r = bakeObject(s);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, code) << r.error().message;
    EXPECT_EQ(r.error().message.rfind("object 'bad': ", 0), 0u) << r.error().message;
  };
  auto open = testing::makeBoxSurface(1, 1, 1);
  open.faces.conservativeResize(11, 3);
  expectCode(open, ErrorCode::OpenMesh);
  auto inward = testing::makeBoxSurface(1, 1, 1);
  inward.faces.col(1).swap(inward.faces.col(2));
  expectCode(inward, ErrorCode::InwardFacing);
  auto crossing = testing::makeBoxSurface(1, 1, 1);
  crossing.vertices.row(7) << -0.5, -0.4, -0.3;
  expectCode(crossing, ErrorCode::SelfIntersection);

  s.material.youngsModulusPa = -1.0;
  s.meshPath = dir / "box.off";
  EXPECT_EQ(bakeObject(s).error().code, ErrorCode::InvalidMaterial);
}

TEST_F(BakePipelineTest, RepairOptionFixesAnInwardMesh) {
  auto s = boxSettings();
  auto sphere = testing::makeIcosphere(0.05, 3);
  sphere.faces.col(1).swap(sphere.faces.col(2));
  testing::writeOff(sphere, dir / "inward.off");
  s.meshPath = dir / "inward.off";
  s.repair = true;
  ObjectBakeReport report;
  auto r = bakeObject(s, nullptr, &report);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_TRUE(r.value().bake.repaired);
  EXPECT_NEAR(r.value().bake.repairVolumeChange, report.repair.relativeVolumeChange, 0.0);
  EXPECT_NEAR(report.repair.relativeVolumeChange, 0.0, 0.03);
}

TEST_F(BakePipelineTest, ManifestLoadsAndRejectsTypos) {
  testing::writeOff(testing::makeBoxSurface(0.1, 0.1, 0.1), dir / "cube.off");
  std::ofstream(dir / "ok.json") << R"({"objects": [{"name": "c", "mesh": "cube.off", "material": "glass", "tets": 800, "modes": 6, "seed": 3}]})";
  auto ok = loadBakeManifest(dir / "ok.json");
  ASSERT_TRUE(ok.ok()) << ok.error().message;
  ASSERT_EQ(ok.value().size(), 1u);
  EXPECT_EQ(ok.value()[0].name, "c");
  EXPECT_EQ(ok.value()[0].meshPath, dir / "cube.off");
  EXPECT_EQ(ok.value()[0].tetMesh.targetTets, 800);
  EXPECT_EQ(ok.value()[0].modal.modeCount, 6);
  EXPECT_EQ(ok.value()[0].modal.seed, 3u);
  std::ofstream(dir / "typo.json") << R"({"objects": [{"mesh": "cube.off", "material": "glass", "tet": 800}]})";
  EXPECT_EQ(loadBakeManifest(dir / "typo.json").error().code, ErrorCode::ParseError);
  std::ofstream(dir / "unknown.json") << R"({"objects": [{"mesh": "cube.off", "material": "unobtainium"}]})";
  EXPECT_EQ(loadBakeManifest(dir / "unknown.json").error().code, ErrorCode::UnknownMaterial);
  EXPECT_EQ(loadBakeManifest(dir / "missing.json").error().code, ErrorCode::FileNotFound);
  auto dup = ok.value();
  dup.push_back(dup[0]);
  EXPECT_EQ(bakePack(dup).error().code, ErrorCode::InvalidArgument);
  // Two different materials under one name: even a damping difference is refused.
  auto clash = ok.value();
  clash.push_back(clash[0]);
  clash[1].name = "c2";
  clash[1].material.rayleighBetaS *= 2.0;
  EXPECT_EQ(bakePack(clash).error().code, ErrorCode::InvalidArgument);
  std::ofstream(dir / "range.json") << R"({"objects": [{"mesh": "cube.off", "material": "glass", "seed": -1}]})";
  EXPECT_EQ(loadBakeManifest(dir / "range.json").error().code, ErrorCode::ParseError);
  std::ofstream(dir / "frac.json") << R"({"objects": [{"mesh": "cube.off", "material": "glass", "modes": 2.5}]})";
  EXPECT_EQ(loadBakeManifest(dir / "frac.json").error().code, ErrorCode::ParseError);
  EXPECT_EQ(ok.value()[0].tetMesh.meshingRuns, TetMeshSettings{}.meshingRuns);
  std::ofstream(dir / "runs.json") << R"({"objects": [{"mesh": "cube.off", "material": "glass", "meshing_runs": 2}]})";
  auto runs = loadBakeManifest(dir / "runs.json");
  ASSERT_TRUE(runs.ok()) << runs.error().message;
  EXPECT_EQ(runs.value()[0].tetMesh.meshingRuns, 2);
  std::ofstream(dir / "noruns.json") << R"({"objects": [{"mesh": "cube.off", "material": "glass", "meshing_runs": 0}]})";
  EXPECT_EQ(loadBakeManifest(dir / "noruns.json").error().code, ErrorCode::ParseError);
  EXPECT_EQ(ok.value()[0].tetMesh.thinStretch, 1.0);
  std::ofstream(dir / "stretch.json") << R"({"objects": [{"mesh": "cube.off", "material": "glass", "stretch": 2.5}]})";
  auto stretch = loadBakeManifest(dir / "stretch.json");
  ASSERT_TRUE(stretch.ok()) << stretch.error().message;
  EXPECT_EQ(stretch.value()[0].tetMesh.thinStretch, 2.5);
  for (const char* bad : {"0.5", "17", "\"2\""}) {
    std::ofstream(dir / "nostretch.json") << R"({"objects": [{"mesh": "cube.off", "material": "glass", "stretch": )" << bad << "}]}";
    EXPECT_EQ(loadBakeManifest(dir / "nostretch.json").error().code, ErrorCode::ParseError) << bad;
  }
  EXPECT_EQ(ok.value()[0].contactSpreadFraction, 0.0);
  std::ofstream(dir / "spread.json") << R"({"objects": [{"mesh": "cube.off", "material": "glass", "contact_spread": 0.15}]})";
  auto spread = loadBakeManifest(dir / "spread.json");
  ASSERT_TRUE(spread.ok()) << spread.error().message;
  EXPECT_EQ(spread.value()[0].contactSpreadFraction, 0.15);
  for (const char* bad : {"-0.1", "1", "\"0.1\""}) {
    std::ofstream(dir / "nospread.json") << R"({"objects": [{"mesh": "cube.off", "material": "glass", "contact_spread": )" << bad << "}]}";
    EXPECT_EQ(loadBakeManifest(dir / "nospread.json").error().code, ErrorCode::ParseError) << bad;
  }
  ObjectBakeSettings outside = spread.value()[0];
  outside.contactSpreadFraction = 1.0;
  const auto refused = bakeObject(outside);
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().code, ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace brittle

// The brittle CLI end to end: exit codes, typed errors on stderr, and no pack left behind.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "brittle/database/Pack.h"
#include "brittle/testing/AssetChecks.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

struct CliRun {
  int exitCode = -1;
  std::string out;  // stdout and stderr together
};

CliRun run(const std::string& args) {
  const std::string cmd = std::string(BRITTLE_CLI) + " " + args + " 2>&1";
  CliRun r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  std::array<char, 4096> buf{};
  while (size_t n = std::fread(buf.data(), 1, buf.size(), pipe)) r.out.append(buf.data(), n);
  const int status = ::pclose(pipe);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

class CliTest : public ::testing::Test {
 protected:
  std::filesystem::path dir = testing::makeTempDir("cli");
  std::string path(const std::string& name) {
    std::string quoted = "\"";
    quoted += (dir / name).string();
    quoted += '"';
    return quoted;
  }
};

TEST_F(CliTest, BakeThenInspectJson) {
  testing::writeOff(testing::makeBoxSurface(0.2, 0.1, 0.05), dir / "box.off");
  const CliRun bake = run("bake --mesh " + path("box.off") + " --material glass --tets 1200 --modes 8 --quiet --out " + path("box.h5"));
  ASSERT_EQ(bake.exitCode, 0) << bake.out;
  EXPECT_NE(bake.out.find("object box"), std::string::npos) << bake.out;
  const CliRun inspect = run("inspect " + path("box.h5") + " --json");
  ASSERT_EQ(inspect.exitCode, 0) << inspect.out;
  const auto doc = nlohmann::json::parse(inspect.out);
  EXPECT_EQ(doc["format"], "brittle-pack");
  EXPECT_EQ(doc["version"], 2);
  const auto& o = doc["objects"][0];
  EXPECT_EQ(o["name"], "box");
  EXPECT_EQ(o["material"]["name"], "glass");
  EXPECT_EQ(o["modes"]["count"], 8);
  EXPECT_LE(o["modes"]["max_residual"].get<double>(), 1e-8);
  EXPECT_NEAR(o["mass_properties"]["mass_kg"].get<double>(), 0.2 * 0.1 * 0.05 * 2500.0, 1e-9);
  EXPECT_GT(o["mesh"]["min_dihedral_deg"].get<double>(), 5.0);
  for (const char* key : {"meshing", "assembly", "modal", "stress_modes", "total"}) {
    EXPECT_TRUE(o["bake"]["timings_s"].contains(key)) << key;
  }
}

TEST_F(CliTest, TwoProcessesBakeIdenticalDatasets) {
  testing::writeOff(testing::makeIcosphere(0.05, 3), dir / "ball.off");
  for (const char* out : {"a.h5", "b.h5"}) {
    const CliRun r = run("bake --mesh " + path("ball.off") + " --material stone --tets 1500 --modes 8 --quiet --out " + path(out));
    ASSERT_EQ(r.exitCode, 0) << r.out;
  }
  auto a = readPack(dir / "a.h5");
  auto b = readPack(dir / "b.h5");
  ASSERT_TRUE(a.ok() && b.ok());
  const ObjectAsset& x = a.value().objects.at(0);
  const ObjectAsset& y = b.value().objects.at(0);
  testing::expectSameBakedData(x, y);
}

TEST_F(CliTest, BadInputsExitNonZeroWithTheirCodeAndWriteNoPack) {
  auto open = testing::makeBoxSurface(1, 1, 1);
  open.faces.conservativeResize(11, 3);
  testing::writeOff(open, dir / "open.off");
  auto inward = testing::makeBoxSurface(1, 1, 1);
  inward.faces.col(1).swap(inward.faces.col(2));
  testing::writeOff(inward, dir / "inward.off");
  auto crossing = testing::makeBoxSurface(1, 1, 1);
  crossing.vertices.row(7) << -0.5, -0.4, -0.3;
  testing::writeOff(crossing, dir / "crossing.off");
  auto a = testing::makeBoxSurface(1, 1, 1);
  TriangleMesh pinched;  // two cubes sharing one corner
  pinched.vertices.resize(15, 3);
  pinched.vertices << a.vertices, (a.vertices.bottomRows(7).rowwise() + Eigen::RowVector3d(1, 1, 1));
  pinched.faces = a.faces;
  pinched.faces.conservativeResize(24, 3);
  for (Eigen::Index f = 0; f < 12; ++f)
    for (int k = 0; k < 3; ++k) {
      const int32_t v = a.faces(f, k);
      pinched.faces(12 + f, k) = v == 0 ? 7 : v + 7;
    }
  testing::writeOff(pinched, dir / "pinched.off");
  std::ofstream(dir / "nan.off") << "OFF\n4 4 0\n0 0 0\n1 0 0\nnan 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
  std::ofstream(dir / "empty.off");
  std::ofstream(dir / "mesh.xyz") << "0 0 0\n";
  testing::writeOff(testing::makeBoxSurface(1, 1, 1), dir / "good.off");
  std::ofstream(dir / "silly.json") << R"({"name": "silly", "youngs_modulus_pa": -5, "poisson_ratio": 0.2,
    "density_kg_per_m3": 1000, "tensile_strength_pa": 1e6, "fracture_energy_j_per_m2": 1,
    "rayleigh_alpha_per_s": 0, "rayleigh_beta_s": 0, "restitution": 0.5, "source": "test"})";

  struct Case {
    std::string mesh, material, code;
    int exit;
  };
  const std::vector<Case> cases = {
      {"open.off", "glass", "open_mesh", 3},         {"inward.off", "glass", "inward_facing", 3},
      {"crossing.off", "glass", "self_intersection", 3}, {"pinched.off", "glass", "non_manifold", 3},
      {"nan.off", "glass", "non_finite_value", 3},   {"empty.off", "glass", "empty_mesh", 3},
      {"mesh.xyz", "glass", "unknown_format", 3},    {"good.off", "unobtainium", "unknown_material", 4},
      {"good.off", (dir / "silly.json").string(), "invalid_material", 4},
  };
  for (const auto& c : cases) {
    const CliRun r = run("bake --mesh " + path(c.mesh) + " --material \"" + c.material + "\" --tets 500 --modes 4 --quiet --out " +
                      path("out.h5"));
    EXPECT_EQ(r.exitCode, c.exit) << c.mesh << ": " << r.out;
    EXPECT_NE(r.out.find("error [" + c.code + "]"), std::string::npos) << c.mesh << ": " << r.out;
    EXPECT_FALSE(std::filesystem::exists(dir / "out.h5")) << c.mesh;
  }
  // A failed bake leaves an existing pack byte-for-byte as it was.
  testing::writeOff(testing::makeBoxSurface(0.1, 0.1, 0.1), dir / "cube.off");
  ASSERT_EQ(run("bake --mesh " + path("cube.off") + " --material glass --tets 400 --modes 4 --quiet --out " + path("keep.h5")).exitCode, 0);
  const auto before = std::filesystem::file_size(dir / "keep.h5");
  std::ifstream keepIn(dir / "keep.h5", std::ios::binary);
  const std::string original((std::istreambuf_iterator<char>(keepIn)), std::istreambuf_iterator<char>());
  EXPECT_EQ(run("bake --mesh " + path("open.off") + " --material glass --quiet --out " + path("keep.h5")).exitCode, 3);
  std::ifstream keepAfter(dir / "keep.h5", std::ios::binary);
  const std::string after((std::istreambuf_iterator<char>(keepAfter)), std::istreambuf_iterator<char>());
  EXPECT_EQ(std::filesystem::file_size(dir / "keep.h5"), before);
  EXPECT_EQ(after, original);
  // A pack that cannot be written (missing directory) is a pack error and leaves nothing.
  const CliRun unwritable = run("bake --mesh " + path("cube.off") + " --material glass --tets 400 --modes 4 --quiet --out " +
                                path("no-such-dir/out.h5"));
  EXPECT_EQ(unwritable.exitCode, 6) << unwritable.out;
  EXPECT_NE(unwritable.out.find("error [pack_io_error]"), std::string::npos) << unwritable.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "no-such-dir"));
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << "leftover " << entry.path();
  }
}

TEST_F(CliTest, UsageErrorsAndHelp) {
  EXPECT_EQ(run("").exitCode, 2);
  const CliRun missingMesh = run("bake --mesh " + path("nowhere.off") + " --material glass --out " + path("x.h5"));
  EXPECT_EQ(missingMesh.exitCode, 3) << missingMesh.out;
  EXPECT_NE(missingMesh.out.find("error [file_not_found]"), std::string::npos) << missingMesh.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.h5"));
  EXPECT_EQ(run("bake --manifest m.json --mesh a.off --out x.h5").exitCode, 2);  // exclusive options
  const CliRun help = run("bake --help");
  EXPECT_EQ(help.exitCode, 0);
  EXPECT_NE(help.out.find("--tets"), std::string::npos);
  EXPECT_NE(help.out.find("glass"), std::string::npos);
  const CliRun missing = run("inspect " + path("none.h5"));
  EXPECT_EQ(missing.exitCode, 6) << missing.out;
}

}  // namespace
}  // namespace brittle

// The brittle CLI end to end: exit codes, typed errors on stderr, and no pack left behind.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <iterator>
#include <string>
#include <vector>
#include <Eigen/Geometry>
#include <cmath>
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

CliRun runCommand(const std::string& command) {
  const std::string cmd = command + " 2>&1";
  CliRun r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  std::array<char, 4096> buf{};
  while (size_t n = std::fread(buf.data(), 1, buf.size(), pipe)) r.out.append(buf.data(), n);
  const int status = ::pclose(pipe);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

CliRun run(const std::string& args) { return runCommand(std::string(BRITTLE_CLI) + " " + args); }

std::string fileBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string shapesOption() {
  return "--shapes \"" + (testing::sourceDir() / "assets" / "shapes" / "base-shapes.json").string() + "\"";
}

// "bake-db: rank R of N: B entries baked, U reused from checkpoints" → {B, U}; {-1, -1} if absent.
std::pair<long, long> bakedAndReused(const std::string& out) {
  const auto at = out.find("entries baked, ");
  if (at == std::string::npos) return {-1, -1};
  const auto start = out.rfind(": ", at);
  return {std::stol(out.substr(start + 2)), std::stol(out.substr(at + 15))};
}

// The comma-separated cells of one CSV line (the benches write no quoted cells).
std::vector<std::string> csvCells(const std::string& line) {
  std::vector<std::string> cells;
  for (size_t at = 0; at != std::string::npos;) {
    const size_t comma = line.find(',', at);
    cells.push_back(line.substr(at, comma == std::string::npos ? std::string::npos : comma - at));
    at = comma == std::string::npos ? comma : comma + 1;
  }
  return cells;
}

// A CSV file: its header line, and each further line whole and split by csvCells.
struct Csv {
  std::string header;
  std::vector<std::string> lines;
  std::vector<std::vector<std::string>> rows;
};

Csv readCsv(const std::filesystem::path& file) {
  Csv csv;
  std::ifstream in(file);
  std::getline(in, csv.header);
  for (std::string line; std::getline(in, line);) {
    csv.rows.push_back(csvCells(line));
    csv.lines.push_back(std::move(line));
  }
  return csv;
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
  EXPECT_EQ(doc["version"], 3);
  const auto& o = doc["objects"][0];
  EXPECT_EQ(o["name"], "box");
  EXPECT_EQ(o["mesh"]["element"], "p1");
  EXPECT_EQ(o["mesh"]["fem_nodes"], o["mesh"]["nodes"]);
  EXPECT_EQ(o["material"]["name"], "glass");
  EXPECT_EQ(o["modes"]["count"], 8);
  EXPECT_LE(o["modes"]["max_residual"].get<double>(), 1e-8);
  EXPECT_NEAR(o["mass_properties"]["mass_kg"].get<double>(), 0.2 * 0.1 * 0.05 * 2500.0, 1e-9);
  EXPECT_GT(o["mesh"]["min_dihedral_deg"].get<double>(), 5.0);
  for (const char* key : {"meshing", "assembly", "modal", "stress_modes", "total"}) {
    EXPECT_TRUE(o["bake"]["timings_s"].contains(key)) << key;
  }
  // A box's edges are real features: nothing to adjust, nothing printed.
  EXPECT_EQ(bake.out.find("adjusted "), std::string::npos) << bake.out;
  // Quadratic tets: one more FEM node per edge; an unknown element is a usage error.
  const CliRun p2 = run("bake --mesh " + path("box.off") + " --material glass --tets 300 --modes 6 --element p2 --quiet --out " +
                        path("p2.h5"));
  ASSERT_EQ(p2.exitCode, 0) << p2.out;
  const auto p2doc = nlohmann::json::parse(run("inspect " + path("p2.h5") + " --json").out);
  const auto& p2mesh = p2doc["objects"][0]["mesh"];
  EXPECT_EQ(p2mesh["element"], "p2");
  EXPECT_GT(p2mesh["fem_nodes"].get<int64_t>(), p2mesh["nodes"].get<int64_t>() + p2mesh["tets"].get<int64_t>());
  EXPECT_EQ(run("bake --mesh " + path("box.off") + " --material glass --element p3 --out " + path("x.h5")).exitCode, 2);
  // The meshing-run budget is at least one run.
  const CliRun noRuns = run("bake --mesh " + path("box.off") + " --material glass --meshing-runs 0 --out " + path("x.h5"));
  EXPECT_EQ(noRuns.exitCode, 2) << noRuns.out;
}

// play: a glass box dropped on a concrete floor with a steel ball thrown at it; the statistics on
// stdout and in --out-stats, the replay, and the typed errors of a missing scene or asset.
TEST_F(CliTest, PlayWritesStatisticsAndAReplayAndReportsBadScenes) {
  testing::writeOff(testing::makeBoxSurface(0.2, 0.1, 0.05), dir / "box.off");
  const CliRun bake = run("bake --mesh " + path("box.off") + " --material glass --tets 1200 --modes 8 --quiet --out " + path("box.h5"));
  ASSERT_EQ(bake.exitCode, 0) << bake.out;
  {
    std::ofstream scene(dir / "scene.json");
    scene << R"({"duration": 0.3, "time_step": 0.005, "substeps": 2, "floor": {"height": 0},
      "objects": [{"asset": "box", "position": [0, 0, 0.3], "rotation": {"axis": [1, 0, 0], "angle_deg": 30}}],
      "impactors": [{"shape": "sphere", "radius": 0.02, "mass": 0.3, "position": [0, -0.5, 0.3], "velocity": [0, 15, 0]}]})";
  }
  const CliRun play = run("play " + path("box.h5") + " " + path("scene.json") + " --json --frames-every 5 --out-stats " +
                          path("stats.json") + " --out " + path("replay.glb"));
  ASSERT_EQ(play.exitCode, 0) << play.out;
  const auto doc = nlohmann::json::parse(play.out);
  EXPECT_EQ(doc["scene"], "scene");
  EXPECT_EQ(doc["frame_count"], 60);
  for (const char* key : {"impacts", "breaks", "deferred_impacts", "failed_impacts", "bodies_at_end", "frame_time_s", "fracture_share"}) {
    EXPECT_TRUE(doc["summary"].contains(key)) << key;
  }
  EXPECT_GE(doc["summary"]["impacts"].get<int>(), 1);
  EXPECT_GE(doc["frames"].size(), 12u);
  const auto stats = nlohmann::json::parse(fileBytes(dir / "stats.json"));
  EXPECT_EQ(stats["summary"]["pose_hash"], doc["summary"]["pose_hash"]);
  EXPECT_EQ(fileBytes(dir / "replay.glb").substr(0, 4), "glTF");
  EXPECT_EQ(doc["seed"], 1);  // the scene's default
  const CliRun text = run("play " + path("box.h5") + " " + path("scene.json"));
  ASSERT_EQ(text.exitCode, 0) << text.out;
  EXPECT_NE(text.out.find("frame time (ms)"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("scene (seed 1):"), std::string::npos) << text.out;
  // --seed replaces the scene's: reported, and the same history in another process.
  std::string hash;
  for (int i = 0; i < 2; ++i) {
    const CliRun seeded = run("play " + path("box.h5") + " " + path("scene.json") + " --seed 7 --json --frames-every 0");
    ASSERT_EQ(seeded.exitCode, 0) << seeded.out;
    const auto s = nlohmann::json::parse(seeded.out);
    EXPECT_EQ(s["seed"], 7);
    if (i == 0) hash = s["summary"]["pose_hash"].get<std::string>();
    else EXPECT_EQ(s["summary"]["pose_hash"].get<std::string>(), hash);
  }
  // ... another history where the box breaks: its cracks draw from the seed.
  EXPECT_GE(doc["summary"]["breaks"].get<int>(), 1);
  EXPECT_NE(hash, doc["summary"]["pose_hash"].get<std::string>());
  EXPECT_EQ(run("play " + path("box.h5") + " " + path("scene.json") + " --seed -3").exitCode, 2);

  const CliRun missing = run("play " + path("box.h5") + " " + path("no-scene.json"));
  EXPECT_EQ(missing.exitCode, 3) << missing.out;
  EXPECT_NE(missing.out.find("file_not_found"), std::string::npos) << missing.out;
  {
    std::ofstream scene(dir / "other.json");
    scene << R"({"duration": 0.1, "time_step": 0.01, "objects": [{"asset": "vase", "position": [0, 0, 1]}]})";
  }
  const CliRun unknown = run("play " + path("box.h5") + " " + path("other.json"));
  EXPECT_EQ(unknown.exitCode, 2) << unknown.out;
  EXPECT_NE(unknown.out.find("'vase'"), std::string::npos) << unknown.out;
}

// calibrate: frequencies of the baked box as if its E were 80 % of glass's, at glass's ν and
// density, give E = 0.8 × 70 GPa back; the written material file bakes.
TEST_F(CliTest, CalibrateFitsTheMaterialAndWritesAFileThatBakes) {
  testing::writeOff(testing::makeBoxSurface(0.2, 0.1, 0.05), dir / "box.off");
  ASSERT_EQ(run("bake --mesh " + path("box.off") + " --material glass --tets 800 --modes 6 --quiet --out " + path("box.h5")).exitCode, 0);
  const auto doc = nlohmann::json::parse(run("inspect " + path("box.h5") + " --json").out);
  std::string frequencies, rates;
  for (int i = 0; i < 4; ++i) {
    const double f = std::sqrt(0.8) * doc["objects"][0]["modes"]["frequencies_hz"][i].get<double>();
    const double omega = 2.0 * M_PI * f;
    frequencies += (i ? "," : "") + std::to_string(f);
    rates += (i ? "," : "") + std::to_string(0.5 * (10.0 + 3e-7 * omega * omega));
  }
  const CliRun fit = run("calibrate " + path("box.h5") + " --object box --fixed-poisson --frequencies " + frequencies +
                         " --decay-rates " + rates + " --out " + path("fitted.json") + " --json");
  ASSERT_EQ(fit.exitCode, 0) << fit.out;
  const auto r = nlohmann::json::parse(fit.out);
  EXPECT_NEAR(r["youngs_modulus_pa"].get<double>() / 56e9, 1.0, 1e-5);  // to_string keeps 6 decimals
  EXPECT_EQ(r["poisson_ratio"].get<double>(), 0.2);
  EXPECT_NEAR(r["rayleigh_alpha_per_s"].get<double>(), 10.0, 1e-3);
  EXPECT_NEAR(r["rayleigh_beta_s"].get<double>() / 3e-7, 1.0, 1e-5);
  EXPECT_LT(r["rms_frequency_error"].get<double>(), 1e-6);
  EXPECT_EQ(r["frequencies"].size(), 4u);
  const CliRun rebake = run("bake --mesh " + path("box.off") + " --material " + path("fitted.json") +
                            " --tets 800 --modes 6 --quiet --json --out " + path("fitted.h5"));
  ASSERT_EQ(rebake.exitCode, 0) << rebake.out;
  EXPECT_EQ(nlohmann::json::parse(rebake.out)["materials"][0]["name"], "glass-calibrated");

  const CliRun one = run("calibrate " + path("box.h5") + " --object box --frequencies 1000");
  EXPECT_EQ(one.exitCode, 2) << one.out;
  EXPECT_NE(one.out.find("error [invalid_argument]"), std::string::npos) << one.out;
  EXPECT_NE(one.out.find("at least 2"), std::string::npos) << one.out;
  const CliRun missing = run("calibrate " + path("box.h5") + " --object vase --frequencies 1000,2000");
  EXPECT_EQ(missing.exitCode, 2) << missing.out;
  std::ofstream(dir / "m.json") << R"({"frequencies_hz": [1000, 2000], "colour": 3})";
  const CliRun badFile = run("calibrate " + path("box.h5") + " --object box --measurements " + path("m.json"));
  EXPECT_EQ(badFile.exitCode, 3) << badFile.out;
  EXPECT_NE(badFile.out.find("unknown key \"colour\""), std::string::npos) << badFile.out;
}

// calibrate on a P2 object fits with P2 tets: the baked plate's own frequencies, scaled as for an
// E of 80 % of glass's, give that E back (a P1 fit would absorb P1's locking into E).
TEST_F(CliTest, CalibrateFitsAQuadraticObjectWithItsOwnElements) {
  testing::writeOff(testing::makeBoxSurface(0.2, 0.2, 0.01), dir / "plate.off");
  ASSERT_EQ(run("bake --mesh " + path("plate.off") + " --material glass --element p2 --tets 600 --modes 6 --quiet --out " +
                path("plate.h5")).exitCode, 0);
  const auto doc = nlohmann::json::parse(run("inspect " + path("plate.h5") + " --json").out);
  std::string frequencies;
  for (int i = 0; i < 3; ++i) {
    frequencies += (i ? "," : "") + std::to_string(std::sqrt(0.8) * doc["objects"][0]["modes"]["frequencies_hz"][i].get<double>());
  }
  const CliRun fit = run("calibrate " + path("plate.h5") + " --object plate --fixed-poisson --frequencies " + frequencies + " --json");
  ASSERT_EQ(fit.exitCode, 0) << fit.out;
  const auto r = nlohmann::json::parse(fit.out);
  EXPECT_EQ(r["element"], "p2");
  EXPECT_NEAR(r["youngs_modulus_pa"].get<double>() / 56e9, 1.0, 1e-5);
}

// Cracks that end at cracks, from the flag or from a runtime settings file (`"end_at_cracks"`),
// give the same fracture, another than crossing cracks give; the flag wins over a file's false.
TEST_F(CliTest, CracksEndAtCracksFromTheFlagOrTheSettingsFile) {
  testing::writeOff(testing::makeBoxSurface(0.1, 0.1, 0.012), dir / "tile.off");
  ASSERT_EQ(run("bake --mesh " + path("tile.off") + " --material glass --tets 600 --modes 12 --quiet --out " + path("tile.h5")).exitCode, 0);
  std::ofstream(dir / "end.json") << R"({ "end_at_cracks": true })";
  std::ofstream(dir / "cross.json") << R"({ "end_at_cracks": false })";
  const std::string hit = "impact " + path("tile.h5") + " --object tile --point 0,0,0.006 --normal 0,0,1 --speed 20 --json";
  const auto fracture = [&](const std::string& flags) {
    const CliRun r = run(hit + flags);
    EXPECT_EQ(r.exitCode, 0) << r.out;
    if (r.exitCode != 0) return std::pair<std::string, size_t>();
    const auto doc = nlohmann::json::parse(r.out);
    EXPECT_TRUE(doc["broken"].get<bool>()) << flags;
    return std::pair{doc["fingerprint"].get<std::string>(), doc["fragments"].size()};
  };
  const auto crossing = fracture(""), ending = fracture(" --end-at-cracks");
  EXPECT_NE(ending.first, crossing.first);
  EXPECT_LT(ending.second, crossing.second) << "a junction makes fewer pieces than a crossing";
  EXPECT_EQ(fracture(" --settings " + path("end.json")), ending);
  EXPECT_EQ(fracture(" --settings " + path("cross.json")), crossing);
  EXPECT_EQ(fracture(" --settings " + path("cross.json") + " --end-at-cracks"), ending);
}

TEST_F(CliTest, ImpactBenchTimesEitherElementAndNamesItInItsCsv) {
  // A P2 slab: every stage's row says p2, and the slab breaks at 80 m/s (this coarse slab's ring
  // spreads the load over ~3 cm, and 50 m/s, the bench's default, broke it in 3 of 4 impacts).
  const CliRun bench =
      run("bench impact --tets 400 --modes 6 --impacts 2 --element p2 --threads 1 --speed 80 --quiet --csv " + path("b.csv"));
  ASSERT_EQ(bench.exitCode, 0) << bench.out;
  const Csv csv = readCsv(dir / "b.csv");
  EXPECT_EQ(csv.header, "target_tets,tets,modes,prune,stage,impacts,median_ms,p99_ms,broken_fraction,mean_fragments,median_evaluations,"
                        "element,cracks,mean_cut_elements");
  for (const std::vector<std::string>& cells : csv.rows) {
    ASSERT_EQ(cells.size(), 14u) << cells[0];
    EXPECT_EQ(cells[5], "2") << cells[4];            // impacts
    EXPECT_EQ(std::stod(cells[8]), 1.0) << cells[4];  // every one broke the slab
    EXPECT_EQ(cells[11], "p2") << cells[4];
    EXPECT_EQ(cells[12], "cross") << cells[4];        // the World's default
    EXPECT_GT(std::stod(cells[13]), 0.0) << cells[4];
  }
  EXPECT_EQ(csv.rows.size(), 2u * 10);  // pruned and unpruned, ten stages each
  // Cracks that end at cracks: rows of their own beside the crossing ones, on the same impacts.
  ASSERT_EQ(run("bench impact --tets 400 --modes 6 --impacts 2 --element p2 --threads 1 --speed 80 --pruning on --cracks both "
                "--quiet --csv " + path("c.csv")).exitCode, 0);
  std::map<std::string, double> cut;
  for (const std::vector<std::string>& cells : readCsv(dir / "c.csv").rows) {
    if (cells[4] == "total") cut[cells[12]] = std::stod(cells[13]);
  }
  ASSERT_EQ(cut.size(), 2u);
  EXPECT_GT(cut["end"], 0.0);
  EXPECT_GT(cut["cross"], 0.0);
  EXPECT_EQ(run("bench impact --element p3 --csv " + path("x.csv")).exitCode, 2);
  EXPECT_EQ(run("bench impact --cracks sideways --csv " + path("x.csv")).exitCode, 2);
}

// bench place: a row per pack object, the placement against its bytes' read, the background
// preparation, and Worlds destroyed when prepared and midway through it, beside the preparation
// left then (the reference: what the destructor waited for before it stopped running work).
TEST_F(CliTest, PlacementBenchTimesPlacementPreparationAndWorldsDestroyedDuringIt) {
  testing::writeOff(testing::makeBoxSurface(0.2, 0.1, 0.05), dir / "box.off");
  ASSERT_EQ(run("bake --mesh " + path("box.off") + " --material glass --tets 800 --modes 6 --quiet --out " + path("box.h5")).exitCode, 0);
  const CliRun bench = run("bench place " + path("box.h5") + " --repeats 2 --csv " + path("p.csv"));
  ASSERT_EQ(bench.exitCode, 0) << bench.out;
  EXPECT_NE(bench.out.find("destroyed: prepared"), std::string::npos) << bench.out;
  const Csv csv = readCsv(dir / "p.csv");
  EXPECT_EQ(csv.header,
            "object,tets,read_share_ms,place_ms,place_over_read,background_prepare_ms,destroy_prepared_ms,"
            "destroy_midway_ms,destroy_midway_max_ms,preparation_left_ms");
  ASSERT_EQ(csv.rows.size(), 1u);
  const std::vector<std::string>& c = csv.rows[0];
  ASSERT_EQ(c.size(), 10u);
  EXPECT_EQ(c[0], "box");
  for (size_t i = 2; i < c.size(); ++i) EXPECT_GE(std::stod(c[i]), 0.0) << i;
  EXPECT_GE(std::stod(c[8]), std::stod(c[7]));                             // the max is at least the median
  EXPECT_NEAR(std::stod(c[9]), 0.5 * std::stod(c[5]), 2e-5 * std::stod(c[5]));  // left: 3/4, 1/2, 1/4 of it (6 digits)
  EXPECT_EQ(run("bench place " + path("missing.h5")).exitCode, 2);
}

// bench elements: the beam (converged 526.0 Hz) in both orders. P1 converges from above and P2
// at 446 tets is already closer than P1 at 2 071 (measured −4.4 % against +12.5 %).
TEST_F(CliTest, ElementBenchComparesP1AndP2AgainstTheConvergedFrequency) {
  const CliRun bench = run("bench elements --cases beam --p1-tets 500,2000 --p2-tets 300 --modes 8 --impacts 1 --quiet --csv " +
                           path("e.csv"));
  ASSERT_EQ(bench.exitCode, 0) << bench.out;
  const Csv csv = readCsv(dir / "e.csv");
  EXPECT_EQ(csv.header,
            "case,element,target_tets,tets,dofs,first_frequency_hz,reference_hz,error,bake_s,impacts,median_impact_ms,"
            "median_stress_ms,broken_fraction");
  ASSERT_EQ(csv.rows.size(), 3u);
  for (const std::vector<std::string>& c : csv.rows) {
    ASSERT_EQ(c.size(), 13u);
    EXPECT_EQ(c[0], "beam");
    EXPECT_EQ(c[6], "526");
    EXPECT_NEAR(std::stod(c[7]), std::stod(c[5]) / 526.0 - 1.0, 1e-5);  // the error is f1 against the reference
    EXPECT_EQ(c[9], "1");
    EXPECT_GT(std::stod(c[10]), 0.0);
  }
  const double coarse = std::stod(csv.rows[0][7]), fine = std::stod(csv.rows[1][7]), quadratic = std::stod(csv.rows[2][7]);
  EXPECT_GT(coarse, fine);  // P1 converges from above
  EXPECT_GT(fine, 0.0);
  EXPECT_LT(std::abs(quadratic), fine);
  EXPECT_GT(std::stoll(csv.rows[2][4]), std::stoll(csv.rows[1][4]));  // P2's DOF per tet
  EXPECT_EQ(run("bench elements --cases bowl --csv " + path("x.csv")).exitCode, 2);
}

// The speed/accuracy benches write what their chart scripts read, with values that make sense.
TEST_F(CliTest, SpeedAccuracyBenchesWriteTheirCsv) {
  const CliRun integrators = run("bench integrators --points 5 --csv " + path("i.csv") + " --timing-csv " + path("t.csv"));
  ASSERT_EQ(integrators.exitCode, 0) << integrators.out;
  const Csv csv = readCsv(dir / "i.csv");
  EXPECT_EQ(csv.header, "integrator,zeta,omega_h,steps_per_period,peak_error,late_amplitude");
  for (size_t i = 0; i < csv.rows.size(); ++i) {
    const std::vector<std::string>& cells = csv.rows[i];
    const std::string& line = csv.lines[i];
    ASSERT_EQ(cells.size(), 6u) << line;
    const double omegaH = std::stod(cells[2]), error = std::stod(cells[4]), late = std::stod(cells[5]);
    if (cells[0] == "exact") {
      EXPECT_LT(error, 0.05) << line;  // stable and accurate at every step
      EXPECT_LE(late, 1.0) << line;
    }
    if (cells[0] == "explicit-euler" && omegaH >= 100.0) {
      EXPECT_FALSE(error < 1.0) << line;  // blown up
    }
  }
  EXPECT_EQ(csv.rows.size(), 4u * 2 * 5);
  const CliRun modes = run("bench modes --tets 3000 --modes 4,8 --points 1 --repeats 1 --quiet --csv " + path("m.csv"));
  ASSERT_EQ(modes.exitCode, 0) << modes.out;
  const Csv m = readCsv(dir / "m.csv");
  EXPECT_EQ(m.header.substr(0, 40), "point,x,y,tets,modes,reference_pa,correc");
  EXPECT_EQ(m.rows.size(), 2u);
  EXPECT_EQ(run("bench integrators --zeta 1.5 --csv " + path("z.csv")).exitCode, 2);

  // Resolution: the coarser mesh is further from the extrapolated frequencies than the finer.
  const CliRun resolution = run("bench resolution --tets 300,2000 --modes 3 --quiet --csv " + path("r.csv"));
  ASSERT_EQ(resolution.exitCode, 0) << resolution.out;
  const Csv r = readCsv(dir / "r.csv");
  EXPECT_EQ(r.header, "target_tets,tets,mode,frequency_hz,reference_hz,error,difference_from_finest,meshing_s,modal_s,bake_s");
  std::vector<double> errors;
  for (const std::vector<std::string>& cells : r.rows) {
    ASSERT_EQ(cells.size(), 10u);
    errors.push_back(std::abs(std::stod(cells[5])));
  }
  ASSERT_EQ(errors.size(), 6u);
  for (int j = 0; j < 3; ++j) EXPECT_GT(errors[static_cast<size_t>(j)], errors[static_cast<size_t>(3 + j)]) << j;
  EXPECT_EQ(run("bench resolution --tets 300 --csv " + path("one.csv")).exitCode, 2);
}

// Chart 5 on a small pack: a tile and a six-entry database.
TEST_F(CliTest, ExactModesBenchComparesTheMatchWithTheFragmentsOwnModes) {
  testing::writeOff(testing::makeBoxSurface(0.1, 0.1, 0.012), dir / "tile.off");
  const CliRun tile = run("bake --mesh " + path("tile.off") + " --material glass --tets 1500 --modes 10 --quiet --out " + path("tile.h5"));
  ASSERT_EQ(tile.exitCode, 0) << tile.out;
  const CliRun noDatabase = run("bench exact-modes " + path("tile.h5") + " --quiet --csv " + path("no.csv"));
  EXPECT_NE(noDatabase.exitCode, 0);
  EXPECT_NE(noDatabase.out.find("no fragment database"), std::string::npos) << noDatabase.out;
  std::ofstream(dir / "m.json") << R"({ "objects": [ { "name": "tile", "mesh": "tile.off", "material": "glass", "tets": 1500, "modes": 10 } ],
      "database": { "shapes": ")" + (testing::sourceDir() / "assets" / "shapes" / "base-shapes.json").generic_string() +
                                       R"(", "only": ["box", "plate"], "entries": 6, "tets": 300, "modes": 6 } })";
  const CliRun bake = run("bake --manifest " + path("m.json") + " --quiet --out " + path("p.h5"));
  ASSERT_EQ(bake.exitCode, 0) << bake.out;
  // The bodies' frequency errors calibrated on the tile's own pieces, stored in the pack.
  const CliRun calibrate = run("calibrate-errors " + path("p.h5") + " --speeds 40 --seeds 2 --max-fragments 4 --bins 2 --quiet --csv " +
                               path("cal.csv") + " --json");
  ASSERT_EQ(calibrate.exitCode, 0) << calibrate.out;
  const auto calibrated = nlohmann::json::parse(calibrate.out);
  EXPECT_GE(calibrated["database"]["frequency_errors"]["ritz"]["samples"].get<int>(), 2);
  EXPECT_TRUE(calibrated["database"]["frequency_errors"].contains("checked_p2"));
  EXPECT_EQ(readCsv(dir / "cal.csv").rows.size(), calibrated["database"]["frequency_errors"]["ritz"]["samples"].get<size_t>());
  EXPECT_EQ(run("calibrate-errors " + path("tile.h5") + " --quiet").exitCode, 2);  // no database: InvalidArgument
  // At a scene's own impacts (a requirements file, as for size): its objects, impactors and speed ends.
  std::ofstream(dir / "scene.json") << R"({ "objects": [ { "name": "tile", "speeds_mps": [30, 40], "impactors": [ { "mass_kg": 0.05, "radius_m": 0.01 } ] } ] })";
  const CliRun scene = run("calibrate-errors " + path("p.h5") + " --scene " + path("scene.json") +
                           " --seeds 1 --max-fragments 2 --bins 2 --no-p2 --quiet --out " + path("scene.h5"));
  ASSERT_EQ(scene.exitCode, 0) << scene.out;
  EXPECT_NE(scene.out.find("pieces per object: tile "), std::string::npos) << scene.out;
  EXPECT_NE(scene.out.find("(2 impacts)"), std::string::npos) << scene.out;
  std::ofstream(dir / "vase.json") << R"({ "objects": [ { "name": "vase", "speeds_mps": [1, 2], "impactors": [ { "ground": true } ] } ] })";
  const CliRun vase = run("calibrate-errors " + path("p.h5") + " --scene " + path("vase.json") + " --quiet --out " + path("vase.h5"));
  EXPECT_EQ(vase.exitCode, 2);
  EXPECT_NE(vase.out.find("'vase' is not in the pack"), std::string::npos) << vase.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "vase.h5"));
  // Each fragment against the first 3 entries and against all 6: a row for each.
  const CliRun bench = run("bench exact-modes " + path("p.h5") + " --speeds 40 --seeds 1 --max-fragments 3 --exact-modes 6 "
                           "--repeats 1 --entries 3,0 --quiet --csv " + path("x.csv"));
  ASSERT_EQ(bench.exitCode, 0) << bench.out;
  const Csv csv = readCsv(dir / "x.csv");
  EXPECT_EQ(csv.header.substr(0, 62), "object,speed_mps,seed,fragment,volume_fraction,parent_tets,sub");
  EXPECT_NE(csv.header.find(",database_entries,ritz_indicator,"), std::string::npos);
  EXPECT_EQ(csv.header.substr(csv.header.size() - 20), ",check_predicted_p90");
  EXPECT_NE(csv.header.find(",polynomial5_freq_err,"), std::string::npos);
  const auto entriesColumn = static_cast<size_t>(std::count(csv.header.begin(), csv.header.begin() + static_cast<std::ptrdiff_t>(csv.header.find(",database_entries")), ',') + 1);
  std::map<std::string, int> perSize;
  for (size_t k = 0; k < csv.lines.size(); ++k) {
    const std::string& line = csv.lines[k];
    EXPECT_EQ(line.substr(0, 8), "tile,40,") << line;
    // Both paths, the polynomial Ritz, the reference and the bodies' predictions (the calibrated pack) ran.
    EXPECT_EQ(line.find("nan"), std::string::npos) << line;
    ++perSize[csv.rows[k][entriesColumn]];
  }
  ASSERT_EQ(perSize.size(), 2u);
  EXPECT_EQ(perSize["3"], perSize["6"]);
  EXPECT_GE(perSize["6"], 2);
  EXPECT_LE(perSize["6"], 3);
  const CliRun negative = run("bench exact-modes " + path("p.h5") + " --entries -1 --quiet --csv " + path("y.csv"));
  EXPECT_NE(negative.exitCode, 0);
  // An impact that breaks the tile: each fragment that became an object reports its first
  // frequency (a matched one rings at its own, from its polynomial Ritz analysis), the others null.
  const std::string hit = "impact " + path("p.h5") + " --object tile --point 0.05,0.05,0.012 --normal 0,0,1 --speed 60 --json";
  for (const std::string degree : {"5", "0"}) {
    const CliRun broken = run(hit + " --polynomial-degree " + degree);
    ASSERT_EQ(broken.exitCode, 0) << broken.out;
    const auto doc = nlohmann::json::parse(broken.out);
    int objects = 0;
    for (const auto& f : doc["fragments"]) {
      const bool object = f["path"] == "matched" || f["path"] == "exact_modes";
      objects += object ? 1 : 0;
      EXPECT_EQ(f["frequency_hz"].is_number(), object) << f.dump();
      if (object) {
        EXPECT_GT(f["frequency_hz"].get<double>(), 0.0) << f.dump();
      }
    }
    EXPECT_GE(objects, 2) << broken.out;
  }
}

TEST_F(CliTest, FractureStatisticsBenchWritesOneRowPerSeedAndSpeed) {
  const CliRun bench = run("bench fracture --plate-speeds 2,40 --brick-speeds 40 --seeds 3 --plate-tets 3000 --brick-tets 500 "
                           "--modes 8 --quiet --brick-mesh \"" + (testing::sourceDir() / "assets" / "meshes" / "brick.off").string() +
                           "\" --csv " + path("f.csv"));
  ASSERT_EQ(bench.exitCode, 0) << bench.out;
  const Csv csv = readCsv(dir / "f.csv");
  EXPECT_EQ(csv.header, "case,tets,modes,speed_mps,seed,broken,fragments,pieces,largest_mass_fraction,peak_pa,impact_ms");
  double slow = 0.0, fast = 0.0;
  for (size_t i = 0; i < csv.rows.size(); ++i) {
    const std::vector<std::string>& c = csv.rows[i];
    const std::string& line = csv.lines[i];
    ASSERT_EQ(c.size(), 11u) << line;
    const int fragments = std::stoi(c[6]), pieces = std::stoi(c[7]);
    const double largest = std::stod(c[8]);
    EXPECT_GE(fragments, 1) << line;
    EXPECT_LE(pieces, fragments) << line;
    EXPECT_TRUE(largest > 0.0 && largest <= 1.0) << line;
    EXPECT_EQ(c[5] == "1", fragments > 1) << line;
    if (c[0] == "plate") (std::stod(c[3]) < 10.0 ? slow : fast) += fragments;
  }
  EXPECT_EQ(csv.rows.size(), 3u * 3);
  EXPECT_GT(fast, slow);  // a 40 m/s ball breaks the plate into more pieces than a 2 m/s one
  EXPECT_EQ(run("bench fracture --plate-speeds -1 --csv " + path("bad.csv")).exitCode, 2);
}

TEST_F(CliTest, SizeBakesTheSceneObjectsAtTheirModeCountsAndReports) {
  testing::writeOff(testing::makeBoxSurface(0.1, 0.1, 0.012), dir / "tile.off");
  testing::writeOff(testing::makeBoxSurface(0.2, 0.1, 0.06), dir / "block.off");
  std::ofstream(dir / "m.json") << R"({ "objects": [
      { "name": "tile", "mesh": "tile.off", "material": "glass", "tets": 600 },
      { "name": "block", "mesh": "block.off", "material": "concrete", "tets": 500 } ] })";
  std::ofstream(dir / "s.json") << R"({ "peak_stress_error": 0.5, "refracture": false, "objects": [
      { "name": "tile", "speeds_mps": [2, 6], "impactors": [ { "mass_kg": 0.05, "radius_m": 0.01 } ] } ] })";
  std::filesystem::create_directories(dir / "out");
  const CliRun size = run("size --manifest " + path("m.json") + " --scene " + path("s.json") + " --out " + path("out/sized.h5") +
                          " --ladder 4,8 --points 1 --repeats 1 --quiet --report " + path("out/report.json") +
                          " --sized-manifest " + path("out/sized.json"));
  ASSERT_EQ(size.exitCode, 0) << size.out;
  EXPECT_NE(size.out.find("not used by the scene"), std::string::npos) << size.out;
  const auto report = nlohmann::json::parse(fileBytes(dir / "out" / "report.json"));
  ASSERT_EQ(report["objects"].size(), 1u);
  // The ladder's counts, each raised past a pair of equal frequencies it would split (the square
  // tile's modes come in pairs: 4 is measured as 5).
  const int chosen = report["objects"][0]["chosen_modes"].get<int>();
  const auto& trials = report["objects"][0]["trials"];
  ASSERT_EQ(trials.size(), 2u);
  EXPECT_EQ(trials[0]["modes"].get<int>(), 5) << report.dump();
  EXPECT_EQ(trials[1]["modes"].get<int>(), 8) << report.dump();
  EXPECT_TRUE(chosen == trials[0]["modes"].get<int>() || chosen == trials[1]["modes"].get<int>()) << report.dump();
  EXPECT_EQ(report["skipped_objects"], nlohmann::json::array({"block"}));
  EXPECT_TRUE(report["frequency_errors"].is_null());  // no database (the scene does not refracture): nothing to calibrate
  // The sized tile is P2 (below), which stores more than the all-maximum P1 side: the savings at
  // one order are SceneSizingTest's.
  EXPECT_GT(report["sized"]["pack_bytes"].get<int64_t>(), 0);
  EXPECT_GT(report["maximum"]["pack_bytes"].get<int64_t>(), 0);
  const auto inspect = nlohmann::json::parse(run("inspect " + path("out/sized.h5") + " --json").out);
  ASSERT_EQ(inspect["objects"].size(), 1u);
  EXPECT_EQ(inspect["objects"][0]["modes"]["count"].get<int>(), chosen);
  // Both element orders were tried (the default): the thin tile's P1 tets lock in bending, its first
  // frequency far from P2's on the same tets, so P2 is kept, in the pack and in the manifest.
  const auto& elements = report["objects"][0]["element_trials"];
  ASSERT_EQ(elements.size(), 2u) << report.dump();
  EXPECT_EQ(elements[0]["element"], "p1");
  EXPECT_GT(elements[0]["frequency_error"].get<double>(), 0.02) << report.dump();
  EXPECT_FALSE(elements[0]["target_met"].get<bool>());
  EXPECT_EQ(elements[1]["frequency_error"].get<double>(), 0.0);
  EXPECT_EQ(report["objects"][0]["element"], "p2");
  EXPECT_EQ(inspect["objects"][0]["mesh"]["element"], "p2");
  EXPECT_EQ(nlohmann::json::parse(fileBytes(dir / "out" / "sized.json"))["objects"][0]["element"], "p2");
  // The sized manifest bakes the same object from its own directory.
  ASSERT_EQ(run("bake --manifest " + path("out/sized.json") + " --quiet --out " + path("again.h5")).exitCode, 0);
  // The runtime settings beside the sized pack carry the scene's debris threshold; impacts read
  // them, and a flag given on the command line wins.
  const auto settings = nlohmann::json::parse(fileBytes(dir / "out" / "sized.settings.json"));
  EXPECT_EQ(settings["debris_volume_fraction"].get<double>(), report["debris_volume_fraction"].get<double>());
  EXPECT_EQ(report["debris"].size(), 1u);
  const std::string hit = "impact " + path("out/sized.h5") + " --object tile --point 0,0,0.006 --normal 0,0,1 --speed 3 --json";
  EXPECT_EQ(run(hit + " --settings " + path("out/sized.settings.json")).exitCode, 0);
  EXPECT_EQ(run(hit + " --settings " + path("out/sized.settings.json") + " --debris 0.2").exitCode, 0);
  // The truncated modes' own peak is a second scan, run on request only; it changes nothing else.
  const CliRun plain = run(hit), reported = run(hit + " --report-uncorrected");
  ASSERT_EQ(plain.exitCode, 0) << plain.out;
  ASSERT_EQ(reported.exitCode, 0) << reported.out;
  const auto plainDoc = nlohmann::json::parse(plain.out), reportedDoc = nlohmann::json::parse(reported.out);
  EXPECT_TRUE(plainDoc["peak_without_correction_pa"].is_null());
  EXPECT_GT(reportedDoc["peak_without_correction_pa"].get<double>(), 0.0);
  EXPECT_EQ(plainDoc["peak_principal_stress_pa"].get<double>(), reportedDoc["peak_principal_stress_pa"].get<double>());
  EXPECT_EQ(plainDoc["cracks"], reportedDoc["cracks"]);
  // Repeats on fresh instances: warm stage times over the repeats, the first impact as reported.
  const CliRun repeated = run(hit + " --repeat 3");
  ASSERT_EQ(repeated.exitCode, 0) << repeated.out;
  const auto repeatedDoc = nlohmann::json::parse(repeated.out);
  EXPECT_EQ(repeatedDoc["warm_times_s"]["repeats"].get<int>(), 2);
  EXPECT_GT(repeatedDoc["warm_times_s"]["stress"].get<double>(), 0.0);
  EXPECT_EQ(repeatedDoc["fingerprint"], plainDoc["fingerprint"]);
  EXPECT_FALSE(plainDoc.contains("warm_times_s"));
  EXPECT_EQ(run(hit + " --repeat 0").exitCode, 2);
  std::ofstream(dir / "typo.settings.json") << R"({ "debris": 0.1 })";
  const CliRun typo = run(hit + " --settings " + path("typo.settings.json"));
  EXPECT_EQ(typo.exitCode, 3);
  EXPECT_NE(typo.out.find("error [parse_error]"), std::string::npos) << typo.out;
  EXPECT_NE(run(hit + " --settings " + path("none.settings.json")).exitCode, 0);
  // A scene object the manifest lacks, and a broken requirements file, are typed errors.
  std::ofstream(dir / "vase.json") << R"({ "objects": [ { "name": "vase", "speeds_mps": [1, 2], "impactors": [ { "ground": true } ] } ] })";
  const CliRun missing = run("size --manifest " + path("m.json") + " --scene " + path("vase.json") + " --quiet --out " + path("no.h5"));
  EXPECT_NE(missing.exitCode, 0);
  EXPECT_NE(missing.out.find("error [invalid_argument]"), std::string::npos) << missing.out;
  std::ofstream(dir / "broken.json") << R"({ "objects": [ { "name": "tile", "speeds_mps": [3, 1], "impactors": [ { "ground": true } ] } ] })";
  const CliRun broken = run("size --manifest " + path("m.json") + " --scene " + path("broken.json") + " --quiet --out " + path("no.h5"));
  EXPECT_EQ(broken.exitCode, 3);
  EXPECT_NE(broken.out.find("error [parse_error]"), std::string::npos) << broken.out;
  // A negative search precision is refused before anything is baked.
  const CliRun precision = run("size --manifest " + path("m.json") + " --scene " + path("s.json") +
                               " --search-precision 1,-0.5 --quiet --out " + path("no.h5"));
  EXPECT_NE(precision.exitCode, 0);
  EXPECT_NE(precision.out.find("--search-precision"), std::string::npos) << precision.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "no.h5"));
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

// bake-db → query → inspect, and the search benchmark, through the CLI.
TEST_F(CliTest, BakeDbThenQueryFindsTheEntryInAnotherPose) {
  const std::string shapes = "\"" + (testing::sourceDir() / "assets" / "shapes" / "base-shapes.json").string() + "\"";
  const CliRun bake = run("bake-db --shapes " + shapes + " --only box,wedge,cone --entries 6 --seed 3 --tets 300 --modes 4 --quiet --out " + path("db.h5"));
  ASSERT_EQ(bake.exitCode, 0) << bake.out;
  auto pack = readPack(dir / "db.h5");
  ASSERT_TRUE(pack) << pack.error().message;
  const FragmentDatabase& db = pack.value().database;
  ASSERT_EQ(db.entries.size(), 6u);
  EXPECT_EQ(db.entries[1].baseShape, "wedge");
  EXPECT_EQ(db.entries[2].asset.modal.frequenciesHz.size(), 4);

  // Entry 4, turned 90° about z, scaled to 0.3 m and moved: found first at ~zero distance, with its
  // mass rescaled by the volume (entries are at unit volume, up to the tet mesh's facet error).
  TriangleMesh query = db.entries[4].surface;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  query.vertices = ((query.vertices * r.transpose()) * 0.3).rowwise() + Eigen::RowVector3d(1, 2, 3);
  testing::writeOff(query, dir / "query.off");
  // The bake's default indexes: the inverted files of the moments and of the improved voxels (one list at 6 entries).
  EXPECT_EQ(db.indexSettings[static_cast<size_t>(DescriptorKind::Moment)].kind, DescriptorIndexSettings::Kind::Ivf);
  EXPECT_EQ(db.indexSettings[static_cast<size_t>(DescriptorKind::VoxelImproved)].kind, DescriptorIndexSettings::Kind::Ivf);
  // Every index, stored or given in place of the stored one (with its own defaults), finds it.
  for (const char* descriptor : {"moment", "voxel-improved"}) {
    for (const char* index : {"brute-force", "kd-forest", "ivf"}) {
      SCOPED_TRACE(std::string(descriptor) + " " + index);
      const CliRun q = run("query " + path("db.h5") + " --mesh " + path("query.off") + " --descriptor " + descriptor +
                           " --index " + index + " --k 3 --json");
      ASSERT_EQ(q.exitCode, 0) << q.out;
      const auto doc = nlohmann::json::parse(q.out);
      ASSERT_EQ(doc["matches"].size(), 3u);
      const auto& best = doc["matches"][0];
      EXPECT_EQ(best["entry"], 4);
      EXPECT_LT(best["distance"].get<double>(), 1e-3);
      EXPECT_LE(best["distance"].get<double>(), doc["matches"][1]["distance"].get<double>());
      EXPECT_NEAR(best["entry_to_query"]["scale_m"].get<double>(), 0.3, 1e-9);
      const double entryMass = db.entries[4].asset.massProperties.massKg;  // ≈ ρ · 1 m³
      EXPECT_NEAR(entryMass, db.referenceMaterial.densityKgPerM3, 0.01 * entryMass);
      EXPECT_NEAR(best["physics"]["mass_kg"].get<double>(), 0.027 * entryMass, 1e-9 * entryMass);
      // Frequencies scale as 1/size: f(0.3 m) = f(1 m) / 0.3.
      EXPECT_NEAR(best["physics"]["frequencies_hz"][0].get<double>() * 0.3,
                  db.entries[4].asset.modal.frequenciesHz[0], 1e-6 * db.entries[4].asset.modal.frequenciesHz[0]);
    }
  }
  const CliRun text = run("query " + path("db.h5") + " --mesh " + path("query.off"));
  EXPECT_EQ(text.exitCode, 0) << text.out;
  EXPECT_NE(text.out.find("-00004"), std::string::npos) << text.out;
  // --digest: the built index's digest, 16 hex digits, the same for two builds and another for
  // another index (tests/tools/determinism_across_processes.sh compares it across processes).
  const auto digestOf = [&](const std::string& index) {
    const CliRun q = run("query " + path("db.h5") + " --mesh " + path("query.off") + " --index " + index + " --k 1 --digest --json");
    EXPECT_EQ(q.exitCode, 0) << q.out;
    return q.exitCode == 0 ? nlohmann::json::parse(q.out)["query"]["index_digest"].get<std::string>() : std::string();
  };
  const std::string digest = digestOf("hnsw");
  EXPECT_EQ(digest.size(), 16u);
  EXPECT_EQ(digest.find_first_not_of("0123456789abcdef"), std::string::npos) << digest;
  EXPECT_EQ(digestOf("hnsw"), digest);
  EXPECT_NE(digestOf("kd-forest"), digest);
  const CliRun digestText = run("query " + path("db.h5") + " --mesh " + path("query.off") + " --digest");
  EXPECT_NE(digestText.out.find("index digest "), std::string::npos) << digestText.out;
  const CliRun inspect = run("inspect " + path("db.h5") + " --json");
  ASSERT_EQ(inspect.exitCode, 0) << inspect.out;
  const auto inspected = nlohmann::json::parse(inspect.out);
  int64_t tets = 0;
  for (const FragmentEntry& e : db.entries) tets += e.asset.tetMesh.tets.rows();
  EXPECT_EQ(inspected["database"]["total_tets"].get<int64_t>(), tets);  // counted without reading the entries
  EXPECT_TRUE(inspected["database"]["physics"].get<bool>());
  // inspect checks every entry, one at a time: a damaged one is a pack error (exit 6).
  std::filesystem::copy_file(dir / "db.h5", dir / "damaged.h5");
  ASSERT_TRUE(testing::damageChunk(dir / "damaged.h5", "/database/entries/stress_modes", 0));
  const CliRun damaged = run("inspect " + path("damaged.h5"));
  EXPECT_EQ(damaged.exitCode, 6) << damaged.out;
  EXPECT_NE(damaged.out.find("error [pack_corrupt]"), std::string::npos) << damaged.out;
  EXPECT_NE(damaged.out.find("/database/entries/stress_modes"), std::string::npos) << damaged.out;

  // Errors: an unknown shape, an unknown descriptor, a pack without a database, an open query mesh.
  const CliRun unknownShape = run("bake-db --shapes " + shapes + " --only teapot --entries 2 --quiet --out " + path("x.h5"));
  EXPECT_EQ(unknownShape.exitCode, 2) << unknownShape.out;  // invalid_argument is a usage error
  EXPECT_NE(unknownShape.out.find("teapot"), std::string::npos) << unknownShape.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.h5"));
  EXPECT_EQ(run("query " + path("db.h5") + " --mesh " + path("query.off") + " --descriptor zernike").exitCode, 2);
  testing::writeOff(testing::makeBoxSurface(0.2, 0.1, 0.05), dir / "box.off");
  ASSERT_EQ(run("bake --mesh " + path("box.off") + " --material glass --tets 300 --modes 4 --quiet --out " + path("objects.h5")).exitCode, 0);
  const CliRun noDatabase = run("query " + path("objects.h5") + " --mesh " + path("query.off"));
  EXPECT_NE(noDatabase.exitCode, 0) << noDatabase.out;
  EXPECT_NE(noDatabase.out.find("error ["), std::string::npos) << noDatabase.out;
  auto open = testing::makeBoxSurface(1, 1, 1);
  open.faces.conservativeResize(11, 3);
  testing::writeOff(open, dir / "open.off");
  const CliRun openQuery = run("query " + path("db.h5") + " --mesh " + path("open.off"));
  EXPECT_EQ(openQuery.exitCode, 3) << openQuery.out;
  EXPECT_NE(openQuery.out.find("error [open_mesh]"), std::string::npos) << openQuery.out;
}

TEST_F(CliTest, SearchBenchWritesItsCsv) {
  const std::string shapes = "\"" + (testing::sourceDir() / "assets" / "shapes" / "base-shapes.json").string() + "\"";
  const CliRun bench = run("bench search --shapes " + shapes + " --sizes 40,80 --queries 8 --physics-queries 0 --index kd-forest:2:16 --quiet --csv " +
                           path("search.csv") + " --cost-csv " + path("cost.csv"));
  ASSERT_EQ(bench.exitCode, 0) << bench.out;
  const Csv csv = readCsv(dir / "search.csv");
  EXPECT_EQ(csv.header.rfind("entries,descriptor,index,", 0), 0u) << csv.header;
  int bruteForce = 0;
  for (const std::string& line : csv.lines) {
    if (line.find(",brute-force,") != std::string::npos) {
      ++bruteForce;
      EXPECT_NE(line.find(",1,0,0,0,0"), std::string::npos) << "exact search has recall 1: " << line;
    }
  }
  EXPECT_EQ(csv.lines.size(), 2u * 3 * 2);  // sizes × kinds × (brute force, kd-forest)
  EXPECT_EQ(bruteForce, 2 * 3);
  std::ifstream cost(dir / "cost.csv");
  const std::string costText((std::istreambuf_iterator<char>(cost)), std::istreambuf_iterator<char>());
  for (const char* stage : {"fragment-cut", "canonical-frame", "moment", "voxel", "voxel-improved", "moment-total",
                            "voxel-total", "voxel-improved-total", "canonical-frame-warm", "moment-total-warm"}) {
    EXPECT_NE(costText.find(std::string("\n") + stage + ","), std::string::npos) << stage;
  }
}

// A database baked once (bake-db) searched by `bench search --database`: the pack's entries and its
// descriptor settings (an 8³ grid here, not the bench's 16³), sizes above its entry count skipped,
// and typed refusals.
TEST_F(CliTest, SearchBenchSearchesAPacksDatabase) {
  const std::string shapes = "\"" + (testing::sourceDir() / "assets" / "shapes" / "base-shapes.json").string() + "\"";
  ASSERT_EQ(run("bake-db " + shapesOption() + " --entries 30 --descriptors-only --voxel-resolution 8 --runtime-fraction 0.5 --quiet --out " +
                path("db.h5")).exitCode, 0);
  // The CSV's share of runtime-broken entries is the pack's own, counted here from its entries.
  const auto pack = readPack(dir / "db.h5");
  ASSERT_TRUE(pack) << pack.error().message;
  const auto& entries = pack.value().database.entries;
  const auto fromRuntime = std::count_if(entries.begin(), entries.end(), brokenByTheRuntime);
  ASSERT_GT(fromRuntime, 0);
  ASSERT_LT(fromRuntime, 30);
  std::ostringstream share;
  share << static_cast<double>(fromRuntime) / 30.0;
  const std::string bench = "bench search --shapes " + shapes + " --sizes 30,60 --queries 5 --physics-queries 0 --index hnsw:16:16 --csv " +
                            path("search.csv") + " --cost-csv " + path("cost.csv");
  const CliRun searched = run(bench + " --database " + path("db.h5"));
  ASSERT_EQ(searched.exitCode, 0) << searched.out;
  EXPECT_NE(searched.out.find("database: 30 entries read from"), std::string::npos) << searched.out;
  EXPECT_NE(searched.out.find("skip moment at 60 entries (the pack's database holds 30)"), std::string::npos) << searched.out;
  const Csv csv = readCsv(dir / "search.csv");
  ASSERT_EQ(csv.lines.size(), 3u * 2);  // 30 entries × kinds × (brute force, the graph); 60 skipped
  for (const std::string& line : csv.lines) {
    EXPECT_EQ(line.rfind("30,", 0), 0u) << line;
    EXPECT_NE(line.find("," + share.str() + ",cut,4,8,each"), std::string::npos) << "the pack's settings and runtime share: " << line;
    if (line.find(",brute-force,") != std::string::npos) {
      EXPECT_NE(line.find(",1,0,0,0,0"), std::string::npos) << line;
    }
  }
  // The pack's settings are the database's: the bake's own options are refused beside it.
  const CliRun both = run(bench + " --database " + path("db.h5") + " --voxel-resolution 16");
  EXPECT_EQ(both.exitCode, 2) << both.out;
  EXPECT_NE(both.out.find("excludes"), std::string::npos) << both.out;
  // A pack of objects only: a typed error, no CSV written.
  testing::writeOff(testing::makeBoxSurface(0.2, 0.1, 0.05), dir / "box.off");
  ASSERT_EQ(run("bake --mesh " + path("box.off") + " --material glass --tets 300 --modes 4 --quiet --out " + path("objects.h5")).exitCode, 0);
  std::filesystem::remove(dir / "search.csv");
  const CliRun objects = run(bench + " --database " + path("objects.h5"));
  EXPECT_EQ(objects.exitCode, 2) << objects.out;  // invalid_argument
  EXPECT_NE(objects.out.find("holds no fragment database"), std::string::npos) << objects.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "search.csv"));
}

TEST_F(CliTest, SearchBenchWithRuntimeFragmentsAsQueriesAndEntries) {
  const std::string shapes = "\"" + (testing::sourceDir() / "assets" / "shapes" / "base-shapes.json").string() + "\"";
  const CliRun bench = run("bench search --shapes " + shapes +
                           " --sizes 14 --kinds moment --queries 4 --physics-queries 2 --physics-tets 300"
                           " --runtime-fraction 0.5 --runtime-queries --index kd-forest:1:8 --quiet --csv " +
                           path("search.csv") + " --cost-csv " + path("cost.csv"));
  ASSERT_EQ(bench.exitCode, 0) << bench.out;
  const Csv csv = readCsv(dir / "search.csv");
  EXPECT_NE(csv.header.find(",database_runtime_fraction,query_source"), std::string::npos) << csv.header;
  for (const std::string& line : csv.lines) EXPECT_NE(line.find(",0.5,runtime"), std::string::npos) << line;
  EXPECT_EQ(csv.lines.size(), 2u);  // brute force and the kd-forest
}


// Killed mid-bake: the pack at --out is still the previous one, whole; --resume then reuses the
// finished chunks and gives the same database as an uninterrupted bake.
TEST_F(CliTest, KilledDatabaseBakeKeepsThePreviousPackAndResumesToTheSameDatabase) {
  const std::string bake = "bake-db " + shapesOption() + " --entries 12 --tets 400 --modes 6 --threads 1 --checkpoint-every 2 --quiet";
  const CliRun reference = run(bake + " --out " + path("reference.h5"));
  ASSERT_EQ(reference.exitCode, 0) << reference.out;
  EXPECT_EQ(bakedAndReused(reference.out), std::make_pair(12l, 0l)) << reference.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "reference.h5.checkpoints"));  // removed once the pack is whole
  const CliRun previous = run("bake-db " + shapesOption() + " --entries 2 --descriptors-only --quiet --out " + path("out.h5"));
  ASSERT_EQ(previous.exitCode, 0) << previous.out;
  const std::string previousBytes = fileBytes(dir / "out.h5");

  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const std::string command = "exec " + std::string(BRITTLE_CLI) + " " + bake + " --out " + path("out.h5") + " >/dev/null 2>&1";
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const auto firstChunk = dir / "out.h5.checkpoints" / "entries-000000000-000000002.h5";
  bool running = true;
  for (int waited = 0; waited < 60000 && !std::filesystem::exists(firstChunk); waited += 5) {
    if (::waitpid(child, nullptr, WNOHANG) == child) {
      running = false;
      break;
    }
    ::usleep(5000);
  }
  ASSERT_TRUE(running) << "the bake ended before it could be killed";
  ASSERT_TRUE(std::filesystem::exists(firstChunk));
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  EXPECT_TRUE(fileBytes(dir / "out.h5") == previousBytes) << "a killed bake touched the previous pack";

  const CliRun resumed = run(bake + " --resume --out " + path("out.h5"));
  ASSERT_EQ(resumed.exitCode, 0) << resumed.out;
  const auto [baked, reused] = bakedAndReused(resumed.out);
  EXPECT_GE(reused, 2) << resumed.out;
  EXPECT_EQ(baked + reused, 12) << resumed.out;
  auto a = readPack(dir / "reference.h5");
  auto b = readPack(dir / "out.h5");
  ASSERT_TRUE(a && b);
  testing::expectSameDatabase(a.value().database, b.value().database);

  // Resuming under other settings is refused with the pack untouched.
  const std::string before = fileBytes(dir / "out.h5");
  ASSERT_TRUE(std::filesystem::create_directories(dir / "other"));
  // Checkpoints of a smaller bake do: a resume compares the settings before it bakes or reuses anything.
  const std::string two = "bake-db " + shapesOption() + " --entries 2 --tets 400 --checkpoint-every 2 --quiet";
  const CliRun first = run(two + " --modes 6 --keep-checkpoints --checkpoint-dir " + path("other") + " --out " + path("x.h5"));
  ASSERT_EQ(first.exitCode, 0) << first.out;
  const CliRun other = run(two + " --modes 7 --resume --checkpoint-dir " + path("other") + " --out " + path("out.h5"));
  EXPECT_NE(other.exitCode, 0);
  EXPECT_NE(other.out.find("other settings"), std::string::npos) << other.out;
  EXPECT_TRUE(fileBytes(dir / "out.h5") == before);
}

// mpirun -np N brittle bake-db gives the single-process pack, byte for byte (descriptors only:
// no wall-clock timings in the pack), and the same database with physics.
TEST_F(CliTest, MpiBakeEqualsTheSingleProcessBake) {
#ifndef BRITTLE_MPIEXEC
  GTEST_SKIP() << "built without MPI";
#else
  ::setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);  // CI containers run as root
  ::setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  // The ranks run without LeakSanitizer (AddressSanitizer still checks every access): OpenMPI's
  // libraries have no frame pointers, so a leftover of theirs at MPI_Finalize has a stack that no
  // suppression can name unless every allocation is unwound slowly, which made this test 15x
  // slower under the sanitizers. The same bake in one process, without MPI, is leak-checked here
  // and in the database bake tests.
  const char* asan = std::getenv("ASAN_OPTIONS");
  const std::string mpiexec = "env ASAN_OPTIONS=" + std::string(asan ? asan : "") + (asan && *asan ? ":" : "") +
                              "detect_leaks=0 " + BRITTLE_MPIEXEC;
  const std::string descriptors = "bake-db " + shapesOption() + " --entries 10 --descriptors-only --checkpoint-every 2 --quiet";
  const CliRun single = run(descriptors + " --out " + path("single.h5"));
  ASSERT_EQ(single.exitCode, 0) << single.out;
  for (int ranks : {2, 4}) {
    const std::string out = "ranks" + std::to_string(ranks) + ".h5";
    const CliRun r = runCommand(mpiexec + " --oversubscribe -np " + std::to_string(ranks) + " " +
                                BRITTLE_CLI + " " + descriptors + " --out " + path(out));
    ASSERT_EQ(r.exitCode, 0) << r.out;
    EXPECT_NE(r.out.find("rank " + std::to_string(ranks - 1) + " of " + std::to_string(ranks)), std::string::npos) << r.out;
    EXPECT_TRUE(fileBytes(dir / out) == fileBytes(dir / "single.h5")) << ranks << " ranks";
  }
  const std::string physics = "bake-db " + shapesOption() + " --entries 5 --tets 400 --modes 6 --checkpoint-every 2 --quiet";
  ASSERT_EQ(run(physics + " --out " + path("p1.h5")).exitCode, 0);
  const CliRun two = runCommand(mpiexec + " --oversubscribe -np 2 " + BRITTLE_CLI + " " + physics +
                                " --threads 1 --out " + path("p2.h5"));
  ASSERT_EQ(two.exitCode, 0) << two.out;
  auto a = readPack(dir / "p1.h5");
  auto b = readPack(dir / "p2.h5");
  ASSERT_TRUE(a && b);
  testing::expectSameDatabase(a.value().database, b.value().database);
#endif
}

}  // namespace
}  // namespace brittle

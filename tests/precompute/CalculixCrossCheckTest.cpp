// The full-FEM reference (FullFemReference.h) against an independent FEM code: CalculiX (ccx,
// Debian's calculix-ccx) with linear tetrahedra C3D4 and direct implicit dynamics, on one real
// case — a Mesh_3 glass plate hit by a steel ball through the runtime's own contact (pulse,
// load nodes, direction), Rayleigh damping included.
//
// How the deck matches our model (each point checked against an independent numpy solver):
// - *DYNAMIC, DIRECT, ALPHA=0: HHT with α = 0 is Newmark average acceleration (γ = ½, β = ¼);
//   ccx's default α = −0.05 changes the stresses by ~3 %. The step is fixed with DIRECT, and
//   *STEP, INC= must exceed the step count (the default limit is 100 increments).
// - Mass: ccx integrates the C3D4 mass with one point, M_e = ρV/16·𝟙 (neither consistent nor
//   lumped). The tets get density 0.8ρ and every node a point mass Σ ρV_e/20 over its tets, so
//   the sum is ρV/20·(𝟙 + I), exactly the consistent matrix we use (without this, +2 % on the
//   peak and the peak at another step).
// - Load: the amplitude is tabulated at every step and ccx applies it at t_{n+1}, as we do; an
//   explicit zero past the end avoids relying on ccx's extrapolation. A free body needs no
//   *BOUNDARY (the effective matrix holds M).
// - Output: *EL PRINT S writes one line per element and increment (sxx syy szz sxy sxz syz,
//   tensor shears) to the .dat file, 7 significant digits; the largest principal stress over
//   elements and increments is compared with ours.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

#include "brittle/core/Timing.h"
#include "brittle/precompute/FullFemReference.h"
#include "brittle/runtime/World.h"
#include "brittle/testing/BakeFixtures.h"
#include "brittle/testing/Calculix.h"

namespace brittle {
namespace {

using testing::ccxNumber;
using testing::fortranDouble;

struct Impact {
  TetMesh mesh;
  Material material;
  ImpactResult result;
};

Impact plateImpact() {
  Impact c;
  c.material = testing::presetGlass();
  Pack pack = testing::makeGlassPlatePack(1500, 10, 0.1).value();
  c.mesh = pack.objects[0].tetMesh;
  WorldSettings s;
  s.fracture.matchFragments = false;
  World world = World::create(std::move(pack), s).value();
  ImpactDesc d;
  d.object = world.addObject({.asset = "plate"}).value();
  d.pointWorld = Eigen::Vector3d(0.045, 0.052, 0.01);
  d.normalWorld = Eigen::Vector3d::UnitZ();
  d.speedMps = 3.0;
  d.impactorMassKg = 0.02;
  d.impactorRadiusM = 0.008;
  c.result = world.impact(d).value();
  return c;
}

/// The deck: C3D4 at 0.8ρ plus nodal point masses (the consistent mass), Rayleigh damping, the
/// pulse tabulated at every step, the load on the contact nodes.
void writeDeck(const std::filesystem::path& path, const Impact& c, double h, int64_t steps) {
  const TetMesh& mesh = c.mesh;
  const Material& m = c.material;
  std::ofstream out(path);
  out << "*HEADING\nbrittle full-FEM reference cross-check\n*NODE, NSET=NALL\n";
  for (Eigen::Index n = 0; n < mesh.nodes.rows(); ++n) {
    out << n + 1 << ", " << ccxNumber(mesh.nodes(n, 0)) << ", " << ccxNumber(mesh.nodes(n, 1)) << ", " << ccxNumber(mesh.nodes(n, 2)) << "\n";
  }
  out << "*ELEMENT, TYPE=C3D4, ELSET=ETET\n";
  std::vector<double> nodeMass(static_cast<size_t>(mesh.nodes.rows()), 0.0);
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
    out << e + 1;
    Eigen::Vector3d p[4];
    for (int i = 0; i < 4; ++i) {
      out << ", " << mesh.tets(e, i) + 1;
      p[i] = mesh.nodes.row(mesh.tets(e, i)).transpose();
    }
    out << "\n";
    const double volume = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])) / 6.0;
    for (int i = 0; i < 4; ++i) nodeMass[static_cast<size_t>(mesh.tets(e, i))] += m.densityKgPerM3 * volume / 20.0;
  }
  const Eigen::Index first = mesh.tets.rows() + 1;
  for (Eigen::Index n = 0; n < mesh.nodes.rows(); ++n) {
    out << "*ELEMENT, TYPE=MASS, ELSET=EM" << n + 1 << "\n" << first + n << ", " << n + 1 << "\n";
  }
  out << "*MATERIAL, NAME=GLASS\n*ELASTIC\n" << ccxNumber(m.youngsModulusPa) << ", " << ccxNumber(m.poissonRatio) << "\n";
  out << "*DENSITY\n" << ccxNumber(0.8 * m.densityKgPerM3) << "\n";
  out << "*DAMPING, ALPHA=" << ccxNumber(m.rayleighAlphaPerS) << ", BETA=" << ccxNumber(m.rayleighBetaS) << "\n";
  out << "*SOLID SECTION, ELSET=ETET, MATERIAL=GLASS\n";
  for (Eigen::Index n = 0; n < mesh.nodes.rows(); ++n) {
    out << "*MASS, ELSET=EM" << n + 1 << "\n" << ccxNumber(nodeMass[static_cast<size_t>(n)]) << "\n";
  }
  out << "*AMPLITUDE, NAME=PULSE\n";
  for (int64_t n = 0; n <= steps; ++n) {
    const double t = static_cast<double>(n) * h;
    out << ccxNumber(t) << ", " << ccxNumber(hertzPulseForceN(c.result.contact, t)) << "\n";
  }
  out << ccxNumber(static_cast<double>(steps + 10) * h) << ", " << ccxNumber(0.0) << "\n";
  out << "*STEP, INC=" << steps + 10 << "\n*DYNAMIC, DIRECT, ALPHA=0.\n" << ccxNumber(h) << ", "
      << ccxNumber(static_cast<double>(steps) * h) << "\n*CLOAD, AMPLITUDE=PULSE\n";
  for (const auto& [node, w] : c.result.loadWeights) {
    for (int j = 0; j < 3; ++j) {
      if (c.result.forceDirectionLocal[j] != 0.0) out << node + 1 << ", " << j + 1 << ", " << ccxNumber(w * c.result.forceDirectionLocal[j]) << "\n";
    }
  }
  out << "*EL PRINT, ELSET=ETET\nS\n*END STEP\n";
}

struct CcxPeak {
  double peakPa = -1.0;
  int64_t increment = -1;
  std::vector<int64_t> elementsAtPeak;  ///< 0-based; mirror-image elements can tie
  int64_t increments = 0;
};

/// The largest principal stress over the stress blocks of a .dat file.
CcxPeak readPeak(const std::filesystem::path& dat) {
  std::ifstream in(dat);
  const std::regex header(R"(^\s*stresses \(.*\) for set (\S+) and time\s+(\S+))");
  CcxPeak out;
  std::vector<std::pair<int64_t, double>> block;
  auto flush = [&] {
    for (const auto& [e, s1] : block) {
      if (s1 > out.peakPa * (1.0 + 1e-6)) {
        out.peakPa = s1;
        out.increment = out.increments;
        out.elementsAtPeak = {e};
      } else if (std::abs(s1 - out.peakPa) <= 1e-6 * std::abs(out.peakPa) && out.increment == out.increments) {
        out.elementsAtPeak.push_back(e);
      }
    }
    block.clear();
  };
  std::string line;
  bool inStress = false;
  while (std::getline(in, line)) {
    if (std::regex_search(line, header)) {  // one block per increment, t = h, 2h, …
      flush();
      ++out.increments;
      inStress = true;
      continue;
    }
    std::istringstream fields(line);
    int64_t element = 0, point = 0;
    std::string v[6];
    if (!inStress || !(fields >> element >> point >> v[0] >> v[1] >> v[2] >> v[3] >> v[4] >> v[5])) {
      if (inStress && line.find_first_not_of(" \t\r") != std::string::npos) inStress = false;
      continue;
    }
    Eigen::Matrix3d s;
    const double xx = fortranDouble(v[0]), yy = fortranDouble(v[1]), zz = fortranDouble(v[2]);
    const double xy = fortranDouble(v[3]), xz = fortranDouble(v[4]), yz = fortranDouble(v[5]);
    s << xx, xy, xz, xy, yy, yz, xz, yz, zz;
    block.emplace_back(element - 1, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(s, Eigen::EigenvaluesOnly).eigenvalues()[2]);
  }
  flush();
  return out;
}

TEST(CalculixCrossCheck, TheFullFemReferenceMatchesCalculixOnAPlateImpact) {
  const Impact c = plateImpact();
  ASSERT_GT(c.result.loadWeights.size(), 1u);
  FullFemSettings fs;
  fs.stepsPerContact = 40;
  fs.durationS = 3.0 * c.result.contact.durationS;  // the contact and as long again twice: ccx refactorises per increment
  const double h = c.result.contact.durationS / fs.stepsPerContact;
  const auto start = SteadyClock::now();
  auto ours = solveFullFemImpact(c.mesh, c.material, c.result.loadWeights, c.result.forceDirectionLocal, c.result.contact, fs);
  const double oursS = secondsSince(start);
  ASSERT_TRUE(ours) << ours.error().message;

  const auto dir = testing::makeTempDir("calculix");
  writeDeck(dir / "check.inp", c, h, ours.value().steps);
  const auto ccxStart = SteadyClock::now();
  const int status = testing::runCcx(dir, "check");
  const double ccxS = secondsSince(ccxStart);
  ASSERT_EQ(status, 0) << "ccx failed (is calculix-ccx installed? tools/setup.sh installs it); see " << (dir / "ccx.log");
  const CcxPeak theirs = readPeak(dir / "check.dat");
  ASSERT_EQ(theirs.increments, ours.value().steps);

  const double relative = ours.value().peakPrincipalPa / theirs.peakPa - 1.0;
  std::printf("plate, %lld tets, %lld steps: ours %.6e Pa (element %d, step %lld, %.2f s); ccx %.6e Pa (increment %lld, %.2f s); "
              "relative difference %.2e\n",
              static_cast<long long>(c.mesh.tets.rows()), static_cast<long long>(ours.value().steps), ours.value().peakPrincipalPa,
              ours.value().peakElement, static_cast<long long>(std::llround(ours.value().peakTimeS / h)), oursS, theirs.peakPa,
              static_cast<long long>(theirs.increment), ccxS, relative);
  EXPECT_LT(std::abs(relative), 1e-5);  // ccx prints 7 significant digits
  EXPECT_EQ(std::llround(ours.value().peakTimeS / h), theirs.increment);
  EXPECT_NE(std::find(theirs.elementsAtPeak.begin(), theirs.elementsAtPeak.end(), ours.value().peakElement),
            theirs.elementsAtPeak.end());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace brittle

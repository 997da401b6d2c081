// brittle's P2 (10-node tet) stiffness and consistent mass against CalculiX C3D10 (ccx, Debian's
// calculix-ccx 2.20), by the eigenfrequencies of a free body: the same Mesh_3 mesh, the same
// material, *FREQUENCY against brittle's own modal analysis (ARPACK).
//
// How ccx integrates the C3D10 mass, and how the deck makes it exact:
// - e_c3d.f evaluates the mass at the stiffness's integration points, and *FREQUENCY (arpack.c)
//   calls it with intscheme = 0: for C3D10 that is the 4-point rule of degree 2. The P2 mass
//   integrand has degree 4, so ccx's C3D10 mass is not exact; it is not even definite (each
//   element's is a sum of 4 rank-one terms N Nᵀ). The second test shows it: ccx's plain deck
//   matches brittle's K paired with that 4-point mass, and differs from brittle's exact mass.
// - So the first deck gives the C3D10 elements zero density (stiffness only) and carries the
//   mass on extra nodes, one per point of a degree-5 rule with positive weights (14 points,
//   tests/common TetQuadrature.h) in every element: a point mass ρV·w_q tied to the element's
//   nodes by *EQUATION u_q = Σ_a N_a(λ_q) u_a. ccx eliminates the tied dofs, which adds
//   Σ_q ρV w_q N(λ_q) N(λ_q)ᵀ per element: the exact consistent mass, as the C3D4 cross-check
//   (CalculixCrossCheckTest.cpp) builds the exact P1 mass from point masses.
//
// How the numbers are read to full precision:
// - ccx factorises K − σM with σ fixed at 1 (time unit)⁻². In seconds that is nearly singular
//   for a free body (its rigid modes sit at λ = 0, the elastic ones at ~1e9 rad²/s²), and the
//   eigenvalues come out only to ~3e-7. The deck therefore counts time in milliseconds (E in
//   kg/(m·ms²), i.e. × 1e-6; ρ and lengths unchanged), which puts σ at 1e6 rad²/s², still far
//   below the first elastic mode.
// - The .dat file prints 7 significant digits; *FREQUENCY, STORAGE=YES writes the eigenvalues
//   as doubles to the .eig file, which is what the test reads.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <vector>

#include "brittle/core/Timing.h"
#include "brittle/precompute/BakeManifest.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/MeshIO.h"
#include "brittle/precompute/ModalAnalysis.h"
#include "brittle/precompute/TetMesher.h"
#include "brittle/runtime/FemAssembly.h"
#include "brittle/runtime/QuadraticTetMesh.h"
#include "brittle/testing/BakeFixtures.h"
#include "brittle/testing/Calculix.h"
#include "brittle/testing/TetQuadrature.h"

namespace brittle {
namespace {

using testing::ccxNumber;

constexpr int kElasticModes = 10;
constexpr double kDeckTimeUnitS = 1e-3;  ///< the deck's time unit (see the top of the file)

/// A small irregular mesh: a Mesh_3 glass slab 0.1 × 0.06 × 0.02 m, made quadratic.
QuadraticTetMesh slab() {
  TetMeshSettings ts;
  ts.targetTets = 0;
  ts.cellSizeM = 0.025;
  auto tets = tetrahedralize(testing::makeBoxSurface(0.1, 0.06, 0.02), ts);
  EXPECT_TRUE(tets.ok()) << tets.error().message;
  return makeQuadraticTetMesh(tets.value().mesh).value();
}

double tetVolume(const QuadraticTetMesh& mesh, Eigen::Index t, Eigen::Matrix<double, 4, 3>* corners) {
  for (int a = 0; a < 4; ++a) corners->row(a) = mesh.nodes.row(mesh.tets(t, a));
  const Eigen::Vector3d p0 = corners->row(0).transpose();
  return (corners->row(1).transpose() - p0).dot((corners->row(2).transpose() - p0).cross(corners->row(3).transpose() - p0)) / 6.0;
}

/// The deck: C3D10 elements and *FREQUENCY for the six rigid and kElasticModes elastic modes.
/// exactMass: zero density on the elements and the consistent mass from tied point masses (see
/// the top of the file); otherwise the material's density on the elements (ccx's own mass).
void writeDeck(const std::filesystem::path& path, const QuadraticTetMesh& mesh, const Material& m, bool exactMass, int elasticModes) {
  std::ofstream out(path);
  out << "*HEADING\nbrittle P2 frequency cross-check\n*NODE, NSET=NALL\n";
  const Eigen::Index n = mesh.nodes.rows();
  for (Eigen::Index i = 0; i < n; ++i) {
    out << i + 1 << ", " << ccxNumber(mesh.nodes(i, 0)) << ", " << ccxNumber(mesh.nodes(i, 1)) << ", " << ccxNumber(mesh.nodes(i, 2)) << "\n";
  }
  const auto rule = testing::degreeFiveTetRule();
  struct PointMass {
    Eigen::Index node, tet;
    Eigen::Matrix<double, 10, 1> shape;
    double massKg;
  };
  std::vector<PointMass> points;
  if (exactMass) {
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
      Eigen::Matrix<double, 4, 3> corners;
      const double volume = tetVolume(mesh, t, &corners);
      for (const auto& [l, w] : rule) {
        const Eigen::Vector3d x = corners.transpose() * l;
        const Eigen::Index node = n + static_cast<Eigen::Index>(points.size()) + 1;
        out << node << ", " << ccxNumber(x(0)) << ", " << ccxNumber(x(1)) << ", " << ccxNumber(x(2)) << "\n";
        points.push_back({node, t, quadraticTetShapeFunctions(l), m.densityKgPerM3 * volume * w});
      }
    }
  }
  out << "*ELEMENT, TYPE=C3D10, ELSET=ETET\n";
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    out << t + 1;
    for (int a = 0; a < 10; ++a) out << ", " << mesh.tets(t, a) + 1;
    out << "\n";
  }
  for (size_t i = 0; i < points.size(); ++i) {
    out << "*ELEMENT, TYPE=MASS, ELSET=EM" << i + 1 << "\n" << mesh.tets.rows() + 1 + static_cast<Eigen::Index>(i) << ", " << points[i].node << "\n";
  }
  out << "*MATERIAL, NAME=GLASS\n*ELASTIC\n" << ccxNumber(m.youngsModulusPa * kDeckTimeUnitS * kDeckTimeUnitS) << ", " << ccxNumber(m.poissonRatio) << "\n";
  out << "*DENSITY\n" << ccxNumber(exactMass ? 0.0 : m.densityKgPerM3) << "\n";
  out << "*SOLID SECTION, ELSET=ETET, MATERIAL=GLASS\n";
  for (size_t i = 0; i < points.size(); ++i) out << "*MASS, ELSET=EM" << i + 1 << "\n" << ccxNumber(points[i].massKg) << "\n";
  if (!points.empty()) out << "*EQUATION\n";
  for (const PointMass& p : points) {
    for (int j = 1; j <= 3; ++j) {
      // 11 terms, the dependent (point-mass) dof first; ccx reads at most 4 terms per line.
      out << "11\n" << p.node << ", " << j << ", -1.";
      for (int a = 0; a < 10; ++a) {
        out << ((a + 1) % 4 == 0 ? "\n" : ", ") << mesh.tets(p.tet, a) + 1 << ", " << j << ", " << ccxNumber(p.shape(a));
      }
      out << "\n";
    }
  }
  out << "*STEP\n*FREQUENCY, STORAGE=YES\n" << 6 + elasticModes << "\n*END STEP\n";
}

/// The eigenvalues λ = ω² ((rad/time unit)²) from the head of a .eig file, as arpack.c writes
/// it: ITG 0 (not cyclic), ITG 1 (Hermitian), ITG iperturb (0: linear), ITG nev, nev doubles.
/// ITG is a 32-bit int in Debian's build; the header check says so if it is not.
std::vector<double> readEigenvalues(const std::filesystem::path& eig) {
  std::ifstream in(eig, std::ios::binary);
  int32_t header[4] = {-1, -1, -1, -1};
  in.read(reinterpret_cast<char*>(header), sizeof header);
  EXPECT_TRUE(in && header[0] == 0 && header[1] == 1 && header[2] == 0 && header[3] > 0)
      << eig << ": unexpected header " << header[0] << " " << header[1] << " " << header[2] << " " << header[3];
  if (!in || header[3] <= 0 || header[3] > 1000) return {};
  std::vector<double> out(static_cast<size_t>(header[3]));
  in.read(reinterpret_cast<char*>(out.data()), static_cast<std::streamsize>(out.size() * sizeof(double)));
  EXPECT_TRUE(in) << eig << " is truncated";
  return out;
}

/// ccx's frequencies (Hz) of the elastic modes: all but the six lowest (the rigid modes).
std::vector<double> ccxFrequencies(const QuadraticTetMesh& mesh, const Material& m, bool exactMass, const std::string& job,
                                   int elasticModes = kElasticModes) {
  const auto dir = testing::makeTempDir("calculix-p2-" + job);
  writeDeck(dir / (job + ".inp"), mesh, m, exactMass, elasticModes);
  const auto start = SteadyClock::now();
  const int status = testing::runCcx(dir, job);
  EXPECT_EQ(status, 0) << "ccx failed (is calculix-ccx installed? tools/setup.sh installs it); see " << (dir / "ccx.log");
  std::vector<double> lambda = readEigenvalues(dir / (job + ".eig"));
  for (double& l : lambda) l /= kDeckTimeUnitS * kDeckTimeUnitS;  // to rad²/s²
  std::printf("ccx %s: %.2f s\n", job.c_str(), secondsSince(start));
  EXPECT_EQ(lambda.size(), static_cast<size_t>(6 + elasticModes)) << "see " << (dir / "ccx.log");
  std::vector<double> hz;
  for (size_t i = 0; i < lambda.size(); ++i) {
    if (i < 6) {
      EXPECT_LT(std::abs(lambda[i]), 1e-6 * lambda.back()) << "ccx mode " << i + 1 << " should be rigid";
    } else {
      hz.push_back(std::sqrt(lambda[i]) / (2.0 * std::numbers::pi));
    }
  }
  if (!::testing::Test::HasFailure()) std::filesystem::remove_all(dir);
  return hz;
}

TEST(CalculixFrequency, P2FrequenciesMatchCalculixC3d10WithTheExactMass) {
  const Material glass = testing::presetGlass();
  const QuadraticTetMesh mesh = slab();
  const FemSystem sys = assembleFem(mesh, glass, {}).value();
  ModalSettings ms;
  ms.modeCount = kElasticModes;
  ms.shiftRad2PerS2 = defaultShift(mesh.nodes, glass);
  const auto modes = computeModes(sys, mesh.nodes, ms);
  ASSERT_TRUE(modes.ok()) << modes.error().message;
  const Eigen::VectorXd& ours = modes.value().basis.frequenciesHz;

  const std::vector<double> theirs = ccxFrequencies(mesh, glass, true, "exact");
  ASSERT_EQ(theirs.size(), static_cast<size_t>(kElasticModes));
  double worst = 0.0;
  for (int i = 0; i < kElasticModes; ++i) {
    const double relative = ours(i) / theirs[static_cast<size_t>(i)] - 1.0;
    worst = std::max(worst, std::abs(relative));
    EXPECT_LT(std::abs(relative), 1e-9) << "mode " << i << ": ours " << ours(i) << " Hz, ccx " << theirs[static_cast<size_t>(i)] << " Hz";
  }
  std::printf("%lld P2 tets, %lld nodes: first elastic mode %.6f Hz (ccx %.6f Hz); worst relative difference over %d modes %.2e\n",
              static_cast<long long>(mesh.tets.rows()), static_cast<long long>(mesh.nodes.rows()), ours(0), theirs[0], kElasticModes, worst);
}

TEST(CalculixFrequency, CalculixsOwnC3d10MassIsTheFourPointRule) {
  // ccx's plain deck (density on the elements) against brittle's K with the mass of the 4-point
  // degree-2 rule, Σ_q ρV/4 N(λ_q)N(λ_q)ᵀ per element. That mass is only semi-definite, which
  // shift-invert with σ < 0 tolerates: K − σM stays positive definite.
  const Material glass = testing::presetGlass();
  const QuadraticTetMesh mesh = slab();
  FemSystem sys = assembleFem(mesh, glass, {}).value();
  ModalSettings ms;
  ms.modeCount = kElasticModes;
  ms.shiftRad2PerS2 = defaultShift(mesh.nodes, glass);
  const Eigen::VectorXd exact = computeModes(sys, mesh.nodes, ms).value().basis.frequenciesHz;

  const double a = (5.0 + 3.0 * std::sqrt(5.0)) / 20.0, b = (5.0 - std::sqrt(5.0)) / 20.0;
  std::vector<Eigen::Triplet<double>> triplets;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    Eigen::Matrix<double, 4, 3> corners;
    const double volume = tetVolume(mesh, t, &corners);
    for (int q = 0; q < 4; ++q) {
      Eigen::Vector4d l = Eigen::Vector4d::Constant(b);
      l(q) = a;
      const auto n = quadraticTetShapeFunctions(l);
      for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j)
          for (int k = 0; k < 3; ++k)
            triplets.emplace_back(3 * mesh.tets(t, i) + k, 3 * mesh.tets(t, j) + k, glass.densityKgPerM3 * volume / 4.0 * n(i) * n(j));
    }
  }
  sys.mass.setFromTriplets(triplets.begin(), triplets.end());
  const auto fourPoint = computeModes(sys, mesh.nodes, ms);
  ASSERT_TRUE(fourPoint.ok()) << fourPoint.error().message;

  const std::vector<double> theirs = ccxFrequencies(mesh, glass, false, "plain");
  ASSERT_EQ(theirs.size(), static_cast<size_t>(kElasticModes));
  double largestShift = 0.0, worst = 0.0;
  for (int i = 0; i < kElasticModes; ++i) {
    const double theirsHz = theirs[static_cast<size_t>(i)];
    const double relative = fourPoint.value().basis.frequenciesHz(i) / theirsHz - 1.0;
    worst = std::max(worst, std::abs(relative));
    EXPECT_LT(std::abs(relative), 1e-9) << "mode " << i;
    largestShift = std::max(largestShift, std::abs(exact(i) / theirsHz - 1.0));
  }
  std::printf("first elastic mode: ccx plain C3D10 %.6f Hz, brittle K with the 4-point mass %.6f Hz (worst relative difference "
              "over %d modes %.2e), with the exact mass %.6f Hz; the exact mass moves the modes by up to %.3f%%\n",
              theirs[0], fourPoint.value().basis.frequenciesHz(0), kElasticModes, worst, exact(0), 100.0 * largestShift);
  // The inexact mass moves the frequencies by far more than the cross-check's tolerance.
  EXPECT_GT(largestShift, 1e-4);
}

// Not run by default (2.5 min): the default plate (PlateFrequencyTest.cpp) through ccx, with
// its own C3D10 mass and with the exact one, against brittle's P2. Run with
//   brittle_calculix_tests --gtest_also_run_disabled_tests --gtest_filter=CalculixFrequency.DISABLED_*
// Measured: 7 446 tets, brittle 389.6316 Hz, ccx 389.6317 (own mass) and 389.6316 (exact);
// 11 626 tets, 389.5901 Hz all three. On meshes this fine the 4-point mass costs only ~3e-7.
TEST(CalculixFrequency, DISABLED_DefaultPlate) {
  const Material glass = testing::presetGlass();
  for (int64_t target : {6000, 12000}) {
    TetMeshSettings ts;  // as PlateFrequencyTest meshes it
    ts.targetTets = target;
    auto tets = tetrahedralize(readSurfaceMesh(testing::sourceDir() / "assets" / "meshes" / "plate.off").value(), ts);
    ASSERT_TRUE(tets.ok()) << tets.error().message;
    const QuadraticTetMesh mesh = makeQuadraticTetMesh(tets.value().mesh).value();
    ModalSettings ms;
    ms.modeCount = 1;
    ms.shiftRad2PerS2 = defaultShift(mesh.nodes, glass);
    const double ours = computeModes(assembleFem(mesh, glass, {}).value(), mesh.nodes, ms).value().basis.frequenciesHz(0);
    const std::vector<double> own = ccxFrequencies(mesh, glass, false, "plate-own", 1);
    const std::vector<double> exact = ccxFrequencies(mesh, glass, true, "plate-exact", 1);
    std::printf("plate, %lld tets: brittle P2 %.4f Hz; ccx C3D10 with its own mass %.4f Hz, with the exact mass %.4f Hz\n",
                static_cast<long long>(mesh.tets.rows()), ours, own.empty() ? 0.0 : own[0], exact.empty() ? 0.0 : exact[0]);
    std::fflush(stdout);
  }
}

// Not run by default (a few minutes): the converged references of DefaultObjectsFrequencyTest (the
// vase, the brick and the stone ball, each baked from the default manifest at about the size its
// reference came from) through ccx C3D10 with the exact mass, against brittle's P2 on the same
// mesh: issue 17's "converge it with the project's own P2 solver, and check it once with
// CalculiX". Run with the filter above. With ccx's own 4-point mass the two differed by 4.4e-6,
// 1.5e-6 and 2.0e-5 (vase, brick, ball): that mass's error, not the solver's.
// Measured (3.3 min, ccx 94 / 27 / 29 s): the vase at 18 516 P2 tets 3 680.0376 Hz in both (−4.5e-13),
// the brick at 8 176 tets 4 267.0205 Hz (8.9e-14), the ball at 8 125 tets 12 045.0771 Hz (1.7e-13).
TEST(CalculixFrequency, DISABLED_DefaultSolidsConvergedReferences) {
  auto manifest = loadBakeManifest(testing::sourceDir() / "assets" / "default-pack.json");
  ASSERT_TRUE(manifest) << manifest.error().message;
  // target tets and the reference (Hz) DefaultObjectsFrequencyTest holds each object to
  const std::map<std::string, std::pair<int64_t, double>> references = {
      {"porcelain-vase", {19000, 3679.4}}, {"brick", {10000, 4267.0}}, {"stone-ball", {10000, 12044.4}}};
  int checked = 0;
  for (ObjectBakeSettings o : manifest.value()) {
    if (!references.contains(o.name)) continue;
    const auto [target, referenceHz] = references.at(o.name);
    o.elementOrder = ElementOrder::P2;
    o.tetMesh.targetTets = target;
    // Several modes from both: the ball's lowest is one of five nearly equal (its l = 2 cluster),
    // and a solver asked for one of them may converge to another (ccx asked for one gave 1.1e-5
    // above brittle).
    o.modal.modeCount = 6;
    auto asset = bakeObject(o);
    ASSERT_TRUE(asset) << o.name << ": " << asset.error().message;
    const double ours = asset.value().modal.frequenciesHz(0);
    const QuadraticTetMesh mesh = makeQuadraticTetMesh(asset.value().tetMesh).value();
    const std::vector<double> ccx = ccxFrequencies(mesh, o.material, true, o.name, 6);
    ASSERT_EQ(ccx.size(), 6u) << o.name;
    std::printf("%s, %lld P2 tets: brittle %.4f Hz, ccx C3D10 %.4f Hz (%.2e), the reference %.1f Hz\n", o.name.c_str(),
                static_cast<long long>(mesh.tets.rows()), ours, ccx[0], ours / ccx[0] - 1.0, referenceHz);
    std::fflush(stdout);
    EXPECT_NEAR(ours, ccx[0], 1e-6 * ccx[0]) << o.name;
    // Mesh_3 gives a slightly different mesh at the reference's target than the one it was
    // measured on (the vase 18 516 tets against 19 030): the reference holds to its convergence.
    EXPECT_NEAR(ours, referenceHz, 1e-3 * referenceHz) << o.name;
    ++checked;
  }
  EXPECT_EQ(checked, 3);
}

}  // namespace
}  // namespace brittle

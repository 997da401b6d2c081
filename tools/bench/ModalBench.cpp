// brittle_bench_modal — cost of the offline bake against problem size.
//
// For each target element count it tet-meshes one surface (timing Mesh_3), assembles K and M,
// then for each mode count r solves the same eigenproblem with
//   * ARPACK mode 3 + CHOLMOD (the bake's path),
//   * ARPACK mode 3 + Eigen SimplicialLDLT,
//   * Spectra shift-invert + CHOLMOD,
//   * Eigen's dense generalised solver (where 3N ≤ --dense-max-dof),
// all in the same run, and times one CHOLMOD and one Eigen factorisation of K − σM alone. The
// ratio "whole ARPACK solve / one factorisation" shows how close a solve is to its floor.
// "arpack_*_s" is the whole computeModes call (factorisation, iterations, eigenvectors and the
// checks: rigid-mode detection, residuals, M-orthonormality); "arpack_core_s" is factorisation +
// iterations + eigenvectors only, the same scope as the Spectra timing.
// Output: one CSV row per (size, r); tools/scripts/plot_bench.py turns it into charts.
#include <CLI/CLI.hpp>
#include <Spectra/SymGEigsShiftSolver.h>
#include <Spectra/MatOp/SparseSymMatProd.h>

#include <algorithm>
#include <fstream>
#include <iostream>

#include "BenchSupport.h"
#include "brittle/core/Timing.h"
#include "brittle/runtime/FemAssembly.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/MeshIO.h"
#include "brittle/precompute/ModalAnalysis.h"
#include "brittle/precompute/TetMesher.h"

namespace {

using namespace brittle;

// Spectra's shift-invert operator backed by our factorisation of K − σM.
class FactorOp {
 public:
  using Scalar = double;
  FactorOp(const ShiftInvertFactor& f, Eigen::Index n) : mFactor(f), mN(n) {}
  Eigen::Index rows() const { return mN; }
  Eigen::Index cols() const { return mN; }
  void set_shift(double) {}  // the factor already holds σ
  void perform_op(const double* x, double* y) const { mFactor.solve(x, y); }

 private:
  const ShiftInvertFactor& mFactor;
  Eigen::Index mN;
};

double maxRelDiff(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() != b.size() || a.size() == 0) return std::numeric_limits<double>::quiet_NaN();
  return ((a - b).cwiseAbs().array() / b.cwiseAbs().array()).maxCoeff();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Benchmark: tet meshing and modal solve time against DOF count"};
  std::string meshPath = "assets/meshes/brick.off", materialName = "glass", out = "docs/results/data/modal_solve.csv";
  std::vector<int64_t> sizes = {250, 800, 2500, 8000, 25000, 80000};
  std::vector<int> modeCounts = {20, 40};
  int denseMaxDof = 2000, repeats = 1;
  bool skipEigen = false;
  double tolerance = 1e-12;  // the bake's default
  app.add_option("--mesh", meshPath, "Surface mesh to tet-mesh")->capture_default_str();
  app.add_option("--material", materialName, "Material preset")->capture_default_str();
  app.add_option("--tets", sizes, "Target tet counts")->capture_default_str();
  app.add_option("--modes", modeCounts, "Mode counts r")->capture_default_str();
  app.add_option("--dense-max-dof", denseMaxDof, "Largest 3N for the dense solver")->capture_default_str();
  app.add_option("--repeats", repeats, "Repeats per measurement (median reported)")->capture_default_str();
  app.add_flag("--skip-eigen-ldlt", skipEigen, "Skip ARPACK+Eigen LDLT above 30k DOF (it is slow)");
  app.add_option("--tol", tolerance, "Relative tolerance for ARPACK and Spectra (0: machine precision for ARPACK, 1e-15 for Spectra)")
      ->capture_default_str();
  app.add_option("--out", out, "CSV output")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  auto surface = readSurfaceMesh(meshPath);
  auto material = materialPreset(materialName);
  if (!surface || !material) {
    std::cerr << "error: " << (!surface ? surface.error().message : material.error().message) << "\n";
    return 1;
  }
  std::filesystem::create_directories(std::filesystem::path(out).parent_path().empty() ? "." : std::filesystem::path(out).parent_path());
  std::ofstream csv(out);
  csv << "target_tets,tets,nodes,dof,modes,mesh_s,cholmod_factor_s,eigen_factor_s,arpack_cholmod_s,arpack_eigen_s,"
         "spectra_cholmod_s,dense_s,arpack_over_factor,spectra_vs_arpack_max_rel,dense_vs_arpack_max_rel,"
         "max_residual,orthonormality_error,arpack_core_s,arpack_solves,spectra_solves\n";
  std::cout << "   tets   dof   r  mesh_s  chol_f  eig_f  arpack+chol  arpack+eig  spectra+chol  dense  solve/factor  |spectra-arpack|\n";
  for (int64_t target : sizes) {
    TetMeshSettings ts;
    ts.targetTets = target;
    TetMeshResult tets;
    const double meshS = bench::medianSeconds(repeats, [&] { tets = tetrahedralize(surface.value(), ts).value(); });
    auto sys = assembleFem(tets.mesh, material.value(), {}).value();
    const Eigen::Index dof = sys.stiffness.rows();
    const double shift = defaultShift(tets.mesh.nodes, material.value());
    const double cholF = bench::medianSeconds(repeats, [&] { (void)ShiftInvertFactor::create(sys.stiffness, sys.mass, shift, Factorization::Cholmod); });
    const bool runEigen = !(skipEigen && dof > 30000);
    const double eigF = runEigen ? bench::medianSeconds(repeats, [&] { (void)ShiftInvertFactor::create(sys.stiffness, sys.mass, shift, Factorization::EigenLdlt); }) : NAN;
    for (int r : modeCounts) {
      ModalSettings ms;
      ms.modeCount = r;
      ms.shiftRad2PerS2 = shift;
      ms.tolerance = tolerance;
      ModalResult arpack;
      const double arpackChol = bench::medianSeconds(repeats, [&] { arpack = computeModes(sys, tets.mesh.nodes, ms).value(); });
      ms.factorization = Factorization::EigenLdlt;
      const double arpackEig = runEigen ? bench::medianSeconds(repeats, [&] { (void)computeModes(sys, tets.mesh.nodes, ms).value(); }) : NAN;
      // Spectra: same factor, same nev (r + 6 rigid) and ncv as ARPACK.
      Eigen::VectorXd spectraLambda;
      long spectraSolves = 0;
      const double spectraS = bench::medianSeconds(repeats, [&] {
        auto factor = ShiftInvertFactor::create(sys.stiffness, sys.mass, shift, Factorization::Cholmod).value();
        FactorOp op(*factor, dof);
        Spectra::SparseSymMatProd<double> bop(sys.mass);
        const int nev = r + 6;
        Spectra::SymGEigsShiftSolver<FactorOp, Spectra::SparseSymMatProd<double>, Spectra::GEigsMode::ShiftInvert> eigs(
            op, bop, nev, std::min<Eigen::Index>(dof, std::max(2 * nev + 1, nev + 20)), shift);
        eigs.init();
        eigs.compute(Spectra::SortRule::LargestMagn, 1000, tolerance > 0.0 ? tolerance : 1e-15, Spectra::SortRule::SmallestAlge);
        if (eigs.info() != Spectra::CompInfo::Successful) {
          std::cerr << "warning: Spectra did not converge at " << dof << " DOF, r = " << r << "\n";
          spectraLambda = Eigen::VectorXd::Constant(r, std::numeric_limits<double>::quiet_NaN());
          return;
        }
        spectraLambda = eigs.eigenvalues().tail(r);
        spectraSolves = static_cast<long>(eigs.num_operations());
      });
      double denseS = NAN, denseDiff = NAN;
      if (dof <= denseMaxDof) {
        ms.factorization = Factorization::Cholmod;
        ModalResult dense;
        denseS = bench::medianSeconds(repeats, [&] { dense = computeModesDense(sys, tets.mesh.nodes, ms).value(); });
        denseDiff = maxRelDiff(dense.basis.eigenvaluesRad2PerS2, arpack.basis.eigenvaluesRad2PerS2);
      }
      const double spectraDiff = maxRelDiff(spectraLambda, arpack.basis.eigenvaluesRad2PerS2);
      csv << target << ',' << tets.mesh.tets.rows() << ',' << tets.mesh.nodes.rows() << ',' << dof << ',' << r << ','
          << meshS << ',' << cholF << ',' << eigF << ',' << arpackChol << ',' << arpackEig << ',' << spectraS << ','
          << denseS << ',' << arpackChol / cholF << ',' << spectraDiff << ',' << denseDiff << ','
          << arpack.basis.residuals.maxCoeff() << ',' << arpack.basis.orthonormalityError << ','
          << arpack.stats.factorizationS + arpack.stats.iterationS << ',' << arpack.stats.operatorApplications << ','
          << spectraSolves << '\n';
      csv.flush();
      std::printf("%7ld %6ld %3d %7.3f %7.3f %6.3f %12.3f %11.3f %13.3f %6.3f %13.2f %16.2e\n",
                  static_cast<long>(tets.mesh.tets.rows()), static_cast<long>(dof), r, meshS, cholF, eigF, arpackChol,
                  arpackEig, spectraS, denseS, arpackChol / cholF, spectraDiff);
      std::fflush(stdout);
    }
  }
  std::cout << "wrote " << out << "\n";
  return 0;
}

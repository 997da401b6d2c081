#include "brittle/precompute/ModalIntegrators.h"

#include "brittle/runtime/ModalResponse.h"

namespace brittle {
namespace {

Eigen::Matrix<double, 2, 4> explicitEulerStep(double w, double z, double h) {
  const double k = w * w, c = 2.0 * z * w;
  Eigen::Matrix<double, 2, 4> p;
  p << 1.0, h, 0.0, 0.0,  //
      -h * k, 1.0 - h * c, h, 0.0;
  return p;
}

Eigen::Matrix<double, 2, 4> symplecticEulerStep(double w, double z, double h) {
  // q̇₁ = −hk q₀ + (1 − hc) q̇₀ + h p₀; q₁ = q₀ + h q̇₁.
  const double k = w * w, c = 2.0 * z * w;
  Eigen::Matrix<double, 2, 4> p;
  p << 1.0 - h * h * k, h * (1.0 - h * c), h * h, 0.0,  //
      -h * k, 1.0 - h * c, h, 0.0;
  return p;
}

Eigen::Matrix<double, 2, 4> implicitEulerStep(double w, double z, double h) {
  // [1, −h; hk, 1 + hc] [q₁; q̇₁] = [q₀; q̇₀ + h p₁].
  const double k = w * w, c = 2.0 * z * w;
  const double det = 1.0 + h * c + h * h * k;
  Eigen::Matrix<double, 2, 4> p;
  p << (1.0 + h * c) / det, h / det, 0.0, h * h / det,  //
      -h * k / det, 1.0 / det, 0.0, h / det;
  return p;
}

StepMatrixFunction stepFunction(ModalIntegrator integrator) {
  switch (integrator) {
    case ModalIntegrator::Exact: return &exactStepMatrix;
    case ModalIntegrator::ExplicitEuler: return &explicitEulerStep;
    case ModalIntegrator::SymplecticEuler: return &symplecticEulerStep;
    case ModalIntegrator::ImplicitEuler: return &implicitEulerStep;
  }
  return &exactStepMatrix;
}

}  // namespace

const char* modalIntegratorName(ModalIntegrator integrator) {
  switch (integrator) {
    case ModalIntegrator::Exact: return "exact";
    case ModalIntegrator::ExplicitEuler: return "explicit-euler";
    case ModalIntegrator::SymplecticEuler: return "symplectic-euler";
    case ModalIntegrator::ImplicitEuler: return "implicit-euler";
  }
  return "unknown";
}

Eigen::Matrix<double, 2, 4> stepMatrix(ModalIntegrator integrator, double w, double z, double h) {
  return stepFunction(integrator)(w, z, h);
}

Status integrateModalResponse(const Eigen::VectorXd& w, const Eigen::VectorXd& z, const Eigen::VectorXd& g,
                              const std::vector<double>& t, const std::vector<double>& f, Eigen::MatrixXd& q,
                              ModalIntegrator integrator) {
  return integrateModalResponse(w, z, g, t, f, q, stepFunction(integrator));
}

}  // namespace brittle

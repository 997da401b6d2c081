#include "brittle/runtime/ModalResponse.h"

#include <cmath>
#include <unsupported/Eigen/MatrixFunctions>

namespace brittle {

Eigen::Matrix<double, 2, 4> exactStepMatrixByExponential(double w, double z, double h) {
  // Dimensionless state x = [q, q̇/ω, p/ω², ṗ/ω³] in τ = ωt (the raw matrix mixes ω² with 1 and
  // makes the exponential inaccurate): x' = N x with p linear over the step (ṗ = (p₁ − p₀)/h).
  Eigen::Matrix4d n = Eigen::Matrix4d::Zero();
  n(0, 1) = 1.0;
  n(1, 0) = -1.0;
  n(1, 1) = -2.0 * z;
  n(1, 2) = 1.0;
  n(2, 3) = 1.0;
  const Eigen::Matrix4d e = (n * (w * h)).exp();
  const double w2 = w * w, w3 = w2 * w;
  Eigen::Matrix<double, 2, 4> p;
  for (int row = 0; row < 2; ++row) {
    const double back = row == 0 ? 1.0 : w;  // q̇ = ω x₁
    p(row, 0) = back * e(row, 0);
    p(row, 1) = back * e(row, 1) / w;
    p(row, 2) = back * (e(row, 2) / w2 - e(row, 3) / (w3 * h));
    p(row, 3) = back * e(row, 3) / (w3 * h);
  }
  return p;
}

Eigen::Matrix<double, 2, 4> exactStepMatrix(double w, double z, double h) {
  if (z >= 1.0 || w * h < 1e-2) return exactStepMatrixByExponential(w, z, h);
  const double k = w * w, r = std::sqrt(1.0 - z * z), wd = w * r;
  const double e = std::exp(-z * w * h), s = std::sin(wd * h), c = std::cos(wd * h);
  Eigen::Matrix<double, 2, 4> p;
  p(0, 0) = e * (z / r * s + c);
  p(0, 1) = e * s / wd;
  p(0, 2) = (2.0 * z / (w * h) + e * (((1.0 - 2.0 * z * z) / (wd * h) - z / r) * s - (1.0 + 2.0 * z / (w * h)) * c)) / k;
  p(0, 3) = (1.0 - 2.0 * z / (w * h) + e * ((2.0 * z * z - 1.0) / (wd * h) * s + 2.0 * z / (w * h) * c)) / k;
  p(1, 0) = -e * w / r * s;
  p(1, 1) = e * (c - z / r * s);
  p(1, 2) = (-1.0 / h + e * ((w / r + z / (h * r)) * s + c / h)) / k;
  p(1, 3) = (1.0 - e * (z / r * s + c)) / (k * h);
  return p;
}

void impactTimeGrid(double tc, int pulseSteps, double ringDownS, int ringDownSteps, std::vector<double>& t) {
  t.clear();
  t.reserve(static_cast<size_t>(pulseSteps + ringDownSteps + 1));
  for (int i = 0; i <= pulseSteps; ++i) t.push_back(tc * i / pulseSteps);
  for (int i = 1; i <= ringDownSteps; ++i) t.push_back(tc + ringDownS * i / ringDownSteps);
}

std::vector<double> impactTimeGrid(double tc, int pulseSteps, double ringDownS, int ringDownSteps) {
  std::vector<double> t;
  impactTimeGrid(tc, pulseSteps, ringDownS, ringDownSteps, t);
  return t;
}

Status integrateModalResponse(const Eigen::VectorXd& w, const Eigen::VectorXd& z, const Eigen::VectorXd& g,
                              const std::vector<double>& t, const std::vector<double>& f, Eigen::MatrixXd& q,
                              StepMatrixFunction stepMatrix) {
  const Eigen::Index r = w.size();
  if (z.size() != r || g.size() != r) return makeError(ErrorCode::InvalidArgument, "modal response: ω, ζ and load sizes differ");
  if (t.size() != f.size() || t.empty()) return makeError(ErrorCode::InvalidArgument, "modal response: times and forces differ in size");
  if (!w.allFinite() || !z.allFinite() || !g.allFinite() || (w.array() <= 0.0).any() || (z.array() < 0.0).any()) {
    return makeError(ErrorCode::InvalidArgument, "modal response: ω must be finite and > 0, ζ finite and ≥ 0");
  }
  for (size_t k = 0; k < t.size(); ++k) {
    if (!std::isfinite(t[k]) || !std::isfinite(f[k]) || (k > 0 && !(t[k] > t[k - 1]))) {
      return makeError(ErrorCode::InvalidArgument, "modal response: times must increase and forces be finite");
    }
  }
  const auto steps = static_cast<Eigen::Index>(t.size());
  q.setZero(steps, r);
  for (Eigen::Index j = 0; j < r; ++j) {
    double x = 0.0, v = 0.0, lastH = -1.0;
    Eigen::Matrix<double, 2, 4> p = Eigen::Matrix<double, 2, 4>::Zero();
    for (Eigen::Index k = 1; k < steps; ++k) {
      const double h = t[static_cast<size_t>(k)] - t[static_cast<size_t>(k - 1)];
      // Grids have a few step sizes (equal up to rounding): recompute the map only when h changes.
      if (std::abs(h - lastH) > 1e-9 * h) {
        p = stepMatrix(w[j], z[j], h);
        lastH = h;
      }
      const double p0 = g[j] * f[static_cast<size_t>(k - 1)], p1 = g[j] * f[static_cast<size_t>(k)];
      const double nx = p(0, 0) * x + p(0, 1) * v + p(0, 2) * p0 + p(0, 3) * p1;
      v = p(1, 0) * x + p(1, 1) * v + p(1, 2) * p0 + p(1, 3) * p1;
      x = nx;
      q(k, j) = x;
    }
  }
  return Ok{};
}

}  // namespace brittle

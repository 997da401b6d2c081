// TetQuadrature.h — a tetrahedron quadrature rule independent of the library's, to check its
// integrals against.
#pragma once

#include <Eigen/Core>
#include <array>
#include <utility>
#include <vector>

namespace brittle::testing {

/// The 14-point rule of degree 5 with positive weights (Walkington, "Quadrature on simplices of
/// arbitrary dimension", 2000): barycentric points and weights as fractions of the volume (they
/// sum to 1). Exact for polynomials of degree ≤ 5, so for the P2 mass integrand (degree 4).
inline std::vector<std::pair<Eigen::Vector4d, double>> degreeFiveTetRule() {
  const double x1 = 0.0927352503108912, x2 = 0.3108859192633006, y = 0.0455037041256496;
  const double w1 = 6.0 * 0.01224884051939366, w2 = 6.0 * 0.01878132095300264, w3 = 6.0 * 0.007091003462846911;
  std::vector<std::pair<Eigen::Vector4d, double>> rule;
  for (const auto& [x, w] : {std::pair{x1, w1}, std::pair{x2, w2}}) {
    for (int k = 0; k < 4; ++k) {
      Eigen::Vector4d l = Eigen::Vector4d::Constant(x);
      l(k) = 1.0 - 3.0 * x;
      rule.emplace_back(l, w);
    }
  }
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      Eigen::Vector4d l = Eigen::Vector4d::Constant(0.5 - y);
      l(i) = y;
      l(j) = y;
      rule.emplace_back(l, w3);
    }
  }
  return rule;
}

}  // namespace brittle::testing

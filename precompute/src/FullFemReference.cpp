#include "brittle/precompute/FullFemReference.h"

#include <Eigen/SparseCholesky>
#include <cmath>

#include "brittle/runtime/CrackPropagation.h"
#include "brittle/runtime/FemAssembly.h"

namespace brittle {

Result<FullFemResult> solveFullFemImpact(const TetMesh& mesh, const Material& material,
                                         const std::vector<std::pair<int32_t, double>>& weights,
                                         const Eigen::Vector3d& direction, const HertzContact& contact,
                                         const FullFemSettings& settings) {
  if (settings.stepsPerContact < 2 || !(contact.durationS > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "full FEM reference: stepsPerContact ≥ 2 and a positive contact duration");
  }
  auto femMesh = makeFemMesh(mesh, settings.elementOrder);
  if (!femMesh) return femMesh.error();
  auto fem = assembleFem(femMesh.value(), material, FemSettings{});
  if (!fem) return fem.error();
  auto recovery = ElementStresses::make(femMesh.value(), material);
  if (!recovery) return recovery.error();
  const ElementStresses& stresses = recovery.value();
  const SparseMatrixd& k = fem.value().stiffness;
  const SparseMatrixd& m = fem.value().mass;
  const Eigen::Index dofs = k.rows();
  Eigen::VectorXd pattern = Eigen::VectorXd::Zero(dofs);
  double sum = 0.0;
  for (const auto& [node, w] : weights) {
    if (node < 0 || node >= stresses.femNodeCount()) return makeError(ErrorCode::InvalidArgument, "full FEM reference: node out of range");
    pattern.segment<3>(3 * node) += w * direction;
    sum += w;
  }
  if (std::abs(sum - 1.0) > 1e-9) return makeError(ErrorCode::InvalidArgument, "full FEM reference: weights must sum to 1");

  const double h = contact.durationS / settings.stepsPerContact;
  const double duration = settings.durationS > 0.0 ? settings.durationS : contact.durationS + settings.extraS;
  const auto steps = static_cast<int64_t>(std::ceil(duration / h));
  const double beta = 0.25, gamma = 0.5;
  const SparseMatrixd c = material.rayleighAlphaPerS * m + material.rayleighBetaS * k;
  const SparseMatrixd effective = k + (gamma / (beta * h)) * c + (1.0 / (beta * h * h)) * m;
  Eigen::SimplicialLDLT<SparseMatrixd> solver(effective);
  if (solver.info() != Eigen::Success) return makeError(ErrorCode::FactorizationFailed, "full FEM reference: factorisation failed");

  Eigen::VectorXd u = Eigen::VectorXd::Zero(dofs), v = u, a = u;  // at rest; F(0) = 0
  const int points = stresses.pointsPerElement();
  Eigen::VectorXd sigma;  // every point's, P2 corners as nodal means (as the runtime reads them)
  FullFemResult result;
  result.steps = steps;
  result.peakPrincipalPa = -std::numeric_limits<double>::infinity();
  for (int64_t n = 1; n <= steps; ++n) {
    const double t = static_cast<double>(n) * h;
    // Newmark, average acceleration: u₁ = u + h v + h²(¼ a + ¼ a₁), v₁ = v + h(½ a + ½ a₁).
    const Eigen::VectorXd predictor = (1.0 / (beta * h * h)) * u + (1.0 / (beta * h)) * v + (0.5 / beta - 1.0) * a;
    const Eigen::VectorXd damping = (gamma / (beta * h)) * u + (gamma / beta - 1.0) * v + h * (0.5 * gamma / beta - 1.0) * a;
    const Eigen::VectorXd rhs = hertzPulseForceN(contact, t) * pattern + m * predictor + c * damping;
    const Eigen::VectorXd next = solver.solve(rhs);
    const Eigen::VectorXd aNext = (1.0 / (beta * h * h)) * (next - u) - (1.0 / (beta * h)) * v - (0.5 / beta - 1.0) * a;
    v += h * ((1.0 - gamma) * a + gamma * aNext);
    a = aNext;
    u = next;
    stresses.all(u, sigma);
    for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
      for (int p = 0; p < points; ++p) {
        const double s1 = maxPrincipalStress(sigma.segment<6>(6 * (points * e + p)));
        if (s1 > result.peakPrincipalPa) {
          result.peakPrincipalPa = s1;
          result.peakElement = static_cast<int32_t>(e);
          result.peakTimeS = t;
        }
      }
    }
  }
  return result;
}

}  // namespace brittle

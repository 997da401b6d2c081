#include "brittle/runtime/StaticCorrection.h"

#include <Eigen/SparseCholesky>
#include <cmath>

#include "brittle/runtime/FemAssembly.h"

namespace brittle {

struct StaticCorrection::Data {
  TetMesh mesh;
  Material material;
  SparseMatrixd mass;
  Eigen::MatrixXd rigid;     // 3N by 6, M-orthonormal
  Eigen::MatrixXd modes;     // 3N by r
  Eigen::VectorXd lambdas;   // r, shifted by μ
  Eigen::SimplicialLDLT<SparseMatrixd> solver;
  Eigen::VectorXd inverseD;  // of the LDLᵀ factor (vectorD() returns a copy)
  std::vector<Eigen::Matrix<double, 6, 12>> elementStress;  // C B_e per element
};

Result<StaticCorrection> StaticCorrection::build(const ObjectAsset& asset, const Material& material, int modes) {
  auto fem = assembleFem(asset.tetMesh, material, FemSettings{});
  if (!fem) return fem.error();
  auto data = std::make_shared<Data>();
  data->mesh = asset.tetMesh;
  data->material = material;
  data->mass = fem.value().mass;
  data->rigid = rigidBodyModes(asset.tetMesh.nodes, data->mass);
  const int r = std::min<int>(modes, static_cast<int>(asset.modal.modes.cols()));
  data->modes = asset.modal.modes.leftCols(r);
  const double mu = 1e-6 * asset.modal.eigenvaluesRad2PerS2[0];
  data->lambdas = asset.modal.eigenvaluesRad2PerS2.head(r).array() + mu;
  const SparseMatrixd shifted = fem.value().stiffness + mu * data->mass;
  data->solver.compute(shifted);
  if (data->solver.info() != Eigen::Success) {
    return makeError(ErrorCode::FactorizationFailed, "static correction: K + μM of '" + asset.name + "' did not factorise");
  }
  data->inverseD = data->solver.vectorD().cwiseInverse();
  const Eigen::Matrix<double, 6, 6> c = isotropicElasticity(material.youngsModulusPa, material.poissonRatio);
  const TetMesh& m = asset.tetMesh;
  data->elementStress.resize(static_cast<size_t>(m.tets.rows()));
  for (Eigen::Index t = 0; t < m.tets.rows(); ++t) {
    data->elementStress[static_cast<size_t>(t)] =
        c * tetStrainDisplacement(m.nodes.row(m.tets(t, 0)).transpose(), m.nodes.row(m.tets(t, 1)).transpose(),
                                  m.nodes.row(m.tets(t, 2)).transpose(), m.nodes.row(m.tets(t, 3)).transpose(), nullptr);
  }
  return StaticCorrection(std::move(data));
}

Status StaticCorrection::stressPerNewton(const std::vector<std::pair<int32_t, double>>& weights,
                                         const Eigen::Vector3d& direction, Eigen::VectorXd& stress,
                                         double& compliance) const {
  Workspace workspace;
  return stressPerNewton(weights, direction, stress, compliance, workspace);
}

Status StaticCorrection::stressPerNewton(const std::vector<std::pair<int32_t, double>>& weights,
                                         const Eigen::Vector3d& direction, Eigen::VectorXd& stress,
                                         double& compliance, Workspace& w) const {
  const Data& d = *mData;
  const Eigen::Index dofs = 3 * d.mesh.nodes.rows();
  // Every product below writes into a sized buffer (noalias, fixed-size rigid coefficients).
  w.load.setZero(dofs);
  double sum = 0.0;
  for (const auto& [node, weight] : weights) {
    if (node < 0 || node >= d.mesh.nodes.rows()) return makeError(ErrorCode::InvalidArgument, "static correction: node out of range");
    w.load.segment<3>(3 * node) += weight * direction;
    sum += weight;
  }
  if (std::abs(sum - 1.0) > 1e-9) return makeError(ErrorCode::InvalidArgument, "static correction: weights must sum to 1");
  Eigen::Matrix<double, 6, 1> rigid;
  w.scratch.resize(dofs);
  w.relieved.resize(dofs);
  w.displacement.resize(dofs);
  w.modal.resize(d.modes.cols());
  // Inertia relief: f_e = f − M Ψ Ψᵀ f.
  rigid.noalias() = d.rigid.transpose() * w.load;
  w.scratch.noalias() = d.rigid * rigid;
  w.relieved.noalias() = d.mass * w.scratch;
  w.relieved = w.load - w.relieved;
  // u = (K + μM)⁻¹ f_e from the factors P(K + μM)Pᵀ = L D Lᵀ, step by step: Eigen's solve()
  // permutes its result in place, and that allocates a mask on every call.
  if (d.solver.permutationP().size() > 0) {
    w.scratch.noalias() = d.solver.permutationP() * w.relieved;
  } else {
    w.scratch = w.relieved;
  }
  d.solver.matrixL().solveInPlace(w.scratch);
  w.scratch.array() *= d.inverseD.array();
  d.solver.matrixU().solveInPlace(w.scratch);
  if (d.solver.permutationPinv().size() > 0) {
    w.displacement.noalias() = d.solver.permutationPinv() * w.scratch;
  } else {
    w.displacement = w.scratch;
  }
  // The elastic part only: u −= Ψ Ψᵀ M u.
  w.scratch.noalias() = d.mass * w.displacement;
  rigid.noalias() = d.rigid.transpose() * w.scratch;
  w.displacement.noalias() -= d.rigid * rigid;
  // Minus the kept modes: u −= Φ (Φᵀ f_e / λ).
  w.modal.noalias() = d.modes.transpose() * w.relieved;
  w.modal.array() /= d.lambdas.array();
  w.displacement.noalias() -= d.modes * w.modal;
  compliance = w.load.dot(w.displacement);
  stress.resize(6 * d.mesh.tets.rows());
  Eigen::Matrix<double, 12, 1> ue;
  for (Eigen::Index t = 0; t < d.mesh.tets.rows(); ++t) {
    for (int a = 0; a < 4; ++a) ue.segment<3>(3 * a) = w.displacement.segment<3>(3 * d.mesh.tets(t, a));
    stress.segment<6>(6 * t).noalias() = d.elementStress[static_cast<size_t>(t)] * ue;
  }
  return Ok{};
}

}  // namespace brittle

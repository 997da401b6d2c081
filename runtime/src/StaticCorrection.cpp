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
  return StaticCorrection(std::move(data));
}

Status StaticCorrection::stressPerNewton(const std::vector<std::pair<int32_t, double>>& weights,
                                         const Eigen::Vector3d& direction, Eigen::VectorXd& stress,
                                         double& compliance) const {
  const Data& d = *mData;
  const Eigen::Index dofs = 3 * d.mesh.nodes.rows();
  Eigen::VectorXd f = Eigen::VectorXd::Zero(dofs);
  double sum = 0.0;
  for (const auto& [node, w] : weights) {
    if (node < 0 || node >= d.mesh.nodes.rows()) return makeError(ErrorCode::InvalidArgument, "static correction: node out of range");
    f.segment<3>(3 * node) += w * direction;
    sum += w;
  }
  if (std::abs(sum - 1.0) > 1e-9) return makeError(ErrorCode::InvalidArgument, "static correction: weights must sum to 1");
  const Eigen::VectorXd fe = f - d.mass * (d.rigid * (d.rigid.transpose() * f));  // inertia relief
  Eigen::VectorXd u = d.solver.solve(fe);
  u -= d.rigid * (d.rigid.transpose() * (d.mass * u));                            // elastic part only
  u -= d.modes * ((d.modes.transpose() * fe).array() / d.lambdas.array()).matrix(); // minus the kept modes
  compliance = f.dot(u);
  MatrixXdRow column(dofs, 1);
  column.col(0) = u;
  stress = computeStressModes(d.mesh, d.material, column).col(0);
  return Ok{};
}

}  // namespace brittle

#include "brittle/runtime/StaticCorrection.h"

#include <Eigen/SparseCholesky>
#include <oneapi/tbb/task_arena.h>
#include <cmath>
#include <string>

#include "BackwardSolve.h"
#include "Cancellation.h"
#include "SupernodalCholesky.h"
#include "FixedRanges.h"
#include "brittle/database/ScalingLaws.h"
#include "brittle/runtime/FemAssembly.h"

namespace brittle {
namespace {

// Eigen's SimplicialLDLT analysis with the elimination order given instead of computed: the same
// steps as its ordering() (P a Pᵀ's upper triangle from a's lower one) and analysis.
class OrderedAnalysis final : public ShiftedFactor {
 public:
  OrderedAnalysis(const SparseMatrixd& a, const Eigen::VectorXi& order) {
    m_Pinv.indices() = order;  // Eigen's inverse permutation: new position → row
    m_P = m_Pinv.inverse();
    CholMatrixType ap(a.rows(), a.cols());
    ap.selfadjointView<Eigen::Upper>() = a.selfadjointView<Eigen::Lower>().twistedBy(m_P);
    analyzePattern_preordered(ap, true);
  }
  Eigen::Index analysedNonZeros() const { return m_matrix.nonZeros(); }
};

// The non-zeros of AMD's L after its analysis alone.
class AmdAnalysis final : public ShiftedFactor {
 public:
  explicit AmdAnalysis(const SparseMatrixd& a) { analyzePattern(a); }
  Eigen::Index analysedNonZeros() const { return m_matrix.nonZeros(); }
};

}  // namespace

Result<std::shared_ptr<const ShiftedFactor>> factorInOrder(const SparseMatrixd& a, const Eigen::VectorXi& order) {
  if (order.size() != 0 && (a.rows() != a.cols() || !isPermutation(order, a.rows()))) {
    return makeError(ErrorCode::InvalidArgument, "factorInOrder: the order is not a permutation of the matrix's rows");
  }
  // By supernodes (SupernodalCholesky.h), handed over in SimplicialLDLT's form: the same L pattern
  // and order (AMD's where none is given, as Eigen's own analysis), with bits of their own; a placed
  // object's preparation takes 0.32–0.72 of its time before (docs/realtime.md, "Factorised by
  // supernodes").
  detail::SupernodalCholesky factor;
  if (!(order.size() == 0 ? factor.compute(a) : factor.computeInOrder(a, order))) {
    return makeError(ErrorCode::FactorizationFailed, "the matrix did not factorise");
  }
  detail::cancellationPoint();
  return detail::simplicialForm(factor);
}

Eigen::Index factorNonZeros(const SparseMatrixd& a, const Eigen::VectorXi& order) {
  if (order.size() == 0) return AmdAnalysis(a).analysedNonZeros();
  if (a.rows() != a.cols() || !isPermutation(order, a.rows())) return -1;
  return OrderedAnalysis(a, order).analysedNonZeros();
}

using MatrixXfRow = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct StaticCorrection::Data {
  Eigen::Index femNodes = 0;
  SparseMatrixd mass;
  Eigen::MatrixXd rigid;        // Ψ: 3N by 6, M-orthonormal
  Eigen::MatrixXd massRigid;    // M Ψ
  MatrixXdRow modes;            // Φ: 3N by r (an impact reads its load's rows)
  Eigen::MatrixXd modesMassRigid;  // Φᵀ M Ψ: r by 6 (zero up to rounding for elastic modes)
  // H = L⁻¹ P M [Ψ Φ]: the inertia relief's and the kept modes' share of the forward solve, a row
  // per unknown (read in row order per impact), in double or rounded to float (CorrectionStorage).
  MatrixXdRow loadsForward;
  MatrixXfRow loadsForwardFloat;
  std::shared_ptr<const ShiftedFactor> solver;  // of K + μM
  Eigen::VectorXd inverseD;     // of the LDLᵀ factor (vectorD() returns a copy)
  detail::BackwardSolvePlan backward;  // Lᵀ's solve, shared by the arena's threads
  ElementStresses recovery;     // σ at each element's stress points from u
};

Result<StaticCorrection> StaticCorrection::build(const ObjectAsset& asset, const Material& material, int modes,
                                                 CorrectionStorage storage) {
  auto mesh = makeFemMesh(asset.tetMesh, asset.elementOrder);
  if (!mesh) return mesh.error();
  auto fem = assembleFem(mesh.value(), material, FemSettings{});
  if (!fem) return fem.error();
  if (asset.modal.eigenvaluesRad2PerS2.size() == 0) {
    return makeError(ErrorCode::InvalidArgument, "static correction: '" + asset.name + "' has no modes");
  }
  const double mu = 1e-6 * asset.modal.eigenvaluesRad2PerS2[0];
  // In the pack's elimination order where the bake stored one (less fill: FillOrdering.h).
  auto factor = factorInOrder(fem.value().stiffness + mu * fem.value().mass, asset.eliminationOrder);
  if (!factor) {
    return makeError(factor.error().code, "static correction: K + μM of '" + asset.name + "': " + factor.error().message);
  }
  return fromFactor(asset, material, modes, mesh.value(), fem.value(), std::move(factor).value(), mu, storage);
}

Result<StaticCorrection> StaticCorrection::build(const ObjectAsset& asset, const Material& material, int modes,
                                                 const FemSystem& fem, std::shared_ptr<const ShiftedFactor> factor,
                                                 double mu, CorrectionStorage storage) {
  auto mesh = makeFemMesh(asset.tetMesh, asset.elementOrder);
  if (!mesh) return mesh.error();
  return fromFactor(asset, material, modes, mesh.value(), fem, std::move(factor), mu, storage);
}

Result<StaticCorrection> StaticCorrection::fromFactor(const ObjectAsset& asset, const Material& material, int modes,
                                                      const FemMesh& mesh, const FemSystem& fem,
                                                      std::shared_ptr<const ShiftedFactor> factor, double mu,
                                                      CorrectionStorage storage) {
  if (!factor || factor->info() != Eigen::Success || factor->rows() != fem.stiffness.rows() || !(mu > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "static correction: a factor of K + μM with μ > 0 is needed");
  }
  const Points& nodes = mesh.nodes();
  auto recovery = ElementStresses::make(mesh, material);
  if (!recovery) return recovery.error();
  if (asset.modal.modes.rows() != 3 * nodes.rows()) {
    return makeError(ErrorCode::InvalidArgument, "static correction: the modes of '" + asset.name + "' have " +
                                                     std::to_string(asset.modal.modes.rows()) + " rows, expected " +
                                                     std::to_string(3 * nodes.rows()));
  }
  auto data = std::make_shared<Data>();
  data->femNodes = nodes.rows();
  data->recovery = std::move(recovery).value();
  data->mass = fem.mass;
  data->rigid = rigidBodyModes(nodes, data->mass);
  const int r = std::min<int>(modes, static_cast<int>(asset.modal.modes.cols()));
  data->modes = asset.modal.modes.leftCols(r);
  data->solver = std::move(factor);
  const ShiftedFactor& solver = *data->solver;
  data->inverseD = solver.vectorD().cwiseInverse();
  detail::cancellationPoint();  // between the steps too: each reads all of L or H (tens of ms on the vase)
  const bool floats = storage == CorrectionStorage::Float;
  data->backward = detail::BackwardSolvePlan::make(solver.matrixL().nestedExpression(),
                                                   tbb::this_task_arena::max_concurrency(), floats);
  // H = L⁻¹P M[Ψ Φ], once: L⁻¹P f̃ = L⁻¹P f − H [Ψᵀf; Φᵀf_e] (f̃ = f_e − MΦΦᵀf_e, f_e = f − MΨΨᵀf),
  // so an impact's forward solve stays as sparse as its load. (Not (K + μM)⁻¹MΨ after the whole
  // solve: that is Ψ/μ, and taking it away from (K + μM)⁻¹f would cancel six digits of the
  // elastic part.)
  detail::cancellationPoint();
  data->massRigid = data->mass * data->rigid;
  const Eigen::Index dofs = 3 * data->femNodes;
  MatrixXdRow forward(dofs, 6 + r);
  forward.leftCols(6) = data->massRigid;
  forward.rightCols(r) = data->mass * asset.modal.modes.leftCols(r);
  if (solver.permutationP().size() > 0) forward = solver.permutationP() * forward;
  detail::cancellationPoint();
  // Every column at once, in one pass over L: row i takes −L_ij (row j) for the columns j of L in
  // order, each entry Eigen's column-by-column forward solve's arithmetic in its order. With float
  // storage the impact's forward solve reads L rounded to float (BackwardSolvePlan), and H is made
  // from the same rounded L: y − H c then subtracts two solves with one factor. (H from the double
  // L moved the P2 test slab's stress by 3e-6 of its peak; from the rounded one, by 6.5e-7.)
  const SparseMatrixd& lower = solver.matrixL().nestedExpression();
  const float* rounded = data->backward.forwardFloats();  // the forward solve's own values, or null
  for (Eigen::Index j = 0; j < lower.outerSize(); ++j) {
    if (j % 256 == 0) detail::cancellationPoint();
    for (SparseMatrixd::InnerIterator it(lower, j); it; ++it) {
      const double l = rounded ? static_cast<double>(rounded[&it.value() - lower.valuePtr()]) : it.value();
      forward.row(it.index()) -= l * forward.row(j);
    }
  }
  detail::cancellationPoint();
  if (floats) {
    data->loadsForwardFloat = forward.cast<float>();
  } else {
    data->loadsForward = forward;
  }
  data->modesMassRigid = data->modes.transpose() * data->massRigid;
  return StaticCorrection(std::move(data));
}

Status StaticCorrection::stressPerNewton(const std::vector<std::pair<int32_t, double>>& weights,
                                         const Eigen::Vector3d& direction, Eigen::VectorXd& stress,
                                         double& compliance) const {
  Workspace workspace;
  return stressPerNewton(weights, direction, stress, compliance, workspace);
}

StaticCorrection StaticCorrection::placed(const Eigen::Matrix3d& rotation, double lengthM) const {
  StaticCorrection out = *this;
  out.mRotation = rotation * mRotation;
  out.mLengthM = lengthM * mLengthM;
  out.mPlaced = true;
  return out;
}

Status StaticCorrection::stressPerNewton(const std::vector<std::pair<int32_t, double>>& weights,
                                         const Eigen::Vector3d& direction, Eigen::VectorXd& stress,
                                         double& compliance, Workspace& w) const {
  if (mPlaced) {
    // The body the data were built on, loaded along Rᵀ direction; its answer placed (see placed()).
    const Eigen::Vector3d local = mRotation.transpose() * direction;
    if (Status st = solvePerNewton(weights, local, stress, compliance, w); !st) return st;
    rotateVoigtRows(mRotation, Eigen::Map<MatrixXdRow>(stress.data(), stress.size(), 1));  // as instantiateEntry's
    stress *= 1.0 / (mLengthM * mLengthM);
    compliance /= mLengthM;
    return Ok{};
  }
  return solvePerNewton(weights, direction, stress, compliance, w);
}

Status StaticCorrection::solvePerNewton(const std::vector<std::pair<int32_t, double>>& weights,
                                        const Eigen::Vector3d& direction, Eigen::VectorXd& stress,
                                        double& compliance, Workspace& w) const {
  const Data& d = *mData;
  const Eigen::Index dofs = 3 * d.femNodes;
  const Eigen::Index r = d.modes.cols();
  // Every product below writes into a sized buffer (noalias, fixed-size rigid coefficients). The
  // load touches a few nodes, so Ψᵀf and Φᵀf are sums over them. w.modal holds H's coefficients:
  // Ψᵀf, then Φᵀf_e = Φᵀf − ΦᵀMΨ Ψᵀf.
  w.load.setZero(dofs);
  w.modal.setZero(6 + r);
  auto rigid = w.modal.head<6>();
  auto modal = w.modal.tail(r);
  double sum = 0.0;
  for (const auto& [node, weight] : weights) {
    if (node < 0 || node >= d.femNodes) return makeError(ErrorCode::InvalidArgument, "static correction: node out of range");
    const Eigen::Vector3d f = weight * direction;
    w.load.segment<3>(3 * node) += f;
    rigid.noalias() += d.rigid.middleRows<3>(3 * node).transpose() * f;
    modal.noalias() += d.modes.middleRows(3 * node, 3).transpose() * f;
    sum += weight;
  }
  if (std::abs(sum - 1.0) > 1e-9) return makeError(ErrorCode::InvalidArgument, "static correction: weights must sum to 1");
  modal.noalias() -= d.modesMassRigid * rigid;
  w.scratch.resize(dofs);
  w.displacement.resize(dofs);
  // u = (K + μM)⁻¹ f̃ from the factors P(K + μM)Pᵀ = L D Lᵀ, step by step: Eigen's solve() permutes
  // its result in place, and that allocates a mask on every call. The forward solve skips the
  // zeros of a sparse right-hand side, so it costs only the load's reach in the elimination tree
  // (Eigen's arithmetic, a supernode's rows gathered once: the plate's 0.56 → 0.32 ms warm); the
  // backward solve, over all of L, is shared by the threads (BackwardSolve.h).
  if (d.solver->permutationP().size() > 0) {
    w.scratch.noalias() = d.solver->permutationP() * w.load;
  } else {
    w.scratch = w.load;
  }
  d.backward.forwardInPlace(d.solver->matrixL().nestedExpression(), w.scratch, w.gathered);  // = matrixL().solveInPlace
  // y ← D⁻¹(y − H [Ψᵀf; Φᵀf_e]): the forward solve of f̃. H's rows in 16 fixed ranges on the
  // arena's threads; each row's sum is the same arithmetic in any range, so the bits do not depend
  // on the split or the thread count.
  detail::forFixedRanges(dofs, 16, [&](int, Eigen::Index begin, Eigen::Index end) {
    if (d.loadsForwardFloat.size() > 0) {
      detail::subtractRowProducts(d.loadsForwardFloat.data(), 6 + r, begin, end, w.modal.data(), d.inverseD.data(),
                                  w.scratch.data());
    } else {
      detail::subtractRowProducts(d.loadsForward.data(), 6 + r, begin, end, w.modal.data(), d.inverseD.data(),
                                  w.scratch.data());
    }
  });
  d.backward.solveInPlace(d.solver->matrixL().nestedExpression(), w.scratch, w.gathered);  // = matrixU().solveInPlace
  if (d.solver->permutationPinv().size() > 0) {
    w.displacement.noalias() = d.solver->permutationPinv() * w.scratch;
  } else {
    w.displacement = w.scratch;
  }
  // The elastic part only: u −= Ψ Ψᵀ M u (rounding's rigid share, amplified by 1/μ).
  Eigen::Matrix<double, 6, 1> rigidPart;
  rigidPart.noalias() = d.massRigid.transpose() * w.displacement;
  w.displacement.noalias() -= d.rigid * rigidPart;
  compliance = w.load.dot(w.displacement);
  d.recovery.all(w.displacement, stress);
  return Ok{};
}

}  // namespace brittle

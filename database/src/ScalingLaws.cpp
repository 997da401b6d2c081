#include "brittle/database/ScalingLaws.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>

namespace brittle {
namespace {

Eigen::Matrix3d voigtToTensor(const double* v) {
  Eigen::Matrix3d t;
  t << v[0], v[5], v[4], v[5], v[1], v[3], v[4], v[3], v[2];
  return t;
}

// Rayleigh–Ritz correction for a Poisson ratio ν ≠ ν₀ at the reference size (see the header).
// The strain energy is integrated exactly: P1 strain is constant per tet; straight-sided P2 strain
// is linear, given by its values ε_c at the four corners (the stress points), and with
// ∫λ_iλ_j dV = V(1 + δ_ij)/20, ∫εᵀCε dV = V/20 ((Σ_c ε_c)ᵀC(Σ_c ε_c) + Σ_c ε_cᵀCε_c).
void correctPoisson(const TetMesh& mesh, ElementOrder order, const Material& reference, double poissonRatio,
                    ModalBasis& modal, MatrixXdRow& stressModes) {
  const Eigen::Index r = modal.modes.cols();
  const int points = stressPointsPerElement(order);
  const auto c0 = isotropicElasticity(reference.youngsModulusPa, reference.poissonRatio);
  const auto c1 = isotropicElasticity(reference.youngsModulusPa, poissonRatio);
  const Eigen::Matrix<double, 6, 6> c0Inverse = c0.inverse();
  Eigen::MatrixXd reduced = Eigen::MatrixXd::Zero(r, r);
  MatrixXdRow strains(stressModes.rows(), r);
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
    const auto t = mesh.tets.row(e);
    const double volume = std::abs(signedTetVolume(mesh.nodes.row(t[0]).transpose(), mesh.nodes.row(t[1]).transpose(),
                                                   mesh.nodes.row(t[2]).transpose(), mesh.nodes.row(t[3]).transpose()));
    if (points == 1) {
      const Eigen::MatrixXd eps = c0Inverse * stressModes.middleRows(6 * e, 6);
      strains.middleRows(6 * e, 6) = eps;
      reduced.noalias() += volume * eps.transpose() * c1 * eps;
      continue;
    }
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(6, r);
    for (int c = 0; c < points; ++c) {
      const Eigen::Index row = 6 * (points * e + c);
      const Eigen::MatrixXd eps = c0Inverse * stressModes.middleRows(row, 6);
      strains.middleRows(row, 6) = eps;
      sum += eps;
      reduced.noalias() += (volume / 20.0) * eps.transpose() * c1 * eps;
    }
    reduced.noalias() += (volume / 20.0) * sum.transpose() * c1 * sum;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(0.5 * (reduced + reduced.transpose()));
  const Eigen::MatrixXd y = solver.eigenvectors();
  modal.eigenvaluesRad2PerS2 = solver.eigenvalues();
  modal.modes = modal.modes * y;
  for (Eigen::Index p = 0; p < points * mesh.tets.rows(); ++p) {
    stressModes.middleRows(6 * p, 6) = c1 * strains.middleRows(6 * p, 6) * y;
  }
}

}  // namespace

void rotateVoigtRows(const Eigen::Matrix3d& q, Eigen::Ref<MatrixXdRow> s) {
  const Eigen::Index elements = s.rows() / 6;
  Eigen::Matrix<double, 6, 1> v;
  for (Eigen::Index e = 0; e < elements; ++e) {
    for (Eigen::Index k = 0; k < s.cols(); ++k) {
      for (int i = 0; i < 6; ++i) v[i] = s(6 * e + i, k);
      const Eigen::Matrix3d t = q * voigtToTensor(v.data()) * q.transpose();
      s(6 * e + 0, k) = t(0, 0);
      s(6 * e + 1, k) = t(1, 1);
      s(6 * e + 2, k) = t(2, 2);
      s(6 * e + 3, k) = t(1, 2);
      s(6 * e + 4, k) = t(0, 2);
      s(6 * e + 5, k) = t(0, 1);
    }
  }
}

// The entry's physical data are there and consistent: InvalidArgument otherwise. Sets n, the FEM
// node count (P2 entries: the FEM nodes include one per edge, and each tet has four stress points).
Status checkEntryArrays(const ObjectAsset& a, Eigen::Index& n) {
  const Eigen::Index t = a.tetMesh.tets.rows(), r = a.modal.modes.cols();
  if (t == 0 || r == 0) {
    return makeError(ErrorCode::InvalidArgument, "database entry '" + a.name + "' has no physical data (descriptors only)");
  }
  n = femNodeCount(a.tetMesh, a.elementOrder);
  const Eigen::Index points = stressPointsPerElement(a.elementOrder);
  if (n <= 0 || a.modal.modes.rows() != 3 * n || a.stressModes.rows() != 6 * points * t || a.stressModes.cols() != r ||
      a.modal.eigenvaluesRad2PerS2.size() != r) {
    return makeError(ErrorCode::InvalidArgument, "database entry '" + a.name + "' has inconsistent modal arrays");
  }
  return Ok{};
}

Result<EntryAtPoisson> entryAtPoisson(const FragmentEntry& entry, const Material& reference, double poissonRatio) {
  if (Status st = validateMaterial(reference); !st) return st.error();
  Material target = reference;
  target.poissonRatio = poissonRatio;
  if (Status st = validateMaterial(target); !st) return st.error();
  const ObjectAsset& a = entry.asset;
  Eigen::Index n = 0;
  if (Status st = checkEntryArrays(a, n); !st) return st.error();
  EntryAtPoisson out;
  out.poissonRatio = poissonRatio;
  out.modal = a.modal;
  out.stressModes = a.stressModes;
  correctPoisson(a.tetMesh, a.elementOrder, reference, poissonRatio, out.modal, out.stressModes);
  return out;
}

Result<ObjectAsset> instantiateEntry(const FragmentEntry& entry, const Material& reference, const Material& target,
                                     const CanonicalFrame& frame, InstantiateReport* report, const EntryAtPoisson* atPoisson) {
  if (Status st = validateMaterial(reference); !st) return st.error();
  if (Status st = validateMaterial(target); !st) return st.error();
  if (!frame.rotation.allFinite() || !frame.translationM.allFinite() || !std::isfinite(frame.scalePerM) ||
      !(frame.scalePerM > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "query frame has a non-finite value or a non-positive scale");
  }
  const ObjectAsset& a = entry.asset;
  Eigen::Index n = 0;
  if (Status st = checkEntryArrays(a, n); !st) return st.error();
  const bool otherPoisson = target.poissonRatio != reference.poissonRatio;
  if (otherPoisson && atPoisson &&
      (atPoisson->poissonRatio != target.poissonRatio || atPoisson->modal.modes.rows() != a.modal.modes.rows() ||
       atPoisson->modal.modes.cols() != a.modal.modes.cols() || atPoisson->modal.eigenvaluesRad2PerS2.size() != a.modal.modes.cols() ||
       atPoisson->stressModes.rows() != a.stressModes.rows() || atPoisson->stressModes.cols() != a.stressModes.cols())) {
    return makeError(ErrorCode::InvalidArgument, "database entry '" + a.name + "': the basis given for ν = " +
                                                     std::to_string(atPoisson->poissonRatio) + " does not fit a target of ν = " +
                                                     std::to_string(target.poissonRatio) + " on this entry");
  }

  ObjectAsset out = a;
  out.materialName = target.name;
  InstantiateReport info;
  info.lengthScaleM = 1.0 / frame.scalePerM;
  if (otherPoisson) {
    if (atPoisson) {
      out.modal.modes = atPoisson->modal.modes;
      out.modal.eigenvaluesRad2PerS2 = atPoisson->modal.eigenvaluesRad2PerS2;
      out.stressModes = atPoisson->stressModes;
    } else {
      correctPoisson(a.tetMesh, a.elementOrder, reference, target.poissonRatio, out.modal, out.stressModes);
    }
    info.poissonCorrected = true;
  }

  const double length = info.lengthScaleM;
  const double stiffness = target.youngsModulusPa / reference.youngsModulusPa;
  const double density = target.densityKgPerM3 / reference.densityKgPerM3;
  const Eigen::Matrix3d rt = frame.rotation.transpose();  // canonical → query axes

  out.tetMesh.nodes = (a.tetMesh.nodes * (length * frame.rotation)).rowwise() + frame.translationM.transpose();

  out.modal.eigenvaluesRad2PerS2 *= stiffness / (density * length * length);
  out.modal.frequenciesHz = out.modal.eigenvaluesRad2PerS2.cwiseMax(0.0).cwiseSqrt() / (2.0 * std::numbers::pi);
  const double modeScale = 1.0 / std::sqrt(density * length * length * length);
  for (Eigen::Index v = 0; v < n; ++v) {
    out.modal.modes.middleRows(3 * v, 3) = modeScale * rt * out.modal.modes.middleRows(3 * v, 3);
  }
  out.stressModes *= stiffness * modeScale / length;
  rotateVoigtRows(rt, out.stressModes);

  MassProperties& mp = out.massProperties;
  const MassProperties& m0 = a.massProperties;
  const double l3 = length * length * length, l5 = l3 * length * length;
  mp.volumeM3 = m0.volumeM3 * l3;
  mp.massKg = m0.volumeM3 * l3 * target.densityKgPerM3;
  mp.centerOfMassM = frame.toQuery(m0.centerOfMassM);
  // Î was computed with ρ₀; the volume second moment is density-free.
  mp.secondMomentM5 = l5 * rt * m0.secondMomentM5 * frame.rotation;
  mp.inertiaKgM2 = (target.densityKgPerM3 / reference.densityKgPerM3) * l5 * rt * m0.inertiaKgM2 * frame.rotation;
  out.quality.minTetVolumeM3 = a.quality.minTetVolumeM3 * l3;
  out.bake.cellSizeM = a.bake.cellSizeM * length;
  if (report) *report = info;
  return out;
}

}  // namespace brittle

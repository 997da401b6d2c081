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
void correctPoisson(const TetMesh& mesh, const Material& reference, double poissonRatio, ModalBasis& modal,
                    MatrixXdRow& stressModes) {
  const Eigen::Index r = modal.modes.cols();
  const auto c0 = isotropicElasticity(reference.youngsModulusPa, reference.poissonRatio);
  const auto c1 = isotropicElasticity(reference.youngsModulusPa, poissonRatio);
  const Eigen::Matrix<double, 6, 6> c0Inverse = c0.inverse();
  Eigen::MatrixXd reduced = Eigen::MatrixXd::Zero(r, r);
  MatrixXdRow strains(stressModes.rows(), r);
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
    const auto t = mesh.tets.row(e);
    const double volume = std::abs(signedTetVolume(mesh.nodes.row(t[0]).transpose(), mesh.nodes.row(t[1]).transpose(),
                                                   mesh.nodes.row(t[2]).transpose(), mesh.nodes.row(t[3]).transpose()));
    const Eigen::MatrixXd eps = c0Inverse * stressModes.middleRows(6 * e, 6);
    strains.middleRows(6 * e, 6) = eps;
    reduced.noalias() += volume * eps.transpose() * c1 * eps;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(0.5 * (reduced + reduced.transpose()));
  const Eigen::MatrixXd y = solver.eigenvectors();
  modal.eigenvaluesRad2PerS2 = solver.eigenvalues();
  modal.modes = modal.modes * y;
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
    stressModes.middleRows(6 * e, 6) = c1 * strains.middleRows(6 * e, 6) * y;
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

Result<ObjectAsset> instantiateEntry(const FragmentEntry& entry, const Material& reference, const Material& target,
                                     const CanonicalFrame& frame, InstantiateReport* report) {
  if (Status st = validateMaterial(reference); !st) return st.error();
  if (Status st = validateMaterial(target); !st) return st.error();
  if (!frame.rotation.allFinite() || !frame.translationM.allFinite() || !std::isfinite(frame.scalePerM) ||
      !(frame.scalePerM > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "query frame has a non-finite value or a non-positive scale");
  }
  const ObjectAsset& a = entry.asset;
  const Eigen::Index n = a.tetMesh.nodes.rows(), t = a.tetMesh.tets.rows(), r = a.modal.modes.cols();
  if (t == 0 || r == 0) {
    return makeError(ErrorCode::InvalidArgument, "database entry '" + a.name + "' has no physical data (descriptors only)");
  }
  if (a.modal.modes.rows() != 3 * n || a.stressModes.rows() != 6 * t || a.stressModes.cols() != r ||
      a.modal.eigenvaluesRad2PerS2.size() != r) {
    return makeError(ErrorCode::InvalidArgument, "database entry '" + a.name + "' has inconsistent modal arrays");
  }

  ObjectAsset out = a;
  out.materialName = target.name;
  InstantiateReport info;
  info.lengthScaleM = 1.0 / frame.scalePerM;
  if (target.poissonRatio != reference.poissonRatio) {
    correctPoisson(a.tetMesh, reference, target.poissonRatio, out.modal, out.stressModes);
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

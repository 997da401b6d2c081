#include "brittle/runtime/FragmentModes.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <Spectra/SymEigsSolver.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/runtime/FemAssembly.h"
#include "brittle/runtime/PolynomialModes.h"
#include "brittle/runtime/TetTopology.h"
#include "Cancellation.h"
#include "SupernodalCholesky.h"

namespace brittle {
namespace {


// The shifted problem in standard form. With K − σM = Pᵀ L Lᵀ P (σ < 0, so it is positive
// definite; a supernodal factor, SupernodalCholesky.h) and G = Pᵀ L, K φ = λ M φ is A ψ = θ ψ for
// the symmetric A = G⁻¹ M G⁻ᵀ = L⁻¹ P M Pᵀ L⁻ᵀ, ψ = Gᵀ φ = Lᵀ P φ and θ = 1/(λ − σ): the lowest λ
// are the largest θ. An application of A costs what Spectra's generalised shift-invert operator does
// (one solve with the factor and one product with M), but the Lanczos vectors are then orthogonal in
// the Euclidean product instead of M's, so the several further products with M per step that
// M-orthogonalisation takes are gone (measured on exact-path pieces of 430–1 600 DOF: they were 19 %
// of the build, the solves 28 %). The solves run by panel: on a 25k-DOF quadratic piece 16 of them
// took 144 ms against 235 through Eigen's SimplicialLDLT.
class StandardFormOp {
 public:
  using Scalar = double;
  StandardFormOp(const detail::SupernodalCholesky& factor, const SparseMatrixd& mass)
      : mFactor(factor), mMass(mass), mT(factor.rows()), mU(factor.rows()) {}
  Eigen::Index rows() const { return mFactor.rows(); }
  Eigen::Index cols() const { return mFactor.rows(); }
  void perform_op(const double* x, double* y) const {
    detail::cancellationPoint();  // a step of Lanczos: a World closing stops its analyses here
    std::copy(x, x + rows(), mT.data());
    mFactor.solveLt(mT.data());
    mFactor.permuteBack(mT.data(), mU.data());
    mT.noalias() = mMass * mU;
    mFactor.permute(mT.data(), y);
    mFactor.solveL(y);
  }
  // ψ = Lᵀ P φ
  Eigen::VectorXd psi(const Eigen::VectorXd& phi) const {
    Eigen::VectorXd out(rows());
    mFactor.permute(phi.data(), mT.data());
    mFactor.multiplyLt(mT.data(), out.data());
    return out;
  }
  // φ = G⁻ᵀ ψ = Pᵀ L⁻ᵀ ψ, column by column.
  Eigen::MatrixXd modes(const Eigen::MatrixXd& psi) const {
    Eigen::MatrixXd phi(psi.rows(), psi.cols());
    for (Eigen::Index c = 0; c < psi.cols(); ++c) {
      mT = psi.col(c);
      mFactor.solveLt(mT.data());
      mFactor.permuteBack(mT.data(), phi.col(c).data());
    }
    return phi;
  }

 private:
  const detail::SupernodalCholesky& mFactor;
  const SparseMatrixd& mMass;
  mutable Eigen::VectorXd mT, mU;
};

// Lowest `count` eigenpairs of K φ = λ M φ, ascending, M-normalised; `factor` gets the sparse
// path's factorisation of K − σM (null on the dense path).
Status lowestEigenpairs(const FemSystem& fem, int count, double sigma, const ExactModesSettings& s,
                        Eigen::VectorXd& values, Eigen::MatrixXd& vectors,
                        std::shared_ptr<const Eigen::SimplicialLDLT<SparseMatrixd>>& factorOut) {
  const Eigen::Index n = fem.stiffness.rows();
  if (n <= s.denseMaxDof) {
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> dense(Eigen::MatrixXd(fem.stiffness),
                                                                    Eigen::MatrixXd(fem.mass));
    if (dense.info() != Eigen::Success) return makeError(ErrorCode::EigenNotConverged, "dense eigensolver failed");
    values = dense.eigenvalues().head(count);
    vectors = dense.eigenvectors().leftCols(count);
    return Ok{};
  }
  detail::SupernodalCholesky factor;
  if (!factor.compute(fem.stiffness - sigma * fem.mass, 3)) {
    return makeError(ErrorCode::FactorizationFailed, "K − σM did not factorise as positive definite");
  }
  StandardFormOp op(factor, fem.mass);
  const Eigen::Index ncv = std::min<Eigen::Index>(n, std::max<Eigen::Index>(2 * count + 1, count + 20));
  Spectra::SymEigsSolver<StandardFormOp> solver(op, count, ncv);
  solver.init();
  solver.compute(Spectra::SortRule::LargestAlge, 1000, s.tolerance, Spectra::SortRule::LargestAlge);
  if (solver.info() != Spectra::CompInfo::Successful) {
    return makeError(ErrorCode::EigenNotConverged, "Spectra did not converge on " + std::to_string(count) + " modes");
  }
  values = sigma + solver.eigenvalues().cwiseInverse().array();  // θ descending: λ ascending
  vectors = op.modes(solver.eigenvectors());
  // Spectra's tolerance bounds the Ritz values, not the vectors: a P2 piece of the brick came back
  // with ‖Kφ − λMφ‖/‖Kφ‖ = 1.8e-8 at a tolerance of 1e-10 and of 1e-12 alike. Where an elastic
  // vector is worse than 1e-8 (the bake's own bound, ModalAnalysis.cpp), one step of inverse
  // iteration with the same factor and a Rayleigh–Ritz projection on its span bring it to ~1e-11.
  auto worstResidual = [&] {
    double worst = 0.0;
    for (Eigen::Index j = 6; j < vectors.cols(); ++j) {
      const Eigen::VectorXd kphi = fem.stiffness * vectors.col(j);
      worst = std::max(worst, (kphi - values[j] * (fem.mass * vectors.col(j))).norm() / kphi.norm());
    }
    return worst;
  };
  constexpr double kMaxResidual = 1e-8;
  if (worstResidual() > kMaxResidual) {
    Eigen::MatrixXd y(n, vectors.cols());
    for (Eigen::Index c = 0; c < vectors.cols(); ++c) {
      Eigen::VectorXd column = fem.mass * vectors.col(c);
      factor.solve(column);
      y.col(c) = column;
    }
    const Eigen::MatrixXd a = y.transpose() * (fem.stiffness * y), b = y.transpose() * (fem.mass * y);
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> ritz(0.5 * (a + a.transpose()), 0.5 * (b + b.transpose()));
    if (ritz.info() != Eigen::Success) return makeError(ErrorCode::EigenNotConverged, "the Rayleigh–Ritz step failed");
    values = ritz.eigenvalues();
    vectors = y * ritz.eigenvectors();
  }
  factorOut = detail::simplicialForm(factor);  // for the static correction (ExactModesFactor)
  return Ok{};
}

// Lanczos vectors beyond the wanted count in lowestElasticEigenvalues (Spectra's ncv − nev): 12
// took the least time on the default objects' pieces (8, 12 and 20 measured).
constexpr int kElasticLanczosExtra = 12;

// The standard form with the six rigid motions taken out: A' = (I − QQᵀ) A (I − QQᵀ), Q an
// orthonormal basis of the rigid modes' ψ = Gᵀ φ. Elastic modes are (K − σM)-orthogonal to the
// rigid ones, so their ψ are orthogonal to Q and keep θ; the rigid directions go to 0. Lanczos
// then needs only the elastic modes wanted, not six more ahead of them at the top of A's spectrum.
class ElasticFormOp {
 public:
  using Scalar = double;
  ElasticFormOp(const StandardFormOp& op, Eigen::MatrixXd q) : mOp(op), mQ(std::move(q)), mT(op.rows()) {}
  Eigen::Index rows() const { return mOp.rows(); }
  Eigen::Index cols() const { return mOp.rows(); }
  void perform_op(const double* x, double* y) const {
    Eigen::Map<const Eigen::VectorXd> in(x, rows());
    Eigen::Map<Eigen::VectorXd> out(y, rows());
    mT = in - mQ * (mQ.transpose() * in);
    mOp.perform_op(mT.data(), y);
    out -= mQ * (mQ.transpose() * out);
  }

 private:
  const StandardFormOp& mOp;
  const Eigen::MatrixXd mQ;
  mutable Eigen::VectorXd mT;
};

// The lowest `count` elastic eigenvalues (rad²/s², ascending) of a free solid's K φ = λ M φ,
// without eigenvectors: what the mesh check needs (meshFrequencyRatios). The six rigid motions of
// the nodes are projected out of the shifted standard form (ElasticFormOp) instead of being
// computed first; small systems take the dense solver. A solid that hangs by an edge or a node has
// more than six zero modes: its lowest elastic value then comes out at rounding (RigidModeMismatch).
Result<Eigen::VectorXd> lowestElasticEigenvalues(const FemSystem& fem, const Points& nodes, int count, double sigma,
                                                 const ExactModesSettings& s, const std::string& name) {
  const Eigen::Index n = fem.stiffness.rows();
  Eigen::VectorXd values;
  if (n <= std::max<Eigen::Index>(s.denseMaxDof, 2 * (count + 6) + 1)) {
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> dense(Eigen::MatrixXd(fem.stiffness), Eigen::MatrixXd(fem.mass),
                                                                    Eigen::EigenvaluesOnly);
    if (dense.info() != Eigen::Success) return makeError(ErrorCode::EigenNotConverged, "dense eigensolver failed");
    if (dense.eigenvalues().size() < count + 6) return invalidArgument("fragment '" + name + "': too few degrees of freedom");
    values = dense.eigenvalues().segment(6, count);
    const double largest = dense.eigenvalues().head(count + 6).cwiseAbs().maxCoeff();
    int rigid = 0;
    while (rigid < count + 6 && std::abs(dense.eigenvalues()[rigid]) < 1e-8 * largest) ++rigid;
    if (rigid != 6) {
      return makeError(ErrorCode::RigidModeMismatch, "fragment '" + name + "': " + std::to_string(rigid) + " near-zero modes instead of 6");
    }
    return values;
  }
  // K − σM by supernodes (SupernodalCholesky.h): against Eigen's SimplicialLDLT, the quadratic
  // checks of the default objects' pieces take 0.74 of their time (median; p10 0.54, p90 0.98), the
  // small linear ones about the same (docs/results/speed-accuracy.md, "The checks by supernodes").
  detail::SupernodalCholesky factor;
  if (!factor.compute(fem.stiffness - sigma * fem.mass, 3)) {
    return makeError(ErrorCode::FactorizationFailed, "fragment '" + name + "': K − σM did not factorise as positive definite");
  }
  const StandardFormOp standard(factor, fem.mass);
  // The rigid motions' ψ = Gᵀφ; Q orthonormalises them, so φ need not be M-normal.
  const Eigen::MatrixXd rigid = rigidBodyMotions(nodes);
  Eigen::MatrixXd psi(n, 6);
  for (int c = 0; c < 6; ++c) psi.col(c) = standard.psi(rigid.col(c));
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(psi);
  const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(n, 6);
  ElasticFormOp op(standard, q);
  const Eigen::Index ncv = std::min<Eigen::Index>(n - 6, std::max<Eigen::Index>(2 * count + 1, count + kElasticLanczosExtra));
  Spectra::SymEigsSolver<ElasticFormOp> solver(op, count, ncv);
  solver.init();
  solver.compute(Spectra::SortRule::LargestAlge, 1000, s.tolerance, Spectra::SortRule::LargestAlge);
  if (solver.info() != Spectra::CompInfo::Successful) {
    return makeError(ErrorCode::EigenNotConverged, "fragment '" + name + "': Spectra did not converge on " + std::to_string(count) + " elastic modes");
  }
  values = sigma + solver.eigenvalues().cwiseInverse().array();  // θ descending: λ ascending
  // A seventh zero mode (a mechanism) has θ = −1/σ, the rigid motions' own: λ at rounding.
  if (!(values[0] > 1e-8 * values.cwiseAbs().maxCoeff())) {
    return makeError(ErrorCode::RigidModeMismatch, "fragment '" + name + "': more than 6 near-zero modes");
  }
  return values;
}

// The sub-mesh's FEM system and its lowest modeCount + 6 eigenpairs, six of them rigid: the exact
// path's modal analysis.
struct FragmentEigen {
  FemMesh femMesh;
  FemSystem fem;
  Eigen::VectorXd values;
  Eigen::MatrixXd vectors;
  std::shared_ptr<const Eigen::SimplicialLDLT<SparseMatrixd>> factor;
  double sigma = 0.0;
  bool dense = false;
};

// How many different labels the corners hold (a face's three repeat one).
int distinctLabels(const std::array<int, 4>& l) {
  std::array<int, 4> sorted = l;
  std::sort(sorted.begin(), sorted.end());
  return static_cast<int>(std::unique(sorted.begin(), sorted.end()) - sorted.begin());
}

// The quad v0 v1 v2 v3 (in order around it) as two triangles, split through its corner of least key.
std::array<std::array<int32_t, 3>, 2> splitQuad(const std::array<int32_t, 4>& v, const std::array<int64_t, 4>& key) {
  if (std::min(key[0], key[2]) < std::min(key[1], key[3])) return {{{v[0], v[1], v[2]}, {v[0], v[2], v[3]}}};
  return {{{v[1], v[2], v[3]}, {v[1], v[3], v[0]}}};
}

// σ = −10⁻³ (c/L)², as the bake's shift (ModalAnalysis.h): K − σM is positive definite, and σ
// lies well below the first elastic eigenvalue of any compact body.
double shiftBelow(const FragmentSubMesh& sub, const Material& material) {
  const double length = (sub.mesh.nodes.colwise().maxCoeff() - sub.mesh.nodes.colwise().minCoeff()).norm();
  return -1e-3 * material.youngsModulusPa / material.densityKgPerM3 / (length * length);
}

Status checkExactInput(const FragmentSubMesh& sub, const ExactModesSettings& settings, const std::string& name) {
  if (settings.modeCount < 1 || settings.denseMaxDof < 0 || !(settings.tolerance > 0.0 && settings.tolerance < 1.0)) {
    return invalidArgument("ExactModesSettings: modeCount ≥ 1, denseMaxDof ≥ 0, tolerance in (0, 1)");
  }
  if (sub.mesh.nodes.rows() < 4 || sub.mesh.tets.rows() < 1) return invalidArgument("fragment '" + name + "': fewer than 4 nodes");
  return Ok{};
}

Result<FragmentEigen> fragmentEigen(const FragmentSubMesh& sub, const Material& material, const ExactModesSettings& settings,
                                    const std::string& name) {
  if (Status st = checkExactInput(sub, settings, name); !st) return st.error();
  FragmentEigen out;
  auto femMesh = makeFemMesh(sub.mesh, settings.elementOrder);
  if (!femMesh) return femMesh.error();
  out.femMesh = std::move(femMesh).value();
  auto fem = assembleFem(out.femMesh, material, FemSettings{});
  if (!fem) return fem.error();
  out.fem = std::move(fem).value();

  // Six rigid modes plus the elastic ones; a mesh too small for that keeps what it has.
  const auto dof = static_cast<int>(out.fem.stiffness.rows());
  const int wanted = std::min(settings.modeCount + 6, dof - 1);
  if (wanted <= 6) return invalidArgument("fragment '" + name + "': too few degrees of freedom for an elastic mode");
  ExactModesSettings s = settings;
  if (wanted >= dof - 1 || dof <= 2 * wanted + 1) s.denseMaxDof = std::max(s.denseMaxDof, dof);  // Lanczos needs room
  out.dense = dof <= s.denseMaxDof;
  out.sigma = shiftBelow(sub, material);
  if (Status st = lowestEigenpairs(out.fem, wanted, out.sigma, s, out.values, out.vectors, out.factor); !st) {
    return Error{st.error().code, "fragment '" + name + "': " + st.error().message};
  }
  // Exactly six near-zero modes for one connected solid.
  const double largest = out.values.cwiseAbs().maxCoeff();
  int rigid = 0;
  while (rigid < out.values.size() && std::abs(out.values[rigid]) < 1e-8 * largest) ++rigid;
  if (rigid != 6) {
    return makeError(ErrorCode::RigidModeMismatch,
                     "fragment '" + name + "': " + std::to_string(rigid) + " near-zero modes instead of 6");
  }
  return out;
}

}  // namespace

std::vector<int64_t> fragmentTetCounts(const TetMesh& parent, const Eigen::VectorXi& nodeLabels, int labelCount) {
  std::vector<int64_t> counts(static_cast<size_t>(std::max(labelCount, 0)), 0);
  if (nodeLabels.size() != parent.nodes.rows()) return counts;
  for (Eigen::Index e = 0; e < parent.tets.rows(); ++e) {
    std::array<int, 4> l{};
    for (int k = 0; k < 4; ++k) l[static_cast<size_t>(k)] = nodeLabels[parent.tets(e, k)];
    std::sort(l.begin(), l.end());
    for (int k = 0; k < 4; ++k)
      if ((k == 0 || l[static_cast<size_t>(k)] != l[static_cast<size_t>(k - 1)]) && l[static_cast<size_t>(k)] >= 0 && l[static_cast<size_t>(k)] < labelCount) {
        ++counts[static_cast<size_t>(l[static_cast<size_t>(k)])];
      }
  }
  return counts;
}

int64_t fragmentCutDof(const TetMesh& parent, const TetTopology& topology, const Eigen::VectorXi& nodeLabels, int label,
                       ElementOrder order, CutCells cells) {
  const Eigen::Index n = parent.nodes.rows(), t = parent.tets.rows();
  if (nodeLabels.size() != n || topology.tetEdges.rows() != t || topology.neighbours.rows() != t) return 0;
  auto mine = [&](int32_t v) { return v >= 0 && v < n && nodeLabels[v] == label; };
  if (cells == CutCells::Prisms) {
    if (order != ElementOrder::P1) return 0;
    int64_t points = 0;
    for (Eigen::Index v = 0; v < n; ++v) points += nodeLabels[v] == label ? 1 : 0;
    for (Eigen::Index e = 0; e < topology.edges.rows(); ++e) points += (mine(topology.edges(e, 0)) != mine(topology.edges(e, 1))) ? 1 : 0;
    for (Eigen::Index e = 0; e < t; ++e) {
      std::array<int, 4> l{};
      int c = 0;
      for (int k = 0; k < 4; ++k) {
        const int32_t v = parent.tets(e, k);
        if (v < 0 || v >= n) return 0;
        l[static_cast<size_t>(k)] = nodeLabels[v];
        c += l[static_cast<size_t>(k)] == label ? 1 : 0;
      }
      if (c == 0 || c == 4 || distinctLabels(l) == 2) continue;
      points += 1;  // the tet point
      for (int f = 0; f < 4; ++f) {
        const int32_t across = topology.neighbours(e, f);
        if (across >= 0 && across < e) continue;  // counted from the lower tet
        std::array<int, 4> face{};
        for (int k = 0, j = 0; k < 4; ++k)
          if (k != f) face[static_cast<size_t>(j++)] = l[static_cast<size_t>(k)];
        face[3] = face[0];
        if (distinctLabels(face) == 3 && (face[0] == label || face[1] == label || face[2] == label)) points += 1;  // the face point
      }
    }
    return 3 * points;
  }
  // Points: the label's nodes, a crack point per edge with one end in it (every such edge lies in a
  // crossed tet of the label, whose faces through that end use the point).
  int64_t points = 0, edges = 0;
  for (Eigen::Index v = 0; v < n; ++v) points += nodeLabels[v] == label ? 1 : 0;
  for (Eigen::Index e = 0; e < topology.edges.rows(); ++e) {
    const int ends = (mine(topology.edges(e, 0)) ? 1 : 0) + (mine(topology.edges(e, 1)) ? 1 : 0);
    if (ends == 1) ++points, ++edges;  // the crack point, and its segment to the label's end
    if (ends == 2) ++edges;            // kept as it is
  }
  // Per crossed tet with c of its corners in the label: the tet point, joined to the c corners, the
  // c(4 − c) crack points and the points of the faces that are crossed (3, 4, 3 of them for c = 1,
  // 2, 3). Per crossed face with m corners in the label (counted once, from the lower tet or on the
  // boundary): its face point, joined to the m corners and the two crack points around them.
  static constexpr std::array<int, 4> kCrossedFaces = {0, 3, 4, 3};
  for (Eigen::Index e = 0; e < t; ++e) {
    int c = 0;
    for (int k = 0; k < 4; ++k) c += mine(parent.tets(e, k)) ? 1 : 0;
    if (c == 0 || c == 4) continue;
    points += 1;
    edges += c + c * (4 - c) + kCrossedFaces[static_cast<size_t>(c)];
    for (int f = 0; f < 4; ++f) {
      const int m = c - (mine(parent.tets(e, f)) ? 1 : 0);  // face f is opposite corner f
      const int32_t across = topology.neighbours(e, f);
      if (m == 0 || m == 3 || (across >= 0 && across < e)) continue;
      points += 1;
      edges += m + 2;
    }
  }
  return 3 * (order == ElementOrder::P2 ? points + edges : points);
}

Result<FragmentSubMesh> fragmentSubMesh(const TetMesh& parent, const TetTopology& topology,
                                        const Eigen::VectorXi& nodeLabels, const Eigen::VectorXd& edgeCuts, int label, CutCells cells) {
  const Eigen::Index n = parent.nodes.rows(), t = parent.tets.rows();
  if (nodeLabels.size() != n || edgeCuts.size() != topology.edges.rows() || topology.tetEdges.rows() != t) {
    return invalidArgument("fragmentSubMesh: one label per node, one cut per edge and the mesh's topology expected");
  }
  auto mixed = [&](int32_t edge) { return nodeLabels[topology.edges(edge, 0)] != nodeLabels[topology.edges(edge, 1)]; };
  auto edgeOf = [&](Eigen::Index e, int i, int j) {
    for (int k = 0; k < 6; ++k)
      if ((kTetEdges[k][0] == i && kTetEdges[k][1] == j) || (kTetEdges[k][0] == j && kTetEdges[k][1] == i)) return topology.tetEdges(e, k);
    return int32_t{-1};
  };

  // Points of the sub-mesh, created on first use: parent nodes, crack points on mixed edges (at
  // FragmentSurfaces.h's clamped parameter), face points (mean of the face's crack points, keyed
  // by the sorted node ids so that both tets of a face share it) and tet points.
  std::vector<Eigen::Vector3d> points;
  // Point of each parent node, edge and tet (−1: none yet), by index: the parent's size once per
  // fragment, where a map's node per point cost more than the cutting.
  std::array<std::vector<int32_t>, 3> ids = {std::vector<int32_t>(static_cast<size_t>(n), -1),
                                             std::vector<int32_t>(static_cast<size_t>(topology.edges.rows()), -1),
                                             std::vector<int32_t>(static_cast<size_t>(t), -1)};
  std::map<std::array<int32_t, 3>, int32_t> faceIds;
  // Each point's key in the parent (node v: v; crack point on edge g: N + g; others after them):
  // Prisms split quads of corners and crack points through their least key, the same from every
  // tet and every fragment that has the quad.
  std::vector<int64_t> keys;
  const int64_t edgeKeys = n, otherKeys = n + topology.edges.rows();
  auto point = [&](int kind, int64_t key, const Eigen::Vector3d& x) {
    int32_t& id = ids[static_cast<size_t>(kind)][static_cast<size_t>(key)];
    if (id < 0) {
      id = static_cast<int32_t>(points.size());
      points.push_back(x);
      keys.push_back(kind == 0 ? key : (kind == 1 ? edgeKeys + key : otherKeys));
    }
    return id;
  };
  auto node = [&](int32_t v) { return point(0, v, parent.nodes.row(v).transpose()); };
  auto edgePoint = [&](int32_t edge) {
    const double s = std::clamp(edgeCuts[edge], 0.05, 0.95);
    const Eigen::Vector3d a = parent.nodes.row(topology.edges(edge, 0)), b = parent.nodes.row(topology.edges(edge, 1));
    return std::pair{point(1, edge, a + s * (b - a)), Eigen::Vector3d(a + s * (b - a))};
  };
  std::vector<std::array<int32_t, 4>> tets;
  auto addTet = [&](int32_t a, int32_t b, int32_t c, int32_t d) {
    const Eigen::Vector3d pa = points[static_cast<size_t>(a)];
    const double v = (points[static_cast<size_t>(b)] - pa).dot((points[static_cast<size_t>(c)] - pa).cross(points[static_cast<size_t>(d)] - pa));
    if (v > 0.0) tets.push_back({a, b, c, d});
    else if (v < 0.0) tets.push_back({a, c, b, d});
  };
  // A prism with long edges a_i–b_i in three tets. Each quad (a_i, a_i+1, b_i+1, b_i) is split
  // through its corner of least key (as splitQuad), so that a face shared with the next tet is
  // split the same way from both sides; with the prism's least key at a_0, two quads split through
  // it, and the third picks one of two decompositions.
  auto keyOf = [&](int32_t id) { return keys[static_cast<size_t>(id)]; };
  auto addPrism = [&](std::array<int32_t, 3> a, std::array<int32_t, 3> b) {
    int32_t least = a[0];
    for (int32_t id : {a[1], a[2], b[0], b[1], b[2]})
      if (keyOf(id) < keyOf(least)) least = id;
    if (std::find(b.begin(), b.end(), least) != b.end()) std::swap(a, b);
    while (a[0] != least) {
      std::rotate(a.begin(), a.begin() + 1, a.end());
      std::rotate(b.begin(), b.begin() + 1, b.end());
    }
    if (std::min(keyOf(a[1]), keyOf(b[2])) < std::min(keyOf(a[2]), keyOf(b[1]))) {
      addTet(a[0], a[1], a[2], b[2]);
      addTet(a[0], a[1], b[2], b[1]);
    } else {
      addTet(a[0], a[1], a[2], b[1]);
      addTet(a[0], a[2], b[2], b[1]);
    }
    addTet(a[0], b[1], b[2], b[0]);
  };

  FragmentSubMesh sub;
  for (Eigen::Index e = 0; e < t; ++e) {
    std::array<int, 4> l{};
    int own = 0;
    for (int k = 0; k < 4; ++k) {
      const int32_t v = parent.tets(e, k);
      if (v < 0 || v >= n) return invalidArgument("fragmentSubMesh: tet " + std::to_string(e) + " has a node out of range");
      l[static_cast<size_t>(k)] = nodeLabels[v];
      own += l[static_cast<size_t>(k)] == label ? 1 : 0;
    }
    if (own == 0) continue;
    if (own == 4) {
      tets.push_back({node(parent.tets(e, 0)), node(parent.tets(e, 1)), node(parent.tets(e, 2)), node(parent.tets(e, 3))});
      ++sub.wholeTets;
      continue;
    }
    // A tet the crack crosses: the label's corner cells (FragmentSurfaces.h), as tets from the tet
    // point to the label's part of each face, fanned from the face point.
    ++sub.splitTets;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    int crossings = 0;
    for (int k = 0; k < 6; ++k) {
      const int32_t edge = topology.tetEdges(e, k);
      if (!mixed(edge)) continue;
      if (!std::isfinite(edgeCuts[edge])) return invalidArgument("fragmentSubMesh: a crossed edge without a finite cut");
      centre += edgePoint(edge).second;
      ++crossings;
    }
    if (cells == CutCells::Prisms && distinctLabels(l) == 2) {
      // One crack through the tet: the label's part is a tet (one corner) or a prism (two or three)
      // between its corners and the crack points, with no point of its own.
      std::array<int, 4> in{}, out{};
      int nIn = 0, nOut = 0;
      for (int k = 0; k < 4; ++k) (l[static_cast<size_t>(k)] == label ? in[static_cast<size_t>(nIn++)] : out[static_cast<size_t>(nOut++)]) = k;
      auto cut = [&](int i, int j) { return edgePoint(edgeOf(e, i, j)).first; };
      auto corner = [&](int k) { return node(parent.tets(e, k)); };
      if (nIn == 1) {
        addTet(corner(in[0]), cut(in[0], out[0]), cut(in[0], out[1]), cut(in[0], out[2]));
      } else if (nIn == 3) {
        addPrism({corner(in[0]), corner(in[1]), corner(in[2])}, {cut(in[0], out[0]), cut(in[1], out[0]), cut(in[2], out[0])});
      } else {
        addPrism({corner(in[0]), cut(in[0], out[0]), cut(in[0], out[1])}, {corner(in[1]), cut(in[1], out[0]), cut(in[1], out[1])});
      }
      continue;
    }
    const int32_t tetPoint = point(2, e, centre / crossings);
    for (int f = 0; f < 4; ++f) {
      const auto local = tetFaceNodes(f);
      std::array<int32_t, 3> v{}, fl{};
      int mine = 0;
      for (int k = 0; k < 3; ++k) {
        v[static_cast<size_t>(k)] = parent.tets(e, local[static_cast<size_t>(k)]);
        fl[static_cast<size_t>(k)] = l[static_cast<size_t>(local[static_cast<size_t>(k)])];
        mine += fl[static_cast<size_t>(k)] == label ? 1 : 0;
      }
      if (mine == 0) continue;
      if (mine == 3) {
        addTet(tetPoint, node(v[0]), node(v[1]), node(v[2]));
        continue;
      }
      if (cells == CutCells::Prisms && distinctLabels(std::array<int, 4>{fl[0], fl[1], fl[2], fl[0]}) == 2) {
        // Two labels on the face: the label's part is a triangle or a quad of its corners and crack
        // points, split as the prisms split theirs (a face shared with a prism tet agrees).
        int startK = 0;
        while (!(fl[static_cast<size_t>(startK)] == label && fl[static_cast<size_t>((startK + 2) % 3)] != label)) ++startK;
        const int32_t before = edgePoint(edgeOf(e, local[static_cast<size_t>((startK + 2) % 3)], local[static_cast<size_t>(startK)])).first;
        const int next = (startK + 1) % 3;
        if (mine == 1) {
          addTet(tetPoint, before, node(v[static_cast<size_t>(startK)]),
                 edgePoint(edgeOf(e, local[static_cast<size_t>(startK)], local[static_cast<size_t>(next)])).first);
        } else {
          const std::array<int32_t, 4> quad = {before, node(v[static_cast<size_t>(startK)]), node(v[static_cast<size_t>(next)]),
                                               edgePoint(edgeOf(e, local[static_cast<size_t>(next)], local[static_cast<size_t>((next + 1) % 3)])).first};
          for (const auto& tri : splitQuad(quad, {keyOf(quad[0]), keyOf(quad[1]), keyOf(quad[2]), keyOf(quad[3])})) addTet(tetPoint, tri[0], tri[1], tri[2]);
        }
        continue;
      }
      std::array<int32_t, 3> key = v;
      std::sort(key.begin(), key.end());
      auto [it, inserted] = faceIds.try_emplace(key, -1);
      if (inserted) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        int count = 0;
        for (int k = 0; k < 3; ++k) {
          const int32_t edge = edgeOf(e, local[static_cast<size_t>(k)], local[static_cast<size_t>((k + 1) % 3)]);
          if (mixed(edge)) sum += edgePoint(edge).second, ++count;
        }
        it->second = static_cast<int32_t>(points.size());
        points.push_back(sum / count);
        keys.push_back(otherKeys);
      }
      const int32_t facePoint = it->second;
      // The label's corners are consecutive around the face: the crack point before the run, the
      // run, the crack point after it; with the face point, that closes the label's part.
      int startK = 0;
      while (!(fl[static_cast<size_t>(startK)] == label && fl[static_cast<size_t>((startK + 2) % 3)] != label)) ++startK;
      std::vector<int32_t> polygon;
      polygon.push_back(edgePoint(edgeOf(e, local[static_cast<size_t>((startK + 2) % 3)], local[static_cast<size_t>(startK)])).first);
      int k = startK;
      while (true) {
        polygon.push_back(node(v[static_cast<size_t>(k)]));
        const int next = (k + 1) % 3;
        if (fl[static_cast<size_t>(next)] != label) {
          polygon.push_back(edgePoint(edgeOf(e, local[static_cast<size_t>(k)], local[static_cast<size_t>(next)])).first);
          break;
        }
        k = next;
      }
      // Fan from the face point: the same triangles from both tets of the face.
      for (size_t j = 0; j + 1 < polygon.size(); ++j) addTet(tetPoint, facePoint, polygon[j], polygon[j + 1]);
    }
  }
  if (tets.empty()) return invalidArgument("fragmentSubMesh: label " + std::to_string(label) + " owns no part of the mesh");

  // Largest face-connected set (a label's nodes are joined by uncut edges, so this is normally all).
  std::vector<int32_t> root(tets.size());
  for (size_t i = 0; i < tets.size(); ++i) root[i] = static_cast<int32_t>(i);
  auto find = [&](int32_t i) {
    while (root[static_cast<size_t>(i)] != i) i = root[static_cast<size_t>(i)] = root[static_cast<size_t>(root[static_cast<size_t>(i)])];
    return i;
  };
  std::vector<std::pair<std::array<int32_t, 3>, int32_t>> faces;
  faces.reserve(4 * tets.size());
  for (size_t i = 0; i < tets.size(); ++i)
    for (int f = 0; f < 4; ++f) {
      std::array<int32_t, 3> key{};
      for (int k = 0, j = 0; k < 4; ++k)
        if (k != f) key[static_cast<size_t>(j++)] = tets[i][static_cast<size_t>(k)];
      std::sort(key.begin(), key.end());
      faces.emplace_back(key, static_cast<int32_t>(i));
    }
  std::sort(faces.begin(), faces.end());
  for (size_t i = 1; i < faces.size(); ++i)
    if (faces[i].first == faces[i - 1].first) root[static_cast<size_t>(find(faces[i].second))] = find(faces[i - 1].second);
  auto volume = [&](const std::array<int32_t, 4>& q) {
    const Eigen::Vector3d a = points[static_cast<size_t>(q[0])];
    return (points[static_cast<size_t>(q[1])] - a).dot((points[static_cast<size_t>(q[2])] - a).cross(points[static_cast<size_t>(q[3])] - a)) / 6.0;
  };
  std::vector<double> setVolume(tets.size(), 0.0);
  for (size_t i = 0; i < tets.size(); ++i) setVolume[static_cast<size_t>(find(static_cast<int32_t>(i)))] += volume(tets[i]);
  const auto keep = static_cast<int32_t>(std::max_element(setVolume.begin(), setVolume.end()) - setVolume.begin());

  std::vector<int32_t> renumber(points.size(), -1);
  std::vector<int32_t> kept;
  for (size_t i = 0; i < tets.size(); ++i) {
    if (find(static_cast<int32_t>(i)) != keep) {
      sub.droppedVolumeM3 += volume(tets[i]);
      continue;
    }
    kept.push_back(static_cast<int32_t>(i));
    for (int32_t p : tets[i])
      if (renumber[static_cast<size_t>(p)] < 0) renumber[static_cast<size_t>(p)] = 0;
  }
  int32_t next = 0;
  for (int32_t& r : renumber)
    if (r == 0) r = next++;
  sub.mesh.nodes.resize(next, 3);
  for (size_t p = 0; p < points.size(); ++p)
    if (renumber[p] >= 0) sub.mesh.nodes.row(renumber[p]) = points[p].transpose();
  sub.mesh.tets.resize(static_cast<Eigen::Index>(kept.size()), 4);
  for (size_t i = 0; i < kept.size(); ++i)
    for (int k = 0; k < 4; ++k) sub.mesh.tets(static_cast<Eigen::Index>(i), k) = renumber[static_cast<size_t>(tets[static_cast<size_t>(kept[i])][static_cast<size_t>(k)])];
  return sub;
}

Result<MeshFrequencyRatios> meshFrequencyRatios(const FragmentSubMesh& sub, const Material& material, int degree, int count,
                                                ElementOrder order) {
  if (degree < 1 || degree > kMaxPolynomialModeDegree || count < 1) {
    return invalidArgument("meshFrequencyRatios: degree " + std::to_string(degree) + " (in [1, " + std::to_string(kMaxPolynomialModeDegree) +
                           "]) and count " + std::to_string(count) + " (≥ 1)");
  }
  ExactModesSettings s;
  s.modeCount = count;
  if (Status st = checkExactInput(sub, s, "mesh ratios"); !st) return st.error();
  auto femMesh = makeFemMesh(sub.mesh, order);
  if (!femMesh) return femMesh.error();
  auto fem = assembleFem(femMesh.value(), material, FemSettings{});
  if (!fem) return fem.error();
  if (fem.value().stiffness.rows() < count + 7) {
    return invalidArgument("meshFrequencyRatios: the sub-mesh has " + std::to_string(fem.value().stiffness.rows()) +
                           " degrees of freedom, too few for " + std::to_string(count) + " elastic modes");
  }
  auto solved = lowestElasticEigenvalues(fem.value(), femMesh.value().nodes(), count, shiftBelow(sub, material), s, "mesh ratios");
  if (!solved) return solved.error();
  const Eigen::VectorXd& elastic = solved.value();
  auto polynomial = polynomialFrequenciesOnMesh(femMesh.value().nodes(), fem.value(), degree, count);
  if (!polynomial) return polynomial.error();
  if (polynomial.value().size() < count) return invalidArgument("meshFrequencyRatios: too few polynomial modes for " + std::to_string(count));
  MeshFrequencyRatios out;
  out.meshHz = elastic.cwiseMax(0.0).cwiseSqrt() / (2.0 * std::numbers::pi);
  out.polynomialHz = polynomial.value().head(count);
  // f_h ≤ f_p holds exactly (a subspace); the eigen solvers' tolerances can put a ratio a hair above.
  out.ratios = out.meshHz.cwiseQuotient(out.polynomialHz).cwiseMin(1.0);
  if (!out.ratios.allFinite() || !(out.ratios.minCoeff() > 0.0)) {
    return makeError(ErrorCode::EigenNotConverged, "meshFrequencyRatios: a ratio is not in (0, 1]");
  }
  return out;
}

void applyMeshRatios(Eigen::VectorXd& frequenciesHz, const MeshFrequencyRatios& ratios) {
  const Eigen::Index k = std::min(frequenciesHz.size(), ratios.ratios.size());
  frequenciesHz.head(k) = frequenciesHz.head(k).cwiseProduct(ratios.ratios.head(k));
  std::sort(frequenciesHz.data(), frequenciesHz.data() + k);
}

double meshGain(const MeshFrequencyRatios& ratios) {
  if (ratios.ratios.size() == 0) return std::numeric_limits<double>::quiet_NaN();
  return std::max(0.0, 1.0 - ratios.ratios.minCoeff());
}

Result<ObjectAsset> exactFragmentAsset(const FragmentSubMesh& sub, const Material& material,
                                       const ExactModesSettings& settings, const std::string& name,
                                       ExactModesFactor* factorOut) {
  if (factorOut) *factorOut = ExactModesFactor{};
  if (Status st = checkExactInput(sub, settings, name); !st) return st.error();
  auto topology = buildTetTopology(sub.mesh);
  if (!topology) return topology.error();
  auto solved = fragmentEigen(sub, material, settings, name);
  if (!solved) return solved.error();
  FragmentEigen& e = solved.value();
  const Eigen::VectorXd& values = e.values;
  const Eigen::MatrixXd& vectors = e.vectors;
  const Eigen::Index nodes = sub.mesh.nodes.rows();
  const Eigen::Index dof = e.fem.stiffness.rows();
  const auto r = static_cast<Eigen::Index>(values.size() - 6);
  ObjectAsset a;
  a.name = name;
  a.materialName = material.name;
  a.tetMesh = sub.mesh;
  a.surfaceFaces = topology.value().boundaryTriangles;
  a.quality.nodeCount = nodes;
  a.quality.tetCount = sub.mesh.tets.rows();
  a.quality.surfaceFaceCount = a.surfaceFaces.rows();
  a.quality.minTetVolumeM3 = topology.value().tetVolumesM3.minCoeff();
  a.massProperties = computeSurfaceMassProperties(TriangleMesh{sub.mesh.nodes, a.surfaceFaces}, material.densityKgPerM3);
  ModalBasis& m = a.modal;
  m.eigenvaluesRad2PerS2 = values.tail(r);
  m.frequenciesHz = m.eigenvaluesRad2PerS2.cwiseMax(0.0).cwiseSqrt() / (2.0 * std::numbers::pi);
  m.modes.resize(dof, r);
  m.residuals.resize(r);
  for (Eigen::Index j = 0; j < r; ++j) {
    Eigen::VectorXd phi = vectors.col(6 + j);
    phi /= std::sqrt(phi.dot(e.fem.mass * phi));
    m.modes.col(j) = phi;
    const Eigen::VectorXd kphi = e.fem.stiffness * phi;
    m.residuals[j] = (kphi - values[6 + j] * (e.fem.mass * phi)).norm() / kphi.norm();
  }
  const Eigen::MatrixXd gram = Eigen::MatrixXd(m.modes).transpose() * (e.fem.mass * Eigen::MatrixXd(m.modes));
  m.orthonormalityError = (gram - Eigen::MatrixXd::Identity(r, r)).cwiseAbs().maxCoeff();
  a.stressModes = computeStressModes(e.femMesh, material, m.modes);
  a.elementOrder = settings.elementOrder;
  a.bake.requestedModes = settings.modeCount;
  a.bake.factorization = e.dense ? "dense" : "supernodal-ldlt";
  if (factorOut && e.factor) {
    factorOut->fem = std::move(e.fem);
    factorOut->factor = std::move(e.factor);
    factorOut->shiftRad2PerS2 = e.sigma;
  }
  return a;
}

}  // namespace brittle

#include "brittle/runtime/PolynomialModes.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Spectra/SymEigsSolver.h>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace brittle {
namespace {

// The Ritz problem of the fields e_i y^α: k[i][j] the stiffness between component i of monomial
// A and component j of monomial B, massGram the monomials' Gram matrix, the same for every
// component (M = density · massGram ⊗ I₃). massGram = V D Vᵀ, and the problem is solved in the
// M-orthonormal directions W = V D^(−1/2) ⊗ I₃ / √density whose mass is above rounding. Dense and
// small (56 by 56 blocks, 168 by 168 at p = 5). Used from the moments and from a mesh.
struct RitzSolution {
  Eigen::VectorXd values;   ///< ascending (rad²/s²), the rigid motions' first
  Eigen::MatrixXd vectors;  ///< in the directions W, with shapes only
  Eigen::MatrixXd wg;       ///< W = wg ⊗ I₃
};

// (R − σI)⁻¹ of a dense symmetric R, by its Cholesky factor: the lowest λ of R are the largest
// θ = 1/(λ − σ).
class DenseShiftInvert {
 public:
  using Scalar = double;
  explicit DenseShiftInvert(const Eigen::LLT<Eigen::MatrixXd>& llt) : mLlt(llt) {}
  Eigen::Index rows() const { return mLlt.rows(); }
  Eigen::Index cols() const { return mLlt.rows(); }
  void perform_op(const double* x, double* y) const {
    Eigen::Map<Eigen::VectorXd> out(y, rows());
    out = Eigen::Map<const Eigen::VectorXd>(x, rows());
    mLlt.solveInPlace(out);
  }

 private:
  const Eigen::LLT<Eigen::MatrixXd>& mLlt;
};

// The lowest `wanted` eigenvalues of the symmetric positive semi-definite R, ascending, by Lanczos
// on (R − σI)⁻¹ (Spectra) with σ just below 0: a Cholesky factor and a few dozen solves, where the
// full solve reduces all of R to tridiagonal form (the 168-by-168 Ritz problem at p = 5: 2 ms
// against ~0.6). Empty where the factor or Lanczos fails; the caller then solves in full.
Eigen::VectorXd lowestEigenvalues(const Eigen::MatrixXd& r, Eigen::Index wanted) {
  const Eigen::Index n = r.rows();
  const double sigma = -1e-9 * r.diagonal().cwiseAbs().maxCoeff();
  Eigen::MatrixXd shifted = r;
  shifted.diagonal().array() -= sigma;
  const Eigen::LLT<Eigen::MatrixXd> llt(shifted);
  if (llt.info() != Eigen::Success) return {};
  DenseShiftInvert op(llt);
  Spectra::SymEigsSolver<DenseShiftInvert> solver(op, wanted, std::min<Eigen::Index>(n, std::max<Eigen::Index>(2 * wanted + 1, wanted + 12)));
  solver.init();
  solver.compute(Spectra::SortRule::LargestAlge, 1000, 1e-13, Spectra::SortRule::LargestAlge);
  if (solver.info() != Spectra::CompInfo::Successful) return {};
  return (sigma + solver.eigenvalues().cwiseInverse().array()).matrix();  // θ descending: λ ascending
}

Result<RitzSolution> solveRitz(const std::array<std::array<Eigen::MatrixXd, 3>, 3>& k, const Eigen::MatrixXd& massGram,
                               double density, bool withShapes, Eigen::Index wanted = -1) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> gram(massGram);
  if (gram.info() != Eigen::Success) return makeError(ErrorCode::EigenNotConverged, "polynomial Ritz: the Gram matrix's eigen solve failed");
  const Eigen::Index monomials = massGram.rows();
  const double largest = gram.eigenvalues().maxCoeff();
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < monomials; ++i)
    if (gram.eigenvalues()[i] > 1e-13 * largest) kept.push_back(i);
  const auto directions = static_cast<Eigen::Index>(kept.size());
  RitzSolution out;
  out.wg.resize(monomials, directions);
  for (Eigen::Index c = 0; c < directions; ++c) {
    out.wg.col(c) = gram.eigenvectors().col(kept[static_cast<size_t>(c)]) / std::sqrt(density * gram.eigenvalues()[kept[static_cast<size_t>(c)]]);
  }
  // Wᵀ K W block by block: entry (3c + i, 3d + j) is wgᵀ k[i][j] wg, a third of the work of the
  // whole product.
  Eigen::MatrixXd reduced(3 * directions, 3 * directions);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Eigen::MatrixXd block = out.wg.transpose() * k[static_cast<size_t>(i)][static_cast<size_t>(j)] * out.wg;
      for (Eigen::Index c = 0; c < directions; ++c)
        for (Eigen::Index d = 0; d < directions; ++d) reduced(3 * c + i, 3 * d + j) = block(c, d);
    }
  }
  // Values only, and few of them: the lowest `wanted` by shift-invert Lanczos (the six rigid motions
  // among them).
  if (!withShapes && wanted > 0 && 3 * wanted <= reduced.rows()) {
    out.values = lowestEigenvalues(0.5 * (reduced + reduced.transpose()), wanted);
    if (out.values.size() == wanted) return out;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ritz(0.5 * (reduced + reduced.transpose()),
                                                      withShapes ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly);
  if (ritz.info() != Eigen::Success) return makeError(ErrorCode::EigenNotConverged, "polynomial Ritz: the eigen solve failed");
  out.values = ritz.eigenvalues();
  if (withShapes) out.vectors = ritz.eigenvectors();
  return out;
}

// y^α for every monomial of degree ≤ `degree` (graded order, monomialExponents) at y, into `out`:
// the powers of each coordinate once, then a product of three per monomial.
void monomialsAt(const Eigen::Vector3d& y, int degree, double* out) {
  std::array<std::array<double, kMaxPolynomialModeDegree + 1>, 3> powers;
  for (size_t q = 0; q < 3; ++q) {
    powers[q][0] = 1.0;
    for (size_t d = 1; d <= static_cast<size_t>(degree); ++d) powers[q][d] = powers[q][d - 1] * y[static_cast<Eigen::Index>(q)];
  }
  const int monomials = monomialCount(degree);
  for (int a = 0; a < monomials; ++a) {
    const std::array<int, 3> e = monomialExponents(a);
    out[a] = powers[0][static_cast<size_t>(e[0])] * powers[1][static_cast<size_t>(e[1])] * powers[2][static_cast<size_t>(e[2])];
  }
}

// The elastic frequencies (Hz) of Ritz values, the six rigid motions dropped.
Eigen::VectorXd elasticFrequencies(const Eigen::VectorXd& values) {
  const Eigen::Index elastic = std::max<Eigen::Index>(values.size() - 6, 0);
  Eigen::VectorXd hz(elastic);
  for (Eigen::Index i = 6; i < values.size(); ++i) hz[i - 6] = std::sqrt(std::max(values[i], 0.0)) / (2.0 * M_PI);
  return hz;
}

}  // namespace

Result<PolynomialModes> polynomialModes(const VolumeMoments& moments, const Material& material, int degree, bool withShapes,
                                        Eigen::Index count) {
  if (degree < 1 || degree > kMaxPolynomialModeDegree) {
    return makeError(ErrorCode::InvalidArgument, "polynomialModes: degree " + std::to_string(degree) + " is outside [1, " +
                                                     std::to_string(kMaxPolynomialModeDegree) + "]");
  }
  if (moments.maxOrder < 2 * degree || moments.values.size() < monomialCount(2 * degree)) {
    return makeError(ErrorCode::InvalidArgument, "polynomialModes: degree " + std::to_string(degree) + " needs moments of order " +
                                                     std::to_string(2 * degree) + ", given " + std::to_string(moments.maxOrder));
  }
  if (!moments.values.head(monomialCount(2 * degree)).allFinite()) {
    return makeError(ErrorCode::NonFiniteValue, "polynomialModes: a volume moment is not finite");
  }
  if (Status st = validateMaterial(material); !st) return st.error();
  const double volume = moments(0, 0, 0);
  if (!(volume > 0.0)) {
    return makeError(ErrorCode::EmptyMesh, "polynomialModes: the solid's volume is " + std::to_string(volume) + " m³ (empty or inward)");
  }
  // Centred on the centroid and scaled by the RMS radius: y = (x − c)/s, moments of order ≤ 2p in y.
  const Eigen::Vector3d centre = Eigen::Vector3d(moments(1, 0, 0), moments(0, 1, 0), moments(0, 0, 1)) / volume;
  const double meanSquare = (moments(2, 0, 0) + moments(0, 2, 0) + moments(0, 0, 2)) / volume - centre.squaredNorm();
  if (!(meanSquare > 0.0)) return makeError(ErrorCode::EmptyMesh, "polynomialModes: the solid has no extent");
  const double s = std::sqrt(meanSquare);
  VolumeMoments order2p;
  order2p.maxOrder = 2 * degree;
  order2p.values = moments.values.head(monomialCount(2 * degree));
  const VolumeMoments y = transformVolumeMoments(order2p, Eigen::Matrix3d::Identity() / s, centre);
  auto m = [&](int a, int b, int c) { return (a < 0 || b < 0 || c < 0) ? 0.0 : y(a, b, c); };

  const int monomials = monomialCount(degree), n = 3 * monomials;
  const double nu = material.poissonRatio, young = material.youngsModulusPa;
  const double lambda = young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), mu = young / (2.0 * (1.0 + nu));
  // K by components: k[i][j](A, B) couples component i of monomial A with component j of B.
  std::array<std::array<Eigen::MatrixXd, 3>, 3> k;
  for (auto& row : k)
    for (Eigen::MatrixXd& block : row) block.resize(monomials, monomials);
  Eigen::MatrixXd g(monomials, monomials);
  for (int A = 0; A < monomials; ++A) {
    const std::array<int, 3> al = monomialExponents(A);
    for (int B = 0; B < monomials; ++B) {
      const std::array<int, 3> be = monomialExponents(B);
      const std::array<int, 3> sum = {al[0] + be[0], al[1] + be[1], al[2] + be[2]};
      auto less = [&](int i, int j) {  // m[α + β − e_i − e_j]
        std::array<int, 3> e = sum;
        --e[static_cast<size_t>(i)];
        --e[static_cast<size_t>(j)];
        return m(e[0], e[1], e[2]);
      };
      double gradients = 0.0;  // ∫ ∇y^α · ∇y^β
      for (int q = 0; q < 3; ++q) gradients += al[static_cast<size_t>(q)] * be[static_cast<size_t>(q)] * less(q, q);
      g(A, B) = m(sum[0], sum[1], sum[2]);
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          const double cross = less(i, j);
          double v = (lambda * al[static_cast<size_t>(i)] * be[static_cast<size_t>(j)] +
                      mu * al[static_cast<size_t>(j)] * be[static_cast<size_t>(i)]) * cross;
          if (i == j) v += mu * gradients;
          k[static_cast<size_t>(i)][static_cast<size_t>(j)](A, B) = v / (s * s);
        }
      }
    }
  }
  // M = ρ G ⊗ I₃ with G the monomials' Gram matrix (m[α+β]).
  auto solved = solveRitz(k, g, material.densityKgPerM3, withShapes, count > 0 ? count + 6 : -1);
  if (!solved) return solved.error();
  const RitzSolution& ritz = solved.value();
  const auto directions = ritz.wg.cols();
  PolynomialModes out;
  out.degree = degree;
  out.basisSize = n;
  out.keptDirections = 3 * directions;
  out.centreM = centre;
  out.scaleM = s;
  out.frequenciesHz = elasticFrequencies(ritz.values);  // ascending; the six rigid motions dropped
  const Eigen::Index elastic = out.frequenciesHz.size();
  // W is M-orthonormal over the solid in y (dV_y = dV / s³): over x, the columns scale by s^(−3/2).
  if (withShapes) {
    const Eigen::MatrixXd vectors = ritz.vectors.rightCols(elastic) / std::pow(s, 1.5);
    out.coefficients.resize(n, elastic);
    Eigen::MatrixXd component(directions, elastic);
    for (int i = 0; i < 3; ++i) {
      for (Eigen::Index c = 0; c < directions; ++c) component.row(c) = vectors.row(3 * c + i);
      const Eigen::MatrixXd perMonomial = ritz.wg * component;
      for (int A = 0; A < monomials; ++A) out.coefficients.row(3 * A + i) = perMonomial.row(A);
    }
  }
  return out;
}

MatrixXdRow PolynomialModes::displacements(const Points& points, Eigen::Index count) const {
  const int monomials = monomialCount(degree);
  MatrixXdRow out(3 * points.rows(), count);
  Eigen::VectorXd powers(monomials);
  for (Eigen::Index p = 0; p < points.rows(); ++p) {
    monomialsAt((points.row(p).transpose() - centreM) / scaleM, degree, powers.data());
    for (int i = 0; i < 3; ++i) {
      for (Eigen::Index k = 0; k < count; ++k) {
        double sum = 0.0;
        for (int a = 0; a < monomials; ++a) sum += coefficients(3 * a + i, k) * powers[a];
        out(3 * p + i, k) = sum;
      }
    }
  }
  return out;
}

Result<PolynomialModes> polynomialModes(const TriangleMesh& surface, const Material& material, int degree, bool withShapes,
                                        Eigen::Index count) {
  if (degree < 1 || degree > kMaxPolynomialModeDegree) return polynomialModes(VolumeMoments{}, material, degree, withShapes, count);
  if (surface.vertices.rows() == 0) return makeError(ErrorCode::EmptyMesh, "polynomialModes: the surface has no vertex");
  const Eigen::Vector3d origin = surface.vertices.colwise().mean().transpose();
  auto moments = computeVolumeMoments(surface, 2 * degree, origin);
  if (!moments) return moments.error();
  auto modes = polynomialModes(moments.value(), material, degree, withShapes, count);
  if (modes) modes.value().centreM += origin;  // the moments were about the origin
  return modes;
}

Result<Eigen::VectorXd> polynomialFrequenciesOnMesh(const Points& nodes, const FemSystem& fem, int degree, Eigen::Index count) {
  if (degree < 1 || degree > kMaxPolynomialModeDegree) {
    return makeError(ErrorCode::InvalidArgument, "polynomialFrequenciesOnMesh: degree " + std::to_string(degree) + " is outside [1, " +
                                                     std::to_string(kMaxPolynomialModeDegree) + "]");
  }
  const Eigen::Index n = nodes.rows();
  if (n < 4 || fem.stiffness.rows() != 3 * n || fem.stiffness.cols() != 3 * n || fem.mass.rows() != 3 * n || fem.mass.cols() != 3 * n) {
    return makeError(ErrorCode::InvalidArgument, "polynomialFrequenciesOnMesh: " + std::to_string(n) + " nodes (at least 4) and a " +
                                                     std::to_string(fem.stiffness.rows()) + "-DOF system (3 per node)");
  }
  if (!nodes.allFinite()) return makeError(ErrorCode::NonFiniteValue, "polynomialFrequenciesOnMesh: a node is not finite");
  // y = (x − c)/s about the nodes' mean c, s their RMS radius: the monomials stay near 1.
  const Eigen::RowVector3d c = nodes.colwise().mean();
  const double s = std::sqrt((nodes.rowwise() - c).squaredNorm() / static_cast<double>(n));
  if (!(s > 0.0)) return makeError(ErrorCode::EmptyMesh, "polynomialFrequenciesOnMesh: the nodes have no extent");
  const int monomials = monomialCount(degree);
  MatrixXdRow values(n, monomials);  // y^α at each node, a row per node
  for (Eigen::Index v = 0; v < n; ++v) monomialsAt(((nodes.row(v) - c) / s).transpose(), degree, &values(v, 0));
  // K between the interpolated fields, by component blocks: kz[i][j] = K_ij Y (K_ij the nodes'
  // i–j couplings), then k[i][j] = Yᵀ kz[i][j]; one pass over K's entries, no 3N-row product. K is
  // symmetric, so k[j][i] = k[i][j]ᵀ and only the blocks i ≤ j are summed. M couples equal
  // components only, alike for each (FemAssembly's M), so its Gram is Yᵀ M₀₀ Y.
  // The six blocks i ≤ j and M₀₀ Y side by side in one n by 7·monomials matrix z, so that the
  // seven products with Yᵀ are one (a wide product runs at about twice the rate of seven narrow ones).
  constexpr std::array<std::array<int, 3>, 3> kBlock = {{{0, 1, 2}, {-1, 3, 4}, {-1, -1, 5}}};
  constexpr int kMassBlock = 6;
  MatrixXdRow z = MatrixXdRow::Zero(n, 7 * monomials);
  for (Eigen::Index col = 0; col < fem.stiffness.outerSize(); ++col) {
    const Eigen::Index w = col / 3, j = col % 3;
    for (SparseMatrixd::InnerIterator it(fem.stiffness, col); it; ++it) {
      const Eigen::Index i = it.row() % 3;
      if (i <= j) z.row(it.row() / 3).segment(kBlock[static_cast<size_t>(i)][static_cast<size_t>(j)] * monomials, monomials) += it.value() * values.row(w);
    }
    if (j != 0) continue;
    for (SparseMatrixd::InnerIterator it(fem.mass, col); it; ++it)
      if (it.row() % 3 == 0) z.row(it.row() / 3).segment(kMassBlock * monomials, monomials) += it.value() * values.row(w);
  }
  const Eigen::MatrixXd projected = values.transpose() * z;
  std::array<std::array<Eigen::MatrixXd, 3>, 3> k;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) {
      k[static_cast<size_t>(i)][static_cast<size_t>(j)] = projected.middleCols(kBlock[static_cast<size_t>(i)][static_cast<size_t>(j)] * monomials, monomials);
      if (j > i) k[static_cast<size_t>(j)][static_cast<size_t>(i)] = k[static_cast<size_t>(i)][static_cast<size_t>(j)].transpose();
    }
  auto solved = solveRitz(k, projected.middleCols(kMassBlock * monomials, monomials), 1.0, /*withShapes=*/false, count > 0 ? count + 6 : -1);
  if (!solved) return solved.error();
  return elasticFrequencies(solved.value().values);
}

Status adoptPolynomialFrequencies(ObjectAsset& asset, const PolynomialModes& modes) {
  return adoptPolynomialFrequencies(asset.modal, modes);
}

Status adoptPolynomialFrequencies(ModalBasis& basis, const PolynomialModes& modes) {
  const Eigen::Index r = basis.eigenvaluesRad2PerS2.size();
  if (modes.frequenciesHz.size() < r) {
    return makeError(ErrorCode::InvalidArgument, "adoptPolynomialFrequencies: " + std::to_string(modes.frequenciesHz.size()) +
                                                     " polynomial modes for an asset of " + std::to_string(r));
  }
  const Eigen::VectorXd entry = basis.eigenvaluesRad2PerS2;
  basis.frequenciesHz = modes.frequenciesHz.head(r);
  basis.eigenvaluesRad2PerS2 = (2.0 * M_PI * basis.frequenciesHz).array().square();
  basis.residuals = (1.0 - basis.eigenvaluesRad2PerS2.array() / entry.array()).abs();
  return Ok{};
}

}  // namespace brittle

#include "brittle/runtime/PolynomialModes.h"

#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace brittle {

Result<PolynomialModes> polynomialModes(const VolumeMoments& moments, const Material& material, int degree, bool withShapes) {
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
  // M = ρ G ⊗ I₃ with G the monomials' Gram matrix (m[α+β]); G = V D Vᵀ, and the Ritz problem is
  // solved in the M-orthonormal directions W = V D^(−1/2) ⊗ I₃ / √ρ whose mass is above rounding.
  // Dense and small (G is 56 by 56, K 168 by 168 at p = 5).
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> gram(g);
  if (gram.info() != Eigen::Success) return makeError(ErrorCode::EigenNotConverged, "polynomialModes: the Gram matrix's eigen solve failed");
  const double largest = gram.eigenvalues().maxCoeff();
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < monomials; ++i)
    if (gram.eigenvalues()[i] > 1e-13 * largest) kept.push_back(i);
  const auto directions = static_cast<Eigen::Index>(kept.size());
  Eigen::MatrixXd wg(monomials, directions);  // W = wg ⊗ I₃
  for (Eigen::Index c = 0; c < directions; ++c) {
    wg.col(c) = gram.eigenvectors().col(kept[static_cast<size_t>(c)]) /
                std::sqrt(material.densityKgPerM3 * gram.eigenvalues()[kept[static_cast<size_t>(c)]]);
  }
  // Wᵀ K W block by block: entry (3c + i, 3d + j) is wgᵀ k[i][j] wg, a third of the work of the
  // whole product.
  Eigen::MatrixXd reduced(3 * directions, 3 * directions);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Eigen::MatrixXd block = wg.transpose() * k[static_cast<size_t>(i)][static_cast<size_t>(j)] * wg;
      for (Eigen::Index c = 0; c < directions; ++c)
        for (Eigen::Index d = 0; d < directions; ++d) reduced(3 * c + i, 3 * d + j) = block(c, d);
    }
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ritz(0.5 * (reduced + reduced.transpose()),
                                                      withShapes ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly);
  if (ritz.info() != Eigen::Success) return makeError(ErrorCode::EigenNotConverged, "polynomialModes: the Ritz eigen solve failed");
  PolynomialModes out;
  out.degree = degree;
  out.basisSize = n;
  out.keptDirections = 3 * static_cast<Eigen::Index>(kept.size());
  out.centreM = centre;
  out.scaleM = s;
  const Eigen::VectorXd& values = ritz.eigenvalues();  // ascending; the first six are the rigid motions
  const Eigen::Index elastic = std::max<Eigen::Index>(values.size() - 6, 0);
  out.frequenciesHz.resize(elastic);
  for (Eigen::Index i = 6; i < values.size(); ++i) out.frequenciesHz[i - 6] = std::sqrt(std::max(values[i], 0.0)) / (2.0 * M_PI);
  // W is M-orthonormal over the solid in y (dV_y = dV / s³): over x, the columns scale by s^(−3/2).
  if (withShapes) {
    const Eigen::MatrixXd vectors = ritz.eigenvectors().rightCols(elastic) / std::pow(s, 1.5);
    out.coefficients.resize(n, elastic);
    Eigen::MatrixXd component(directions, elastic);
    for (int i = 0; i < 3; ++i) {
      for (Eigen::Index c = 0; c < directions; ++c) component.row(c) = vectors.row(3 * c + i);
      const Eigen::MatrixXd perMonomial = wg * component;
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
    const Eigen::Vector3d y = (points.row(p).transpose() - centreM) / scaleM;
    for (int a = 0; a < monomials; ++a) {
      const std::array<int, 3> e = monomialExponents(a);
      powers[a] = std::pow(y.x(), e[0]) * std::pow(y.y(), e[1]) * std::pow(y.z(), e[2]);
    }
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

Result<PolynomialModes> polynomialModes(const TriangleMesh& surface, const Material& material, int degree, bool withShapes) {
  if (degree < 1 || degree > kMaxPolynomialModeDegree) return polynomialModes(VolumeMoments{}, material, degree, withShapes);
  if (surface.vertices.rows() == 0) return makeError(ErrorCode::EmptyMesh, "polynomialModes: the surface has no vertex");
  const Eigen::Vector3d origin = surface.vertices.colwise().mean().transpose();
  auto moments = computeVolumeMoments(surface, 2 * degree, origin);
  if (!moments) return moments.error();
  auto modes = polynomialModes(moments.value(), material, degree, withShapes);
  if (modes) modes.value().centreM += origin;  // the moments were about the origin
  return modes;
}

Status adoptPolynomialFrequencies(ObjectAsset& asset, const PolynomialModes& modes) {
  ModalBasis& basis = asset.modal;
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

#include "brittle/runtime/FemAssembly.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "Cancellation.h"
#include "FixedRanges.h"
#include "brittle/descriptors/MassProperties.h"
#include "brittle/runtime/QuadraticTetMesh.h"

namespace brittle {
namespace {

// K and M (3n by 3n) assembled straight into compressed columns. The pattern comes first, as node
// blocks: node b's column block holds every node that shares an element with it, ascending (K: a
// 3 × 3 block per pair; a consistent M: the equal components only; a lumped M: the diagonal). Each
// element then adds its entries into their slots, in element order. An entry is the sum that
// setFromTriplets made from the same element loop (its first contribution, then the others in
// element order), so K and M are the same bits, without the 144 (P1) or 900 (P2) triplets per
// element it stored, sorted and transposed: a fifth of the mesh check's time on the runtime's
// fragments (FragmentModes.h, meshFrequencyRatios).
template <int P>
class BlockAssembly {
 public:
  using Elements = Eigen::Matrix<int32_t, Eigen::Dynamic, P, Eigen::RowMajor>;

  // `elements` is checked by the caller (every node in [0, n)).
  BlockAssembly(Eigen::Index n, const Elements& elements, bool lumped) {
    // Node → elements, then each node's sorted neighbours.
    std::vector<int64_t> incidenceStart(static_cast<size_t>(n) + 1, 0);
    for (Eigen::Index t = 0; t < elements.rows(); ++t)
      for (int a = 0; a < P; ++a) ++incidenceStart[static_cast<size_t>(elements(t, a)) + 1];
    for (size_t v = 0; v < static_cast<size_t>(n); ++v) incidenceStart[v + 1] += incidenceStart[v];
    std::vector<int32_t> incidence(static_cast<size_t>(incidenceStart.back()));
    {
      std::vector<int64_t> fill(incidenceStart.begin(), incidenceStart.end() - 1);
      for (Eigen::Index t = 0; t < elements.rows(); ++t)
        for (int a = 0; a < P; ++a) incidence[static_cast<size_t>(fill[static_cast<size_t>(elements(t, a))]++)] = static_cast<int32_t>(t);
    }
    mStart.assign(static_cast<size_t>(n) + 1, 0);
    std::vector<int32_t> buffer;
    for (Eigen::Index b = 0; b < n; ++b) {
      buffer.clear();
      for (int64_t k = incidenceStart[static_cast<size_t>(b)]; k < incidenceStart[static_cast<size_t>(b) + 1]; ++k)
        for (int a = 0; a < P; ++a) buffer.push_back(elements(incidence[static_cast<size_t>(k)], a));
      std::sort(buffer.begin(), buffer.end());
      buffer.erase(std::unique(buffer.begin(), buffer.end()), buffer.end());
      mNeighbours.insert(mNeighbours.end(), buffer.begin(), buffer.end());
      mStart[static_cast<size_t>(b) + 1] = static_cast<int64_t>(mNeighbours.size());
    }
    const auto blocks = static_cast<Eigen::Index>(mNeighbours.size());
    mSys.stiffness.resize(3 * n, 3 * n);
    mSys.mass.resize(3 * n, 3 * n);
    mSys.stiffness.resizeNonZeros(9 * blocks);
    mSys.mass.resizeNonZeros(lumped ? 3 * n : 3 * blocks);
    int* kOuter = mSys.stiffness.outerIndexPtr();
    int* kInner = mSys.stiffness.innerIndexPtr();
    int* mOuter = mSys.mass.outerIndexPtr();
    int* mInner = mSys.mass.innerIndexPtr();
    for (Eigen::Index b = 0; b < n; ++b) {
      const int64_t first = mStart[static_cast<size_t>(b)], degree = mStart[static_cast<size_t>(b) + 1] - first;
      for (int j = 0; j < 3; ++j) {
        const int64_t k0 = 9 * first + 3 * j * degree;
        kOuter[3 * b + j] = static_cast<int>(k0);
        for (int64_t q = 0; q < degree; ++q)
          for (int i = 0; i < 3; ++i) kInner[k0 + 3 * q + i] = 3 * mNeighbours[static_cast<size_t>(first + q)] + i;
        if (lumped) {
          mOuter[3 * b + j] = static_cast<int>(3 * b + j);
          mInner[3 * b + j] = static_cast<int>(3 * b + j);
        } else {
          const int64_t m0 = 3 * first + j * degree;
          mOuter[3 * b + j] = static_cast<int>(m0);
          for (int64_t q = 0; q < degree; ++q) mInner[m0 + q] = 3 * mNeighbours[static_cast<size_t>(first + q)] + j;
        }
      }
    }
    kOuter[3 * n] = static_cast<int>(9 * blocks);
    mOuter[3 * n] = static_cast<int>(lumped ? 3 * n : 3 * blocks);
    std::fill_n(mSys.stiffness.valuePtr(), mSys.stiffness.nonZeros(), 0.0);
    std::fill_n(mSys.mass.valuePtr(), mSys.mass.nonZeros(), 0.0);
    mKTouched.assign(static_cast<size_t>(9 * blocks), 0);
    mMTouched.assign(static_cast<size_t>(mSys.mass.nonZeros()), 0);
  }

  // The element whose entries the next calls add: its nodes' positions in each other's blocks.
  void element(const int32_t* v) {
    for (int b = 0; b < P; ++b) {
      const int32_t* first = mNeighbours.data() + mStart[static_cast<size_t>(v[b])];
      const int32_t* last = mNeighbours.data() + mStart[static_cast<size_t>(v[b]) + 1];
      const int64_t degree = last - first;
      for (int a = 0; a < P; ++a) mPos[a][b] = std::lower_bound(first, last, v[a]) - first;
      mColumn[b] = v[b];
      mDegree[b] = degree;
    }
  }
  // K(3 v_a + i, 3 v_b + j) += value.
  void addStiffness(int a, int i, int b, int j, double value) {
    const int64_t slot = 9 * mStart[static_cast<size_t>(mColumn[b])] + 3 * j * mDegree[b] + 3 * mPos[a][b] + i;
    add(mSys.stiffness.valuePtr(), mKTouched, slot, value);
  }
  // M(3 v_a + i, 3 v_b + i) += value (consistent mass).
  void addMass(int a, int b, int i, double value) {
    const int64_t slot = 3 * mStart[static_cast<size_t>(mColumn[b])] + i * mDegree[b] + mPos[a][b];
    add(mSys.mass.valuePtr(), mMTouched, slot, value);
  }
  // M(3 v_a + i, 3 v_a + i) += value (lumped mass).
  void addLumpedMass(int a, int i, double value) { add(mSys.mass.valuePtr(), mMTouched, 3 * int64_t{mColumn[a]} + i, value); }

  FemSystem finish() { return std::move(mSys); }

 private:
  static void add(double* values, std::vector<uint8_t>& touched, int64_t slot, double value) {
    if (touched[static_cast<size_t>(slot)]) {
      values[slot] += value;
    } else {
      values[slot] = value;
      touched[static_cast<size_t>(slot)] = 1;
    }
  }
  std::vector<int64_t> mStart;       // node b's neighbours: mNeighbours[mStart[b], mStart[b + 1])
  std::vector<int32_t> mNeighbours;  // ascending within each node
  std::vector<uint8_t> mKTouched, mMTouched;
  FemSystem mSys;
  std::array<std::array<int64_t, P>, P> mPos{};
  std::array<int32_t, P> mColumn{};
  std::array<int64_t, P> mDegree{};
};

/// Gradients of the barycentric coordinates (rows, 1/m) of the tet p0..p3, and its signed volume.
Eigen::Matrix<double, 4, 3> barycentricGradients(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                                                 const Eigen::Vector3d& p3, double* volumeM3) {
  Eigen::Matrix3d edges;
  edges.col(0) = p1 - p0;
  edges.col(1) = p2 - p0;
  edges.col(2) = p3 - p0;
  if (volumeM3) *volumeM3 = edges.determinant() / 6.0;
  const Eigen::Matrix3d inv = edges.inverse();
  Eigen::Matrix<double, 4, 3> grad;
  grad.bottomRows<3>() = inv;
  grad.row(0) = -(grad.row(1) + grad.row(2) + grad.row(3));
  return grad;
}

/// B (6 by 3n) from the n nodal shape-function gradients (rows, 1/m), Voigt order with engineering
/// shear strains: γ_yz = ∂u_y/∂z + ∂u_z/∂y, γ_xz, γ_xy.
template <int Nodes>
Eigen::Matrix<double, 6, 3 * Nodes> strainDisplacement(const Eigen::Matrix<double, Nodes, 3>& d) {
  Eigen::Matrix<double, 6, 3 * Nodes> b = Eigen::Matrix<double, 6, 3 * Nodes>::Zero();
  for (int n = 0; n < Nodes; ++n) {
    const double dx = d(n, 0), dy = d(n, 1), dz = d(n, 2);
    const int c = 3 * n;
    b(0, c + 0) = dx;
    b(1, c + 1) = dy;
    b(2, c + 2) = dz;
    b(3, c + 1) = dz;
    b(3, c + 2) = dy;
    b(4, c + 0) = dz;
    b(4, c + 2) = dx;
    b(5, c + 0) = dy;
    b(5, c + 1) = dx;
  }
  return b;
}

}  // namespace

Eigen::Matrix<double, 6, 12> tetStrainDisplacement(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                                   const Eigen::Vector3d& p2, const Eigen::Vector3d& p3,
                                                   double* volumeM3) {
  // Shape function gradients: rows of the inverse of the edge matrix give ∇N1..∇N3,
  // and ∇N0 = −(∇N1 + ∇N2 + ∇N3).
  return strainDisplacement<4>(barycentricGradients(p0, p1, p2, p3, volumeM3));
}

double degenerateTetVolumeM3(const Points& nodes) {
  if (nodes.rows() == 0) return 0.0;
  const Eigen::Vector3d extent = (nodes.colwise().maxCoeff() - nodes.colwise().minCoeff()).transpose();
  return 1e-12 * extent.prod();
}

Result<FemSystem> assembleFem(const TetMesh& mesh, const Material& material, const FemSettings& settings) {
  if (Status s = validateMaterial(material); !s) return s.error();
  const Eigen::Index n = mesh.nodes.rows();
  if (n == 0 || mesh.tets.rows() == 0) return makeError(ErrorCode::DegenerateElement, "tet mesh is empty");
  const double minVolume = degenerateTetVolumeM3(mesh.nodes);
  const auto c = isotropicElasticity(material.youngsModulusPa, material.poissonRatio);
  const double rho = material.densityKgPerM3;

  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k) {
      const int32_t i = mesh.tets(t, k);
      if (i < 0 || i >= n) return makeError(ErrorCode::DegenerateElement, "tet " + std::to_string(t) + " refers to node " + std::to_string(i));
    }
  BlockAssembly<4> sys(n, mesh.tets, settings.lumpedMass);
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    if (t % 256 == 0) detail::cancellationPoint();  // assembled on a World's background threads
    std::array<int32_t, 4> v = {mesh.tets(t, 0), mesh.tets(t, 1), mesh.tets(t, 2), mesh.tets(t, 3)};
    double volume = 0.0;
    const auto b = tetStrainDisplacement(mesh.nodes.row(v[0]).transpose(), mesh.nodes.row(v[1]).transpose(),
                                         mesh.nodes.row(v[2]).transpose(), mesh.nodes.row(v[3]).transpose(), &volume);
    if (!(volume > minVolume)) {
      return makeError(ErrorCode::DegenerateElement, "tet " + std::to_string(t) + " has volume " +
                                                         std::to_string(volume) + " m^3 (degenerate or inverted)");
    }
    const Eigen::Matrix<double, 12, 12> ke = volume * b.transpose() * c * b;
    sys.element(v.data());
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i)
        for (int bb = 0; bb < 4; ++bb)
          for (int j = 0; j < 3; ++j) sys.addStiffness(a, i, bb, j, ke(3 * a + i, 3 * bb + j));
    if (settings.lumpedMass) {
      for (int a = 0; a < 4; ++a)
        for (int i = 0; i < 3; ++i) sys.addLumpedMass(a, i, rho * volume / 4.0);
    } else {
      // Consistent P1 mass: ∫ N_a N_b dV = V/20 (1 + δ_ab), per displacement component.
      for (int a = 0; a < 4; ++a)
        for (int bb = 0; bb < 4; ++bb)
          for (int i = 0; i < 3; ++i) sys.addMass(a, bb, i, rho * volume / 20.0 * (a == bb ? 2.0 : 1.0));
    }
  }
  return sys.finish();
}

MatrixXdRow computeStressModes(const TetMesh& mesh, const Material& material, const MatrixXdRow& modes) {
  const auto c = isotropicElasticity(material.youngsModulusPa, material.poissonRatio);
  const Eigen::Index r = modes.cols();
  MatrixXdRow s(6 * mesh.tets.rows(), r);
  Eigen::Matrix<double, 12, Eigen::Dynamic> phiE(12, r);
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    const auto b = tetStrainDisplacement(mesh.nodes.row(mesh.tets(t, 0)).transpose(), mesh.nodes.row(mesh.tets(t, 1)).transpose(),
                                         mesh.nodes.row(mesh.tets(t, 2)).transpose(), mesh.nodes.row(mesh.tets(t, 3)).transpose(),
                                         nullptr);
    for (int a = 0; a < 4; ++a) phiE.middleRows(3 * a, 3) = modes.middleRows(3 * mesh.tets(t, a), 3);
    s.middleRows(6 * t, 6) = c * b * phiE;
  }
  return s;
}

namespace {


/// B (6 by 30) from the barycentric gradients at the point λ.
Eigen::Matrix<double, 6, 30> quadraticB(const Eigen::Matrix<double, 4, 3>& g, const Eigen::Vector4d& l) {
  // ∇N_i = (4λ_i − 1)∇λ_i at the corners, ∇N = 4(λ_i∇λ_j + λ_j∇λ_i) at mid-edge nodes.
  Eigen::Matrix<double, 10, 3> d;
  for (int i = 0; i < 4; ++i) d.row(i) = (4.0 * l(i) - 1.0) * g.row(i);
  for (int k = 0; k < 6; ++k) {
    const auto [i, j] = kQuadraticTetEdges[static_cast<size_t>(k)];
    d.row(4 + k) = 4.0 * (l(i) * g.row(j) + l(j) * g.row(i));
  }
  return strainDisplacement<10>(d);
}

/// The 4-point rule of degree 2 on a tet (Keast): λ = permutations of (a, b, b, b), weight V/4.
const std::array<Eigen::Vector4d, 4>& degreeTwoPoints() {
  static const std::array<Eigen::Vector4d, 4> points = [] {
    const double a = (5.0 + 3.0 * std::sqrt(5.0)) / 20.0, b = (5.0 - std::sqrt(5.0)) / 20.0;
    std::array<Eigen::Vector4d, 4> p;
    for (int q = 0; q < 4; ++q) {
      p[static_cast<size_t>(q)].setConstant(b);
      p[static_cast<size_t>(q)](q) = a;
    }
    return p;
  }();
  return points;
}

}  // namespace

Eigen::Matrix<double, 10, 1> quadraticTetShapeFunctions(const Eigen::Vector4d& l) {
  Eigen::Matrix<double, 10, 1> n;
  for (int i = 0; i < 4; ++i) n(i) = l(i) * (2.0 * l(i) - 1.0);
  for (int k = 0; k < 6; ++k) {
    const auto [i, j] = kQuadraticTetEdges[static_cast<size_t>(k)];
    n(4 + k) = 4.0 * l(i) * l(j);
  }
  return n;
}

Eigen::Matrix<double, 6, 30> quadraticTetStrainDisplacement(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                                            const Eigen::Vector3d& p2, const Eigen::Vector3d& p3,
                                                            const Eigen::Vector4d& barycentric, double* volumeM3) {
  return quadraticB(barycentricGradients(p0, p1, p2, p3, volumeM3), barycentric);
}

const Eigen::Matrix<double, 10, 10>& quadraticTetUnitMass() {
  static const Eigen::Matrix<double, 10, 10> m = [] {
    // ∫N_a N_b dV / V in units of 1/420, by how the two nodes relate.
    auto sharesCorner = [](int edge, int corner) {
      const auto [i, j] = kQuadraticTetEdges[static_cast<size_t>(edge)];
      return i == corner || j == corner;
    };
    Eigen::Matrix<double, 10, 10> out;
    for (int a = 0; a < 10; ++a) {
      for (int b = 0; b < 10; ++b) {
        double k = 0.0;
        if (a < 4 && b < 4) {
          k = a == b ? 6.0 : 1.0;
        } else if (a < 4 || b < 4) {
          const int corner = std::min(a, b), edge = std::max(a, b) - 4;
          k = sharesCorner(edge, corner) ? -4.0 : -6.0;
        } else if (a == b) {
          k = 32.0;
        } else {
          const auto [i, j] = kQuadraticTetEdges[static_cast<size_t>(b - 4)];
          k = (sharesCorner(a - 4, i) || sharesCorner(a - 4, j)) ? 16.0 : 8.0;
        }
        out(a, b) = k / 420.0;
      }
    }
    return out;
  }();
  return m;
}

Result<FemSystem> assembleFem(const QuadraticTetMesh& mesh, const Material& material, const FemSettings& settings) {
  if (Status s = validateMaterial(material); !s) return s.error();
  const Eigen::Index n = mesh.nodes.rows();
  if (n == 0 || mesh.tets.rows() == 0) return makeError(ErrorCode::DegenerateElement, "tet mesh is empty");
  const double minVolume = degenerateTetVolumeM3(mesh.nodes);
  const auto c = isotropicElasticity(material.youngsModulusPa, material.poissonRatio);
  const double rho = material.densityKgPerM3;
  const Eigen::Matrix<double, 10, 10>& unitMass = quadraticTetUnitMass();
  const Eigen::Matrix<double, 10, 1> lumped = unitMass.diagonal() / unitMass.diagonal().sum();

  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int a = 0; a < 10; ++a) {
      const int32_t i = mesh.tets(t, a);
      if (i < 0 || i >= n) return makeError(ErrorCode::DegenerateElement, "tet " + std::to_string(t) + " refers to node " + std::to_string(i));
    }
  BlockAssembly<10> sys(n, mesh.tets, settings.lumpedMass);
  std::array<int32_t, 10> v{};
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    if (t % 64 == 0) detail::cancellationPoint();
    for (int a = 0; a < 10; ++a) v[static_cast<size_t>(a)] = mesh.tets(t, a);
    std::array<Eigen::Vector3d, 4> p;
    for (int a = 0; a < 4; ++a) p[static_cast<size_t>(a)] = mesh.nodes.row(v[static_cast<size_t>(a)]).transpose();
    double volume = 0.0;
    const Eigen::Matrix<double, 4, 3> g = barycentricGradients(p[0], p[1], p[2], p[3], &volume);
    if (!(volume > minVolume)) {
      return makeError(ErrorCode::DegenerateElement, "tet " + std::to_string(t) + " has volume " +
                                                         std::to_string(volume) + " m^3 (degenerate or inverted)");
    }
    for (int k = 0; k < 6; ++k) {
      const auto [i, j] = kQuadraticTetEdges[static_cast<size_t>(k)];
      const Eigen::Vector3d mid = mesh.nodes.row(v[static_cast<size_t>(4 + k)]).transpose();
      const Eigen::Vector3d edge = p[static_cast<size_t>(j)] - p[static_cast<size_t>(i)];
      if (!((mid - 0.5 * (p[static_cast<size_t>(i)] + p[static_cast<size_t>(j)])).norm() <= 1e-9 * edge.norm())) {
        return makeError(ErrorCode::InvalidArgument, "tet " + std::to_string(t) + ": node " +
                                                         std::to_string(v[static_cast<size_t>(4 + k)]) +
                                                         " is not the midpoint of its edge (only straight-sided P2 tets are supported)");
      }
    }
    Eigen::Matrix<double, 30, 30> ke = Eigen::Matrix<double, 30, 30>::Zero();
    for (const Eigen::Vector4d& l : degreeTwoPoints()) {
      const Eigen::Matrix<double, 6, 30> b = quadraticB(g, l);
      ke.noalias() += (0.25 * volume) * (b.transpose() * (c * b));
    }
    sys.element(v.data());
    for (int a = 0; a < 10; ++a)
      for (int i = 0; i < 3; ++i)
        for (int bb = 0; bb < 10; ++bb)
          for (int j = 0; j < 3; ++j) sys.addStiffness(a, i, bb, j, ke(3 * a + i, 3 * bb + j));
    if (settings.lumpedMass) {
      for (int a = 0; a < 10; ++a)
        for (int i = 0; i < 3; ++i) sys.addLumpedMass(a, i, rho * volume * lumped(a));
    } else {
      for (int a = 0; a < 10; ++a)
        for (int bb = 0; bb < 10; ++bb)
          for (int i = 0; i < 3; ++i) sys.addMass(a, bb, i, rho * volume * unitMass(a, bb));
    }
  }
  return sys.finish();
}

MatrixXdRow computeStressModes(const QuadraticTetMesh& mesh, const Material& material, const MatrixXdRow& modes) {
  const auto c = isotropicElasticity(material.youngsModulusPa, material.poissonRatio);
  const Eigen::Index r = modes.cols();
  constexpr int kRows = 6 * kQuadraticTetStressPoints;
  MatrixXdRow s(kRows * mesh.tets.rows(), r);
  Eigen::Matrix<double, 30, Eigen::Dynamic> phiE(30, r);
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    const Eigen::Matrix<double, 4, 3> g =
        barycentricGradients(mesh.nodes.row(mesh.tets(t, 0)).transpose(), mesh.nodes.row(mesh.tets(t, 1)).transpose(),
                             mesh.nodes.row(mesh.tets(t, 2)).transpose(), mesh.nodes.row(mesh.tets(t, 3)).transpose(), nullptr);
    for (int a = 0; a < 10; ++a) phiE.middleRows(3 * a, 3) = modes.middleRows(3 * mesh.tets(t, a), 3);
    for (int corner = 0; corner < kQuadraticTetStressPoints; ++corner) {
      s.middleRows(kRows * t + 6 * corner, 6) = c * quadraticB(g, Eigen::Vector4d::Unit(corner)) * phiE;
    }
  }
  return s;
}

Result<FemMesh> makeFemMesh(const TetMesh& mesh, ElementOrder order) {
  FemMesh out;
  out.linear = &mesh;
  out.order = order;
  if (order == ElementOrder::P2) {
    auto quadratic = makeQuadraticTetMesh(mesh);
    if (!quadratic) return quadratic.error();
    out.quadratic = std::move(quadratic).value();
  }
  return out;
}

Result<FemSystem> assembleFem(const FemMesh& mesh, const Material& material, const FemSettings& settings) {
  if (mesh.order == ElementOrder::P1) return assembleFem(*mesh.linear, material, settings);
  return assembleFem(mesh.quadratic, material, settings);
}

MatrixXdRow computeStressModes(const FemMesh& mesh, const Material& material, const MatrixXdRow& modes) {
  if (mesh.order == ElementOrder::P1) return computeStressModes(*mesh.linear, material, modes);
  return computeStressModes(mesh.quadratic, material, modes);
}

Result<ElementStresses> ElementStresses::make(const FemMesh& fem, const Material& material) {
  if (Status s = validateMaterial(material); !s) return s.error();
  const TetMesh& mesh = *fem.linear;
  ElementStresses out;
  out.mOrder = fem.order;
  out.mFemNodes = fem.nodes().rows();
  out.mElasticity = isotropicElasticity(material.youngsModulusPa, material.poissonRatio);
  const auto t = static_cast<size_t>(mesh.tets.rows());
  auto corner = [&](Eigen::Index e, int a) -> Eigen::Vector3d { return mesh.nodes.row(mesh.tets(e, a)).transpose(); };
  if (fem.order == ElementOrder::P1) {
    out.mElements = mesh.tets;
  } else {
    out.mElements = fem.quadratic.tets;
  }
  out.mGradients.resize(t);
  for (size_t e = 0; e < t; ++e) {
    const auto i = static_cast<Eigen::Index>(e);
    out.mGradients[e] = barycentricGradients(corner(i, 0), corner(i, 1), corner(i, 2), corner(i, 3), nullptr);
  }
  if (fem.order == ElementOrder::P2) {
    auto means = CornerStressMeans::make(mesh);
    if (!means) return means.error();
    out.mMeans = std::move(means).value();
  }
  return out;
}

Result<CornerStressMeans> CornerStressMeans::make(const TetMesh& mesh) {
  const Eigen::Index t = mesh.tets.rows(), n = mesh.nodes.rows();
  CornerStressMeans out;
  out.mElements = t;
  out.mStart.assign(static_cast<size_t>(n) + 1, 0);
  std::vector<double> volume(static_cast<size_t>(t)), nodeVolume(static_cast<size_t>(n), 0.0);
  for (Eigen::Index e = 0; e < t; ++e) {
    Eigen::Vector3d p[4];
    for (int c = 0; c < 4; ++c) {
      const int32_t v = mesh.tets(e, c);
      if (v < 0 || v >= n) return makeError(ErrorCode::InvalidArgument, "corner stress means: tet " + std::to_string(e) + " has a node out of range");
      p[c] = mesh.nodes.row(v).transpose();
    }
    const double v = std::abs(signedTetVolume(p[0], p[1], p[2], p[3]));
    if (!(v > 0.0)) return makeError(ErrorCode::InvalidArgument, "corner stress means: tet " + std::to_string(e) + " has no volume");
    volume[static_cast<size_t>(e)] = v;
    for (int c = 0; c < 4; ++c) {
      ++out.mStart[static_cast<size_t>(mesh.tets(e, c)) + 1];
      nodeVolume[static_cast<size_t>(mesh.tets(e, c))] += v;
    }
  }
  std::partial_sum(out.mStart.begin(), out.mStart.end(), out.mStart.begin());
  out.mPoints.resize(static_cast<size_t>(4 * t));
  out.mWeights.resize(static_cast<size_t>(4 * t));
  std::vector<int32_t> fill(out.mStart.begin(), out.mStart.end() - 1);
  for (Eigen::Index e = 0; e < t; ++e) {  // ascending points within each node
    for (int c = 0; c < 4; ++c) {
      const auto v = static_cast<size_t>(mesh.tets(e, c));
      const auto k = static_cast<size_t>(fill[v]++);
      out.mPoints[k] = static_cast<int32_t>(4 * e + c);
      out.mWeights[k] = volume[static_cast<size_t>(e)] / nodeVolume[v];
    }
  }
  return out;
}

void CornerStressMeans::apply(double* rows, Eigen::Index cols) const {
  const auto nodes = static_cast<Eigen::Index>(mStart.size()) - 1;
  // Each value (component i, column j) of a node's points is read by that node's mean alone, so
  // the mean is written back at once, and nodes in different ranges never touch the same rows.
  // One field (cols = 1: the static correction's recovery, once an impact) takes a node's points
  // one after another into six sums at once, each still in the points' order, so the bits of one
  // sum at a time: on the P2 vase one chain of ~20 dependent additions per value took 0.84–0.92 ms
  // of recovery, 0.66–0.73 this way. Stress modes (cols = r, once a body) keep one sum at a time:
  // the same points-first order over blocks of eight columns placed the vase 1–2 ms slower
  // (12.5–13.0 against 10.8–11.8 ms).
  detail::forFixedRanges(nodes, 16, [&](int, Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index v = begin; v < end; ++v) {
      const auto first = static_cast<size_t>(mStart[static_cast<size_t>(v)]), last = static_cast<size_t>(mStart[static_cast<size_t>(v) + 1]);
      if (last - first < 2) continue;
      if (cols == 1) {
        double mean[6] = {};
        for (size_t k = first; k < last; ++k) {
          const double weight = mWeights[k];
          const double* point = rows + 6 * static_cast<Eigen::Index>(mPoints[k]);
          for (int i = 0; i < 6; ++i) mean[i] += weight * point[i];
        }
        for (size_t k = first; k < last; ++k) std::copy_n(mean, 6, rows + 6 * static_cast<Eigen::Index>(mPoints[k]));
        continue;
      }
      for (int i = 0; i < 6; ++i) {
        for (Eigen::Index j = 0; j < cols; ++j) {
          double mean = 0.0;
          for (size_t k = first; k < last; ++k) mean += mWeights[k] * rows[(6 * static_cast<Eigen::Index>(mPoints[k]) + i) * cols + j];
          for (size_t k = first; k < last; ++k) rows[(6 * static_cast<Eigen::Index>(mPoints[k]) + i) * cols + j] = mean;
        }
      }
    }
  });
}

// σ = C ε(∇u), ∇u(i, j) = ∂u_i/∂x_j, ε in Voigt order (xx, yy, zz, yz, xz, xy; engineering shears).
namespace {
void stressFromGradient(const Eigen::Matrix<double, 6, 6>& elasticity, const Eigen::Matrix3d& grad, double* out) {
  Eigen::Matrix<double, 6, 1> strain;
  strain << grad(0, 0), grad(1, 1), grad(2, 2), grad(1, 2) + grad(2, 1), grad(0, 2) + grad(2, 0), grad(0, 1) + grad(1, 0);
  Eigen::Map<Eigen::Matrix<double, 6, 1>>(out).noalias() = elasticity * strain;
}
}  // namespace

void ElementStresses::element(Eigen::Index e, const Eigen::VectorXd& u, double* out) const {
  const Eigen::Matrix<double, 4, 3>& g = mGradients[static_cast<size_t>(e)];
  if (mOrder == ElementOrder::P1) {
    // ∇u = Σ_a u_a ∇λ_aᵀ: a 3 by 4 times 4 by 3 product, from 96 bytes of gradients an element
    // where C B_e (6 by 12) took 576. The static correction's recovery reads every element's once
    // an impact, and on a 3.4k-tet slab it streamed 2 MB of them in 0.23–0.46 ms.
    Eigen::Matrix<double, 3, 4> a;
    for (int i = 0; i < 4; ++i) a.col(i) = u.segment<3>(3 * mElements(e, i));
    stressFromGradient(mElasticity, a * g, out);
    return;
  }
  // At corner c (λ = e_c) the P2 gradients are ∇N_c = 3∇λ_c, ∇N_i = −∇λ_i (i ≠ c), ∇N_(c,i) = 4∇λ_i
  // and zero for the edges away from c, so ∇u = Σ_i a_i ∇λ_iᵀ with a_c = 3u_c, a_i = 4u_(c,i) − u_i:
  // a 3 by 4 times 4 by 3 product instead of a 6 by 30 B per corner.
  auto node = [&](int a) -> Eigen::Vector3d { return u.segment<3>(3 * mElements(e, a)); };
  Eigen::Vector3d corner[4], edge[6];
  for (int a = 0; a < 4; ++a) corner[a] = node(a);
  for (int k = 0; k < 6; ++k) edge[k] = node(4 + k);
  for (int c = 0; c < kQuadraticTetStressPoints; ++c) {
    Eigen::Matrix<double, 3, 4> a;
    for (int i = 0; i < 4; ++i) a.col(i) = i == c ? Eigen::Vector3d(3.0 * corner[c]) : Eigen::Vector3d(-corner[i]);
    for (int k = 0; k < 6; ++k) {
      const auto [i, j] = kQuadraticTetEdges[static_cast<size_t>(k)];
      if (i == c) a.col(j) += 4.0 * edge[k];
      if (j == c) a.col(i) += 4.0 * edge[k];
    }
    stressFromGradient(mElasticity, a * g, out + 6 * c);
  }
}

void ElementStresses::all(const Eigen::VectorXd& u, Eigen::VectorXd& stress) const {
  const int rows = 6 * pointsPerElement();
  const Eigen::Index count = elementCount();
  stress.resize(rows * count);
  // Each element's stress is its own arithmetic, so the bits do not depend on the threads.
  detail::forFixedRanges(count, 16, [&](int, Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index e = begin; e < end; ++e) element(e, u, stress.data() + rows * e);
  });
  if (mOrder == ElementOrder::P2) mMeans.apply(stress.data(), 1);
}

Eigen::MatrixXd rigidBodyMotions(const Points& nodes) {
  const Eigen::Index n = nodes.rows();
  const Eigen::RowVector3d center = nodes.colwise().mean();
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(3 * n, 6);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d p = (nodes.row(i) - center).transpose();
    for (int k = 0; k < 3; ++k) r(3 * i + k, k) = 1.0;
    // Rotation about axis a: displacement e_a × p.
    for (int a = 0; a < 3; ++a) r.block<3, 1>(3 * i, 3 + a) = Eigen::Vector3d::Unit(a).cross(p);
  }
  return r;
}

Eigen::MatrixXd rigidBodyModes(const Points& nodes, const SparseMatrixd& mass) {
  Eigen::MatrixXd r = rigidBodyMotions(nodes);
  // M-orthonormalise (modified Gram–Schmidt in the M inner product).
  for (int j = 0; j < 6; ++j) {
    for (int k = 0; k < j; ++k) r.col(j) -= (r.col(k).dot(mass * r.col(j))) * r.col(k);
    r.col(j) /= std::sqrt(r.col(j).dot(mass * r.col(j)));
  }
  return r;
}

}  // namespace brittle

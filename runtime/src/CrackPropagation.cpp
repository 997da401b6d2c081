#include "brittle/runtime/CrackPropagation.h"

#include <Eigen/Geometry>
#include <Eigen/Eigenvalues>
#include <oneapi/tbb/parallel_for.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#include <immintrin.h>
#endif
#include <algorithm>
#include <array>
#include <limits>
#include <cmath>
#include <cstring>
#include <numeric>

#include "Cancellation.h"
#include "FixedRanges.h"
#include "brittle/core/Random.h"
#include "brittle/core/Simd.h"

namespace brittle {
namespace {

const Voigt kD = (Voigt() << 1.0, 1.0, 1.0, std::sqrt(2.0), std::sqrt(2.0), std::sqrt(2.0)).finished();

// The scan's fixed ranges (of points, of groups, of seeds): work is split into this many, whatever
// the number of threads, so that the answer does not depend on it.
constexpr int kScanRanges = 16;

Eigen::Matrix3d tensor(const Voigt& s) {
  Eigen::Matrix3d t;
  t << s[0], s[5], s[4], s[5], s[1], s[3], s[4], s[3], s[2];
  return t;
}

// ‖A‖₂ = √λ_max(G), G = A Aᵀ (6 by 6, symmetric positive semi-definite), bounded without an eigen
// solve: with H = G / tr G, λ_max(H)¹⁶ ≤ tr H¹⁶ = ‖H⁸‖_F², so √λ_max(G) ≤ √(tr G · ‖H⁸‖_F^(1/8)),
// at most 6^(1/32) = 1.06 times the norm, for three 6-by-6 products (a fifth of an eigen solve).
// The margin covers the products' rounding.
double spectralNormBound(const Eigen::Matrix<double, 6, Eigen::Dynamic>& a) {
  constexpr double kMargin = 1.0 + 1e-9;
  // Coefficient by coefficient: for a 6 by r block Eigen's general product packs both operands
  // first, which costs more than its 21 r products (matched bodies' CPU on the vase's hit 48.1 →
  // 45.3 ms an impact, the same bits).
  Eigen::Matrix<double, 6, 6> h;
  h.noalias() = a.lazyProduct(a.transpose());
  const double trace = h.trace();
  if (!(trace > 0.0)) return 0.0;
  h /= trace;
  for (int i = 0; i < 3; ++i) h = (h * h).eval();
  return std::sqrt(trace * std::pow(h.norm(), 0.125)) * kMargin;
}

// Σ a_j b_j over n terms in a fixed order, whatever the buffers' alignment (the bounds below decide
// what is evaluated, and so the evaluation count): eight running sums, j mod 8, added pairwise at
// the end. Eight independent sums keep the adds from waiting on each other (one running sum made
// each dot wait n add latencies).
inline __attribute__((always_inline)) double dotInOrder(const double* a, const double* b, Eigen::Index n) {
  double acc[8] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  Eigen::Index j = 0;
  for (; j + 8 <= n; j += 8) {
    for (int l = 0; l < 8; ++l) acc[l] += a[j + l] * b[j + l];
  }
  for (int l = 0; j + l < n; ++l) acc[l] += a[j + l] * b[j + l];
  return ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
}

// σ₁ ≤ p + √(2/3) ‖s‖_F for σ = p I + s (p the mean normal stress, s the deviator, whose largest
// eigenvalue is at most √(2/3) of its norm, reached by (2a, −a, −a)); never above ‖σ‖_F, and near
// σ₁ where σ is compressive (p < 0), which ‖σ‖_F does not see.
constexpr double kDeviatorShare = 0.816496580927726;  // √(2/3)

// The terms of the split bound p + √(2/3)‖d‖ of the Voigt components s[0..5], of one stress
// (V = double) or of four in an AVX register's lanes (V = VectorOf<double, 4>), with the same
// operations in the same order either way: the mean ((s₀ + s₁) + s₂)/3 and the deviator's squared
// norm as (d₀² + (d₂² + d₄²)) + (d₁² + (d₃² + d₅²)), the order in which Eigen sums a 6-vector in SSE2
// pairs, which this bound used before (so no bit moved). The caller takes the square root, with
// the instruction of its own target.
template <class V>
[[gnu::always_inline]] inline void splitBoundTerms(const V* s, V& p, V& squaredDeviator) {
  p = (s[0] + s[1] + s[2]) / 3.0;
  V d[6];
  for (int i = 0; i < 6; ++i) d[i] = kD[i] * s[i];
  for (int i = 0; i < 3; ++i) d[i] = d[i] - p;
  squaredDeviator = (d[0] * d[0] + (d[2] * d[2] + d[4] * d[4])) + (d[1] * d[1] + (d[3] * d[3] + d[5] * d[5]));
}

double splitBound(const Voigt& s) {
  double p, squaredDeviator;
  splitBoundTerms(s.data(), p, squaredDeviator);
  return p + kDeviatorShare * std::sqrt(squaredDeviator);
}

// A bound on σ₁ of an evaluated σ: its split bound, with a margin for the eigen solve's rounding
// (maxPrincipalStress(σ) ≤ principalBound(σ)), at the price of a square root where the eigen solve
// costs an atan2, a sincos and a scaling.
double principalBound(const Voigt& sigma) { return splitBound(sigma) + 1e-9 * kD.cwiseProduct(sigma).norm(); }

// σ_e = S_e q over the first r modes: S's rows 6e..6e+5 (row-major, contiguous) against q, four
// running sums a row (mode j to sum j mod 4, added as (a₀ + a₁) + (a₂ + a₃)): the same order in
// SSE2 pairs and in AVX quads, so the same bits on either (the test
// CrackPropagation.ElementStressIsTheSameBitsInEitherLanesAndNearEigensProduct). The scan and the
// cracks make tens of thousands of these an impact, and one running sum a row made each wait r add
// latencies: on the brick they were 5.7 ms
// of CPU an impact, the largest item of its stress and crack stages. Eigen's general
// matrix-vector kernel costs several times the 6r products for so small a block; fixed sums also
// give the same bits wherever the buffers lie.
template <int L>
[[gnu::always_inline]] inline void elementStressInLanes(const double* row, Eigen::Index stride, const double* q,
                                                        Eigen::Index r, double* out) {
  using Pack = VectorOf<double, L>;
  constexpr int kPacks = 4 / L;  // registers a row
  // The six rows are one block (stride ≥ r): every line of it asked for at once, where the rows'
  // first loads otherwise waited for their lines one stream at a time.
  prefetchBytes(row, row + 5 * stride + r);
  Pack acc[6][kPacks];
  for (int i = 0; i < 6; ++i) {
    for (int n = 0; n < kPacks; ++n) acc[i][n] = Pack{};  // in registers (a zeroed array went through the stack)
  }
  const Eigen::Index whole = r / 4 * 4;
  for (Eigen::Index j = 0; j < whole; j += 4) {
    Pack qj[kPacks];
    for (int n = 0; n < kPacks; ++n) loadLanes<L>(q + j + n * L, qj[n]);
    for (int i = 0; i < 6; ++i) {
      for (int n = 0; n < kPacks; ++n) {
        Pack sij;
        loadLanes<L>(row + i * stride + j + n * L, sij);
        acc[i][n] += sij * qj[n];
      }
    }
  }
  for (int i = 0; i < 6; ++i) {
    double lane[4];
    std::memcpy(lane, acc[i], sizeof lane);
    for (Eigen::Index j = whole; j < r; ++j) lane[j - whole] += row[i * stride + j] * q[j];
    out[i] = (lane[0] + lane[1]) + (lane[2] + lane[3]);
  }
}

void elementStressNarrow(const double* row, Eigen::Index stride, const double* q, Eigen::Index r, double* out) {
  elementStressInLanes<2>(row, stride, q, r, out);
}

BRITTLE_TARGET_AVX void elementStressWide(const double* row, Eigen::Index stride, const double* q, Eigen::Index r,
                                          double* out) {
  elementStressInLanes<4>(row, stride, q, r, out);
}

}  // namespace

Voigt detail::elementStress(const MatrixXdRow& S, Eigen::Index e, const double* q, Eigen::Index r, Lanes lanes) {
  const Eigen::Index stride = S.cols();
  const double* row = S.data() + 6 * e * stride;
  Voigt s;
  if (lanes == Lanes::Wide) {
    elementStressWide(row, stride, q, r, s.data());
  } else {
    elementStressNarrow(row, stride, q, r, s.data());
  }
  return s;
}

namespace {

// A group's centre stress S_c q_k at instants k..k+L−1 into sums[i][lane]: S_c is rows 6g..6g+5 of
// `centres`, q the instants' modal coordinates in float (one column per mode, its rows padded to a
// multiple of kInstantPad). Six running sums per instant in mode order, L instants at a time (four
// to an SSE2 register, eight to an AVX one: each lane the same operations, so the same bits).
template <int L>
[[gnu::always_inline]] inline void centreSumsInLanes(const float* c, Eigen::Index stride, const Eigen::MatrixXf& q,
                                                     Eigen::Index k, float (*sums)[8]) {
  using Pack = VectorOf<float, L>;
  const Eigen::Index rows = q.rows(), r = q.cols();
  Pack acc[6] = {};
  for (Eigen::Index j = 0; j < r; ++j) {
    Pack qj;
    loadLanes<L>(q.data() + j * rows + k, qj);
    for (int i = 0; i < 6; ++i) acc[i] += c[i * stride + j] * qj;
  }
  for (int i = 0; i < 6; ++i) std::memcpy(sums[i], &acc[i], sizeof acc[i]);
}

// Rows of the float q are padded to a multiple of this, so that either form reads whole registers.
constexpr Eigen::Index kInstantPad = 8;

// Whether a scan of `points` stress points and r modes searches by the bounds' groups (and so
// reads the float q that prepareStressScan makes for it).
bool searchesByGroups(const StressBounds& bounds, Eigen::Index points, Eigen::Index r) {
  return bounds.groupStart.size() >= 2 && bounds.groupStart.back() == points && bounds.groupCentres.cols() >= r;
}

// Each stress point's representative where a per-group flag says the group's points are the same
// bits (StressBounds::groupUniform for what reads the modal rows alone, StressScanWorkspace::groupSame
// for what reads the static correction too): the group's first (lowest) point; else the point.
// What reads a point computes it at its representative alone and copies it to the others.
class GroupRepresentatives {
 public:
  GroupRepresentatives(const StressBounds& bounds, const std::vector<char>& flags, bool grouped)
      : mBounds(bounds),
        mFlags(flags),
        mAny(grouped && flags.size() + 1 == bounds.groupStart.size() &&
             std::any_of(flags.begin(), flags.end(), [](char f) { return f != 0; })) {}
  bool any() const { return mAny; }
  Eigen::Index of(Eigen::Index e) const {
    if (!mAny) return e;
    const auto g = static_cast<size_t>(mBounds.groupOf[static_cast<size_t>(e)]);
    return mFlags[g] ? mBounds.groupPoints[static_cast<size_t>(mBounds.groupStart[g])] : e;
  }

 private:
  const StressBounds& mBounds;
  const std::vector<char>& mFlags;
  bool mAny;
};

void centreSumsNarrow(const float* c, Eigen::Index stride, const Eigen::MatrixXf& q, Eigen::Index k, float (*sums)[8]) {
  centreSumsInLanes<4>(c, stride, q, k, sums);
}

// The split bounds of a group's centre stress at every instant k < steps into out[k], in AVX
// registers: the instants in pairs of eight-lane blocks, twelve running sums over the modes, each
// c_ij broadcast once for both blocks (one pass over the modes per sixteen instants, where a block
// at a time took one per eight and spent as long again on its calls and the lanes' conversions);
// then splitBoundTerms four instants to a register, their floats widened in the register. Every
// lane takes centreSumsInLanes' sums and splitBound's operations in their order, so these are the
// bits of the SSE2 form (CrackPropagation.GroupedScanEqualsTheFullScanAndItsGroupBoundsHold
// compares the two). `force`, where not null, has q's padded rows (zero past steps). It calls
// nothing while its registers are live, so GCC clears their upper halves on return (vzeroupper)
// and the SSE2 code after it runs at full speed.
BRITTLE_TARGET_AVX void centreSplitBoundsWide(const float* c, Eigen::Index stride, const Eigen::MatrixXf& q,
                                              Eigen::Index steps, const double* staticCentre, const double* force,
                                              double* out) {
  using Oct = VectorOf<float, 8>;
  using Quarter = VectorOf<float, 4>;
  using Quad = VectorOf<double, 4>;
  const Eigen::Index rows = q.rows(), r = q.cols();
  const float* qData = q.data();
  for (Eigen::Index k = 0; k < steps; k += 16) {
    const int blocks = k + 8 < steps ? 2 : 1;
    Oct acc[2][6];
    for (int b = 0; b < 2; ++b) {
      for (int i = 0; i < 6; ++i) acc[b][i] = Oct{};
    }
    if (blocks == 2) {
      for (Eigen::Index j = 0; j < r; ++j) {
        Oct q0, q1;
        loadLanes<8>(qData + j * rows + k, q0);
        loadLanes<8>(qData + j * rows + k + 8, q1);
        for (int i = 0; i < 6; ++i) {
          const float cij = c[i * stride + j];
          acc[0][i] += cij * q0;
          acc[1][i] += cij * q1;
        }
      }
    } else {
      for (Eigen::Index j = 0; j < r; ++j) {
        Oct q0;
        loadLanes<8>(qData + j * rows + k, q0);
        for (int i = 0; i < 6; ++i) acc[0][i] += c[i * stride + j] * q0;
      }
    }
    for (int b = 0; b < blocks; ++b) {
      for (int half = 0; half < 2; ++half) {
        const Eigen::Index first = k + 8 * b + 4 * half;
        if (first >= steps) break;
        Quad s[6];
        for (int i = 0; i < 6; ++i) {
          const Quarter lanes = half == 0 ? __builtin_shufflevector(acc[b][i], acc[b][i], 0, 1, 2, 3)
                                          : __builtin_shufflevector(acc[b][i], acc[b][i], 4, 5, 6, 7);
          s[i] = __builtin_convertvector(lanes, Quad);
        }
        if (force) {
          Quad f;
          loadLanes<4>(force + first, f);
          for (int i = 0; i < 6; ++i) s[i] = s[i] + staticCentre[i] * f;
        }
        Quad p, squaredDeviator;
        splitBoundTerms(s, p, squaredDeviator);
#if defined(__x86_64__)
        const Quad norm = _mm256_sqrt_pd(squaredDeviator);
#else
        Quad norm = squaredDeviator;
        for (int l = 0; l < 4; ++l) norm[l] = std::sqrt(norm[l]);
#endif
        const Quad bound = p + kDeviatorShare * norm;
        for (int l = 0; l < 4 && first + l < steps; ++l) out[first + l] = bound[l];
      }
    }
  }
}

// The split bound of a group's centre stress σ_c,k = S_c q_k + σ̂_c F_k at every instant k < steps
// into out[k] (centreSumsInLanes), with force null for no static part (else F_k at q's padded rows,
// zero past steps). The sums are in float: they only bound, and the caller's margin covers their
// rounding (at most (r + 2) 2⁻²⁴ Σ_j |S_c,j q_j| per component).
void centreSplitBounds(const MatrixXfRow& centres, Eigen::Index g, const Eigen::MatrixXf& q, Eigen::Index steps,
                       const Voigt& staticCentre, const double* force, Lanes lanes, double* out) {
  const Eigen::Index stride = centres.cols();
  const float* c = centres.data() + 6 * g * stride;
  if (lanes == Lanes::Wide) {
    centreSplitBoundsWide(c, stride, q, steps, staticCentre.data(), force, out);
    return;
  }
  float sums[6][8];
  for (Eigen::Index k = 0; k < steps; k += 4) {
    centreSumsNarrow(c, stride, q, k, sums);
    for (Eigen::Index lane = 0; lane < 4 && k + lane < steps; ++lane) {
      Voigt sigma;
      for (int i = 0; i < 6; ++i) sigma[i] = sums[i][lane];
      if (force) sigma += staticCentre * force[k + lane];
      out[k + lane] = splitBound(sigma);
    }
  }
}

// Rows [first, first + count) of a row-major matrix into the cache ahead of their reads.
template <class Matrix>
void prefetchRows(const Matrix& m, Eigen::Index first, Eigen::Index count) {
  prefetchBytes(m.data() + first * m.cols(), m.data() + (first + count) * m.cols());
}

// Whether n doubles are the same bits (−0 and 0 differ; a NaN equals its own bits).
bool sameBits(const double* a, const double* b, Eigen::Index n) { return std::memcmp(a, b, sizeof(double) * static_cast<size_t>(n)) == 0; }

bool crosses(const Eigen::Vector4d& d) { return d.maxCoeff() > 0.0 && d.minCoeff() < 0.0; }

// Area of the section of the tet where the nodal values d change sign, projected on n: a triangle
// (one node apart from three) or a quadrilateral (two and two), whose corners are ordered by the
// tet's combinatorics (for positive nodes i, j and the others k, l: edges ik, il, jl, jk).
double sectionArea(const TetMesh& mesh, Eigen::Index e, const Eigen::Vector4d& d, const Eigen::Vector3d& n) {
  int positive[4], negative[4], np = 0, nn = 0;
  for (int i = 0; i < 4; ++i) (d[i] > 0.0 ? positive[np++] : negative[nn++]) = i;
  auto crossing = [&](int i, int j) -> Eigen::Vector3d {
    const double s = d[i] / (d[i] - d[j]);
    const Eigen::Vector3d a = mesh.nodes.row(mesh.tets(e, i)), b = mesh.nodes.row(mesh.tets(e, j));
    return a + s * (b - a);
  };
  if (np == 0 || nn == 0) return 0.0;
  if (np == 2) {
    const Eigen::Vector3d p0 = crossing(positive[0], negative[0]), p1 = crossing(positive[0], negative[1]),
                          p2 = crossing(positive[1], negative[1]), p3 = crossing(positive[1], negative[0]);
    return 0.5 * std::abs((p2 - p0).cross(p3 - p1).dot(n));
  }
  const int apex = np == 1 ? positive[0] : negative[0];
  const int* others = np == 1 ? negative : positive;
  const Eigen::Vector3d p0 = crossing(apex, others[0]), p1 = crossing(apex, others[1]), p2 = crossing(apex, others[2]);
  return 0.5 * std::abs((p1 - p0).cross(p2 - p0).dot(n));
}

// The plane's cut through face f of tet e: the segment between the crossing points on its edges
// (false when the plane only touches the face).
bool faceCut(const TetMesh& mesh, Eigen::Index e, int f, const Eigen::Vector4d& d, Eigen::Vector3d& a, Eigen::Vector3d& b) {
  const auto local = tetFaceNodes(f);
  Eigen::Vector3d p[3];
  int count = 0;
  for (int k = 0; k < 3; ++k) {
    const int i = local[static_cast<size_t>(k)], j = local[static_cast<size_t>((k + 1) % 3)];
    if ((d[i] > 0.0) == (d[j] > 0.0)) continue;
    const double s = d[i] / (d[i] - d[j]);
    p[count++] = mesh.nodes.row(mesh.tets(e, i)).transpose() +
                 s * (mesh.nodes.row(mesh.tets(e, j)) - mesh.nodes.row(mesh.tets(e, i))).transpose();
  }
  if (count != 2) return false;
  a = p[0];
  b = p[1];
  return true;
}

// Seeds' order: a lower value, or the same value at a higher point, comes after (a max-heap's
// top is the largest value at the lowest point).
bool lowerSeed(const std::pair<double, int32_t>& a, const std::pair<double, int32_t>& b) {
  return a.first != b.first ? a.first < b.first : a.second > b.second;
}

using Front = CrackWorkspace::Front;
// Heap order: strongest normal stress on top; ties: lowest element id first.
bool weaker(const Front& a, const Front& b) {
  if (a.priority != b.priority) return a.priority < b.priority;
  return a.element > b.element;
}

}  // namespace

double maxPrincipalStress(const Voigt& s, Eigen::Vector3d* direction) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(tensor(s), direction ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly);
  if (direction) *direction = eig.eigenvectors().col(2);
  return eig.eigenvalues()[2];
}

// The most elements a P1 cluster of stressPointNodes takes in (its first node's own may be more).
// Measured on four P1 hits (a shattering 4.1k-tet slab, the 1.5k-tet vase and 1k-tet brick and ball
// drops of the determinism check's pack): 8 let the ball evaluate a third more σ, 32 and no cap
// (one ring) up to 1.8× as many; 12–24 kept the slab's gain and left the others as they were.
constexpr int32_t kClusterElements = 16;

std::vector<int32_t> stressPointNodes(const Tetrahedra& tets, int pointsPerElement) {
  std::vector<int32_t> keys(static_cast<size_t>(tets.rows() * pointsPerElement));
  if (pointsPerElement != 1) {
    for (Eigen::Index e = 0; e < tets.rows(); ++e) {
      for (int c = 0; c < pointsPerElement; ++c) keys[static_cast<size_t>(e * pointsPerElement + c)] = tets(e, c);
    }
    return keys;
  }
  if (tets.rows() == 0) return keys;
  // P1: clusters of nodes, made in node order: a node not yet taken starts one and takes the nodes
  // of the tets around it not yet taken (in the order of those tets and their corners) while the
  // cluster holds at most kClusterElements elements; an element joins the cluster of its lowest
  // node.
  const auto nodes = static_cast<size_t>(tets.maxCoeff()) + 1;
  std::vector<int32_t> start(nodes + 1, 0), around(static_cast<size_t>(4 * tets.rows()));  // tets around each node
  for (Eigen::Index i = 0; i < tets.size(); ++i) ++start[static_cast<size_t>(tets.data()[i]) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int32_t> next(start.begin(), start.end() - 1);
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    for (int c = 0; c < 4; ++c) around[static_cast<size_t>(next[static_cast<size_t>(tets(e, c))]++)] = static_cast<int32_t>(e);
  }
  std::vector<int32_t> cluster(nodes, -1), lowestOf(nodes, 0);  // lowestOf: elements whose lowest node it is
  for (Eigen::Index e = 0; e < tets.rows(); ++e) ++lowestOf[static_cast<size_t>(tets.row(e).minCoeff())];
  for (size_t v = 0; v < nodes; ++v) {
    if (cluster[v] >= 0) continue;
    cluster[v] = static_cast<int32_t>(v);
    int32_t elements = lowestOf[v];
    for (int32_t i = start[v]; i < start[v + 1]; ++i) {
      for (int c = 0; c < 4; ++c) {
        const auto u = static_cast<size_t>(tets(around[static_cast<size_t>(i)], c));
        if (cluster[u] >= 0 || elements + lowestOf[u] > kClusterElements) continue;
        cluster[u] = static_cast<int32_t>(v);
        elements += lowestOf[u];
      }
    }
  }
  for (Eigen::Index e = 0; e < tets.rows(); ++e) keys[static_cast<size_t>(e)] = cluster[static_cast<size_t>(tets.row(e).minCoeff())];
  return keys;
}

StressBounds stressModeBounds(const MatrixXdRow& s, int modes, const Eigen::VectorXd& modeScales,
                              const std::vector<int32_t>& pointKeys) {
  const Eigen::Index t = s.rows() / 6;
  StressBounds b;
  b.pressureModes.resize(t, modes);
  b.deviatorNorms.resize(t, modes);
  b.modeScales = modeScales.size() > 0 ? Eigen::VectorXd(modeScales.head(modes)) : Eigen::VectorXd::Ones(modes);
  b.spectralNorms.resize(t);
  b.deviatorSpectralNorms.resize(t);
  Eigen::Matrix<double, 6, Eigen::Dynamic> a(6, modes);
  for (Eigen::Index e = 0; e < t; ++e) {
    if (e % 256 == 0) detail::cancellationPoint();  // made on a World's background threads
    a.noalias() = kD.asDiagonal() * s.block(6 * e, 0, 6, modes);
    const Eigen::RowVectorXd pressure = a.topRows<3>().colwise().sum() / 3.0;
    b.pressureModes.row(e) = pressure;
    a = a * b.modeScales.asDiagonal();
    b.spectralNorms[e] = spectralNormBound(a);
    a.topRows<3>().rowwise() -= pressure.cwiseProduct(b.modeScales.transpose());  // the deviator, weighted
    b.deviatorSpectralNorms[e] = spectralNormBound(a);
    b.deviatorNorms.row(e) = a.colwise().norm().cwiseQuotient(b.modeScales.transpose());
  }
  if (pointKeys.size() != static_cast<size_t>(t) || t == 0) return b;
  // Groups by key (in order of their lowest point), each centred on its points' mean.
  b.groupPoints.resize(static_cast<size_t>(t));
  std::iota(b.groupPoints.begin(), b.groupPoints.end(), 0);
  std::stable_sort(b.groupPoints.begin(), b.groupPoints.end(),
                   [&](int32_t x, int32_t y) { return pointKeys[static_cast<size_t>(x)] < pointKeys[static_cast<size_t>(y)]; });
  b.groupStart.push_back(0);
  for (size_t i = 1; i < b.groupPoints.size(); ++i) {
    if (pointKeys[static_cast<size_t>(b.groupPoints[i])] != pointKeys[static_cast<size_t>(b.groupPoints[i - 1])]) {
      b.groupStart.push_back(static_cast<int32_t>(i));
    }
  }
  b.groupStart.push_back(static_cast<int32_t>(t));
  const Eigen::Index groups = static_cast<Eigen::Index>(b.groupStart.size()) - 1;
  {
    // Dealt out like cards, every kScanRanges-th group in a row: groups of neighbouring nodes
    // then fall into different ranges of the scan (ranges of consecutive groups), so that the
    // points near a hit, where the search spends its time, are shared by the threads.
    std::vector<int32_t> points, start{0};
    points.reserve(b.groupPoints.size());
    for (Eigen::Index hand = 0; hand < kScanRanges; ++hand) {
      for (Eigen::Index g = hand; g < groups; g += kScanRanges) {
        points.insert(points.end(), b.groupPoints.begin() + b.groupStart[static_cast<size_t>(g)],
                      b.groupPoints.begin() + b.groupStart[static_cast<size_t>(g) + 1]);
        start.push_back(static_cast<int32_t>(points.size()));
      }
    }
    b.groupPoints = std::move(points);
    b.groupStart = std::move(start);
  }
  b.groupOf.resize(static_cast<size_t>(t));
  for (Eigen::Index g = 0; g < groups; ++g) {
    for (int32_t i = b.groupStart[static_cast<size_t>(g)]; i < b.groupStart[static_cast<size_t>(g) + 1]; ++i) {
      b.groupOf[static_cast<size_t>(b.groupPoints[static_cast<size_t>(i)])] = static_cast<int32_t>(g);
    }
  }
  b.groupCentres.resize(6 * groups, modes);
  b.groupRadii.resize(groups);
  b.groupScales.resize(groups);
  b.groupUniform.assign(static_cast<size_t>(groups), 0);
  for (Eigen::Index g = 0; g < groups; ++g) {
    const int32_t* first = b.groupPoints.data() + b.groupStart[static_cast<size_t>(g)];
    const int32_t* last = b.groupPoints.data() + b.groupStart[static_cast<size_t>(g) + 1];
    b.groupUniform[static_cast<size_t>(g)] =
        std::all_of(first + 1, last, [&](int32_t e) { return sameBits(s.row(6 * *first).data(), s.row(6 * e).data(), 6 * s.cols()); });
  }
  Eigen::Matrix<double, 6, Eigen::Dynamic> centre(6, modes);
  for (Eigen::Index g = 0; g < groups; ++g) {
    if (g % 256 == 0) detail::cancellationPoint();
    const int32_t* first = b.groupPoints.data() + b.groupStart[static_cast<size_t>(g)];
    const int32_t* last = b.groupPoints.data() + b.groupStart[static_cast<size_t>(g) + 1];
    centre.setZero();
    for (const int32_t* e = first; e != last; ++e) centre += s.block(6 * *e, 0, 6, modes);
    centre /= static_cast<double>(last - first);
    // The centre is what the scan reads, in float; the radius is measured from it.
    b.groupCentres.middleRows(6 * g, 6) = centre.cast<float>();
    centre = b.groupCentres.middleRows(6 * g, 6).cast<double>();
    // The Frobenius norm bounds the spectral one, and costs 6r products instead of a Gram matrix's
    // powers; on the plate it leaves 263 groups at the peak where the spectral norm leaves 239.
    double radius = 0.0;
    for (const int32_t* e = first; e != last; ++e) {
      a.noalias() = kD.asDiagonal() * (s.block(6 * *e, 0, 6, modes) - centre) * b.modeScales.asDiagonal();
      radius = std::max(radius, a.norm());
    }
    b.groupRadii[g] = radius;
    a.noalias() = kD.asDiagonal() * centre * b.modeScales.asDiagonal();
    b.groupScales[g] = a.norm();
  }
  return b;
}

Voigt StressField::atPoint(Eigen::Index point) const {
  auto compute = [&] {
    Voigt s = detail::elementStress(*stressModes, point, q.data(), q.size(), lanes);
    if (staticStress && staticStress->size() > 0) s += staticStress->segment<6>(6 * point) * forceN;
    return s;
  };
  if (!nodeMemo) return compute();
  const auto node = static_cast<size_t>((*corners)(point / pointsPerElement, point % pointsPerElement));
  if (nodeMemo->known[node]) return nodeMemo->stress[node];
  nodeMemo->stress[node] = compute();
  nodeMemo->known[node] = 1;
  return nodeMemo->stress[node];
}

void StressField::prefetch(int32_t e) const {
  if (!nodeMemo) {
    const Eigen::Index rows = 6 * static_cast<Eigen::Index>(pointsPerElement);
    prefetchRows(*stressModes, rows * e, rows);
    return;
  }
  // With a node memo, only the points whose node is not known yet are read: crack growth reaches
  // most elements through nodes it has already met (the P2 vase's 120 lines an element were a
  // tenth of its crack stage's samples, most of them for rows it would not read).
  for (int c = 0; c < pointsPerElement; ++c) {
    if (nodeMemo->known[static_cast<size_t>((*corners)(e, c))]) continue;
    prefetchRows(*stressModes, 6 * (static_cast<Eigen::Index>(pointsPerElement) * e + c), 6);
  }
}

Voigt StressField::at(int32_t e) const {
  if (pointsPerElement == 1) return atPoint(e);
  // The point with the largest σ₁, the first of equals. A later point whose bound does not exceed
  // the best σ₁ so far can at most tie, and a tie keeps the earlier one, so its eigen solve is left
  // out: the same point, and the same bits, as solving every one.
  const Eigen::Index first = static_cast<Eigen::Index>(pointsPerElement) * e;
  prefetch(e);  // all of its points' rows at once (a P2 element's: 120 cache lines), not one stream after another
  Voigt best = atPoint(first);
  double bestS1 = maxPrincipalStress(best);
  for (int c = 1; c < pointsPerElement; ++c) {
    const Voigt s = atPoint(first + c);
    if (principalBound(s) <= bestS1) continue;
    if (const double s1 = maxPrincipalStress(s); s1 > bestS1) {
      best = s;
      bestS1 = s1;
    }
  }
  return best;
}

StressScan scanStresses(const MatrixXdRow& S, const StressBounds& bounds, const Eigen::MatrixXd& q,
                        const Eigen::VectorXd& staticStress, const std::vector<double>& forceN, double threshold,
                        bool prune, int pointsPerElement) {
  StressScanWorkspace workspace;
  StressScan scan;
  scanStresses(S, bounds, q, staticStress, forceN, threshold, prune, workspace, scan, pointsPerElement);
  return scan;
}

void scanStresses(const MatrixXdRow& S, const StressBounds& bounds, const Eigen::MatrixXd& q,
                  const Eigen::VectorXd& staticStress, const std::vector<double>& forceN, double threshold, bool prune,
                  StressScanWorkspace& w, StressScan& scan, int pointsPerElement) {
  prepareStressScan(bounds, q, prune, w);
  scanPreparedStresses(S, bounds, q, staticStress, forceN, threshold, prune, w, scan, pointsPerElement);
}

void prepareStressScan(const StressBounds& bounds, const Eigen::MatrixXd& q, bool prune, StressScanWorkspace& w) {
  const Eigen::Index t = bounds.spectralNorms.size(), steps = q.rows(), r = q.cols();
  w.qT = q.transpose();  // r by K: each instant's modal coordinates contiguous
  if (!prune) return;
  w.qAbsT = q.cwiseAbs().transpose();  // r by K
  w.qMax = w.qAbsT.rowwise().maxCoeff();
  w.qNorm.resize(steps);  // ‖W⁻¹ q_k‖
  for (Eigen::Index k = 0; k < steps; ++k) w.qNorm[k] = w.qT.col(k).cwiseQuotient(bounds.modeScales.head(r)).norm();
  const double qNormMax = steps > 0 ? w.qNorm.maxCoeff() : 0.0;
  // Each point's modal terms of B_e (scanPreparedStresses adds the static ones): the pass over
  // every point's bound rows, the scan's largest read (two rows of r doubles a point). The points
  // of a uniform group (StressBounds::groupUniform: a P2 node's corners as nodal means, ~13 of
  // them on the default vase) have the same rows bit for bit: the group's first point computes
  // them, and the others copy its values, which are the bits each would have computed. The P2
  // vase's pass read 17 MB, beside the correction's forward solve, which it slowed.
  w.modalPressure.resize(t);
  w.modalDeviator.resize(t);
  const GroupRepresentatives uniform(bounds, bounds.groupUniform, searchesByGroups(bounds, t, r));
  detail::forFixedRanges(t, kScanRanges, [&](int, Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index e = begin; e < end; ++e) {
      if (uniform.of(e) != e) continue;
      const double* pe = bounds.pressureModes.row(e).data();
      const double* de = bounds.deviatorNorms.row(e).data();
      double pressure = 0.0, deviator = 0.0;
      for (Eigen::Index j = 0; j < r; ++j) {
        pressure += std::abs(pe[j]) * w.qMax[j];
        deviator += de[j] * w.qMax[j];
      }
      w.modalPressure[e] = pressure;
      w.modalDeviator[e] = std::min(deviator, bounds.deviatorSpectralNorms[e] * qNormMax);
    }
  });
  if (uniform.any()) {
    detail::forFixedRanges(t, kScanRanges, [&](int, Eigen::Index begin, Eigen::Index end) {
      for (Eigen::Index e = begin; e < end; ++e) {
        const Eigen::Index from = uniform.of(e);
        w.modalPressure[e] = w.modalPressure[from];
        w.modalDeviator[e] = w.modalDeviator[from];
      }
    });
  }
  if (searchesByGroups(bounds, t, r)) {
    w.qFloat.setZero((steps + kInstantPad - 1) / kInstantPad * kInstantPad, r);
    w.qFloat.topRows(steps) = q.cast<float>();
  }
}

void scanPreparedStresses(const MatrixXdRow& S, const StressBounds& bounds, const Eigen::MatrixXd& q,
                          const Eigen::VectorXd& staticStress, const std::vector<double>& forceN, double threshold,
                          bool prune, StressScanWorkspace& w, StressScan& scan, int pointsPerElement) {
  // Every stress point is scanned as one "element" e of S's rows; the peak and the seeds are then
  // reported by the element that holds the point.
  const Eigen::Index t = S.rows() / 6, steps = q.rows(), r = q.cols();
  // A workspace prepared for another shape (or never) is prepared here, so that nothing below reads
  // past its buffers; one prepared for another q of the same shape is the caller's error.
  if (w.qT.rows() != r || w.qT.cols() != steps || (prune && (w.modalPressure.size() != t || w.qNorm.size() != steps))) {
    prepareStressScan(bounds, q, prune, w);
  }
  const bool correction = staticStress.size() > 0;
  w.groupSame.clear();  // made again below by a grouped search: never a previous scan's
  scan.peakPrincipalPa = 0.0;
  scan.peakElement = scan.peakInstant = -1;
  scan.seeds.clear();
  scan.evaluations = 0;
  // σ_e at instant k (w.qT: prepareStressScan's).
  auto voigt = [&](Eigen::Index e, Eigen::Index k) {
    Voigt s = detail::elementStress(S, e, w.qT.col(k).data(), r, w.lanes);
    if (correction) s += staticStress.segment<6>(6 * e) * forceN[static_cast<size_t>(k)];
    return s;
  };
  // A peak (value, point, instant) takes s1 at (e, k) if it is larger; ties break towards the lower
  // instant, then the lower point, in every scan and range.
  auto take = [](double s1, Eigen::Index e, Eigen::Index k, double& value, int32_t& point, int32_t& instant) {
    if (s1 > value || (s1 == value && (k < instant || (k == instant && e < point)))) {
      value = s1;
      point = static_cast<int32_t>(e);
      instant = static_cast<int32_t>(k);
    }
  };
  double best = -std::numeric_limits<double>::infinity();
  auto consider = [&](Eigen::Index e, Eigen::Index k, double s1) {
    take(s1, e, k, best, scan.peakElement, scan.peakInstant);
  };
  // What the tests of one point read, in locals: its bounds, and the instants' arrays (the
  // search takes a point's instants in a row, and would otherwise reload every pointer).
  struct PointView {
    double spectral, staticNorm, staticPressure, staticDeviator, deviatorSpectral, margin;
    const double *pressureRow, *deviatorRow, *forceAbs, *qNorm, *force, *qT, *qAbsT;
  };
  auto pointView = [&](Eigen::Index e) {
    return PointView{bounds.spectralNorms[e],        w.staticNorm[e],
                     w.staticPressure[e],            w.staticDeviator[e],
                     bounds.deviatorSpectralNorms[e], 1e-9 * (w.pressureScale[e] + w.elementBound[e]),
                     bounds.pressureModes.row(e).data(), bounds.deviatorNorms.row(e).data(),
                     w.forceAbs.data(),              w.qNorm.data(),
                     forceN.data(),                  w.qT.data(),
                     w.qAbsT.data()};
  };
  // Whether (e, k) may reach `level`, cheapest test first: the spectral bound (one product); the
  // exact mean stress p_e,k with the deviator's spectral bound, then with its triangle bound (r
  // products each); the evaluated σ's own split bound (below). Their data are made by the pruned
  // peak search. The margin covers the rounding of p_e,k's sum, whose terms may cancel.
  auto mayReachAt = [&](const PointView& v, Eigen::Index k, double level) {
    const double fAbs = v.forceAbs[k], qNormK = v.qNorm[k];
    if ((v.spectral * qNormK + v.staticNorm * fAbs) * (1.0 + 1e-9) < level) return false;
    const double p = dotInOrder(v.pressureRow, v.qT + k * r, r) + (correction ? v.staticPressure * v.force[k] : 0.0);
    if (p + kDeviatorShare * (v.deviatorSpectral * qNormK + v.staticDeviator * fAbs) + v.margin < level) return false;
    const double deviator = dotInOrder(v.deviatorRow, v.qAbsT + k * r, r) * (1.0 + 1e-9);
    return p + kDeviatorShare * (deviator + v.staticDeviator * fAbs) + v.margin >= level;
  };
  auto mayReach = [&](Eigen::Index e, Eigen::Index k, double level) { return mayReachAt(pointView(e), k, level); };
  // The bound of (e, k) itself: the smaller of the spectral and the split bound (both dots).
  auto seedBound = [&](Eigen::Index e, Eigen::Index k) {
    const double fAbs = w.forceAbs[k];
    const double spectral = (bounds.spectralNorms[e] * w.qNorm[k] + w.staticNorm[e] * fAbs) * (1.0 + 1e-9);
    const double margin = 1e-9 * (w.pressureScale[e] + w.elementBound[e]);
    const double p = dotInOrder(bounds.pressureModes.row(e).data(), w.qT.col(k).data(), r) +
                     (correction ? w.staticPressure[e] * forceN[static_cast<size_t>(k)] : 0.0);
    const double deviator =
        std::min(bounds.deviatorSpectralNorms[e] * w.qNorm[k],
                 dotInOrder(bounds.deviatorNorms.row(e).data(), w.qAbsT.col(k).data(), r) * (1.0 + 1e-9)) +
        w.staticDeviator[e] * fAbs;
    return std::min(spectral, p + kDeviatorShare * deviator + margin);
  };
  // The evaluated σ: skipped below `level` by its split bound (with a margin for the eigen
  // solve's rounding), else its σ₁.
  auto principalAbove = [&](const Voigt& sigma, double level, double& s1) {
    if (principalBound(sigma) < level) return false;
    s1 = maxPrincipalStress(sigma);
    return true;
  };
  if (!prune) {
    for (Eigen::Index e = 0; e < t; ++e) {
      for (Eigen::Index k = 0; k < steps; ++k) {
        ++scan.evaluations;
        consider(e, k, maxPrincipalStress(voigt(e, k)));
      }
    }
  } else {
    // Bounds per point over all instants, then per (point, instant) for the points visited; see
    // the header. The static correction adds σ̂_e F_k: its mean normal stress exactly, its norms to
    // the norms.
    // (w.qAbsT, w.qMax, w.qNorm and the points' modal terms: prepareStressScan's.)
    w.forceAbs.setZero(steps);
    if (correction) {
      for (Eigen::Index k = 0; k < steps; ++k) w.forceAbs[k] = std::abs(forceN[static_cast<size_t>(k)]);
    }
    const double forceMax = steps > 0 ? w.forceAbs.maxCoeff() : 0.0, qNormMax = steps > 0 ? w.qNorm.maxCoeff() : 0.0;
    // B_e = min(‖D S_e W‖₂ max‖W⁻¹q_k‖ + ‖Dσ̂_e‖ max|F|,
    //           Σ|P_e,j| max|q_j| + |p̂_e| max|F| + √(2/3) (min(Σ‖s_e,j‖ max|q_j|, ‖s_e W‖₂ max‖W⁻¹q_k‖) + ‖ŝ_e‖ max|F|)),
    // and the scale of the rounding in a point's mean stress, Σ|P_e,j| max|q_j| + |p̂_e| max|F|.
    const bool grouped = searchesByGroups(bounds, t, r);
    const Eigen::Index groups = grouped ? static_cast<Eigen::Index>(bounds.groupStart.size()) - 1 : 0;
    // The static correction's centre of group g (its points' mean) and radius, and the margin of
    // the group's bound, into the workspace, once an impact for every group (the search reads them
    // for the groups it bounds, the seeds' test for all). The centre's float sums
    // (centreSplitBounds) move its split bound by at most 2√6 (r + 2) 2⁻²⁴ ‖D S_c W‖_F ‖W⁻¹q_k‖,
    // under 1e-4 of the scale for r < 4000.
    auto groupStatic = [&](Eigen::Index g) {
      const int32_t* from = bounds.groupPoints.data() + bounds.groupStart[static_cast<size_t>(g)];
      const int32_t* to = bounds.groupPoints.data() + bounds.groupStart[static_cast<size_t>(g) + 1];
      Voigt centre = Voigt::Zero();
      double staticRadius = 0.0;
      if (correction) {
        for (const int32_t* e = from; e != to; ++e) centre += staticStress.segment<6>(6 * *e);
        centre /= static_cast<double>(to - from);
        for (const int32_t* e = from; e != to; ++e) {
          staticRadius = std::max(staticRadius, kD.cwiseProduct(staticStress.segment<6>(6 * *e) - centre).norm());
        }
      }
      Eigen::Map<Voigt>(w.groupStaticCentre.data() + 6 * g) = centre;
      w.groupStaticRadius[static_cast<size_t>(g)] = staticRadius;
      bool same = bounds.groupUniform[static_cast<size_t>(g)] != 0;
      if (same && correction) {
        same = std::all_of(from + 1, to, [&](int32_t e) { return sameBits(staticStress.data() + 6 * *from, staticStress.data() + 6 * e, 6); });
      }
      w.groupSame[static_cast<size_t>(g)] = same ? 1 : 0;
      w.groupMargin[static_cast<size_t>(g)] =
          1e-4 * bounds.groupScales[g] * qNormMax +
          1e-9 * (bounds.groupRadii[g] * qNormMax + (kD.cwiseProduct(centre).norm() + staticRadius) * forceMax);
    };
    if (grouped) {
      w.groupStaticCentre.resize(static_cast<size_t>(6 * groups));
      w.groupStaticRadius.resize(static_cast<size_t>(groups));
      w.groupMargin.resize(static_cast<size_t>(groups));
      w.groupSame.resize(static_cast<size_t>(groups));
      // F_k at the float q's padded rows, zero past the last instant (the group bounds read whole registers).
      if (correction) {
        w.forceLanes.assign(static_cast<size_t>(w.qFloat.rows()), 0.0);
        std::copy_n(forceN.begin(), steps, w.forceLanes.begin());
      }
      detail::forFixedRanges(groups, kScanRanges, [&](int, Eigen::Index begin, Eigen::Index end) {
        for (Eigen::Index g = begin; g < end; ++g) groupStatic(g);
      });
    }
    // A point of a group whose points are the same bits, static correction included (groupSame),
    // has its group's first point's bounds: made there and copied (the same bits).
    const GroupRepresentatives same(bounds, w.groupSame, grouped);
    w.elementBound.resize(t);
    w.pressureScale.resize(t);
    w.staticNorm.resize(t);
    w.staticPressure.resize(t);
    w.staticDeviator.resize(t);
    detail::forFixedRanges(t, kScanRanges, [&](int, Eigen::Index begin, Eigen::Index end) {
      for (Eigen::Index e = begin; e < end; ++e) {
        if (same.of(e) != e) continue;
        // The static correction's norms at e, here with the bounds that read them (on the
        // plate's 29.8k points this was 0.5 ms on one thread before the bounds).
        if (correction) {
          const Voigt se = staticStress.segment<6>(6 * e);
          Voigt d = kD.cwiseProduct(se);
          w.staticNorm[e] = d.norm();
          w.staticPressure[e] = (se[0] + se[1] + se[2]) / 3.0;
          d.head<3>().array() -= w.staticPressure[e];
          w.staticDeviator[e] = d.norm();
        } else {
          w.staticNorm[e] = w.staticPressure[e] = w.staticDeviator[e] = 0.0;
        }
        const double pressure = w.modalPressure[e] + std::abs(w.staticPressure[e]) * forceMax;
        const double deviator = w.modalDeviator[e] + w.staticDeviator[e] * forceMax;
        w.pressureScale[e] = pressure;
        // The relative margin covers the sums' rounding (every term here is ≥ 0).
        w.elementBound[e] = std::min(bounds.spectralNorms[e] * qNormMax + w.staticNorm[e] * forceMax,
                                     pressure + kDeviatorShare * deviator) * (1.0 + 1e-9);
      }
    });
    if (same.any()) {
      detail::forFixedRanges(t, kScanRanges, [&](int, Eigen::Index begin, Eigen::Index end) {
        for (Eigen::Index e = begin; e < end; ++e) {
          const Eigen::Index from = same.of(e);
          if (from == e) continue;
          w.staticNorm[e] = w.staticNorm[from];
          w.staticPressure[e] = w.staticPressure[from];
          w.staticDeviator[e] = w.staticDeviator[from];
          w.pressureScale[e] = w.pressureScale[from];
          w.elementBound[e] = w.elementBound[from];
        }
      });
    }
    // The search runs in 16 fixed ranges of points (of groups, below) on the arena's threads, each
    // over a max-heap of its own points. Every range starts from the same lower bound, the largest
    // of the ranges' floors (each the peak over all instants of the range's point with the largest
    // B_e), so that ranges without the peak still prune and none has to climb to it alone (and,
    // after each of the rounds below, from the best of all ranges so far); each finds its exact
    // maximum above that, and the ranges' maxima are combined in range order with the same tie rule.
    // The answer, and the evaluation count, are the same on any number of threads.
    auto rangeSpan = [&](int c) {  // positions [lo, hi) of range c's points (in groupPoints, if grouped)
      if (!grouped) return std::pair<size_t, size_t>(static_cast<size_t>(t * c / kScanRanges), static_cast<size_t>(t * (c + 1) / kScanRanges));
      return std::pair<size_t, size_t>(static_cast<size_t>(bounds.groupStart[static_cast<size_t>(groups * c / kScanRanges)]),
                                       static_cast<size_t>(bounds.groupStart[static_cast<size_t>(groups * (c + 1) / kScanRanges)]));
    };
    auto pointAt = [&](size_t i) { return grouped ? bounds.groupPoints[i] : static_cast<int32_t>(i); };
    w.rangePeaks.resize(kScanRanges);
    tbb::parallel_for(0, kScanRanges, [&](int c) {
      StressScanWorkspace::RangePeak& out = w.rangePeaks[static_cast<size_t>(c)];
      out = StressScanWorkspace::RangePeak{-std::numeric_limits<double>::infinity(), -1, -1, 0};
      const auto [lo, hi] = rangeSpan(c);
      int32_t top = -1;
      for (size_t i = lo; i < hi; ++i) {  // the largest bound, the lowest point among equal ones
        const int32_t e = pointAt(i);
        if (top < 0 || w.elementBound[e] > w.elementBound[top] || (w.elementBound[e] == w.elementBound[top] && e < top)) top = e;
      }
      for (Eigen::Index k = 0; top >= 0 && k < steps; ++k) {
        ++out.evaluations;
        take(maxPrincipalStress(voigt(top, k)), top, k, out.best, out.point, out.instant);
      }
    });
    for (const StressScanWorkspace::RangePeak& p : w.rangePeaks) {
      scan.evaluations += p.evaluations;
      if (p.point >= 0) consider(p.point, p.instant, p.best);
    }
    const double floorBest = best;
    const int32_t floorPoint = scan.peakElement, floorInstant = scan.peakInstant;
    auto startRange = [&](int c) -> StressScanWorkspace::RangePeak& {
      StressScanWorkspace::RangePeak& out = w.rangePeaks[static_cast<size_t>(c)];
      out.best = floorBest;
      out.point = floorPoint;
      out.instant = floorInstant;
      out.evaluations = 0;
      return out;
    };
    double roundBest = floorBest;
    int32_t roundPoint = floorPoint, roundInstant = floorInstant;
    auto continueRange = [&](int c) -> StressScanWorkspace::RangePeak& {
      StressScanWorkspace::RangePeak& out = w.rangePeaks[static_cast<size_t>(c)];
      take(roundBest, roundPoint, roundInstant, out.best, out.point, out.instant);
      return out;
    };
    // The search runs in rounds: each range takes at most kRoundGroups[i] more groups (points,
    // without groups) from its heap in round i, and every range starts the next round from the best
    // of all ranges so far, a value some (point, instant) reaches. A range alone climbs only to its own
    // maximum, and so tests everything above that; on the P2 vase's hit the floors start at 0.84 of
    // the peak, and in one round the search made 8.6k stresses where the peak as its start would
    // make 3.4k. Rounds of 1, 2 and 4 groups, then the rest, make 3.6k (the 4.1k-tet slab's: 2.0k
    // → 0.85k, 0.78k from the peak): the vase's scan 2.1–2.5 → 1.7–2.0 ms, the slab's 1.02–1.11 →
    // 0.95–1.01. Rounds without the floors were slower on the slab (1.19 ms). The rounds are fixed,
    // so the counts and the answer are the same on any number of threads; each is a parallel loop's
    // fork and join.
    static constexpr std::array<int, 4> kRoundGroups{1, 2, 4, std::numeric_limits<int>::max()};
    // Point e's instants, skipping those whose group bound (if given) is below the best so far.
    auto visitPoint = [&](Eigen::Index e, const double* groupBoundAt, StressScanWorkspace::RangePeak& out) {
      const PointView view = pointView(e);
      for (Eigen::Index k = 0; k < steps; ++k) {
        if ((groupBoundAt && groupBoundAt[k] < out.best) || !mayReachAt(view, k, out.best)) continue;
        double s1 = 0.0;
        if (!principalAbove(voigt(e, k), out.best, s1)) continue;
        ++out.evaluations;
        take(s1, e, k, out.best, out.point, out.instant);
      }
    };
    // With groups (StressBounds), the search runs per range of groups, over a max-heap of groups
    // by their points' largest B_e. A group taken with at least kGroupVisit points still above the
    // best has its bound at every instant made (its centre's exact stress, 6r products each, plus
    // its radii), and is passed over whole where that is below the best at every instant; else
    // its points above the best are tested, at the instants the group's bound leaves. Smaller
    // groups' points are tested as without groups, where the search runs per range of points over
    // a max-heap of them by B_e.
    // A centre's bounds cost 6r products an instant, a point's tests r to 3r: with fewer than three
    // points left, a group's points are tested as they are (a choice, not tuned).
    constexpr int kGroupVisit = 3;
    auto staticCentreOf = [&](Eigen::Index g) { return Eigen::Map<const Voigt>(w.groupStaticCentre.data() + 6 * g); };
    // Group g's bound at every instant into groupBoundAt, and their maximum.
    auto groupBounds = [&](Eigen::Index g) {
      const double radius = bounds.groupRadii[g], staticRadius = w.groupStaticRadius[static_cast<size_t>(g)],
                   margin = w.groupMargin[static_cast<size_t>(g)];
      double* at = w.groupBoundAt.data() + g * steps;
      centreSplitBounds(bounds.groupCentres, g, w.qFloat, steps, staticCentreOf(g),
                        correction ? w.forceLanes.data() : nullptr, w.lanes, at);
      double most = -std::numeric_limits<double>::infinity();
      for (Eigen::Index k = 0; k < steps; ++k) {
        at[k] += (radius * w.qNorm[k] + staticRadius * w.forceAbs[k]) * (1.0 + 1e-9) + margin;
        most = std::max(most, at[k]);
      }
      w.groupBound[g] = most;
    };
    auto searchGroups = [&](int c, int round) {
      StressScanWorkspace::RangePeak& out = round == 0 ? startRange(c) : continueRange(c);
      const Eigen::Index firstGroup = groups * c / kScanRanges, endGroup = groups * (c + 1) / kScanRanges;
      const auto heapBegin = w.heap.begin() + firstGroup;
      auto heapEnd = w.heap.begin() + (round == 0 ? endGroup : out.heapEnd);
      if (round == 0) {
        for (Eigen::Index g = firstGroup; g < endGroup; ++g) {
          double top = -std::numeric_limits<double>::infinity();
          for (int32_t i = bounds.groupStart[static_cast<size_t>(g)]; i < bounds.groupStart[static_cast<size_t>(g) + 1]; ++i) {
            top = std::max(top, w.elementBound[bounds.groupPoints[static_cast<size_t>(i)]]);
          }
          w.heap[static_cast<size_t>(g)] = {top, static_cast<int32_t>(g)};
          w.groupBound[g] = std::numeric_limits<double>::quiet_NaN();
        }
        std::make_heap(heapBegin, heapEnd);
      }
      for (int taken = 0; heapBegin != heapEnd && heapBegin->first >= out.best && taken < kRoundGroups[static_cast<size_t>(round)]; ++taken) {
        std::pop_heap(heapBegin, heapEnd);
        --heapEnd;
        const int32_t g = heapEnd->second;
        // The next group's centre on its way while this one is bounded: the heap takes groups in
        // no array's order, so its rows (15 cache lines of floats for 40 modes) would each miss.
        // (Its radii, margin and row of bounds as well cost more than they saved.)
        if (heapBegin != heapEnd) prefetchRows(bounds.groupCentres, 6 * heapBegin->second, 6);
        const int32_t* from = bounds.groupPoints.data() + bounds.groupStart[static_cast<size_t>(g)];
        const int32_t* to = bounds.groupPoints.data() + bounds.groupStart[static_cast<size_t>(g) + 1];
        if (w.groupSame[static_cast<size_t>(g)]) {
          // Its points' stresses are the same bits: the lowest one stands for all (on a tie the
          // lowest point is the one reported), and its own tests are cheaper than the group's bounds.
          if (w.elementBound[*from] >= out.best) visitPoint(*from, nullptr, out);
          continue;
        }
        const double* at = nullptr;
        if (std::count_if(from, to, [&](int32_t e) { return w.elementBound[e] >= out.best; }) >= kGroupVisit) {
          groupBounds(g);
          if (w.groupBound[g] < out.best) continue;
          at = w.groupBoundAt.data() + static_cast<size_t>(g) * static_cast<size_t>(steps);
        }
        // Each point's bound rows (10 cache lines for 40 modes) on their way while the one before
        // it is tested. The best only rises, so a point found ahead is tested again when its turn
        // comes: the same points are visited as one test at a time would.
        const int32_t* next = std::find_if(from, to, [&](int32_t e) { return w.elementBound[e] >= out.best; });
        while (next != to) {
          const int32_t e = *next;
          next = std::find_if(next + 1, to, [&](int32_t n) { return w.elementBound[n] >= out.best; });
          if (next != to) {
            prefetchRows(bounds.pressureModes, *next, 1);
            prefetchRows(bounds.deviatorNorms, *next, 1);
          }
          if (w.elementBound[e] >= out.best) visitPoint(e, at, out);
        }
      }
      out.heapEnd = heapEnd - w.heap.begin();
    };
    auto searchPoints = [&](int c, int round) {
      StressScanWorkspace::RangePeak& out = round == 0 ? startRange(c) : continueRange(c);
      const auto [lo, hi] = rangeSpan(c);
      const auto heapBegin = w.heap.begin() + static_cast<std::ptrdiff_t>(lo);
      auto heapEnd = w.heap.begin() + (round == 0 ? static_cast<std::ptrdiff_t>(hi) : out.heapEnd);
      if (round == 0) {
        for (size_t e = lo; e < hi; ++e) w.heap[e] = {w.elementBound[static_cast<Eigen::Index>(e)], static_cast<int32_t>(e)};
        std::make_heap(heapBegin, heapEnd);
      }
      for (int taken = 0; heapBegin != heapEnd && heapBegin->first >= out.best && taken < kRoundGroups[static_cast<size_t>(round)]; ++taken) {
        std::pop_heap(heapBegin, heapEnd);
        --heapEnd;
        visitPoint(heapEnd->second, nullptr, out);
      }
      out.heapEnd = heapEnd - w.heap.begin();
    };
    w.heap.resize(static_cast<size_t>(t));  // points, or groups (fewer)
    if (grouped) {
      w.groupBound.resize(groups);
      w.groupBoundAt.resize(static_cast<size_t>(groups * steps));
    }
    for (int round = 0; round < static_cast<int>(kRoundGroups.size()); ++round) {
      if (round > 0) {
        roundBest = floorBest, roundPoint = floorPoint, roundInstant = floorInstant;
        for (const StressScanWorkspace::RangePeak& p : w.rangePeaks) take(p.best, p.point, p.instant, roundBest, roundPoint, roundInstant);
      }
      tbb::parallel_for(0, kScanRanges, [&](int c) { grouped ? searchGroups(c, round) : searchPoints(c, round); });
    }
    for (const StressScanWorkspace::RangePeak& p : w.rangePeaks) {
      scan.evaluations += p.evaluations;
      consider(p.point, p.instant, p.best);
    }
    // Each group's bound at the peak instant (the search's, at one instant; its centre's sums in
    // double from the same float centre, so within the same margin): no point of a group below σ_t
    // there is a seed. At the plate's peak the spectral test alone let 86 % of its points through
    // to the exact mean stress, a cache-missing row each.
    w.seedGroupBound.clear();
    if (grouped && scan.peakInstant >= 0) {
      const Eigen::Index k = scan.peakInstant;
      w.seedGroupBound.resize(groups);
      detail::forFixedRanges(groups, kScanRanges, [&](int, Eigen::Index begin, Eigen::Index end) {
        const double* qk = w.qT.col(k).data();
        const Eigen::Index stride = bounds.groupCentres.cols();
        for (Eigen::Index g = begin; g < end; ++g) {
          const float* c = bounds.groupCentres.data() + 6 * g * stride;
          double sums[6] = {};
          for (Eigen::Index j = 0; j < r; ++j) {  // six running sums in mode order
            for (int i = 0; i < 6; ++i) sums[i] += static_cast<double>(c[i * stride + j]) * qk[j];
          }
          Voigt sigma;
          for (int i = 0; i < 6; ++i) sigma[i] = sums[i];
          if (correction) sigma += staticCentreOf(g) * forceN[static_cast<size_t>(k)];
          w.seedGroupBound[g] = principalBound(sigma) +
                                (bounds.groupRadii[g] * w.qNorm[k] + w.groupStaticRadius[static_cast<size_t>(g)] * w.forceAbs[k]) *
                                    (1.0 + 1e-9) +
                                w.groupMargin[static_cast<size_t>(g)];
        }
      });
    }
  }
  scan.peakPrincipalPa = best;
  const int32_t peakPoint = scan.peakElement;
  if (peakPoint >= 0) scan.peakElement = peakPoint / pointsPerElement;
  // Seeds at the peak instant, in fixed ranges, each into its own list, gathered in range order.
  // Unpruned: every point over σ_t there, evaluated and sorted. Pruned: the candidates, each point
  // whose bound there reaches σ_t, with that bound; SeedOrder evaluates them as crack growth takes
  // seeds, strongest first (a shattering hit puts most of a body over σ_t and starts a few cracks).
  const Eigen::Index k = scan.peakInstant;
  scan.seedThresholdPa = threshold;
  scan.pointsPerElement = pointsPerElement;
  scan.seedCandidates.clear();
  w.seeds.clear();
  w.rangeSeeds.resize(kScanRanges);
  w.rangeEvaluations.assign(kScanRanges, 0);
  // A group whose points are the same bits, static correction included (groupSame), has one test
  // and one bound for all of them: made once, at its first point, before the ranges read them
  // (NaN: no seed), instead of each point reading the same two rows of bounds.
  const bool sameGroups = prune && k >= 0 && !w.seedGroupBound.empty() && w.groupSame.size() == w.seedGroupBound.size();
  if (sameGroups) {
    const auto groupCount = static_cast<Eigen::Index>(w.groupSame.size());
    w.seedGroupValue.resize(static_cast<size_t>(groupCount));
    detail::forFixedRanges(groupCount, kScanRanges, [&](int, Eigen::Index begin, Eigen::Index end) {
      for (Eigen::Index g = begin; g < end; ++g) {
        double& value = w.seedGroupValue[static_cast<size_t>(g)];
        value = std::numeric_limits<double>::quiet_NaN();
        if (!w.groupSame[static_cast<size_t>(g)] || w.seedGroupBound[static_cast<size_t>(g)] < threshold) continue;
        const int32_t first = bounds.groupPoints[static_cast<size_t>(bounds.groupStart[static_cast<size_t>(g)])];
        if (mayReach(first, k, threshold)) value = seedBound(first, k);
      }
    });
  }
  auto seedRange = [&](int c, Eigen::Index begin, Eigen::Index end) {
    std::vector<std::pair<double, int32_t>>& out = w.rangeSeeds[static_cast<size_t>(c)];
    out.clear();
    if (k < 0) return;
    for (Eigen::Index e = begin; e < end; ++e) {
      if (prune) {
        const auto g = w.seedGroupBound.empty() ? size_t{0} : static_cast<size_t>(bounds.groupOf[static_cast<size_t>(e)]);
        if (!w.seedGroupBound.empty() && w.seedGroupBound[g] < threshold) continue;
        if (sameGroups && w.groupSame[g]) {
          if (!std::isnan(w.seedGroupValue[g])) out.emplace_back(w.seedGroupValue[g], static_cast<int32_t>(e));
          continue;
        }
        if (!mayReach(e, k, threshold)) continue;
        out.emplace_back(seedBound(e, k), static_cast<int32_t>(e));
        continue;
      }
      const double s1 = maxPrincipalStress(voigt(e, k));
      ++w.rangeEvaluations[static_cast<size_t>(c)];
      if (s1 >= threshold) out.emplace_back(s1, static_cast<int32_t>(e));
    }
  };
  detail::forFixedRanges(t, kScanRanges, seedRange);
  std::vector<std::pair<double, int32_t>>& gathered = prune ? scan.seedCandidates : w.seeds;
  for (int c = 0; c < kScanRanges; ++c) {
    scan.evaluations += w.rangeEvaluations[static_cast<size_t>(c)];
    gathered.insert(gathered.end(), w.rangeSeeds[static_cast<size_t>(c)].begin(), w.rangeSeeds[static_cast<size_t>(c)].end());
  }
  if (prune) {
    std::make_heap(scan.seedCandidates.begin(), scan.seedCandidates.end(), lowerSeed);
    return;
  }
  std::sort(w.seeds.begin(), w.seeds.end(), [](const auto& a, const auto& b) { return lowerSeed(b, a); });
  if (pointsPerElement == 1) {
    for (const auto& [s1, e] : w.seeds) scan.seeds.push_back(e);
    return;
  }
  // Each element once, at its strongest point.
  w.seedTaken.assign(static_cast<size_t>(t / pointsPerElement), 0);
  for (const auto& [s1, point] : w.seeds) {
    const int32_t e = point / pointsPerElement;
    if (w.seedTaken[static_cast<size_t>(e)]) continue;
    w.seedTaken[static_cast<size_t>(e)] = 1;
    scan.seeds.push_back(e);
  }
}

SeedOrder::SeedOrder(const StressScan& scan, const StressField& field, SeedOrderWorkspace& workspace)
    : mScan(scan), mField(field), mW(workspace) {
  mW.candidates.assign(scan.seedCandidates.begin(), scan.seedCandidates.end());  // a heap already
  mW.evaluated.clear();
  mW.bounded.clear();
  if (scan.seeds.empty() && scan.pointsPerElement > 1 && field.stressModes) {
    mW.taken.assign(static_cast<size_t>(field.stressModes->rows() / 6 / scan.pointsPerElement), 0);
  }
}

bool SeedOrder::next(int32_t& element) {
  if (!mScan.seeds.empty() || mScan.seedCandidates.empty()) {  // an unpruned scan's list
    if (mNext >= mScan.seeds.size()) return false;
    element = mScan.seeds[mNext++];
    return true;
  }
  // The candidates are taken exactly as if each were solved when evaluated: while nothing
  // evaluated reaches σ_t, or the top candidate's bound reaches the strongest σ₁ evaluated. An
  // evaluated σ waits in `bounded` with its split bound until that bound decides a comparison;
  // then its eigen solve moves it to `evaluated` (or drops it below σ_t). The evaluations, and
  // the seeds in their order, are those of solving each at once.
  auto& candidates = mW.candidates;
  auto& evaluated = mW.evaluated;
  auto& bounded = mW.bounded;
  const double threshold = mScan.seedThresholdPa;
  auto lowerBounded = [](const SeedOrderWorkspace::Bounded& a, const SeedOrderWorkspace::Bounded& b) {
    return lowerSeed({a.bound, a.point}, {b.bound, b.point});
  };
  auto solveStrongestBounded = [&] {
    std::pop_heap(bounded.begin(), bounded.end(), lowerBounded);
    const SeedOrderWorkspace::Bounded b = bounded.back();
    bounded.pop_back();
    const double s1 = maxPrincipalStress(b.sigma);
    if (s1 < threshold) return;
    evaluated.emplace_back(s1, b.point);
    std::push_heap(evaluated.begin(), evaluated.end(), lowerSeed);
  };
  for (;;) {
    while (!candidates.empty()) {
      const double top = candidates.front().first;
      if (!evaluated.empty() && top < evaluated.front().first) break;
      if (!bounded.empty() && bounded.front().bound > top) {  // it may be stronger than the candidate
        solveStrongestBounded();
        continue;
      }
      std::pop_heap(candidates.begin(), candidates.end(), lowerSeed);
      const int32_t point = candidates.back().second;
      candidates.pop_back();
      ++mEvaluations;
      const Voigt sigma = mField.atPoint(point);
      const double bound = principalBound(sigma);
      if (bound < threshold) continue;  // σ₁ < σ_t without its eigen solve
      bounded.push_back({bound, point, sigma});
      std::push_heap(bounded.begin(), bounded.end(), lowerBounded);
    }
    // The strongest of both: a bound that reaches the strongest σ₁ is solved first.
    while (!bounded.empty() && (evaluated.empty() || bounded.front().bound >= evaluated.front().first)) {
      solveStrongestBounded();
    }
    if (evaluated.empty()) return false;
    std::pop_heap(evaluated.begin(), evaluated.end(), lowerSeed);
    const int32_t point = evaluated.back().second;
    evaluated.pop_back();
    element = point / mScan.pointsPerElement;
    if (mScan.pointsPerElement > 1) {  // each element once, at its strongest point
      char& taken = mW.taken[static_cast<size_t>(element)];
      if (taken) continue;
      taken = 1;
    }
    return true;
  }
}

std::vector<int32_t> orderedSeeds(const StressScan& scan, const StressField& field) {
  SeedOrderWorkspace workspace;
  SeedOrder order(scan, field, workspace);
  std::vector<int32_t> seeds;
  for (int32_t e = 0; order.next(e);) seeds.push_back(e);
  return seeds;
}

void CrackWorkspace::reserve(Eigen::Index nodes, Eigen::Index tets, Eigen::Index edges, int cracks) {
  const auto n = static_cast<size_t>(nodes), t = static_cast<size_t>(tets), c = static_cast<size_t>(std::max(cracks, 1));
  front.reserve(4 * t);
  fronts.reserve(4 * t);
  seedOrder.candidates.reserve(4 * t);  // stress points: up to 4 per element (P2)
  seedOrder.evaluated.reserve(4 * t);
  seedOrder.bounded.reserve(4 * t);
  seedOrder.taken.reserve(t);
  cut.reserve(t);
  stressKnown.reserve(t);
  stressCache.reserve(t);
  phi.reserve(c * n);
  cutBy.reserve(c * t);
  seedNormals.reserve(c);
  for (auto* v : {&parent, &labelOfRoot, &size, &low, &root, &shared, &head, &tail, &touched, &next, &fill}) v->reserve(n);
  nodeMemo.stress.reserve(n);
  nodeMemo.known.reserve(n);
  start.reserve(n + 1);
  incident.reserve(2 * static_cast<size_t>(edges));
  stuck.reserve(n);
}

Result<FractureState> propagateCracks(const TetMesh& mesh, const TetTopology& topo, const StressScan& scan,
                                      const StressField& field, double sigmaT, double gc, double budget,
                                      const CrackSettings& settings) {
  CrackWorkspace workspace;
  FractureState state;
  if (Status st = propagateCracks(mesh, topo, scan, field, sigmaT, gc, budget, settings, workspace, state); !st) {
    return st.error();
  }
  return state;
}

Status propagateCracks(const TetMesh& mesh, const TetTopology& topo, const StressScan& scan, const StressField& field,
                       double sigmaT, double gc, double budget, const CrackSettings& settings, CrackWorkspace& w,
                       FractureState& state) {
  if (settings.maxCracks < 0 || std::isnan(settings.propagationStressRatio) || !(settings.directionBlend >= 0.0) ||
      !(settings.directionBlend <= 1.0) || !(settings.noiseRad >= 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "crack settings: maxCracks ≥ 0, propagationStressRatio not NaN, "
                                                 "directionBlend in [0, 1], noiseRad ≥ 0");
  }
  if (!(sigmaT > 0.0) || !(gc > 0.0) || !std::isfinite(budget)) {
    return makeError(ErrorCode::InvalidArgument, "crack growth needs σ_t > 0, G_c > 0 and a finite energy budget");
  }
  const Eigen::Index t = mesh.tets.rows();
  const auto nodeCount = static_cast<size_t>(mesh.nodes.rows()), tetCount = static_cast<size_t>(t);
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  state.clear();
  // Their bounds, so that a reused state never grows (HotPathAllocationTest: a later impact that
  // cut more than any before grew them): an element is listed once, and each crack gives it at
  // most one plane. Reserved, not touched: on the vase (6.6k tets, 6 cracks) 1.3 MB of address
  // space, of which its default hit writes a few per cent (1.4k cut elements).
  state.cutElements.reserve(tetCount);
  state.cutPlanes.reserve(static_cast<size_t>(std::max(settings.maxCracks, 1)) * tetCount);
  state.energyBudgetJ = budget;
  state.edgeCuts.swap(w.spareEdgeCuts);  // clear() left them empty: the spares' storage, if any
  state.nodeLabels.swap(w.spareNodeLabels);
  state.edgeCuts.resize(topo.edges.rows());
  state.edgeCuts.setConstant(kNaN);
  w.cut.assign(tetCount, 0);
  w.seedEvaluations = 0;
  w.front.clear();
  w.fronts.clear();
  w.seedNormals.clear();  // per crack: the plane it started on
  w.phi.clear();
  w.cutBy.clear();
  SplitMix64 draws(settings.seed);  // the seeded turns (nearNormal: the same bits on every platform)

  // Each crack is the zero set of a nodal level set φ_c, piecewise linear over the tets. A cut
  // element gives its plane's signed distance to those of its nodes that have no value yet; the
  // crack surface is where φ_c changes sign. Sharing nodal values makes the surface continuous
  // across elements, so a crack crosses a layer of elements instead of thickening into a blob, and
  // every edge it crosses is cut at the same point from every element around it.
  // Stresses at the peak instant, each computed once (an element is read by its cut neighbours),
  // with their largest principal value and direction (read when a front reaches the element: once,
  // where an element met by several cracks or fronts solved it each time). Growth computes each as
  // it needs it, on this thread. (A helper thread that computed ahead the stresses growth would ask
  // for next was tried, stops 59 to 67: once a P2 node's stress was memoised and an element's rows
  // summed four at a time it no longer paid. On the default objects the crack stage took 2–10 %
  // less without it in three interleaved rounds, and on the P1 slab 10 % less: its
  // hand-over cost more than the stresses it took over, and it kept the other core spinning.)
  w.stressCache.resize(tetCount);
  w.stressKnown.assign(tetCount, 0);
  auto stressAt = [&](int32_t e) -> const CrackWorkspace::Principal& {
    CrackWorkspace::Principal& p = w.stressCache[static_cast<size_t>(e)];
    if (!w.stressKnown[static_cast<size_t>(e)]) {
      p.stress = field.at(e);
      p.value = maxPrincipalStress(p.stress, &p.direction);
      w.stressKnown[static_cast<size_t>(e)] = 1;
    }
    return p;
  };
  // Per crack c: φ_c at w.phi[c·#N + node], and whether it cut element e at w.cutBy[c·#T + e]
  // (cracks cross each other, each needs its whole sheet).
  auto cutBy = [&](int32_t crack, int32_t e) -> char& { return w.cutBy[static_cast<size_t>(crack) * tetCount + static_cast<size_t>(e)]; };
  auto apply = [&](int32_t e, const Eigen::Vector3d& n, double offset, int32_t crack) -> bool {
    double* level = w.phi.data() + static_cast<size_t>(crack) * nodeCount;
    Eigen::Vector4d d;
    for (int i = 0; i < 4; ++i) {
      double& v = level[static_cast<size_t>(mesh.tets(e, i))];
      if (std::isnan(v)) v = n.dot(mesh.nodes.row(mesh.tets(e, i)).transpose()) - offset;
      d[i] = v;
    }
    if (!crosses(d)) return true;  // the crack surface misses this element: nothing to pay, nothing to cut
    const double area = sectionArea(mesh, e, d, n);
    const double cost = gc * area;
    if (state.energySpentJ + cost > budget) {
      state.arrestedByEnergy = true;
      return false;
    }
    state.energySpentJ += cost;
    state.crackAreaM2 += area;
    cutBy(crack, e) = 1;
    const bool junction = w.cut[static_cast<size_t>(e)] != 0;  // another crack cut it first
    if (!junction) state.cutElements.push_back(e);
    w.cut[static_cast<size_t>(e)] = 1;
    state.cutPlanes.emplace_back(n.x(), n.y(), n.z(), offset);
    for (int k = 0; k < 6; ++k) {
      const auto [i, j] = kTetEdges[static_cast<size_t>(k)];
      if ((d[i] > 0.0) == (d[j] > 0.0)) continue;
      const int32_t edge = topo.tetEdges(e, k);
      if (!std::isnan(state.edgeCuts[edge])) continue;  // the first crack through an edge places the cut
      const bool forward = topo.edges(edge, 0) == mesh.tets(e, i);
      const double sCut = d[i] / (d[i] - d[j]);
      state.edgeCuts[edge] = forward ? sCut : 1.0 - sCut;
    }
    // The neighbours the plane reaches through a face, each a front, pushed in face order; none
    // past another crack's surface where cracks end at cracks (CrackSettings::endAtCracks). Every
    // face path from one side of a sheet to the other passes through an element the sheet cuts
    // (an uncut element's nodes lie on one side), so such a crack cannot cross another.
    if (junction && settings.endAtCracks) return true;
    for (int f = 0; f < 4; ++f) {
      const int32_t nb = topo.neighbours(e, f);
      Eigen::Vector3d a, b;
      if (nb < 0 || cutBy(crack, nb) || !faceCut(mesh, e, f, d, a, b)) continue;
      const Voigt& sNb = stressAt(nb).stress;
      w.front.push_back({n.dot(tensor(sNb) * n), nb, static_cast<int32_t>(w.fronts.size())});
      w.fronts.push_back({crack, n, a, b});
      std::push_heap(w.front.begin(), w.front.end(), weaker);
    }
    return true;
  };

  // Seeds: strongest first; one crack per seed that is neither cut nor next to a cut element.
  SeedOrder seeds(scan, field, w.seedOrder);
  for (int32_t e = 0; seeds.next(e);) {
    if (state.crackCount >= settings.maxCracks || state.arrestedByEnergy) break;
    bool nearCut = w.cut[static_cast<size_t>(e)] != 0;
    for (int f = 0; f < 4 && !nearCut; ++f) {
      const int32_t nb = topo.neighbours(e, f);
      nearCut = nb >= 0 && w.cut[static_cast<size_t>(nb)];
    }
    if (nearCut) continue;
    const Eigen::Vector3d dir = stressAt(e).direction;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int i = 0; i < 4; ++i) centroid += 0.25 * mesh.nodes.row(mesh.tets(e, i)).transpose();
    w.seedNormals.push_back(dir);
    w.phi.insert(w.phi.end(), nodeCount, kNaN);
    w.cutBy.insert(w.cutBy.end(), tetCount, 0);
    if (!apply(e, dir, dir.dot(centroid), state.crackCount)) break;
    ++state.crackCount;
  }
  w.seedEvaluations = seeds.evaluations();
  // Fronts advance together, strongest normal stress first.
  while (!w.front.empty() && !state.arrestedByEnergy) {
    std::pop_heap(w.front.begin(), w.front.end(), weaker);
    const int32_t element = w.front.back().element;
    const CrackWorkspace::FrontPath& f = w.fronts[static_cast<size_t>(w.front.back().entry)];
    w.front.pop_back();
    if (cutBy(f.crack, element)) continue;
    const CrackWorkspace::Principal& principal = stressAt(element);
    const Voigt& s = principal.stress;
    const double s1 = principal.value;
    Eigen::Vector3d dir = principal.direction;
    if (dir.dot(f.normal) < 0.0) dir = -dir;
    // Blend with the crack's starting plane, not the parent's: blending with the parent would let
    // the noise accumulate into a random walk of orientations, and the sheet would curl up and fill
    // the body instead of running through it.
    Eigen::Vector3d start = w.seedNormals[static_cast<size_t>(f.crack)];
    if (start.dot(f.normal) < 0.0) start = -start;
    // The local direction steers in proportion to how close the tension is to σ_t: where the
    // stress is low its direction means little, and the crack runs on straight.
    const double steer = (1.0 - settings.directionBlend) * std::clamp(s1 / sigmaT, 0.0, 1.0);
    Eigen::Vector3d n = (1.0 - steer) * start + steer * dir;
    // Seeded turn: a random tangent direction scaled by noiseRad (one draw per statement), each
    // component of unit variance (nearNormal).
    const double gx = nearNormal(draws.next()), gy = nearNormal(draws.next()), gz = nearNormal(draws.next());
    Eigen::Vector3d turn(gx, gy, gz);
    n = n.normalized();
    turn -= turn.dot(n) * n;
    n = (n + settings.noiseRad * turn).normalized();
    // The new plane contains the parent's cut through the shared face, so the sheet is continuous
    // from element to element (and the shared edges are cut at the same points): keep only the
    // part of the wanted normal that is orthogonal to that segment.
    const Eigen::Vector3d along = (f.point2 - f.point).normalized();
    n = (n - n.dot(along) * along).normalized();
    if (!n.allFinite() || n.dot(f.normal) <= 0.0) n = f.normal;
    if (n.dot(tensor(s) * n) < settings.propagationStressRatio * sigmaT) continue;
    if (!apply(element, n, n.dot(f.point), f.crack)) break;
  }
  state.fragmentCount = labelFragments(topo, state.edgeCuts, mesh.nodes.rows(), state.nodeLabels, w);
  state.mergedCrumbs = mergeCrumbs(topo, settings.minFragmentNodes, state.edgeCuts, state.nodeLabels, state.fragmentCount, w);
  return Ok{};
}

int mergeCrumbs(const TetTopology& topo, int minNodes, Eigen::VectorXd& edgeCuts, Eigen::VectorXi& labels,
                int& fragmentCount) {
  CrackWorkspace workspace;
  return mergeCrumbs(topo, minNodes, edgeCuts, labels, fragmentCount, workspace);
}

int mergeCrumbs(const TetTopology& topo, int minNodes, Eigen::VectorXd& edgeCuts, Eigen::VectorXi& labels,
                int& fragmentCount, CrackWorkspace& w) {
  // The components as they come in (labels numbered by lowest node), merged one crumb at a time:
  // the smallest (ties: lowest first node, i.e. lowest label) joins the neighbour it shares most
  // cut edges with (ties: lowest first node). Merging two components that share edges and
  // un-cutting those edges gives exactly their union, so the components are tracked with a
  // union-find instead of relabelling the mesh after each merge; the labels are recomputed once.
  const int count = fragmentCount;
  const auto n = static_cast<size_t>(labels.size()), c = static_cast<size_t>(count);
  w.size.assign(c, 0);
  w.low.assign(c, std::numeric_limits<int32_t>::max());
  for (Eigen::Index i = 0; i < labels.size(); ++i) {
    const auto l = static_cast<size_t>(labels[i]);
    ++w.size[l];
    w.low[l] = std::min(w.low[l], static_cast<int32_t>(i));
  }
  if (std::none_of(w.size.begin(), w.size.end(), [&](int32_t k) { return k < minNodes; }) || count < 2) return 0;
  // Members of each component as linked lists (head, next, tail), so that a merge is a splice.
  w.head.assign(c, -1);
  w.tail.assign(c, -1);
  w.next.assign(n, -1);
  for (Eigen::Index i = 0; i < labels.size(); ++i) {
    const auto l = static_cast<size_t>(labels[i]);
    if (w.tail[l] < 0) w.head[l] = static_cast<int32_t>(i);
    else w.next[static_cast<size_t>(w.tail[l])] = static_cast<int32_t>(i);
    w.tail[l] = static_cast<int32_t>(i);
  }
  // Edges per node (CSR).
  w.start.assign(n + 1, 0);
  w.incident.resize(static_cast<size_t>(2 * topo.edges.rows()));
  for (Eigen::Index e = 0; e < topo.edges.rows(); ++e) {
    ++w.start[static_cast<size_t>(topo.edges(e, 0)) + 1];
    ++w.start[static_cast<size_t>(topo.edges(e, 1)) + 1];
  }
  std::partial_sum(w.start.begin(), w.start.end(), w.start.begin());
  w.fill.assign(w.start.begin(), w.start.end() - 1);
  for (Eigen::Index e = 0; e < topo.edges.rows(); ++e) {
    w.incident[static_cast<size_t>(w.fill[static_cast<size_t>(topo.edges(e, 0))]++)] = static_cast<int32_t>(e);
    w.incident[static_cast<size_t>(w.fill[static_cast<size_t>(topo.edges(e, 1))]++)] = static_cast<int32_t>(e);
  }
  w.root.resize(c);
  std::iota(w.root.begin(), w.root.end(), 0);
  auto find = [&](int32_t x) {
    while (w.root[static_cast<size_t>(x)] != x) {
      x = w.root[static_cast<size_t>(x)] = w.root[static_cast<size_t>(w.root[static_cast<size_t>(x)])];
    }
    return x;
  };
  auto componentOf = [&](int32_t node) { return find(labels[node]); };
  // Calls visit(edge, other node) for each edge from a member of component `from`.
  auto forEachEdgeOut = [&](int32_t from, auto&& visit) {
    for (int32_t v = w.head[static_cast<size_t>(from)]; v >= 0; v = w.next[static_cast<size_t>(v)]) {
      for (int32_t j = w.start[static_cast<size_t>(v)]; j < w.start[static_cast<size_t>(v) + 1]; ++j) {
        const auto e = w.incident[static_cast<size_t>(j)];
        visit(e, topo.edges(e, 0) == v ? topo.edges(e, 1) : topo.edges(e, 0));
      }
    }
  };
  w.stuck.assign(c, 0);  // a crumb with no neighbour (a mesh in pieces)
  w.shared.assign(c, 0);
  int merged = 0, alive = count;
  while (alive > 1) {
    int32_t crumb = -1;
    for (int32_t k = 0; k < count; ++k) {
      const auto i = static_cast<size_t>(k);
      if (w.root[i] != k || w.stuck[i] || w.size[i] >= minNodes) continue;
      if (crumb < 0 || w.size[i] < w.size[static_cast<size_t>(crumb)] ||
          (w.size[i] == w.size[static_cast<size_t>(crumb)] && w.low[i] < w.low[static_cast<size_t>(crumb)])) {
        crumb = k;
      }
    }
    if (crumb < 0) break;
    w.touched.clear();
    forEachEdgeOut(crumb, [&](int32_t, int32_t other) {
      const int32_t k = componentOf(other);
      if (k != crumb && w.shared[static_cast<size_t>(k)]++ == 0) w.touched.push_back(k);
    });
    int32_t into = -1;
    for (int32_t k : w.touched) {
      const auto i = static_cast<size_t>(k);
      if (into < 0 || w.shared[i] > w.shared[static_cast<size_t>(into)] ||
          (w.shared[i] == w.shared[static_cast<size_t>(into)] && w.low[i] < w.low[static_cast<size_t>(into)])) {
        into = k;
      }
    }
    for (int32_t k : w.touched) w.shared[static_cast<size_t>(k)] = 0;
    if (into < 0) {
      w.stuck[static_cast<size_t>(crumb)] = 1;
      continue;
    }
    forEachEdgeOut(crumb, [&](int32_t e, int32_t other) {
      if (componentOf(other) == into) edgeCuts[e] = std::numeric_limits<double>::quiet_NaN();
    });
    const auto a = static_cast<size_t>(into), b = static_cast<size_t>(crumb);
    w.root[b] = into;
    w.size[a] += w.size[b];
    w.low[a] = std::min(w.low[a], w.low[b]);
    w.next[static_cast<size_t>(w.tail[a])] = w.head[b];  // splice b's members after a's
    w.tail[a] = w.tail[b];
    w.head[b] = w.tail[b] = -1;
    ++merged;
    --alive;
  }
  if (merged > 0) fragmentCount = labelFragments(topo, edgeCuts, labels.size(), labels, w);
  return merged;
}

int labelFragments(const TetTopology& topo, const Eigen::VectorXd& edgeCuts, Eigen::Index nodeCount,
                   Eigen::VectorXi& labels) {
  CrackWorkspace workspace;
  return labelFragments(topo, edgeCuts, nodeCount, labels, workspace);
}

int labelFragments(const TetTopology& topo, const Eigen::VectorXd& edgeCuts, Eigen::Index nodeCount,
                   Eigen::VectorXi& labels, CrackWorkspace& w) {
  std::vector<int32_t>& parent = w.parent;
  parent.resize(static_cast<size_t>(nodeCount));
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int32_t x) {
    while (parent[static_cast<size_t>(x)] != x) {
      parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];
      x = parent[static_cast<size_t>(x)];
    }
    return x;
  };
  for (Eigen::Index e = 0; e < topo.edges.rows(); ++e) {
    if (!std::isnan(edgeCuts[e])) continue;
    const int32_t a = find(topo.edges(e, 0)), b = find(topo.edges(e, 1));
    if (a != b) parent[static_cast<size_t>(std::max(a, b))] = std::min(a, b);  // root = lowest node
  }
  labels.resize(nodeCount);
  w.labelOfRoot.assign(static_cast<size_t>(nodeCount), -1);
  int count = 0;
  for (Eigen::Index i = 0; i < nodeCount; ++i) {
    int32_t& l = w.labelOfRoot[static_cast<size_t>(find(static_cast<int32_t>(i)))];
    if (l < 0) l = count++;
    labels[i] = l;
  }
  return count;
}

}  // namespace brittle

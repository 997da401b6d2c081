#include "brittle/descriptors/VolumeMoments.h"

#include <Eigen/Dense>
#include <cassert>
#include <cmath>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "MonomialTables.h"
#include "SurfaceChecks.h"

namespace brittle {

namespace detail {

const MonomialTables& monomialTables() {
  static const MonomialTables tables = [] {
    MonomialTables t;
    const int count = monomialCount(kMaxMomentOrder);
    t.exponents.resize(count);
    t.degree.resize(count);
    t.parent.assign(count, -1);
    t.parentVar.assign(count, -1);
    t.times.assign(count, {-1, -1, -1});
    t.lower.assign(count, {-1, -1, -1});
    t.factorial.resize(count);
    t.multinomial.resize(count);
    int i = 0;
    for (int n = 0; n <= kMaxMomentOrder; ++n) {
      for (int p = n; p >= 0; --p) {
        for (int q = n - p; q >= 0; --q) {
          const int r = n - p - q;
          t.exponents[i] = {p, q, r};
          t.degree[i] = n;
          t.lookup[p][q][r] = i;
          ++i;
        }
      }
    }
    auto fact = [](int k) {
      double f = 1.0;
      for (int j = 2; j <= k; ++j) f *= j;
      return f;
    };
    for (int m = 0; m < count; ++m) {
      const auto [p, q, r] = t.exponents[m];
      t.factorial[m] = fact(p) * fact(q) * fact(r);
      t.multinomial[m] = fact(p + q + r) / t.factorial[m];
      t.lower[m] = {p > 0 ? t.lookup[p - 1][q][r] : -1, q > 0 ? t.lookup[p][q - 1][r] : -1,
                    r > 0 ? t.lookup[p][q][r - 1] : -1};
      if (t.degree[m] < kMaxMomentOrder) {
        t.times[m] = {t.lookup[p + 1][q][r], t.lookup[p][q + 1][r], t.lookup[p][q][r + 1]};
      }
      // The parent drops one power of the first variable present, so every monomial is its
      // parent times one variable.
      if (p > 0) {
        t.parent[m] = t.lookup[p - 1][q][r], t.parentVar[m] = 0;
      } else if (q > 0) {
        t.parent[m] = t.lookup[p][q - 1][r], t.parentVar[m] = 1;
      } else if (r > 0) {
        t.parent[m] = t.lookup[p][q][r - 1], t.parentVar[m] = 2;
      }
    }
    return t;
  }();
  return tables;
}

}  // namespace detail

int monomialIndex(int p, int q, int r) {
  assert(p >= 0 && q >= 0 && r >= 0 && p + q + r <= kMaxMomentOrder);
  return detail::monomialTables().lookup[p][q][r];
}

std::array<int, 3> monomialExponents(int index) { return detail::monomialTables().exponents[index]; }

namespace {

// Powers u_j^k for k ≤ order, so a directional moment costs one product per monomial.
struct Powers {
  double x[kMaxMomentOrder + 1], y[kMaxMomentOrder + 1], z[kMaxMomentOrder + 1];
  Powers(const Eigen::Vector3d& u, int order) {
    x[0] = y[0] = z[0] = 1.0;
    for (int k = 1; k <= order; ++k) x[k] = x[k - 1] * u.x(), y[k] = y[k - 1] * u.y(), z[k] = z[k - 1] * u.z();
  }
};

}  // namespace

double VolumeMoments::directional(const Eigen::Vector3d& u, int order) const {
  assert(order >= 0 && order <= maxOrder);
  const auto& t = detail::monomialTables();
  const Powers pw(u, order);
  double sum = 0.0;
  // n!/(p!q!r!) from the table: the same quotient as dividing here, without a division a term.
  for (int m = monomialCount(order - 1); m < monomialCount(order); ++m) {
    const auto [p, q, r] = t.exponents[m];
    sum += t.multinomial[m] * pw.x[p] * pw.y[q] * pw.z[r] * values[m];
  }
  return sum;
}

namespace {

// VolumeMoments::directional for directions [0, L⌊count/L⌋), L to a register: each lane takes
// the scalar loop's operations in its order (the powers, then each term's products left to right
// and the sum from 0.0), so each value is the same bits. Returns how many it did.
template <int L>
[[gnu::always_inline]] inline size_t directionalInLanes(const VolumeMoments& moments, const Eigen::Vector3d* u, size_t count,
                                                        int order, double* out) {
  using Pack = VectorOf<double, L>;
  const auto& t = detail::monomialTables();
  const int begin = monomialCount(order - 1), end = monomialCount(order);
  const size_t packs = count / L;
  for (size_t i = 0; i < packs; ++i) {
    Pack x[kMaxMomentOrder + 1], y[kMaxMomentOrder + 1], z[kMaxMomentOrder + 1], ux, uy, uz;
    for (int l = 0; l < L; ++l) {
      const Eigen::Vector3d& d = u[L * i + l];
      x[0][l] = y[0][l] = z[0][l] = 1.0;
      ux[l] = d.x(), uy[l] = d.y(), uz[l] = d.z();
    }
    for (int k = 1; k <= order; ++k) x[k] = x[k - 1] * ux, y[k] = y[k - 1] * uy, z[k] = z[k - 1] * uz;
    Pack sum = {};
    for (int m = begin; m < end; ++m) {
      const auto [p, q, r] = t.exponents[m];
      sum += t.multinomial[m] * x[p] * y[q] * z[r] * moments.values[m];
    }
    std::memcpy(out + L * i, &sum, sizeof sum);
  }
  return L * packs;
}

size_t directionalNarrow(const VolumeMoments& moments, const Eigen::Vector3d* u, size_t count, int order, double* out) {
  return directionalInLanes<2>(moments, u, count, order, out);
}

BRITTLE_TARGET_AVX size_t directionalWide(const VolumeMoments& moments, const Eigen::Vector3d* u, size_t count, int order,
                                          double* out) {
  return directionalInLanes<4>(moments, u, count, order, out);
}

}  // namespace

namespace detail {

void directional(const VolumeMoments& moments, const Eigen::Vector3d* u, size_t count, int order, double* out, Lanes lanes) {
  assert(order >= 0 && order <= moments.maxOrder);
  size_t k = lanes == Lanes::Wide ? directionalWide(moments, u, count, order, out)
                                  : directionalNarrow(moments, u, count, order, out);
  for (; k < count; ++k) out[k] = moments.directional(u[k], order);
}

}  // namespace detail

void VolumeMoments::directional(const Eigen::Vector3d* u, size_t count, int order, double* out) const {
  detail::directional(*this, u, count, order, out, widestLanes());
}

Eigen::Vector3d VolumeMoments::directionalGradient(const Eigen::Vector3d& u, int order) const {
  assert(order >= 1 && order <= maxOrder);
  const auto& t = detail::monomialTables();
  const Powers pw(u, order);
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  for (int m = monomialCount(order - 1); m < monomialCount(order); ++m) {
    const auto [p, q, r] = t.exponents[m];
    const double c = t.multinomial[m] * values[m];
    if (p > 0) g.x() += c * p * pw.x[p - 1] * pw.y[q] * pw.z[r];
    if (q > 0) g.y() += c * q * pw.x[p] * pw.y[q - 1] * pw.z[r];
    if (r > 0) g.z() += c * r * pw.x[p] * pw.y[q] * pw.z[r - 1];
  }
  return g;
}

Result<VolumeMoments> computeVolumeMoments(const TriangleMesh& surface, int maxOrder,
                                           const Eigen::Vector3d& originM) {
  if (maxOrder < 0 || maxOrder > kMaxMomentOrder) {
    return makeError(ErrorCode::InvalidArgument, "maxOrder " + std::to_string(maxOrder) +
                                                     " is outside [0, " + std::to_string(kMaxMomentOrder) + "]");
  }
  if (!originM.allFinite()) return makeError(ErrorCode::NonFiniteValue, "originM is not finite");
  if (auto status = detail::checkClosedSurface(surface); !status) return status.error();

  const auto& t = detail::monomialTables();
  const int count = monomialCount(maxOrder);
  // Coefficient arrays in u of h_n(A), h_n(A,B), h_n(A,B,C), all degrees ≤ maxOrder at once, in
  // gather form: [u^α] (w·u) P = Σ_{j: α_j > 0} w_j [u^(α−e_j)] P.
  std::vector<double> ha(count), hab(count), habc(count), sum(count, 0.0);
  ha[0] = hab[0] = habc[0] = 1.0;
  // Order 4 and above (the canonical frames' and the default descriptor's 4, the polynomial modes'
  // 10): two or four faces at a time, the same arithmetic lane by lane, so the sums are this loop's
  // bit for bit (surfaceMoments); this loop does the faces left over, and orders below 4.
  const Eigen::Index paired = detail::surfaceMoments(surface, originM, maxOrder, sum.data(), widestLanes());
  for (Eigen::Index f = paired; f < surface.faces.rows(); ++f) {
    const Eigen::Vector3d a = surface.vertices.row(surface.faces(f, 0)).transpose() - originM;
    const Eigen::Vector3d b = surface.vertices.row(surface.faces(f, 1)).transpose() - originM;
    const Eigen::Vector3d c = surface.vertices.row(surface.faces(f, 2)).transpose() - originM;
    const double det = a.dot(b.cross(c));
    sum[0] += det;
    for (int m = 1; m < count; ++m) {
      const auto& src = t.lower[m];
      double sa = 0.0, sb = 0.0, sc = 0.0;
      for (int j = 0; j < 3; ++j) {
        if (src[j] < 0) continue;
        sa += a[j] * ha[src[j]];
        sb += b[j] * hab[src[j]];
        sc += c[j] * habc[src[j]];
      }
      ha[m] = sa;
      hab[m] = sa + sb;
      habc[m] = sa + sb + sc;
      sum[m] += det * habc[m];
    }
  }

  VolumeMoments out;
  out.maxOrder = maxOrder;
  out.values.resize(count);
  for (int m = 0; m < count; ++m) {
    double denominator = 1.0;  // (n+3)!
    for (int j = 2; j <= t.degree[m] + 3; ++j) denominator *= j;
    out.values[m] = sum[m] * t.factorial[m] / denominator;
  }
  return out;
}

namespace {

// The gather step of the recurrences for four vertices, monomial m from its lower monomials.
// h[0..3] are the coefficient arrays of h(A), h(A,B), h(A,B,C), h(A,B,C,D); p[v][j] is vertex v's
// coordinate j. The value is a double or a register of tets in lanes, with the same operations.
// The monomial's integral over the tet, up to det × scale, is then h[3][m].
template <class Lower, class Points, class Coefficients>
[[gnu::always_inline]] inline void tetMonomial(const Lower& lower, int m, const Points& p, Coefficients& h) {
  using Value = std::remove_cvref_t<decltype(h[0][0])>;
  Value s[4] = {};
  for (int j = 0; j < 3; ++j) {
    const int src = lower[j];
    if (src < 0) continue;
    for (int v = 0; v < 4; ++v) s[v] += p[v][j] * h[v][src];
  }
  h[0][m] = s[0];
  h[1][m] = h[0][m] + s[1];
  h[2][m] = h[1][m] + s[2];
  h[3][m] = h[2][m] + s[3];
}

// Order 4 with tables known at compile time, so that the loop unrolls into straight-line code.
struct Order4Tables {
  static constexpr int kCount = monomialCount(4);
  std::array<std::array<int, 3>, kCount> lower{};
  std::array<double, kCount> scale{};  // α! / (n+3)!
};

constexpr Order4Tables makeOrder4Tables() {
  Order4Tables t;
  int index[5][5][5] = {};
  int i = 0;
  for (int n = 0; n <= 4; ++n) {
    for (int p = n; p >= 0; --p) {
      for (int q = n - p; q >= 0; --q) index[p][q][n - p - q] = i++;
    }
  }
  auto fact = [](int k) {
    double f = 1.0;
    for (int j = 2; j <= k; ++j) f *= j;
    return f;
  };
  for (int n = 0; n <= 4; ++n) {
    for (int p = n; p >= 0; --p) {
      for (int q = n - p; q >= 0; --q) {
        const int r = n - p - q, m = index[p][q][r];
        t.lower[m] = {p > 0 ? index[p - 1][q][r] : -1, q > 0 ? index[p][q - 1][r] : -1, r > 0 ? index[p][q][r - 1] : -1};
        t.scale[m] = fact(p) * fact(q) * fact(r) / fact(n + 3);
      }
    }
  }
  return t;
}

constexpr Order4Tables kOrder4 = makeOrder4Tables();

// computeVolumeMoments' loop for faces [0, L⌊F/L⌋), L faces at a time: lane l of each register
// (two doubles to an SSE2 register, four to an AVX one) holds face f + l, and every lane takes the
// generic loop's operations in its order (a sum from 0.0, a product then a sum, no fused
// multiply-add), so each face's h values are the same bits; sum[m] takes face f's term, then
// f + 1's and so on, as the generic loop adds them. Returns the number of faces done. Count > 0:
// that many monomials with tables known at compile time (order 4: the loop unrolls into
// straight-line code, 71 → 37–41 ns a face with two lanes); Count = 0: `count` monomials, the
// tables read at run time (orders above 4: the polynomial modes' order 10).
template <int L, int Count, class Lower>
[[gnu::always_inline]] inline Eigen::Index momentsInLanes(const TriangleMesh& surface, const Eigen::Vector3d& originM, int count,
                                                          const Lower& lower, double* sum) {
  using Pack = VectorOf<double, L>;
  constexpr int kSize = Count > 0 ? Count : monomialCount(kMaxMomentOrder);
  const int monomials = Count > 0 ? Count : count;
  const Eigen::Index packs = surface.faces.rows() / L;
  Pack ha[kSize], hab[kSize], habc[kSize];
  Pack one;
  for (int l = 0; l < L; ++l) one[l] = 1.0;
  ha[0] = hab[0] = habc[0] = one;
  for (Eigen::Index i = 0; i < packs; ++i) {
    // Filled lane by lane (faster here than loading them from arrays); GCC 12 takes the lane stores
    // for reads of unset registers and warns.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
    Pack a[3], b[3], c[3], dets;
    for (int l = 0; l < L; ++l) {
      Eigen::Vector3d v[3];
      for (int k = 0; k < 3; ++k) v[k] = surface.vertices.row(surface.faces(L * i + l, k)).transpose() - originM;
      dets[l] = v[0].dot(v[1].cross(v[2]));
      for (int j = 0; j < 3; ++j) a[j][l] = v[0][j], b[j][l] = v[1][j], c[j][l] = v[2][j];
    }
#pragma GCC diagnostic pop
    for (int l = 0; l < L; ++l) sum[0] += dets[l];
#pragma GCC unroll 40
    for (int m = 1; m < monomials; ++m) {
      Pack sa = {}, sb = {}, sc = {};
      for (int j = 0; j < 3; ++j) {
        const int src = lower[m][j];
        if (src < 0) continue;
        sa += a[j] * ha[src];
        sb += b[j] * hab[src];
        sc += c[j] * habc[src];
      }
      ha[m] = sa;
      hab[m] = sa + sb;
      habc[m] = sa + sb + sc;
      const Pack term = dets * habc[m];
      for (int l = 0; l < L; ++l) sum[m] += term[l];
    }
  }
  return L * packs;
}

Eigen::Index momentsNarrow(const TriangleMesh& surface, const Eigen::Vector3d& originM, int maxOrder, double* sum) {
  return momentsInLanes<2, 0>(surface, originM, monomialCount(maxOrder), detail::monomialTables().lower, sum);
}

BRITTLE_TARGET_AVX Eigen::Index momentsWide(const TriangleMesh& surface, const Eigen::Vector3d& originM, int maxOrder,
                                            double* sum) {
  return momentsInLanes<4, 0>(surface, originM, monomialCount(maxOrder), detail::monomialTables().lower, sum);
}

Eigen::Index momentsOrder4Narrow(const TriangleMesh& surface, const Eigen::Vector3d& originM, double* sum) {
  return momentsInLanes<2, Order4Tables::kCount>(surface, originM, Order4Tables::kCount, kOrder4.lower, sum);
}

BRITTLE_TARGET_AVX Eigen::Index momentsOrder4Wide(const TriangleMesh& surface, const Eigen::Vector3d& originM,
                                                  double* sum) {
  return momentsInLanes<4, Order4Tables::kCount>(surface, originM, Order4Tables::kCount, kOrder4.lower, sum);
}

// addTetVolumeMoments at order 4 for tets [0, L⌊count/L⌋), L at a time: lane l holds tet i + l,
// and every lane takes the scalar kernel's operations in its order (the determinant by the same
// Eigen expression, sums from 0.0, (det × scale) × h, no fused multiply-add), so each tet's terms
// are the same bits, added to values[m] in tet order as successive calls add them. Returns the
// number of tets done.
template <int L>
[[gnu::always_inline]] inline int tetMomentsOrder4InLanes(const std::array<Eigen::Vector3d, 4>* tets, int count,
                                                          double* values) {
  using Pack = VectorOf<double, L>;
  constexpr int n = Order4Tables::kCount;
  const int packs = count / L;
  Pack h[4][n];  // h(A), h(A,B), h(A,B,C), h(A,B,C,D), as tetMonomial's
  Pack one;
  for (int l = 0; l < L; ++l) one[l] = 1.0;
  h[0][0] = h[1][0] = h[2][0] = h[3][0] = one;
  for (int i = 0; i < packs; ++i) {
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
    Pack p[4][3], dets;
    for (int l = 0; l < L; ++l) {
      const std::array<Eigen::Vector3d, 4>& t = tets[L * i + l];
      dets[l] = (t[1] - t[0]).dot((t[2] - t[0]).cross(t[3] - t[0]));
      for (int v = 0; v < 4; ++v)
        for (int j = 0; j < 3; ++j) p[v][j][l] = t[static_cast<size_t>(v)][j];
    }
#pragma GCC diagnostic pop
    for (int l = 0; l < L; ++l) values[0] += dets[l] * kOrder4.scale[0];
#pragma GCC unroll 40
    for (int m = 1; m < n; ++m) {
      tetMonomial(kOrder4.lower[m], m, p, h);
      const Pack term = (dets * kOrder4.scale[m]) * h[3][m];
      for (int l = 0; l < L; ++l) values[m] += term[l];
    }
  }
  return L * packs;
}

int tetMomentsOrder4Narrow(const std::array<Eigen::Vector3d, 4>* tets, int count, double* values) {
  return tetMomentsOrder4InLanes<2>(tets, count, values);
}

BRITTLE_TARGET_AVX int tetMomentsOrder4Wide(const std::array<Eigen::Vector3d, 4>* tets, int count, double* values) {
  return tetMomentsOrder4InLanes<4>(tets, count, values);
}

}  // namespace

namespace detail {

void tetMomentsOrder4(const std::array<Eigen::Vector3d, 4>* tets, int count, double* values, Lanes lanes) {
  int done = lanes == Lanes::Wide ? tetMomentsOrder4Wide(tets, count, values) : 0;
  done += tetMomentsOrder4Narrow(tets + done, count - done, values);  // a pair left after fours, or pairs
  for (; done < count; ++done) {
    const std::array<Eigen::Vector3d, 4>& t = tets[done];
    addTetVolumeMoments(t[0], t[1], t[2], t[3], 4, values);
  }
}

Eigen::Index surfaceMomentsOrder4(const TriangleMesh& surface, const Eigen::Vector3d& originM, double* sum, Lanes lanes) {
  return lanes == Lanes::Wide ? momentsOrder4Wide(surface, originM, sum) : momentsOrder4Narrow(surface, originM, sum);
}

Eigen::Index surfaceMoments(const TriangleMesh& surface, const Eigen::Vector3d& originM, int maxOrder, double* sum, Lanes lanes) {
  if (maxOrder == 4) return surfaceMomentsOrder4(surface, originM, sum, lanes);
  if (maxOrder < 4) return 0;
  return lanes == Lanes::Wide ? momentsWide(surface, originM, maxOrder, sum) : momentsNarrow(surface, originM, maxOrder, sum);
}

}  // namespace detail

void addTetVolumeMomentsOrder4(const std::array<Eigen::Vector3d, 4>* tets, int count, double* values) {
  detail::tetMomentsOrder4(tets, count, values, widestLanes());
}

void addTetVolumeMoments(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                         const Eigen::Vector3d& d, int maxOrder, double* values) {
  assert(maxOrder >= 0 && maxOrder <= kMaxMomentOrder);
  const Eigen::Vector3d p[4] = {a, b, c, d};
  const double det = (b - a).dot((c - a).cross(d - a));
  if (maxOrder == 4) {
    constexpr int count = Order4Tables::kCount;
    double ha[count], hab[count], habc[count], habcd[count];
    double* h[4] = {ha, hab, habc, habcd};
    ha[0] = hab[0] = habc[0] = habcd[0] = 1.0;
    values[0] += det * kOrder4.scale[0];
#pragma GCC unroll 40
    for (int m = 1; m < count; ++m) {
      tetMonomial(kOrder4.lower[m], m, p, h);
      values[m] += det * kOrder4.scale[m] * habcd[m];
    }
    return;
  }
  const auto& t = detail::monomialTables();
  const int count = monomialCount(maxOrder);
  std::array<double, monomialCount(kMaxMomentOrder)> ha, hab, habc, habcd;
  double* h[4] = {ha.data(), hab.data(), habc.data(), habcd.data()};
  ha[0] = hab[0] = habc[0] = habcd[0] = 1.0;
  auto scale = [&](int m) {
    double denominator = 1.0;  // (n+3)!
    for (int j = 2; j <= t.degree[m] + 3; ++j) denominator *= j;
    return t.factorial[m] / denominator;
  };
  values[0] += det * scale(0);
  for (int m = 1; m < count; ++m) {
    tetMonomial(t.lower[m], m, p, h);
    values[m] += det * scale(m) * habcd[m];
  }
}

VolumeMoments transformVolumeMoments(const VolumeMoments& moments, const Eigen::Matrix3d& linearMap,
                                     const Eigen::Vector3d& offset) {
  const auto& t = detail::monomialTables();
  const int count = monomialCount(moments.maxOrder);
  // poly.row(β) holds the coefficients in x of (A(x − b))^β, built from its parent by one product
  // with the affine form y_j = A_j·x − A_j·b.
  Eigen::MatrixXd poly = Eigen::MatrixXd::Zero(count, count);
  poly(0, 0) = 1.0;
  const Eigen::Vector3d shift = -(linearMap * offset);
  for (int beta = 1; beta < count; ++beta) {
    const int parent = t.parent[beta], j = t.parentVar[beta];
    const int parentEnd = monomialCount(t.degree[parent]);
    for (int m = 0; m < parentEnd; ++m) {
      const double coeff = poly(parent, m);
      if (coeff == 0.0) continue;
      poly(beta, m) += coeff * shift[j];
      const auto& up = t.times[m];
      for (int k = 0; k < 3; ++k) poly(beta, up[k]) += coeff * linearMap(j, k);
    }
  }
  VolumeMoments out;
  out.maxOrder = moments.maxOrder;
  out.values = std::abs(linearMap.determinant()) * (poly * moments.values);
  return out;
}

}  // namespace brittle

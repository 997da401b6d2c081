#include "SupernodalCholesky.h"

#include "Cancellation.h"

#include "brittle/database/ObjectAsset.h"  // isPermutation

#include <Eigen/Cholesky>
#include <Eigen/OrderingMethods>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>

namespace brittle::detail {

bool SupernodalCholesky::compute(const Eigen::SparseMatrix<double>& a, Eigen::Index block) {
  *this = SupernodalCholesky{};
  const Eigen::Index n = a.rows();
  if (n == 0 || a.cols() != n || n > INT32_MAX / 2) return false;
  // The elimination order: AMD on the symmetric pattern (Eigen's, which returns the inverse
  // permutation), of the nodes' graph where the DOF come in blocks of `block` (each node's DOF then
  // eliminated together, in order: a ninth of the entries to order, and panels at least a block
  // wide), else of the DOF's own.
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> inverse(n);
  if (block > 1 && n % block == 0) {
    const Eigen::Index nodes = n / block;
    // The nodes' graph from the lower triangle's node blocks, a column per node with its rows
    // sorted and unique (Eigen's AMD orders the pattern of G + Gᵀ).
    std::vector<int> outer(static_cast<size_t>(nodes) + 1, 0), inner;
    std::vector<int> seen(static_cast<size_t>(nodes), -1);
    inner.reserve(static_cast<size_t>(a.nonZeros() / (block * block)) + static_cast<size_t>(nodes));
    for (Eigen::Index w = 0; w < nodes; ++w) {
      const size_t from = inner.size();
      for (Eigen::Index col = w * block; col < (w + 1) * block; ++col)
        for (Eigen::SparseMatrix<double>::InnerIterator it(a, col); it; ++it) {
          const auto v = static_cast<int>(it.row() / block);
          if (it.row() >= col && seen[static_cast<size_t>(v)] != w) {
            seen[static_cast<size_t>(v)] = static_cast<int>(w);
            inner.push_back(v);
          }
        }
      std::sort(inner.begin() + static_cast<std::ptrdiff_t>(from), inner.end());
      outer[static_cast<size_t>(w) + 1] = static_cast<int>(inner.size());
    }
    const std::vector<double> ones(inner.size(), 1.0);
    const Eigen::SparseMatrix<double> graph = Eigen::Map<const Eigen::SparseMatrix<double>>(
        nodes, nodes, static_cast<Eigen::Index>(inner.size()), outer.data(), inner.data(), ones.data());
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> nodeInverse;
    Eigen::AMDOrdering<int> amd;
    amd(graph, nodeInverse);
    for (Eigen::Index k = 0; k < nodes; ++k)
      for (Eigen::Index c = 0; c < block; ++c) inverse.indices()[k * block + c] = static_cast<int>(nodeInverse.indices()[k] * block + c);
  } else {
    const Eigen::SparseMatrix<double> full = a.selfadjointView<Eigen::Lower>();
    Eigen::AMDOrdering<int> amd;
    amd(full, inverse);
  }
  return computeInOrder(a, inverse.indices());
}

bool SupernodalCholesky::computeInOrder(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXi& order) {
  *this = SupernodalCholesky{};
  const Eigen::Index n = a.rows();
  if (n == 0 || a.cols() != n || n > INT32_MAX / 2 || !isPermutation(order, n)) return false;
  for (Eigen::Index col = 0; col < n; ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, col); it; ++it)
      if (it.row() >= col && !std::isfinite(it.value())) return false;
  using Permutation = Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int>;
  Permutation inverse(n);
  inverse.indices() = order;
  const Permutation p = inverse.inverse();
  Eigen::SparseMatrix<double> ap(n, n);
  ap.selfadjointView<Eigen::Upper>() = a.selfadjointView<Eigen::Lower>().twistedBy(p);
  mPerm.assign(inverse.indices().data(), inverse.indices().data() + n);

  // The elimination tree and each column's count below the diagonal, row by row (Liu's row
  // subtrees, as SimplicialLDLT's analysis): ap's upper triangle holds row k's entries left of k.
  const auto count = static_cast<size_t>(n);
  std::vector<int32_t> parent(count, -1), tag(count), below(count, 0);
  for (int32_t k = 0; k < static_cast<int32_t>(n); ++k) {
    if (k % 4096 == 0) cancellationPoint();
    tag[static_cast<size_t>(k)] = k;
    for (Eigen::SparseMatrix<double>::InnerIterator it(ap, k); it; ++it) {
      for (auto i = static_cast<int32_t>(it.row()); i < k && tag[static_cast<size_t>(i)] != k; i = parent[static_cast<size_t>(i)]) {
        if (parent[static_cast<size_t>(i)] == -1) parent[static_cast<size_t>(i)] = k;
        ++below[static_cast<size_t>(i)];
        tag[static_cast<size_t>(i)] = k;
      }
    }
  }

  // Supernodes: column j joins j − 1's when j − 1's pattern is j's plus j.
  mFirst.push_back(0);
  for (int32_t j = 1; j < static_cast<int32_t>(n); ++j) {
    const size_t prev = static_cast<size_t>(j) - 1;
    if (!(parent[prev] == j && below[prev] == below[static_cast<size_t>(j)] + 1)) mFirst.push_back(j);
  }
  mFirst.push_back(static_cast<int32_t>(n));
  const size_t supernodes = mFirst.size() - 1;
  std::vector<int32_t> superOf(count);
  for (size_t s = 0; s < supernodes; ++s)
    for (int32_t j = mFirst[s]; j < mFirst[s + 1]; ++j) superOf[static_cast<size_t>(j)] = static_cast<int32_t>(s);

  // Each supernode's rows below its columns: its columns' entries below them and its children's
  // rows below them (a child: a supernode whose last column's parent is one of its columns).
  std::vector<std::vector<int32_t>> rowsBelow(supernodes);
  std::vector<int32_t> firstChild(supernodes, -1), nextSibling(supernodes, -1), mark(count, -1);
  for (size_t s = supernodes; s-- > 0;) {
    const int32_t up = parent[static_cast<size_t>(mFirst[s + 1]) - 1];
    if (up < 0) continue;
    const auto u = static_cast<size_t>(superOf[static_cast<size_t>(up)]);
    nextSibling[s] = firstChild[u];
    firstChild[u] = static_cast<int32_t>(s);
  }
  // ap's lower triangle by columns, for each supernode's own entries.
  Eigen::SparseMatrix<double> lower(n, n);
  lower = ap.transpose();
  mRowsAt.assign(supernodes + 1, 0);
  mValuesAt.assign(supernodes + 1, 0);
  size_t widest = 0;
  for (size_t s = 0; s < supernodes; ++s) {
    if (s % 256 == 0) cancellationPoint();
    const int32_t f = mFirst[s], l = mFirst[s + 1];
    std::vector<int32_t>& rows = rowsBelow[s];
    auto add = [&](int32_t r) {
      if (r >= l && mark[static_cast<size_t>(r)] != static_cast<int32_t>(s)) {
        mark[static_cast<size_t>(r)] = static_cast<int32_t>(s);
        rows.push_back(r);
      }
    };
    for (int32_t j = f; j < l; ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(lower, j); it; ++it) add(static_cast<int32_t>(it.row()));
    for (int32_t c = firstChild[s]; c >= 0; c = nextSibling[static_cast<size_t>(c)]) {
      for (int32_t r : rowsBelow[static_cast<size_t>(c)]) add(r);
      rowsBelow[static_cast<size_t>(c)] = {};
    }
    std::sort(rows.begin(), rows.end());
    assert(static_cast<int32_t>(rows.size()) == below[static_cast<size_t>(l) - 1]);
    for (int32_t j = f; j < l; ++j) mRows.push_back(j);
    mRows.insert(mRows.end(), rows.begin(), rows.end());
    const auto k = static_cast<int64_t>(l - f), m = k + static_cast<int64_t>(rows.size());
    mRowsAt[s + 1] = mRowsAt[s] + m;
    mValuesAt[s + 1] = mValuesAt[s] + m * k;
    mNonZeros += k * (k + 1) / 2 + (m - k) * k;
    widest = std::max(widest, rows.size());
  }
  rowsBelow = {};
  if (mNonZeros - n > INT32_MAX) return false;  // toUnitLower's 32-bit column starts
  mValues.assign(static_cast<size_t>(mValuesAt[supernodes]), 0.0);
  ap = std::move(lower);

  // P A Pᵀ's lower triangle into the panels.
  std::vector<int32_t> position(count, -1);
  auto place = [&](size_t s) {
    for (int64_t i = mRowsAt[s]; i < mRowsAt[s + 1]; ++i) position[static_cast<size_t>(mRows[static_cast<size_t>(i)])] = static_cast<int32_t>(i - mRowsAt[s]);
  };
  for (size_t s = 0; s < supernodes; ++s) {
    if (s % 256 == 0) cancellationPoint();
    place(s);
    const int32_t f = mFirst[s];
    const int64_t m = mRowsAt[s + 1] - mRowsAt[s];
    for (int32_t j = f; j < mFirst[s + 1]; ++j) {
      double* column = mValues.data() + mValuesAt[s] + (j - f) * m;
      for (Eigen::SparseMatrix<double>::InnerIterator it(ap, j); it; ++it)
        if (it.row() >= j) column[position[static_cast<size_t>(it.row())]] += it.value();
    }
  }

  // Right-looking: each supernode in ascending order is factorised, then sends its update to the
  // supernodes that hold its rows below as columns.
  std::vector<double> update(widest * widest);
  for (size_t s = 0; s < supernodes; ++s) {
    cancellationPoint();  // a World closing stops its background factorisations here
    const int32_t f = mFirst[s];
    const Eigen::Index k = mFirst[s + 1] - f, m = mRowsAt[s + 1] - mRowsAt[s], r = m - k;
    Eigen::Map<Eigen::MatrixXd> panel(mValues.data() + mValuesAt[s], m, k);
    Eigen::Ref<Eigen::MatrixXd> top = panel.topRows(k);
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower> llt(top);
    if (llt.info() != Eigen::Success) {
      *this = SupernodalCholesky{};
      return false;
    }
    if (r == 0) continue;
    auto offDiagonal = panel.bottomRows(r);
    top.triangularView<Eigen::Lower>().adjoint().solveInPlace<Eigen::OnTheRight>(offDiagonal);
    Eigen::Map<Eigen::MatrixXd> c(update.data(), r, r);
    c.triangularView<Eigen::Lower>().setZero();
    c.selfadjointView<Eigen::Lower>().rankUpdate(offDiagonal);
    const int32_t* rows = mRows.data() + mRowsAt[s] + k;
    for (Eigen::Index from = 0; from < r;) {
      const auto t = static_cast<size_t>(superOf[static_cast<size_t>(rows[from])]);
      Eigen::Index to = from;
      while (to < r && rows[to] < mFirst[t + 1]) ++to;
      place(t);
      const int64_t mt = mRowsAt[t + 1] - mRowsAt[t];
      for (Eigen::Index b = from; b < to; ++b) {
        double* column = mValues.data() + mValuesAt[t] + (rows[b] - mFirst[t]) * mt;
        for (Eigen::Index i = b; i < r; ++i) column[position[static_cast<size_t>(rows[i])]] -= c(i, b);
      }
      from = to;
    }
  }
  mN = n;
  mScratch.assign(std::max<size_t>(widest, 1), 0.0);
  return true;
}

void SupernodalCholesky::toUnitLower(Eigen::SparseMatrix<double>& unitLower, Eigen::VectorXd& pivots) const {
  const int64_t strict = mNonZeros - mN;
  std::vector<int> outer(static_cast<size_t>(mN) + 1, 0), inner(static_cast<size_t>(strict));
  std::vector<double> values(static_cast<size_t>(strict));
  pivots.resize(mN);
  int64_t at = 0;
  for (size_t s = 0; s + 1 < mFirst.size(); ++s) {
    if (s % 256 == 0) cancellationPoint();
    const int32_t f = mFirst[s];
    const Eigen::Index k = mFirst[s + 1] - f, m = mRowsAt[s + 1] - mRowsAt[s];
    const double* panel = mValues.data() + mValuesAt[s];
    const int32_t* rows = mRows.data() + mRowsAt[s];
    for (Eigen::Index c = 0; c < k; ++c) {
      const double* column = panel + c * m;
      const double diagonal = column[c];
      pivots[f + c] = diagonal * diagonal;
      for (Eigen::Index i = c + 1; i < m; ++i) {
        inner[static_cast<size_t>(at)] = rows[i];
        values[static_cast<size_t>(at)] = column[i] / diagonal;
        ++at;
      }
      outer[static_cast<size_t>(f + c) + 1] = static_cast<int>(at);
    }
  }
  unitLower = Eigen::Map<const Eigen::SparseMatrix<double>>(mN, mN, strict, outer.data(), inner.data(), values.data());
}

void SupernodalCholesky::permute(const double* x, double* out) const {
  for (Eigen::Index i = 0; i < mN; ++i) out[i] = x[mPerm[static_cast<size_t>(i)]];
}

void SupernodalCholesky::permuteBack(const double* x, double* out) const {
  for (Eigen::Index i = 0; i < mN; ++i) out[mPerm[static_cast<size_t>(i)]] = x[i];
}

void SupernodalCholesky::solveL(double* x) const {
  for (size_t s = 0; s + 1 < mFirst.size(); ++s) {
    const int32_t f = mFirst[s];
    const Eigen::Index k = mFirst[s + 1] - f, m = mRowsAt[s + 1] - mRowsAt[s], r = m - k;
    const Eigen::Map<const Eigen::MatrixXd> panel(mValues.data() + mValuesAt[s], m, k);
    Eigen::Map<Eigen::VectorXd> own(x + f, k);
    panel.topRows(k).triangularView<Eigen::Lower>().solveInPlace(own);
    if (r == 0) continue;
    Eigen::Map<Eigen::VectorXd> t(mScratch.data(), r);
    t.noalias() = panel.bottomRows(r) * own;
    const int32_t* rows = mRows.data() + mRowsAt[s] + k;
    for (Eigen::Index i = 0; i < r; ++i) x[rows[i]] -= t[i];
  }
}

void SupernodalCholesky::solveLt(double* x) const {
  for (size_t s = mFirst.size() - 1; s-- > 0;) {
    const int32_t f = mFirst[s];
    const Eigen::Index k = mFirst[s + 1] - f, m = mRowsAt[s + 1] - mRowsAt[s], r = m - k;
    const Eigen::Map<const Eigen::MatrixXd> panel(mValues.data() + mValuesAt[s], m, k);
    Eigen::Map<Eigen::VectorXd> own(x + f, k);
    if (r > 0) {
      Eigen::Map<Eigen::VectorXd> t(mScratch.data(), r);
      const int32_t* rows = mRows.data() + mRowsAt[s] + k;
      for (Eigen::Index i = 0; i < r; ++i) t[i] = x[rows[i]];
      own.noalias() -= panel.bottomRows(r).transpose() * t;
    }
    panel.topRows(k).triangularView<Eigen::Lower>().adjoint().solveInPlace(own);
  }
}

void SupernodalCholesky::multiplyLt(const double* x, double* out) const {
  for (size_t s = 0; s + 1 < mFirst.size(); ++s) {
    const int32_t f = mFirst[s];
    const Eigen::Index k = mFirst[s + 1] - f, m = mRowsAt[s + 1] - mRowsAt[s], r = m - k;
    const Eigen::Map<const Eigen::MatrixXd> panel(mValues.data() + mValuesAt[s], m, k);
    Eigen::Map<Eigen::VectorXd> own(out + f, k);
    own.noalias() = panel.topRows(k).triangularView<Eigen::Lower>().adjoint() * Eigen::Map<const Eigen::VectorXd>(x + f, k);
    if (r == 0) continue;
    Eigen::Map<Eigen::VectorXd> t(mScratch.data(), r);
    const int32_t* rows = mRows.data() + mRowsAt[s] + k;
    for (Eigen::Index i = 0; i < r; ++i) t[i] = x[rows[i]];
    own.noalias() += panel.bottomRows(r).transpose() * t;
  }
}

void SupernodalCholesky::solve(Eigen::VectorXd& x) const {
  Eigen::VectorXd y(mN);
  permute(x.data(), y.data());
  solveL(y.data());
  solveLt(y.data());
  permuteBack(y.data(), x.data());
}

namespace {

// SimplicialLDLT with its state set from outside: everything that reads the factor reads what the
// constructor sets.
class SimplicialForm final : public Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> {
 public:
  explicit SimplicialForm(const SupernodalCholesky& factor) {
    const Eigen::Index n = factor.rows();
    m_Pinv.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) m_Pinv.indices()[i] = factor.orderAt(i);
    m_P = m_Pinv.inverse();
    factor.toUnitLower(m_matrix, m_diag);
    m_info = Eigen::Success;
    // private in SimplicialCholeskyBase, protected in the base that holds it
    this->Eigen::SparseSolverBase<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>>::m_isInitialized = true;
    m_analysisIsOk = true;
    m_factorizationIsOk = true;
  }
};

}  // namespace

std::shared_ptr<const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>> simplicialForm(const SupernodalCholesky& factor) {
  assert(factor.rows() > 0);
  return std::make_shared<SimplicialForm>(factor);
}

}  // namespace brittle::detail

// FillOrdering.h — a fill-reducing elimination order for an object's K, baked into the pack.
//
// The runtime factorises K + μM once per object for the static correction (StaticCorrection.h)
// and solves with the factor on every impact, and its backward solve reads all of L. Eigen's
// SimplicialLDLT orders by AMD. METIS's nested dissection (METIS_NodeND on the graph of K's
// non-zeros, seeded) gives less fill on the default objects, measured on their K + μM:
//
//   object        nnz(L) AMD → METIS   backward solve, 2 threads   factorisation
//   P2 plate      8.65M → 7.95M        6.4 → 5.7 ms                1.30 → 1.05 s
//   P2 stone ball 2.07M → 1.72M        1.13 → 0.75 ms              441 → 244 ms
//   P2 brick      0.72M → 0.70M        0.31 → 0.24 ms              79 → 55 ms
//   P1 vase       1.01M → 1.03M        0.92 → 0.86 ms              88 → 100 ms
//
// so the bake keeps whichever of the two has fewer non-zeros, and the runtime, which links no
// METIS, factorises with it. The order is the same for the same K in any process (METIS's own
// seeded generator, one thread).
#pragma once

#include <Eigen/Core>

#include "brittle/core/Result.h"
#include "brittle/runtime/FemAssembly.h"

namespace brittle {

/// The elimination order of K's rows (a permutation of 0..rows−1: position k holds the row
/// eliminated k-th) with the fewer non-zeros in L (factorNonZeros, StaticCorrection.h): METIS's
/// nested dissection, or an empty vector where AMD (the runtime's default) has no more. K: square, symmetric pattern.
/// Errors: InvalidArgument (not square, empty), Internal (METIS failed).
Result<Eigen::VectorXi> fillReducingOrdering(const SparseMatrixd& k);

}  // namespace brittle

// MonomialTables.h — index tables for monomials x^p y^q z^r up to kMaxMomentOrder (private).
#pragma once

#include <array>
#include <vector>

#include "brittle/core/Simd.h"
#include "brittle/descriptors/VolumeMoments.h"

namespace brittle::detail {

struct MonomialTables {
  std::vector<std::array<int, 3>> exponents;  ///< (p, q, r) per graded index
  std::vector<int> degree;                    ///< p + q + r
  std::vector<double> factorial;              ///< p! q! r!
  std::vector<double> multinomial;            ///< n! / (p! q! r!), n = p + q + r: a directional moment's weight
  std::vector<std::array<int, 3>> times;      ///< index of this monomial times x, y, z (−1 at top)
  std::vector<std::array<int, 3>> lower;      ///< index of this monomial divided by x, y, z (−1 if absent)
  std::vector<int> parent;                    ///< this monomial divided by parentVar (−1 for 1)
  std::vector<int> parentVar;
  int lookup[kMaxMomentOrder + 1][kMaxMomentOrder + 1][kMaxMomentOrder + 1] = {};
};

/// Built once, thread-safe (function-local static).
const MonomialTables& monomialTables();

/// computeVolumeMoments' pass at order 4 over the first faces, a register's worth at a time (two
/// with Narrow lanes, four with Wide), adding each face's terms to sum[0..34] in face order:
/// the generic loop's operations, so the same bits with either lanes. Returns how many faces it
/// did; the caller does the rest. Wide needs widestLanes() == Lanes::Wide.
Eigen::Index surfaceMomentsOrder4(const TriangleMesh& surface, const Eigen::Vector3d& originM, double* sum, Lanes lanes);
/// The same at any maxOrder: surfaceMomentsOrder4 at 4, a loop over the run-time tables above it
/// (the same bits with either lanes, and the generic loop's), none below (returns 0).
Eigen::Index surfaceMoments(const TriangleMesh& surface, const Eigen::Vector3d& originM, int maxOrder, double* sum, Lanes lanes);

/// addTetVolumeMomentsOrder4 with the given lanes (the same bits with either): fours with Wide, then
/// pairs, then a last tet by the scalar kernel. Wide needs widestLanes() == Lanes::Wide.
void tetMomentsOrder4(const std::array<Eigen::Vector3d, 4>* tets, int count, double* values, Lanes lanes);

/// VolumeMoments::directional over count directions with the given lanes (the same bits with
/// either). Wide needs widestLanes() == Lanes::Wide.
void directional(const VolumeMoments& moments, const Eigen::Vector3d* u, size_t count, int order, double* out, Lanes lanes);

}  // namespace brittle::detail

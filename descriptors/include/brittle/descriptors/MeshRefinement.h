// MeshRefinement.h — more triangles for the same solid.
//
// Midpoint subdivision splits every triangle into four through its edge midpoints: the surface is
// the same polyhedron (every new vertex lies on an old edge), closed meshes stay closed and
// consistently oriented, and volume moments are unchanged up to rounding. Used to bring meshes to
// a given triangle count (the descriptor benchmarks measure cost on ≈1k-triangle fragments) and in
// the remeshing-invariance tests.
#pragma once

#include <cstdint>

#include "brittle/core/MeshTypes.h"

namespace brittle {

/// One 1-to-4 midpoint subdivision: 4F faces, V + E vertices (E edges; shared midpoints once).
/// Face 4f + k holds corner k of face f (k < 3) or the middle triangle (k = 3), so the output is
/// a deterministic function of the input arrays. Precondition: face indices are in range.
TriangleMesh subdivideMidpoints(const TriangleMesh& mesh);

/// Subdivides until the mesh has at least `minFaces` faces (no-op if it already does).
TriangleMesh subdivideToAtLeast(const TriangleMesh& mesh, int64_t minFaces);

/// The unit icosphere: a regular icosahedron subdivided `level` times (level ≥ 0), every vertex
/// projected onto the unit sphere after each subdivision. 20·4^level outward faces.
TriangleMesh unitIcosphere(int level);

}  // namespace brittle

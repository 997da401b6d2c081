// MeshValidation.h — checks that a surface mesh bounds one solid that can be tetrahedralised.
#pragma once

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"

namespace brittle {

/// Checks, in this order, and stops at the first failure (each with its own code and a message
/// saying what and where, e.g. "open mesh: 12 boundary edges, first at vertex 481"):
///  1. EmptyMesh — no vertices or faces;
///  2. NonFiniteValue — a NaN or infinite coordinate;
///  3. ParseError — a face index out of range;
///  4. DegenerateFace — repeated corner or zero area (relative to the bounding box);
///  5. OpenMesh — edges with one incident face;
///  6. NonManifold — edges with more than two faces;
///  7. InconsistentOrientation — two faces traverse a shared edge in the same direction;
///  8. NonManifold — vertices whose faces form several fans (pinched), or more than one
///     connected component (one object is one body);
///  9. SelfIntersection — two non-adjacent faces intersect (CGAL Polygon_mesh_processing);
/// 10. InwardFacing — the enclosed signed volume is negative.
Status validateSurfaceMesh(const TriangleMesh& mesh);

}  // namespace brittle

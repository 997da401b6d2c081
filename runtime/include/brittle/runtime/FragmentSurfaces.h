// FragmentSurfaces.h — closed surfaces of the fragments of a cracked tet mesh.
//
// Input: a fragment label per node (nodes joined by uncut edges share a label) and, for every edge
// whose two nodes carry different labels, where the crack crosses it (a parameter in (0, 1)).
// Each tet is split into four corner cells, one per node, bounded by points on its edges, faces
// and centre (a barycentric dual). A fragment is the union of the corner cells of its nodes, so
// the fragments partition the mesh exactly and their volumes add up to the body's.
//
// Points: a point on each "mixed" edge (at the crack's parameter), one on each mixed face (the
// mean of its mixed-edge points) and one in each mixed tet (the mean of its mixed-edge points).
// When one plane crosses a tet, all of them lie on that plane, so the crack faces are planar there.
// Surfaces: the boundary faces of the body (whole triangles when all three nodes share a label,
// otherwise split at the edge and face points), and inside each mixed tet, for each mixed edge,
// the quad (edge point, face point, tet point, face point) between the two corner cells. A quad
// is triangulated the same way for both fragments, so the pieces fit without gaps.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"
#include "brittle/descriptors/VolumeMoments.h"
#include "brittle/runtime/TetTopology.h"

namespace brittle {

/// One closed, outward triangle surface per label 0..labelCount−1 (m, the mesh's frame).
/// nodeLabels: #N in [0, labelCount); edgeCuts: #E, used where the labels of an edge differ,
/// clamped to [0.05, 0.95] so that no face degenerates.
/// Errors: InvalidArgument (sizes, labels out of range, a label with no node, an edge between two
/// labels without a finite cut).
Result<std::vector<TriangleMesh>> buildFragmentSurfaces(const TetMesh& mesh, const TetTopology& topology,
                                                        const Eigen::VectorXi& nodeLabels, int labelCount,
                                                        const Eigen::VectorXd& edgeCuts);

/// Buffers of buildFragmentSurfaces, kept between calls: once they have grown to the largest body
/// (or been reserved for it), building surfaces allocates only the output meshes' arrays.
struct FragmentSurfaceWorkspace {
  std::vector<Eigen::Vector3d> points;           ///< nodes first, then created points
  std::vector<int32_t> edgePoint, facePoint;     ///< per edge; per (tet, local face): −1 until created
  std::vector<std::array<int32_t, 4>> triangles; ///< (label, three points), in creation order
  std::vector<int32_t> labelStart, fill, order;  ///< the triangles sorted by label (counting sort)
  std::vector<int32_t> local, used;              ///< per fragment: each point's local index; its points
  void reserve(Eigen::Index nodes, Eigen::Index tets, Eigen::Index edges, Eigen::Index boundaryFaces);
};

/// The same into `out` (resized to labelCount; each mesh keeps its storage where its size is
/// unchanged), with the buffers of `workspace`.
Status buildFragmentSurfaces(const TetMesh& mesh, const TetTopology& topology, const Eigen::VectorXi& nodeLabels,
                             int labelCount, const Eigen::VectorXd& edgeCuts, FragmentSurfaceWorkspace& workspace,
                             std::vector<TriangleMesh>& out);

/// Moment order kept per tet and per fragment: what the canonical frames and the moment descriptor
/// read (VolumeMoments.h).
inline constexpr int kFragmentMomentOrder = 4;
inline constexpr int kFragmentMomentCount = monomialCount(kFragmentMomentOrder);

/// Volume moments of every tet about one origin, and their sum (the body's).
struct TetMoments {
  Eigen::Vector3d originM = Eigen::Vector3d::Zero();
  std::vector<double> perTet;  // #T blocks of kFragmentMomentCount values (graded order, as VolumeMoments::values)
  std::array<double, kFragmentMomentCount> total{};  // Σ perTet, summed in tet order
};
TetMoments tetVolumeMoments(const TetMesh& mesh, const Eigen::Vector3d& originM);

/// Volume moments of each fragment about tetMoments.originM, those of the solids
/// buildFragmentSurfaces bounds (equal up to rounding), without a pass over their surfaces. The
/// fragment with the most nodes (ties: the lowest label) is the body minus the others, so the cost
/// follows the smaller fragments and the cut band, not the body. For the others: a tet whose nodes
/// share a label adds its stored moments; a tet whose nodes carry several labels is split into the
/// same corner cells as the surfaces are, each six sub-tets (node, edge point, face point, tet
/// point; on an edge or face the crack does not cross, the midpoint or centroid, which only moves
/// a boundary inside one fragment): its largest group of nodes (ties: the one with the lowest local
/// node) takes the tet's moments minus the others' cells. Cost: 6–18 sub-tets per cut tet.
/// Output: moments resized to labelCount blocks of kFragmentMomentCount values (its storage kept).
/// Errors: those of buildFragmentSurfaces for the labels and cuts; InvalidArgument when tetMoments
/// does not have one block per tet.
///
/// The tets are summed in kMomentChunks fixed ranges of tet ids, in parallel where the caller runs
/// in a oneTBB arena with more than one thread, each range into its own sums, which are then added
/// in range order: the bits do not depend on the number of threads.
Status fragmentVolumeMoments(const TetMesh& mesh, const TetTopology& topology, const TetMoments& tetMoments,
                             const Eigen::VectorXi& nodeLabels, int labelCount,
                             const Eigen::VectorXd& edgeCuts, std::vector<double>& moments);

inline constexpr int kMomentChunks = 16;

/// The same with the per-range sums in `chunkSums` (kept between calls: once grown to the most
/// fragments, summing allocates nothing).
Status fragmentVolumeMoments(const TetMesh& mesh, const TetTopology& topology, const TetMoments& tetMoments,
                             const Eigen::VectorXi& nodeLabels, int labelCount, const Eigen::VectorXd& edgeCuts,
                             std::vector<double>& chunkSums, std::vector<double>& moments);

}  // namespace brittle

// CrackPropagation.h — from modal response to fracture state: element stresses over time with
// bound-based pruning, Rankine initiation, crack growth through face neighbours with a Griffith
// energy stop, and the node labels that say which fragment each node ends up in.
//
// Stress of element e at instant k: σ_e = S_e q_k (+ σ̂_e F_k, the static correction of the
// truncated modes, when given). Split σ into its mean normal stress p and its deviator s. The
// deviator's largest eigenvalue is at most √(2/3) ‖s‖_F, so
//   σ₁ ≤ p + √(2/3) ‖s‖_F ≤ ‖σ‖_F,
// and p is linear: p_e,k = P_e · q_k (+ p̂_e F_k) is exact for the cost of r products, P_e,j the
// mean stress of mode j. Where the point is compressed (half of a bent plate, every point of a
// ringing body half of the time) p is negative and the bound falls with it, which no norm of σ
// sees. The deviator is bounded by the smaller of
//   Σ_j ‖D s_e,j‖ |q_j,k|  and  ‖D s_e W‖₂ ‖W⁻¹ q_k‖  (+ ‖D ŝ_e‖ |F_k|),
// D = diag(1, 1, 1, √2, √2, √2). The first (the triangle inequality) is tight when one mode
// dominates; the second (the spectral norm of the 6-by-r block, which has rank ≤ 6) when many do.
// A point or instant whose bound is below what is sought is skipped without changing the answer.
// Points are visited by a bound over all instants (p and the deviator bounded with max |q_j|), and
// per-instant bounds are formed only for the points visited. On the default P2 plate this leaves
// 2.3k of its 1.2M (point, instant) pairs above the peak, where ‖σ‖_F's bounds left 153k. Points
// that share a mesh node are grouped (StressBounds): one exact stress at the group's centre, plus
// its radius, bounds every point of it at an instant, so that most groups are ruled out whole (on
// the plate 263 of 2 824 reach the peak, where 23.2k of 29.8k points had an all-instant bound above it).
// scanStresses with prune = false evaluates everything, for tests and benchmarks.
//
// Growth: seeds are the elements whose σ₁ reaches σ_t at the instant of the peak, strongest first,
// each the start of one crack with its plane normal to the principal direction. A crack advances
// into a face neighbour its plane crosses. There the plane is a blend of the crack's starting
// plane and the local principal direction, plus seeded noise (independent per element, so it
// roughens the sheet without making its orientation random-walk), and passes through the centre of the parent's cut on the
// shared face. It advances only where the normal stress on the new plane is at least
// propagationStressRatio · σ_t (by default there is no such limit). Each cut costs G_c × (area of the plane inside the element), paid from the
// elastic energy stored at the peak instant, ½ Σ ω_j² q_j²; growth stops when the next cut would
// overspend it (Griffith). Fronts of all cracks advance together, strongest normal stress first.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <vector>

#include "brittle/database/ObjectAsset.h"
#include "brittle/core/Result.h"
#include "brittle/core/Simd.h"
#include "brittle/runtime/TetTopology.h"

namespace brittle {

using Voigt = Eigen::Matrix<double, 6, 1>;
using MatrixXfRow = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Largest principal stress (Pa) of a Voigt stress (xx, yy, zz, yz, xz, xy), and its unit direction.
double maxPrincipalStress(const Voigt& stress, Eigen::Vector3d* direction = nullptr);

/// What bounds a stress point's stress per unit of modal amplitude, for the pruned scan.
struct StressBounds {
  MatrixXdRow pressureModes;     ///< PT by modes: P_e,j, the mean normal stress per unit q_j (signed)
  MatrixXdRow deviatorNorms;     ///< PT by modes: ‖D s_e,j‖, the deviator's norm per unit |q_j|
  Eigen::VectorXd modeScales;    ///< modes: w_j > 0 (1/ω_j: see stressModeBounds)
  Eigen::VectorXd spectralNorms; ///< PT: ‖D S_e W‖₂ over the first `modes` modes, per unit ‖W⁻¹ q‖
  Eigen::VectorXd deviatorSpectralNorms;  ///< PT: ‖D s_e W‖₂, the same for the deviator
  /// Groups of stress points (empty: none), each with a centre c, the mean of its points' stress
  /// modes, and a radius ρ_G = max ‖D (S_e − S_c) W‖_F ≥ ‖D (S_e − S_c) W‖₂ over its points e. By Weyl's inequality
  /// σ₁(σ_c + Δ) ≤ σ₁(σ_c) + λ_max(Δ) ≤ σ₁(σ_c) + ‖D Δ‖, so at every instant
  ///   σ₁(e, k) ≤ splitBound(σ_c,k) + ρ_G ‖W⁻¹ q_k‖ (+ the static correction's own radius |F_k|):
  /// one exact stress (6r products) bounds the whole group, tightly where its points agree.
  std::vector<int32_t> groupStart;   ///< G + 1 offsets into groupPoints
  std::vector<int32_t> groupPoints;  ///< PT stress points, group by group, ascending in each
  std::vector<int32_t> groupOf;      ///< PT: each point's group
  MatrixXfRow groupCentres;          ///< 6G by modes: S_c, in float (the radii are measured from it)
  Eigen::VectorXd groupRadii;        ///< G: ρ_G
  Eigen::VectorXd groupScales;       ///< G: ‖D S_c W‖_F ≥ ‖D S_c W‖₂, the scale of the centre's rounding
  /// G: 1 where every point of the group has the same rows of stressModes, bit for bit (a P2 node's
  /// corners as nodal means, CornerStressMeans): with a static correction equal on them too, the
  /// peak search evaluates only the group's lowest point, which the tie rule would report anyway.
  std::vector<char> groupUniform;
};

/// The bounds of every stress point over the first `modes` modes of stressModes (6PT by ≥ modes).
/// modeScales (w_j > 0, ≥ modes entries; empty: all 1) weigh the spectral bound
/// ‖D S_e q‖ ≤ ‖D S_e W‖₂ ‖W⁻¹ q‖ (and the deviator's). With w_j = 1/ω_j, ‖W⁻¹ q‖² = Σ ω_j² q_j² is twice the kept
/// modes' strain energy, which a hit shares out over many modes while the stress per unit q_j
/// grows with ω_j: the bound is then stress per unit √energy, and holds for any fewer modes.
/// pointKeys (PT entries, or empty for no groups) group the points: points with the same key form
/// one group. Any grouping gives true bounds; points whose stresses agree give tight ones, and
/// stressPointNodes groups them by mesh node (P2) or by clusters of nodes (P1).
StressBounds stressModeBounds(const MatrixXdRow& stressModes, int modes, const Eigen::VectorXd& modeScales = {},
                              const std::vector<int32_t>& pointKeys = {});

/// A key per stress point, to group the points (stressModeBounds). P2: the corner node the point
/// sits at (the corners of the elements around a node see nearly the same stress). P1: a cluster
/// of nodes, made in node order, each a node and the nodes of the tets around it not yet taken,
/// up to 16 elements; an element joins the cluster of its lowest node (the key is the cluster's
/// first node). Grouped by lowest node alone, a P1 group held ~4 elements, too few for its bound
/// to pay (a group is bounded once 3 of its points are left), and a shattering hit on a 4.1k-tet
/// slab visited 3 335 of its 4 133 points one by one. Clusters of P2 corners made the plate's
/// groups too wide for their bounds (its scan 3.5× slower), so P2 keeps one node a group.
std::vector<int32_t> stressPointNodes(const Tetrahedra& tets, int pointsPerElement);

struct StressScan {
  double peakPrincipalPa = 0.0;   ///< exact maximum of σ₁ over elements and instants
  int32_t peakElement = -1;
  int32_t peakInstant = -1;
  /// An unpruned scan: the elements with σ₁ ≥ threshold at the peak instant, strongest first (ties:
  /// the lower point first). A pruned scan leaves it empty and lists the candidates instead.
  std::vector<int32_t> seeds;
  /// A pruned scan: (bound, point) for each stress point whose bound at the peak instant reaches
  /// the threshold, a max-heap; SeedOrder makes the same seeds from it, evaluated as they are taken.
  std::vector<std::pair<double, int32_t>> seedCandidates;
  double seedThresholdPa = 0.0;
  int pointsPerElement = 1;
  int64_t evaluations = 0;        ///< element stresses evaluated (SeedOrder counts its own)
  /// Whether there is a seed: the peak point is one exactly when the peak reaches the threshold.
  bool hasSeeds() const { return peakInstant >= 0 && peakPrincipalPa >= seedThresholdPa; }
};

/// Scans σ₁ over every stress point and instant. stressModes: 6PT by ≥ r, P = pointsPerElement
/// (ObjectAsset::stressModes: 1 for P1, the 4 corners for P2); q: K by r; bounds from
/// stressModeBounds over ≥ r modes; staticStress (6PT, per newton, may be empty) and forceN (K) add the
/// static correction. The peak and the seeds name elements: an element's σ₁ is the largest at its
/// points (for P2 that is its maximum over the element, the stress being linear in it). Pruned and
/// unpruned scans return the same peak, element and instant; the unpruned scan lists the seeds, the
/// pruned one their candidates, from which SeedOrder makes the same seeds.
StressScan scanStresses(const MatrixXdRow& stressModes, const StressBounds& bounds, const Eigen::MatrixXd& q,
                        const Eigen::VectorXd& staticStress, const std::vector<double>& forceN, double thresholdPa,
                        bool prune, int pointsPerElement = 1);

/// Buffers of scanStresses, kept between calls so that a scan allocates nothing once they have
/// grown to the largest body scanned.
struct StressScanWorkspace {
  Eigen::MatrixXd qAbsT;                       ///< r by K: |q|ᵀ
  Eigen::MatrixXd qT;                          ///< r by K: qᵀ
  Eigen::VectorXd qMax, forceAbs;              ///< r, K
  Eigen::VectorXd staticNorm, staticPressure, staticDeviator;  ///< T: ‖Dσ̂_e‖, p̂_e, ‖Dŝ_e‖
  Eigen::VectorXd qNorm;                       ///< K: ‖W⁻¹ q_k‖ (StressBounds::modeScales)
  Eigen::VectorXd elementBound, pressureScale; ///< T: B_e over all instants; Σ|P_e,j| max|q_j| + |p̂_e| max|F|
  /// T: B_e's modal terms, Σ|P_e,j| max|q_j| and min(Σ‖s_e,j‖ max|q_j|, ‖s_e W‖₂ max‖W⁻¹q_k‖)
  /// (prepareStressScan's).
  Eigen::VectorXd modalPressure, modalDeviator;
  std::vector<std::pair<double, int32_t>> heap, seeds;
  std::vector<std::vector<std::pair<double, int32_t>>> rangeSeeds;  ///< per fixed range of elements
  std::vector<int64_t> rangeEvaluations;
  /// The pruned peak search per fixed range of stress points: its peak (value, point, instant)
  /// and its evaluations.
  struct RangePeak {
    double best = 0.0;
    int32_t point = -1, instant = -1;
    int64_t evaluations = 0;
    int64_t heapEnd = 0;  // where the range's heap stood after the search's last round so far
  };
  std::vector<RangePeak> rangePeaks;
  // The groups (StressBounds::groupStart): each group's bound at every instant (G by K, row-major)
  // and over all of them, for the groups whose bounds the last scan made (NaN for the others).
  Eigen::VectorXd groupBound;
  std::vector<double> seedGroupBound;          ///< G: each group's bound at the peak instant (empty: no groups)
  std::vector<double> seedGroupValue;          ///< G: a groupSame group's seed bound at the peak instant (NaN: none)
  /// Per group: the static correction's centre (6G), radius and the bound's margin (G each).
  std::vector<double> groupStaticCentre, groupStaticRadius, groupMargin;
  std::vector<char> groupSame;  ///< G: groupUniform, and the static correction equal on the group's points (empty after an ungrouped scan)
  std::vector<double> groupBoundAt;
  Eigen::MatrixXf qFloat;                      ///< K (padded to a multiple of 8) by r: q in float
  std::vector<double> forceLanes;              ///< F_k at qFloat's rows, zero past K (the group bounds' loads)
  /// The group centres' bounds take instants four to an SSE2 register or eight to an AVX one, with
  /// the same bits (brittle/core/Simd.h); tests run both.
  Lanes lanes = widestLanes();
  std::vector<char> seedTaken;                 ///< T, when an element has several stress points
};

/// The same scan into `out` (its seeds keep their capacity), with the buffers of `workspace`. The
/// seeds are gathered over fixed ranges of elements, in parallel where the caller runs in a oneTBB
/// arena with more than one thread, and in range order: the scan is the same on any number of
/// threads.
void scanStresses(const MatrixXdRow& stressModes, const StressBounds& bounds, const Eigen::MatrixXd& q,
                  const Eigen::VectorXd& staticStress, const std::vector<double>& forceN, double thresholdPa, bool prune,
                  StressScanWorkspace& workspace, StressScan& out, int pointsPerElement = 1);

/// scanStresses in two steps. prepareStressScan makes what reads q alone into `workspace`: the
/// instants' arrays and each point's modal terms of its bound over all instants, a pass over two
/// rows of r doubles a point (on the P2 plate 0.9 ms of its scan). It needs neither the static
/// correction nor the force, so the impact makes it on one thread while the correction's serial
/// forward solve runs on another. scanPreparedStresses is then the scan itself, with the same q,
/// bounds and prune as the preparation (several scans may follow one preparation), and gives
/// scanStresses' answer bit for bit: the same arithmetic in the same order.
void prepareStressScan(const StressBounds& bounds, const Eigen::MatrixXd& q, bool prune, StressScanWorkspace& workspace);
void scanPreparedStresses(const MatrixXdRow& stressModes, const StressBounds& bounds, const Eigen::MatrixXd& q,
                          const Eigen::VectorXd& staticStress, const std::vector<double>& forceN, double thresholdPa,
                          bool prune, StressScanWorkspace& workspace, StressScan& out, int pointsPerElement = 1);

struct CrackSettings {
  int maxCracks = 6;                     ///< seeds that start a crack, strongest first
  /// A crack advances where the normal stress on its plane is σ_nn ≥ ratio · σ_t. The default, −∞,
  /// leaves the Griffith energy balance as the only stop. Measured on the default pack: with a
  /// positive ratio, cracks stall in the compressed half of a bent plate and never run through its
  /// thickness (nothing separates); with −1, strong impacts compress so much of the body that they
  /// break it into fewer pieces than weaker ones (60 m/s: 2 fragments, 20 m/s: 17).
  double propagationStressRatio = -std::numeric_limits<double>::infinity();
  /// Weight of the crack's starting plane against the local principal direction; the local
  /// direction's share, 1 − blend, is scaled by σ₁/σ_t (clamped to [0, 1]) where it is read.
  double directionBlend = 0.5;
  double noiseRad = 0.15;                ///< standard deviation of the seeded turn per element (rad)
  /// Fragments with fewer nodes are merged into the neighbour they share most cut edges with: a
  /// crack plane per element zigzags at the mesh's scale and would otherwise chip off single-node
  /// crumbs that are artefacts of the resolution, not fracture.
  int minFragmentNodes = 8;
  /// Whether a crack ends where it meets another crack's surface (a T-junction) instead of
  /// running on through it. No stress crosses a free surface, so a real crack that reaches another
  /// stops there; with this set, a front that enters an element another crack has cut cuts it too
  /// (so the sheets join without a gap) and spreads no further. Off by default: it changes every
  /// fracture, and on the default objects it makes about half as many fragments (each pair of
  /// crossing sheets made four pieces where a junction makes three, and most of the crossings'
  /// pieces were crumbs merged away), so the scenes and calibrations made with crossing cracks
  /// would need to be made again. Measured in docs/realtime.md (stop 86).
  bool endAtCracks = false;
  uint64_t seed = 1;
};

struct FractureState {
  std::vector<int32_t> cutElements;                 ///< in cut order
  /// Per cut, in cut order (an element cut by several cracks has a plane from each): unit normal n
  /// and offset, n·x = offset.
  std::vector<Eigen::Vector4d> cutPlanes;
  Eigen::VectorXd edgeCuts;                         ///< #E: parameter of the cut from edges(e,0), NaN if uncut
  Eigen::VectorXi nodeLabels;                       ///< #N: fragment of each node
  int fragmentCount = 1;
  int crackCount = 0;
  double crackAreaM2 = 0.0;
  double energyBudgetJ = 0.0;
  double energySpentJ = 0.0;
  bool arrestedByEnergy = false;                    ///< growth ended because the energy ran out
  int mergedCrumbs = 0;                             ///< fragments below minFragmentNodes merged away

  /// Back to an uncracked state. The lists keep their storage; the two Eigen arrays, which have no
  /// capacity, are emptied (a breaking impact allocates them anew, see HotPathAllocationTest).
  void clear() {
    cutElements.clear();
    cutPlanes.clear();
    edgeCuts.resize(0);
    nodeLabels.resize(0);
    fragmentCount = 1;
    crackCount = mergedCrumbs = 0;
    crackAreaM2 = energyBudgetJ = energySpentJ = 0.0;
    arrestedByEnergy = false;
  }
};

/// The stresses of a P2 field's corner nodes, each computed once (StressField::nodeMemo). A body's
/// P2 corner stresses are nodal means (CornerStressMeans), so every element at a node reads the
/// same rows there: the same bits from whichever point computes them first. One thread's: crack
/// growth runs on one thread (StressField::at writes it, const as it is).
struct NodeStressMemo {
  std::vector<Voigt> stress;  ///< per node
  std::vector<char> known;    ///< per node
  /// Every node unknown (no allocation within the reserved size).
  void reset(Eigen::Index nodes) {
    stress.resize(static_cast<size_t>(nodes));
    known.assign(static_cast<size_t>(nodes), 0);
  }
};

/// The stress field at one instant: σ_e = S_e q (+ σ̂_e F).
struct StressField {
  const MatrixXdRow* stressModes = nullptr;  ///< 6PT by ≥ r
  Eigen::VectorXd q;                         ///< r modal coordinates
  const Eigen::VectorXd* staticStress = nullptr;  ///< 6PT per newton, or null
  double forceN = 0.0;
  int pointsPerElement = 1;                  ///< P: 1 (P1) or 4 (P2, the corners)
  Lanes lanes = widestLanes();               ///< the registers of its sums (the same bits in either)
  /// P2 only, and only where every point of a node has the same rows of stressModes and of
  /// staticStress, bit for bit (a body's nodal means; the crack stage sets it where the scan found
  /// so, StressBounds::groupUniform and StressScanWorkspace::groupSame): the tets' corners and a memo
  /// per corner node, so that each node's stress is computed once (null: every point computed).
  /// Values are the same bits either way.
  const Tetrahedra* corners = nullptr;
  NodeStressMemo* nodeMemo = nullptr;
  /// The element's stress: at its point of largest σ₁, the first of equals (the one point of a P1 element).
  Voigt at(int32_t element) const;
  /// The stress at one stress point (row block `point` of stressModes).
  Voigt atPoint(Eigen::Index point) const;
  /// Asks the cache for the element's rows of stressModes ahead of at(element) (a hint: no effect
  /// on any value).
  void prefetch(int32_t element) const;
};

/// Buffers of SeedOrder, kept between calls.
struct SeedOrderWorkspace {
  /// A candidate evaluated whose eigen solve waits until its split bound decides an order.
  struct Bounded {
    double bound;  ///< σ₁ ≤ bound: the split bound of σ, with a margin for the eigen solve's rounding
    int32_t point;
    Voigt sigma;
  };
  std::vector<std::pair<double, int32_t>> candidates, evaluated;  ///< max-heaps: (bound, point), (σ₁, point)
  std::vector<Bounded> bounded;                                   ///< a max-heap by (bound, point)
  std::vector<char> taken;                                        ///< per element, with several points each
};

/// The seeds of a scan, strongest first, exactly the unpruned scan's list, made as they are taken:
/// a pruned scan's candidates are evaluated at the peak instant (`field`) in the order of their
/// bounds, and a seed is handed out once no candidate left could be stronger. An evaluated σ's
/// eigen solve is left until its split bound decides an order (most never need one). Crack growth takes
/// seeds until it has started its cracks; a shattering hit puts most of a body over σ_t and
/// evaluates a fraction of it here.
class SeedOrder {
 public:
  SeedOrder(const StressScan& scan, const StressField& field, SeedOrderWorkspace& workspace);
  /// The next seed's element; false when there is none left.
  bool next(int32_t& element);
  /// Stresses evaluated so far.
  int64_t evaluations() const { return mEvaluations; }

 private:
  const StressScan& mScan;
  const StressField& mField;
  SeedOrderWorkspace& mW;
  size_t mNext = 0;
  int64_t mEvaluations = 0;
};

/// Every seed of a scan in SeedOrder's order (tests, tools).
std::vector<int32_t> orderedSeeds(const StressScan& scan, const StressField& field);

/// Buffers of crack growth, labelling and crumb merging, kept between calls: once they have grown
/// to the largest body cracked (or been reserved for it), growing cracks allocates nothing.
struct CrackWorkspace {
  /// A front's place in the heap: what orders it, and its entry in `fronts` (the heap moves 16 bytes
  /// an entry, not the path's 88).
  struct Front {
    double priority;         ///< normal stress on the parent plane
    int32_t element, entry;
  };
  struct FrontPath {
    int32_t crack;
    Eigen::Vector3d normal;  ///< parent's plane normal (orients the local principal direction)
    Eigen::Vector3d point, point2;  ///< the parent's cut through the shared face
  };
  /// An element's stress at the peak instant, with its largest principal value and direction.
  struct Principal {
    Voigt stress;
    Eigen::Vector3d direction;
    double value;
  };
  std::vector<Front> front;              ///< a max-heap
  std::vector<FrontPath> fronts;         ///< every front pushed in this growth, in push order
  std::vector<char> cut, stressKnown;    ///< #T
  std::vector<Principal> stressCache;    ///< #T
  std::vector<double> phi;               ///< cracks × #N: each crack's nodal level set
  std::vector<char> cutBy;               ///< cracks × #T
  std::vector<Eigen::Vector3d> seedNormals;
  NodeStressMemo nodeMemo;               ///< #N: a P2 field's corner stresses (StressField::nodeMemo)
  /// Storage for the next FractureState's two arrays, which have no capacity of their own: the
  /// runtime puts a reused result's old arrays here before it clears the result (recycle), and a
  /// growth whose state is empty takes them, so that it does not allocate them again.
  Eigen::VectorXd spareEdgeCuts;
  Eigen::VectorXi spareNodeLabels;
  /// Takes `state`'s arrays as the spares (state's are left empty, as clear() leaves them).
  void recycle(FractureState& state) {
    spareEdgeCuts.swap(state.edgeCuts);
    spareNodeLabels.swap(state.nodeLabels);
    state.edgeCuts.resize(0);
    state.nodeLabels.resize(0);
  }
  SeedOrderWorkspace seedOrder;
  int64_t seedEvaluations = 0;           ///< stresses SeedOrder evaluated for the last growth
  // labelFragments
  std::vector<int32_t> parent, labelOfRoot;
  // mergeCrumbs: per component, per node (member lists), per node (incident edges, CSR)
  std::vector<int32_t> size, low, root, shared, head, tail, touched, next, start, fill, incident;
  std::vector<char> stuck;
  /// Reserves for a body of the given counts and up to `cracks` cracks.
  void reserve(Eigen::Index nodes, Eigen::Index tets, Eigen::Index edges, int cracks);
};

/// Grows cracks from the scan's seeds (SeedOrder) in the field at the peak instant, within energyBudgetJ.
/// Errors: InvalidArgument (bad settings, sizes or material values).
Result<FractureState> propagateCracks(const TetMesh& mesh, const TetTopology& topology, const StressScan& scan,
                                      const StressField& field, double tensileStrengthPa, double fractureEnergyJPerM2,
                                      double energyBudgetJ, const CrackSettings& settings);
/// The same into `out` (its arrays keep their storage), with the buffers of `workspace`.
Status propagateCracks(const TetMesh& mesh, const TetTopology& topology, const StressScan& scan,
                       const StressField& field, double tensileStrengthPa, double fractureEnergyJPerM2,
                       double energyBudgetJ, const CrackSettings& settings, CrackWorkspace& workspace,
                       FractureState& out);

/// Merges fragments of fewer than minNodes nodes into their best-connected neighbour (by
/// un-cutting the edges between them), smallest first, and relabels. Returns the merges done.
int mergeCrumbs(const TetTopology& topology, int minNodes, Eigen::VectorXd& edgeCuts, Eigen::VectorXi& labels,
                int& fragmentCount);
int mergeCrumbs(const TetTopology& topology, int minNodes, Eigen::VectorXd& edgeCuts, Eigen::VectorXi& labels,
                int& fragmentCount, CrackWorkspace& workspace);

/// Labels nodes by connected components over uncut edges (NaN in edgeCuts), numbered in order of
/// their lowest node. Returns the number of labels.
int labelFragments(const TetTopology& topology, const Eigen::VectorXd& edgeCuts, Eigen::Index nodeCount,
                   Eigen::VectorXi& labels);
int labelFragments(const TetTopology& topology, const Eigen::VectorXd& edgeCuts, Eigen::Index nodeCount,
                   Eigen::VectorXi& labels, CrackWorkspace& workspace);

namespace detail {
/// σ = S_p q of stress point p over the first r modes (S's rows 6p..6p+5), in four running sums a
/// row: the same bits in either lanes, within 1e-15 r of the scale Σ|S_ij q_j| of Eigen's product
/// (which sums in another order). The scan and StressField both read stresses through it.
Voigt elementStress(const MatrixXdRow& S, Eigen::Index point, const double* q, Eigen::Index r,
                    Lanes lanes = widestLanes());
}  // namespace detail

}  // namespace brittle

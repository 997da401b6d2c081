// The only translation unit that instantiates CGAL Mesh_3 (see TetMesher.h).
#include "brittle/precompute/TetMesher.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>
#include <CGAL/Random.h>
#include <CGAL/make_mesh_3.h>  // includes CGAL/Mesh_3/Dump_c3t3.h, specialised below

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <string>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>
#include <unordered_map>
#include <vector>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/FeatureCurves.h"
#include "brittle/precompute/TetMeshQuality.h"
#include "brittle/runtime/FemAssembly.h"

namespace brittle {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Polyhedron = CGAL::Mesh_polyhedron_3<Kernel>::type;
using Domain = CGAL::Polyhedral_mesh_domain_with_features_3<Kernel>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr, Domain::Corner_index, Domain::Curve_index>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;

}  // namespace
}  // namespace brittle

// Mesh_3 writes the complex to dump-bug.mesh and dump-bug.binary.cgal in the working directory
// before it raises some errors (an already inserted surface point, a protection failure). The
// error reaches the caller as MeshingFailed; files left in whatever directory the bake ran in do
// not, so this complex is never dumped.
template <>
struct CGAL::Dump_c3t3<brittle::C3t3, true> {
  void dump_c3t3(const brittle::C3t3&, const std::string&) const {}
};
template <>
struct CGAL::Dump_c3t3<brittle::C3t3, false> {
  void dump_c3t3(const brittle::C3t3&, const std::string&) const {}
};

namespace brittle {
namespace {

// Only the vertices the faces use: an unused one would be an isolated polyhedron vertex, on
// which CGAL's feature detection crashes (libcgal-demo's prim.off lists three).
Polyhedron toPolyhedron(const TriangleMesh& surface) {
  std::vector<std::size_t> index(static_cast<size_t>(surface.vertices.rows()), SIZE_MAX);
  for (Eigen::Index i = 0; i < surface.faces.size(); ++i) index[static_cast<size_t>(surface.faces.data()[i])] = 0;
  std::vector<Kernel::Point_3> points;  // in the surface's order, so a mesh without unused vertices is unchanged
  for (size_t v = 0; v < index.size(); ++v) {
    if (index[v] == SIZE_MAX) continue;
    index[v] = points.size();
    const auto row = static_cast<Eigen::Index>(v);
    points.emplace_back(surface.vertices(row, 0), surface.vertices(row, 1), surface.vertices(row, 2));
  }
  std::vector<std::array<std::size_t, 3>> faces;
  for (Eigen::Index f = 0; f < surface.faces.rows(); ++f) {
    faces.push_back({index[static_cast<size_t>(surface.faces(f, 0))], index[static_cast<size_t>(surface.faces(f, 1))],
                     index[static_cast<size_t>(surface.faces(f, 2))]});
  }
  Polyhedron poly;
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, faces, poly);
  return poly;
}

// Where a run puts its elements: the cell size h everywhere, scaled by a ball's factor inside it
// (the smallest factor where balls overlap).
struct SizingBall {
  Eigen::Vector3d center;
  double radiusM = 0.0;
  double factor = 0.5;
};

struct LocalSize {
  double h = 0.0;
  std::vector<SizingBall> balls;
  template <class Index>
  Kernel::FT operator()(const Kernel::Point_3& p, int /*dim*/, const Index& /*index*/) const {
    const Eigen::Vector3d q(p.x(), p.y(), p.z());
    double factor = 1.0;
    for (const auto& b : balls) {
      if ((q - b.center).squaredNorm() <= b.radiusM * b.radiusM) factor = std::min(factor, b.factor);
    }
    return h * factor;
  }
};

enum class Protection { None, Detected, Curves };

// Raises Mesh_3's stop flag once a run has taken `seconds` of wall clock (none when ≤ 0). Mesh_3
// polls the flag between the elements it refines, in protection and in refinement alike.
class RunDeadline {
 public:
  explicit RunDeadline(double seconds) {
    if (!(seconds > 0.0)) return;
    mWatch = std::thread([this, seconds] {
      std::unique_lock lock(mMutex);
      if (!mDone.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return mFinished; })) mStop = true;
    });
  }
  RunDeadline(const RunDeadline&) = delete;
  RunDeadline& operator=(const RunDeadline&) = delete;
  ~RunDeadline() {
    {
      std::lock_guard lock(mMutex);
      mFinished = true;
    }
    mDone.notify_one();
    if (mWatch.joinable()) mWatch.join();
  }
  std::atomic<bool>* flag() { return &mStop; }
  bool passed() const { return mStop.load(); }

 private:
  std::atomic<bool> mStop{false};
  std::mutex mMutex;
  std::condition_variable mDone;
  bool mFinished = false;
  std::thread mWatch;
};

// A Mesh_3 run stopped by its deadline (caught in meshSurface like Mesh_3's own errors).
struct RunTimedOut : std::runtime_error {
  explicit RunTimedOut(double seconds)
      : std::runtime_error("a Mesh_3 run did not finish within its time limit of " + std::to_string(seconds) +
                           " s (TetMeshSettings::runTimeLimitS); Mesh_3's refinement can cycle without inserting "
                           "points on some inputs") {}
};

// What one final run does: the settings' values plus the mesher's adjustments.
struct RunPlan {
  double h = 0.0;
  Protection features = Protection::None;
  std::vector<SizingBall> balls;
};

// One Mesh_3 run. Nodes are numbered in the order the complex's cells first reach them, which is
// deterministic for a fixed input and seed (no pointer ordering).
TetMesh meshOnce(const Polyhedron& poly, const TetMeshSettings& s, const RunPlan& plan, const FeatureCurves& curves) {
  // CGAL's generator takes 32 bits: fold the high half in so every 64-bit seed counts.
  CGAL::get_default_random() = CGAL::Random(static_cast<unsigned int>(s.seed ^ (s.seed >> 32)));
  Domain domain(poly);
  if (plan.features == Protection::Detected) {
    domain.detect_features(s.featureAngleDeg);
  } else if (plan.features == Protection::Curves) {
    std::vector<std::vector<Kernel::Point_3>> lines;
    for (const auto& line : curves.polylines) {
      auto& out = lines.emplace_back();
      for (const auto& q : line) out.emplace_back(q.x(), q.y(), q.z());
    }
    domain.add_features(lines.begin(), lines.end());
  }
  namespace params = CGAL::parameters;
  const double h = plan.h;
  auto criteria = [&] {
    if (plan.balls.empty()) {
      return Criteria(params::edge_size = h, params::facet_angle = s.facetAngleDeg, params::facet_size = h,
                      params::facet_distance = s.facetDistanceFraction * h,
                      params::cell_radius_edge_ratio = s.cellRadiusEdgeRatio, params::cell_size = h);
    }
    const LocalSize size{h, plan.balls};
    return Criteria(params::edge_size = size, params::facet_angle = s.facetAngleDeg, params::facet_size = size,
                    params::facet_distance = s.facetDistanceFraction * h,
                    params::cell_radius_edge_ratio = s.cellRadiusEdgeRatio, params::cell_size = size);
  }();
  // Mesh_3 gives perturbation and exudation a wall-clock budget equal to the refinement time
  // unless told otherwise, which makes the mesh depend on machine load. time_limit = 0 means
  // "no clock"; the perturber then stops once every dihedral angle reaches sliverBoundDeg, so the
  // result depends on the input, the settings and the seed only.
  //
  // A run that outlasts s.runTimeLimitS is stopped and thrown away: the limit changes no mesh
  // that is made within it.
  RunDeadline deadline(s.runTimeLimitS);
  const auto options = params::mesh_3_options(params::pointer_to_stop_atomic_boolean = deadline.flag());
  C3t3 c3t3 = s.optimize
                  ? CGAL::make_mesh_3<C3t3>(
                        domain, criteria,
                        params::perturb(params::time_limit = 0.0, params::sliver_bound = s.sliverBoundDeg),
                        params::exude(params::time_limit = 0.0, params::sliver_bound = s.sliverBoundDeg), options)
                  : CGAL::make_mesh_3<C3t3>(domain, criteria, params::no_perturb(), params::no_exude(), options);
  if (deadline.passed()) throw RunTimedOut(s.runTimeLimitS);

  std::unordered_map<Tr::Vertex_handle, int32_t> index;
  std::vector<Eigen::Vector3d> nodes;
  std::vector<std::array<int32_t, 4>> tets;
  for (auto cell = c3t3.cells_in_complex_begin(); cell != c3t3.cells_in_complex_end(); ++cell) {
    std::array<int32_t, 4> tet;
    for (int k = 0; k < 4; ++k) {
      const auto vh = cell->vertex(k);
      auto [it, inserted] = index.emplace(vh, static_cast<int32_t>(nodes.size()));
      if (inserted) {
        const auto& p = vh->point();
        nodes.emplace_back(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
      }
      tet[k] = it->second;
    }
    if (signedTetVolume(nodes[tet[0]], nodes[tet[1]], nodes[tet[2]], nodes[tet[3]]) < 0.0) std::swap(tet[2], tet[3]);
    tets.push_back(tet);
  }
  TetMesh mesh;
  mesh.nodes.resize(static_cast<Eigen::Index>(nodes.size()), 3);
  for (size_t i = 0; i < nodes.size(); ++i) mesh.nodes.row(static_cast<Eigen::Index>(i)) = nodes[i].transpose();
  mesh.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
  for (size_t t = 0; t < tets.size(); ++t) {
    mesh.tets.row(static_cast<Eigen::Index>(t)) << tets[t][0], tets[t][1], tets[t][2], tets[t][3];
  }
  return compactNodes(mesh);
}

std::string fmt(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

// What is wrong with a run's mesh, if anything.
struct Check {
  enum Kind { Ok, Pieces, Degenerate } kind = Ok;
  int64_t pieces = 1;
  int64_t tets = 0;
  std::vector<SizingBall> splitOff;  ///< a ball around each piece but the largest
  int64_t degenerateTet = -1;
  double volumeM3 = 0.0, thresholdM3 = 0.0;
};

Check checkMesh(const TetMesh& mesh, double h) {
  Check c;
  c.tets = mesh.tets.rows();
  const auto labels = labelFaceConnectedComponents(mesh);
  c.pieces = labels.empty() ? 0 : int64_t{*std::max_element(labels.begin(), labels.end())} + 1;
  if (c.pieces > 1) {
    c.kind = Check::Pieces;
    std::vector<int64_t> size(static_cast<size_t>(c.pieces), 0);
    for (int32_t l : labels) ++size[static_cast<size_t>(l)];
    const auto largest = std::max_element(size.begin(), size.end()) - size.begin();  // first on ties
    for (int64_t piece = 0; piece < c.pieces; ++piece) {
      if (piece == largest) continue;
      // The ball around the piece's tet centroids, grown by a cell size to reach where it split.
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      std::vector<Eigen::Vector3d> centroids;
      for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
        if (labels[static_cast<size_t>(t)] != piece) continue;
        Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
        for (int k = 0; k < 4; ++k) centroid += mesh.nodes.row(mesh.tets(t, k)).transpose() / 4.0;
        centroids.push_back(centroid);
        sum += centroid;
      }
      SizingBall ball;
      ball.center = sum / static_cast<double>(centroids.size());
      for (const auto& q : centroids) ball.radiusM = std::max(ball.radiusM, (q - ball.center).norm());
      ball.radiusM += 2.0 * h;
      c.splitOff.push_back(ball);
    }
    return c;
  }
  c.thresholdM3 = degenerateTetVolumeM3(mesh.nodes);
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    const double v = signedTetVolume(mesh.nodes.row(mesh.tets(t, 0)).transpose(), mesh.nodes.row(mesh.tets(t, 1)).transpose(),
                                     mesh.nodes.row(mesh.tets(t, 2)).transpose(), mesh.nodes.row(mesh.tets(t, 3)).transpose());
    if (!(v > c.thresholdM3)) {
      c.kind = Check::Degenerate;
      c.degenerateTet = t;
      c.volumeM3 = v;
      return c;
    }
  }
  return c;
}

std::string describe(const Check& c, int run) {
  if (c.kind == Check::Pieces) {
    return "run " + std::to_string(run) + " gave " + std::to_string(c.pieces) + " face-connected pieces of " +
           std::to_string(c.tets) + " tets (a part thinner than the cell size)";
  }
  return "run " + std::to_string(run) + " gave a degenerate tet (" + fmt(c.volumeM3) + " m^3, at most " + fmt(c.thresholdM3) +
         " m^3)";
}

// The map x' = c + A(x − c), A = I + (k − 1) n nᵀ: a stretch by k along the unit axis n.
struct Stretch {
  Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  double k = 1.0;
  Eigen::Vector3d apply(const Eigen::Vector3d& x, double factor) const {
    const Eigen::Vector3d d = x - c;
    return c + d + (factor - 1.0) * n.dot(d) * n;
  }
  void apply(Points& points, double factor) const {
    for (Eigen::Index i = 0; i < points.rows(); ++i) points.row(i) = apply(Eigen::Vector3d(points.row(i).transpose()), factor).transpose();
  }
};

// tetrahedralize of `surface`, given stretched by `stretch`: Mesh_3 meshes it as given, and each
// run's nodes are taken back before they are checked, so that the checks and their adjustments
// see the mesh that is returned (a split-off piece's ball is stretched again for the next run).
Result<TetMeshResult> meshSurface(const TriangleMesh& surface, const TetMeshSettings& s, const Stretch& stretch,
                                  ProgressSink* progress) {
  if (s.targetTets <= 0 && !(s.cellSizeM > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "tet meshing needs a target tet count or a cell size > 0");
  }
  if (s.meshingRuns < 1) return makeError(ErrorCode::InvalidArgument, "tet meshing needs meshingRuns >= 1");
  const double volume = computeSurfaceMassProperties(surface, 1.0).volumeM3;
  if (!(volume > 0.0)) return makeError(ErrorCode::MeshingFailed, "surface encloses no volume");

  Polyhedron poly;
  try {
    poly = toPolyhedron(surface);
  } catch (const std::exception& e) {
    return makeError(ErrorCode::MeshingFailed, std::string("cannot build CGAL polyhedron: ") + e.what());
  }

  // Mesh_3 tets at cell size h average about 0.175 h³ (circumradius ~0.7 h, near-regular).
  // The size search runs refinement only (cheap); optimisation, which changes the count by a
  // few per cent, runs once at the chosen size.
  auto estimate = [&](int64_t target) { return std::cbrt(volume / (0.175 * static_cast<double>(target))); };
  double h = s.targetTets > 0 ? estimate(s.targetTets) : s.cellSizeM;
  TetMeshResult best;
  RunPlan plan;
  FeatureCurves curves;
  if (s.detectSharpFeatures) {
    // The creases worth protecting, measured against the first estimate of the cell size (the
    // size search moves it little), so that the choice does not depend on the search.
    curves = detectFeatureCurves(surface, {s.featureAngleDeg, s.minFeatureLengthCells * h, s.needleTurnDeg});
    // Nothing dropped: CGAL's own detection as before (it also splits the surface into patches).
    if (!curves.droppedAny()) {
      plan.features = Protection::Detected;
    } else {
      plan.features = curves.keptEdges > 0 ? Protection::Curves : Protection::None;
    }
    if (curves.droppedAny()) {
      best.adjustments.push_back(
          {"feature curves", "protecting " + std::to_string(curves.keptEdges) + " of " + std::to_string(curves.creaseEdges) +
                                 " crease edges (" + std::to_string(curves.keptGroups) + " of " + std::to_string(curves.groups) +
                                 " groups); " + std::to_string(curves.shortGroups) + " groups are shorter than " +
                                 fmt(s.minFeatureLengthCells) + " cell sizes and " + std::to_string(curves.needleGroups) +
                                 " turn back sharper than " + fmt(s.needleTurnDeg) + " deg, as scan noise does"});
    }
  }

  const int attemptsAllowed = s.targetTets > 0 ? std::max(1, s.maxAttempts) : 0;
  TetMeshSettings search = s;
  search.optimize = false;
  Check check;
  std::string tried;  // the adjustments, for an error message
  // The cell size that gives about `target` tets with the plan's features and local sizes,
  // searched from h0 with refinement-only runs.
  auto searchSize = [&](int64_t target, double h0) {
    double size = h0, chosen = h0;
    double bestMiss = std::numeric_limits<double>::infinity();
    for (int attempt = 0; attempt < attemptsAllowed; ++attempt) {
      reportProgress(progress, "tet meshing: sizing", static_cast<double>(attempt) / attemptsAllowed);
      plan.h = size;
      const double count = static_cast<double>(meshOnce(poly, search, plan, curves).tets.rows());
      ++best.attempts;
      if (count == 0) break;
      const double miss = std::abs(count / static_cast<double>(target) - 1.0);
      if (miss < bestMiss) bestMiss = miss, chosen = size;
      if (miss <= s.countTolerance) break;
      size *= std::cbrt(count / static_cast<double>(target));
    }
    return chosen;
  };
  int64_t target = s.targetTets;
  bool localSized = false;
  try {
    if (isInterrupted(progress)) return makeError(ErrorCode::Cancelled, "tet meshing cancelled");
    plan.h = searchSize(target, h);
    for (int run = 1;; ++run) {
      if (isInterrupted(progress)) return makeError(ErrorCode::Cancelled, "tet meshing cancelled");
      reportProgress(progress, s.optimize ? "tet meshing: refine + optimise" : "tet meshing: refine",
                     static_cast<double>(run - 1) / s.meshingRuns);
      best.mesh = meshOnce(poly, s, plan, curves);
      ++best.attempts;
      best.meshingRuns = run;
      if (best.mesh.tets.rows() == 0) {
        return makeError(ErrorCode::MeshingFailed,
                         "CGAL Mesh_3 produced no tetrahedra at cell size " + std::to_string(plan.h) + " m" + tried);
      }
      if (stretch.k != 1.0) stretch.apply(best.mesh.nodes, 1.0 / stretch.k);
      check = checkMesh(best.mesh, plan.h);
      for (SizingBall& ball : check.splitOff) {
        ball.center = stretch.apply(ball.center, stretch.k);
        ball.radiusM *= stretch.k;
      }
      if (check.kind == Check::Ok || run == s.meshingRuns) break;
      // The next adjustment (see TetMesher.h).
      MeshingAdjustment adjusted;
      if (check.kind == Check::Pieces && !localSized) {
        localSized = true;
        // Halve the size where each piece split off.
        for (const auto& ball : check.splitOff) plan.balls.push_back(ball);
        adjusted = {"local size halved", "around " + std::to_string(check.splitOff.size()) + " split-off piece" +
                                             (check.splitOff.size() == 1 ? "" : "s") + ": " + describe(check, run)};
      } else if (check.kind == Check::Degenerate && plan.features != Protection::None) {
        // Protection adds tets along the features: the size is searched again without it.
        plan.features = Protection::None;
        if (target > 0) plan.h = searchSize(target, estimate(target));
        adjusted = {"sharp features off", describe(check, run) + " with feature curves protected"};
      } else if (target > 0) {
        // Twice the tets, by a fresh size search (without local sizes) from the estimate for
        // twice the target: thin parts make the count far from cubic in the cell size, and a
        // search that starts from the last size can stall far from the target.
        target *= 2;
        plan.balls.clear();
        if (isInterrupted(progress)) return makeError(ErrorCode::Cancelled, "tet meshing cancelled");
        plan.h = searchSize(target, estimate(target));
        adjusted = {"tets doubled", describe(check, run) + "; now " + std::to_string(target) + " tets targeted, cell size " +
                                        fmt(plan.h) + " m"};
      } else {
        plan.h /= std::cbrt(2.0);
        adjusted = {"tets doubled", describe(check, run) + "; cell size now " + fmt(plan.h) + " m"};
      }
      tried += (tried.empty() ? "; adjusted: " : ", ") + adjusted.what;
      best.adjustments.push_back(std::move(adjusted));
    }
  } catch (const std::exception& e) {
    return makeError(ErrorCode::MeshingFailed, std::string("CGAL Mesh_3 failed: ") + e.what() + tried);
  }
  reportProgress(progress, "tet meshing", 1.0);
  best.cellSizeM = plan.h;
  best.sharpFeatures = plan.features != Protection::None;

  const std::string runs = " after " + std::to_string(best.meshingRuns) + " Mesh_3 run" + (best.meshingRuns == 1 ? "" : "s");
  if (check.kind == Check::Pieces) {
    return makeError(ErrorCode::MeshingFailed,
                     "Mesh_3 output is not one solid: " + std::to_string(check.pieces) +
                         " face-connected pieces at cell size " + std::to_string(plan.h) + " m" + runs + tried +
                         " (a part thinner than the cell size? try more tets)");
  }
  if (check.kind == Check::Degenerate) {
    return makeError(ErrorCode::DegenerateElement, "Mesh_3 output has a degenerate tet: tet " + std::to_string(check.degenerateTet) +
                                                       " has volume " + fmt(check.volumeM3) + " m^3 (at most " +
                                                       fmt(check.thresholdM3) + " m^3)" + runs + tried);
  }
  best.surfaceFaces = boundaryFaces(best.mesh);
  best.quality = computeMeshQuality(best.mesh);
  return best;
}

// The unit axis the solid extends least along: the second moment of volume's smallest principal
// direction (Eigen's self-adjoint solver sorts its values ascending), snapped onto a coordinate
// axis within 1e-12 so that an axis-aligned part is stretched and taken back exactly. None when
// the two smallest principal values are within a factor 2 (a cube, a ball, a bar, a vase).
std::optional<Eigen::Vector3d> thinAxis(const TriangleMesh& surface) {
  const Eigen::Matrix3d second = computeSurfaceMassProperties(surface, 1.0).secondMomentM5;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(second);
  const Eigen::Vector3d values = eigen.eigenvalues();
  if (!(values(0) > 0.0) || values(0) > 0.5 * values(1)) return std::nullopt;
  Eigen::Vector3d n = eigen.eigenvectors().col(0).normalized();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(n(a)) > 1.0 - 1e-12) n = Eigen::Vector3d::Unit(a);
  }
  return n;
}

}  // namespace

Result<TetMeshResult> tetrahedralize(const TriangleMesh& surface, const TetMeshSettings& s, ProgressSink* progress) {
  if (!isThinStretch(s.thinStretch)) {
    return makeError(ErrorCode::InvalidArgument, "tet meshing needs a thin-axis stretch in [1, 16]");
  }
  if (s.thinStretch == 1.0) return meshSurface(surface, s, Stretch{}, progress);
  // Mesh_3 makes near-regular tets, so a thin part gets as many elements as its thickness
  // demands. Stretched by k across its thinnest axis n, the part is meshed with tets k times
  // wider than thick once the nodes are taken back. The cell size, the target count and the
  // optimisers' sliver bound are those of the stretched solid.
  const auto n = thinAxis(surface);
  if (!n) {
    return makeError(ErrorCode::InvalidArgument, "a thin-axis stretch needs a flat part: the surface's two smallest "
                                                 "second moments are within a factor 2, so it has no one thin axis");
  }
  Stretch stretch;
  stretch.n = *n;
  stretch.c = surface.vertices.colwise().mean().transpose();
  stretch.k = s.thinStretch;
  TriangleMesh stretched = surface;
  stretch.apply(stretched.vertices, stretch.k);
  return meshSurface(stretched, s, stretch, progress);
}

}  // namespace brittle

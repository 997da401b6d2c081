#include "brittle/runtime/FragmentSurfaces.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <array>
#include <string>

#include "FixedRanges.h"

namespace brittle {
namespace {

struct Builder {
  const TetMesh& mesh;
  const TetTopology& topo;
  const Eigen::VectorXi& labels;
  const Eigen::VectorXd& cuts;
  FragmentSurfaceWorkspace& w;

  Builder(const TetMesh& m, const TetTopology& t, const Eigen::VectorXi& l, const Eigen::VectorXd& c,
          FragmentSurfaceWorkspace& workspace)
      : mesh(m), topo(t), labels(l), cuts(c), w(workspace) {
    w.edgePoint.assign(static_cast<size_t>(t.edges.rows()), -1);
    w.facePoint.assign(static_cast<size_t>(4 * m.tets.rows()), -1);
    w.triangles.clear();
    w.points.clear();
    for (Eigen::Index i = 0; i < m.nodes.rows(); ++i) w.points.emplace_back(m.nodes.row(i).transpose());
  }

  bool mixed(int32_t edge) const { return labels[topo.edges(edge, 0)] != labels[topo.edges(edge, 1)]; }

  int32_t onEdge(int32_t edge) {
    int32_t& id = w.edgePoint[static_cast<size_t>(edge)];
    if (id < 0) {
      const double s = std::clamp(cuts[edge], 0.05, 0.95);
      const Eigen::Vector3d a = w.points[static_cast<size_t>(topo.edges(edge, 0))];
      const Eigen::Vector3d b = w.points[static_cast<size_t>(topo.edges(edge, 1))];
      id = static_cast<int32_t>(w.points.size());
      w.points.push_back(a + s * (b - a));
    }
    return id;
  }

  // The edge id joining two nodes of tet e (local ids).
  int32_t edgeOf(Eigen::Index e, int i, int j) const {
    for (int k = 0; k < 6; ++k) {
      if ((kTetEdges[k][0] == i && kTetEdges[k][1] == j) || (kTetEdges[k][0] == j && kTetEdges[k][1] == i)) {
        return topo.tetEdges(e, k);
      }
    }
    return -1;
  }

  // The point of a mixed face (three local nodes of tet e): mean of its mixed-edge points. Shared
  // by the two tets of an interior face, so it is recorded on both sides.
  int32_t onFace(Eigen::Index e, std::array<int, 3> local) {
    const int f = 6 - local[0] - local[1] - local[2];  // the face opposite the fourth node
    const int32_t known = w.facePoint[static_cast<size_t>(4 * e + f)];
    if (known >= 0) return known;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (int k = 0; k < 3; ++k) {
      const int32_t edge = edgeOf(e, local[static_cast<size_t>(k)], local[static_cast<size_t>((k + 1) % 3)]);
      if (mixed(edge)) {
        sum += w.points[static_cast<size_t>(onEdge(edge))];
        ++count;
      }
    }
    const auto id = static_cast<int32_t>(w.points.size());
    w.points.push_back(sum / count);
    w.facePoint[static_cast<size_t>(4 * e + f)] = id;
    if (const int32_t nb = topo.neighbours(e, f); nb >= 0) {
      for (int g = 0; g < 4; ++g) {
        if (topo.neighbours(nb, g) == e) w.facePoint[static_cast<size_t>(4 * nb + g)] = id;
      }
    }
    return id;
  }

  // Triangulates a convex polygon of `count` points as a fan from its first.
  void fan(int label, const int32_t* polygon, int count) {
    for (int k = 1; k + 1 < count; ++k) w.triangles.push_back({label, polygon[0], polygon[k], polygon[k + 1]});
  }

  void boundaryFace(size_t i) {
    const auto [e, f] = topo.boundaryFaces[i];
    const auto local = tetFaceNodes(f);
    std::array<int32_t, 3> node{}, label{};
    for (int k = 0; k < 3; ++k) {
      node[static_cast<size_t>(k)] = mesh.tets(e, local[static_cast<size_t>(k)]);
      label[static_cast<size_t>(k)] = labels[node[static_cast<size_t>(k)]];
    }
    if (label[0] == label[1] && label[1] == label[2]) {
      w.triangles.push_back({label[0], node[0], node[1], node[2]});
      return;
    }
    const int32_t center = onFace(e, local);
    // With three corners, the corners of one label are consecutive around the face: walk from the
    // first corner of each run to its last, then through the edge point after it, the face point
    // and the edge point before it.
    for (int start = 0; start < 3; ++start) {
      const int prev = (start + 2) % 3;
      if (label[static_cast<size_t>(prev)] == label[static_cast<size_t>(start)]) continue;  // not a run start
      int32_t polygon[6];  // at most two corners, two edge points and the face point
      int size = 0;
      int k = start;
      while (true) {
        polygon[size++] = node[static_cast<size_t>(k)];
        const int next = (k + 1) % 3;
        if (label[static_cast<size_t>(next)] != label[static_cast<size_t>(start)]) {
          polygon[size++] = onEdge(edgeOf(e, local[static_cast<size_t>(k)], local[static_cast<size_t>(next)]));
          break;
        }
        k = next;
      }
      polygon[size++] = center;
      polygon[size++] = onEdge(edgeOf(e, local[static_cast<size_t>(prev)], local[static_cast<size_t>(start)]));
      fan(label[static_cast<size_t>(start)], polygon, size);
    }
  }

  void interior(Eigen::Index e) {
    std::array<int32_t, 6> edge{};
    bool any = false;
    for (int k = 0; k < 6; ++k) {
      edge[static_cast<size_t>(k)] = topo.tetEdges(e, k);
      any = any || mixed(edge[static_cast<size_t>(k)]);
    }
    if (!any) return;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (int32_t id : edge) {
      if (!mixed(id)) continue;
      sum += w.points[static_cast<size_t>(onEdge(id))];
      ++count;
    }
    const auto center = static_cast<int32_t>(w.points.size());
    w.points.push_back(sum / count);
    for (int k = 0; k < 6; ++k) {
      if (!mixed(edge[static_cast<size_t>(k)])) continue;
      const int i = kTetEdges[k][0], j = kTetEdges[k][1];
      int others[2], o = 0;
      for (int m = 0; m < 4; ++m) {
        if (m != i && m != j) others[o++] = m;
      }
      const int32_t p = onEdge(edge[static_cast<size_t>(k)]);
      const int32_t f1 = onFace(e, {i, j, others[0]});
      const int32_t f2 = onFace(e, {i, j, others[1]});
      std::array<int32_t, 4> quad = {p, f1, center, f2};
      // Orient the quad from node i's cell towards node j's.
      const Eigen::Vector3d normal = (w.points[static_cast<size_t>(center)] - w.points[static_cast<size_t>(p)])
                                         .cross(w.points[static_cast<size_t>(f2)] - w.points[static_cast<size_t>(f1)]);
      const Eigen::Vector3d along = mesh.nodes.row(mesh.tets(e, j)) - mesh.nodes.row(mesh.tets(e, i));
      if (normal.dot(along) < 0.0) std::swap(quad[1], quad[3]);
      fan(labels[mesh.tets(e, i)], quad.data(), 4);
      std::reverse(quad.begin(), quad.end());
      // Same diagonal (p, centre) for the other side: rotate so p leads again.
      std::rotate(quad.begin(), quad.begin() + 3, quad.end());
      fan(labels[mesh.tets(e, j)], quad.data(), 4);
    }
  }
};

Status checkLabelsAndCuts(const TetMesh& mesh, const TetTopology& topology, const Eigen::VectorXi& nodeLabels,
                          int labelCount, const Eigen::VectorXd& edgeCuts) {
  if (nodeLabels.size() != mesh.nodes.rows() || edgeCuts.size() != topology.edges.rows() || labelCount < 1) {
    return makeError(ErrorCode::InvalidArgument, "fragment surfaces: label or cut arrays do not match the mesh");
  }
  if (nodeLabels.minCoeff() < 0 || nodeLabels.maxCoeff() >= labelCount) {
    return makeError(ErrorCode::InvalidArgument, "fragment surfaces: node label out of range");
  }
  for (Eigen::Index e = 0; e < topology.edges.rows(); ++e) {
    if (nodeLabels[topology.edges(e, 0)] != nodeLabels[topology.edges(e, 1)] && !std::isfinite(edgeCuts[e])) {
      return makeError(ErrorCode::InvalidArgument, "fragment surfaces: edge " + std::to_string(e) +
                                                       " joins two fragments but has no finite cut");
    }
  }
  return Ok{};
}

// Parity of the permutation (i, j, k, l) of (0, 1, 2, 3): true when odd.
bool oddPermutation(int i, int j, int k, int l) {
  const int p[4] = {i, j, k, l};
  int inversions = 0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) inversions += p[a] > p[b] ? 1 : 0;
  return (inversions & 1) != 0;
}

}  // namespace

TetMoments tetVolumeMoments(const TetMesh& mesh, const Eigen::Vector3d& originM) {
  TetMoments out;
  out.originM = originM;
  out.perTet.assign(static_cast<size_t>(mesh.tets.rows()) * kFragmentMomentCount, 0.0);
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    Eigen::Vector3d p[4];
    for (int i = 0; i < 4; ++i) p[i] = mesh.nodes.row(mesh.tets(t, i)).transpose() - originM;
    double* block = out.perTet.data() + t * kFragmentMomentCount;
    addTetVolumeMoments(p[0], p[1], p[2], p[3], kFragmentMomentOrder, block);
    for (int m = 0; m < kFragmentMomentCount; ++m) out.total[static_cast<size_t>(m)] += block[m];
  }
  return out;
}

namespace {

// Adds the moments of tets [begin, end) to their fragments' blocks in `sums` (labelCount blocks,
// zeroed by the caller), leaving out the fragment `body`.
void addRangeMoments(const TetMesh& mesh, const TetTopology& topology, const TetMoments& tetMoments,
                     const Eigen::VectorXi& nodeLabels, const Eigen::VectorXd& edgeCuts, int body, Eigen::Index begin,
                     Eigen::Index end, double* sums) {
  constexpr int count = kFragmentMomentCount;
  const Eigen::Vector3d& originM = tetMoments.originM;
  double cell[count];
  for (Eigen::Index t = begin; t < end; ++t) {
    int label[4];
    for (int i = 0; i < 4; ++i) label[i] = nodeLabels[mesh.tets(t, i)];
    const double* whole = tetMoments.perTet.data() + t * count;
    if (label[0] == label[1] && label[1] == label[2] && label[2] == label[3]) {
      if (label[0] == body) continue;
      double* into = sums + static_cast<size_t>(label[0]) * count;
      for (int m = 0; m < count; ++m) into[m] += whole[m];
      continue;
    }
    // The points of the corner cells, relative to the origin, as the surface builder places them.
    Eigen::Vector3d x[4], edgePoint[4][4], facePoint[4], centre = Eigen::Vector3d::Zero();
    for (int i = 0; i < 4; ++i) x[i] = mesh.nodes.row(mesh.tets(t, i)).transpose() - originM;
    bool mixed[4][4] = {};
    int mixedEdges = 0;
    for (int k = 0; k < 6; ++k) {
      const int i = kTetEdges[static_cast<size_t>(k)][0], j = kTetEdges[static_cast<size_t>(k)][1];
      const int32_t edge = topology.tetEdges(t, k);
      Eigen::Vector3d p = 0.5 * (x[i] + x[j]);
      if (label[i] != label[j]) {
        const double s = std::clamp(edgeCuts[edge], 0.05, 0.95);
        const bool forward = topology.edges(edge, 0) == mesh.tets(t, i);
        const Eigen::Vector3d& a = forward ? x[i] : x[j];
        const Eigen::Vector3d& b = forward ? x[j] : x[i];
        p = a + s * (b - a);
        mixed[i][j] = mixed[j][i] = true;
        centre += p;
        ++mixedEdges;
      }
      edgePoint[i][j] = edgePoint[j][i] = p;
    }
    centre /= mixedEdges;
    for (int f = 0; f < 4; ++f) {  // face f: the three nodes other than f
      const auto local = tetFaceNodes(f);
      Eigen::Vector3d sum = Eigen::Vector3d::Zero(), corners = Eigen::Vector3d::Zero();
      int crossed = 0;
      for (int k = 0; k < 3; ++k) {
        const int i = local[static_cast<size_t>(k)], j = local[static_cast<size_t>((k + 1) % 3)];
        corners += x[i];
        if (mixed[i][j]) sum += edgePoint[i][j], ++crossed;
      }
      facePoint[f] = crossed > 0 ? Eigen::Vector3d(sum / crossed) : Eigen::Vector3d(corners / 3.0);
    }
    // The largest group of nodes with one label (ties: the lowest local node) takes the rest.
    int rest = 0, restSize = 0;
    for (int i = 0; i < 4; ++i) {
      int size = 0;
      for (int j = 0; j < 4; ++j) size += label[j] == label[i] ? 1 : 0;
      if (size > restSize) rest = i, restSize = size;
    }
    double* restInto = label[rest] == body ? nullptr : sums + static_cast<size_t>(label[rest]) * count;
    if (restInto) {
      for (int m = 0; m < count; ++m) restInto[m] += whole[m];
    }
    for (int i = 0; i < 4; ++i) {
      if (label[i] == label[rest]) continue;
      // Node i's corner cell: the sub-tets (x_i, e_ij, f_ijk, c) of the flags i ⊂ ij ⊂ ijk, each
      // oriented as the permutation (i, j, k, l) orients the tet.
      // The six sub-tets in this order, their moments added in it (addTetVolumeMomentsOrder4 takes
      // several at a time in wide registers, with the bits of one at a time).
      static_assert(kFragmentMomentOrder == 4);
      std::array<Eigen::Vector3d, 4> sub[6];
      int subs = 0;
      for (int j = 0; j < 4; ++j) {
        if (j == i) continue;
        for (int k = 0; k < 4; ++k) {
          if (k == i || k == j) continue;
          const int l = 6 - i - j - k;
          const bool odd = oddPermutation(i, j, k, l);
          sub[subs++] = {x[i], edgePoint[i][j], odd ? centre : facePoint[l], odd ? facePoint[l] : centre};
        }
      }
      std::fill(cell, cell + count, 0.0);
      addTetVolumeMomentsOrder4(sub, subs, cell);
      if (label[i] != body) {
        double* into = sums + static_cast<size_t>(label[i]) * count;
        for (int m = 0; m < count; ++m) into[m] += cell[m];
      }
      if (restInto) {
        for (int m = 0; m < count; ++m) restInto[m] -= cell[m];
      }
    }
  }
}

}  // namespace

Status fragmentVolumeMoments(const TetMesh& mesh, const TetTopology& topology, const TetMoments& tetMoments,
                             const Eigen::VectorXi& nodeLabels, int labelCount, const Eigen::VectorXd& edgeCuts,
                             std::vector<double>& moments) {
  std::vector<double> chunkSums;
  return fragmentVolumeMoments(mesh, topology, tetMoments, nodeLabels, labelCount, edgeCuts, chunkSums, moments);
}

Status fragmentVolumeMoments(const TetMesh& mesh, const TetTopology& topology, const TetMoments& tetMoments,
                             const Eigen::VectorXi& nodeLabels, int labelCount, const Eigen::VectorXd& edgeCuts,
                             std::vector<double>& chunkSums, std::vector<double>& moments) {
  if (Status st = checkLabelsAndCuts(mesh, topology, nodeLabels, labelCount, edgeCuts); !st) return st;
  constexpr int count = kFragmentMomentCount;
  if (tetMoments.perTet.size() != static_cast<size_t>(mesh.tets.rows()) * count) {
    return makeError(ErrorCode::InvalidArgument, "fragment moments: tetMoments needs one block per tet");
  }
  moments.assign(static_cast<size_t>(labelCount) * count, 0.0);
  if (labelCount == 0) return Ok{};
  // The fragment with the most nodes is left out of the sums and is the body minus the others.
  // Its block serves as a node count first.
  for (Eigen::Index n = 0; n < nodeLabels.size(); ++n) moments[static_cast<size_t>(nodeLabels[n]) * count] += 1.0;
  int body = 0;
  for (int l = 1; l < labelCount; ++l) {
    if (moments[static_cast<size_t>(l) * count] > moments[static_cast<size_t>(body) * count]) body = l;
  }
  for (int l = 0; l < labelCount; ++l) moments[static_cast<size_t>(l) * count] = 0.0;
  // Fixed ranges, each into its own sums, added in range order.
  const size_t block = static_cast<size_t>(labelCount) * count;
  chunkSums.assign(block * kMomentChunks, 0.0);
  const Eigen::Index tets = mesh.tets.rows();
  detail::forFixedRanges(tets, kMomentChunks, [&](int c, Eigen::Index begin, Eigen::Index end) {
    addRangeMoments(mesh, topology, tetMoments, nodeLabels, edgeCuts, body, begin, end,
                    chunkSums.data() + block * static_cast<size_t>(c));
  });
  for (int c = 0; c < kMomentChunks; ++c) {
    const double* sums = chunkSums.data() + block * static_cast<size_t>(c);
    for (size_t m = 0; m < block; ++m) moments[m] += sums[m];
  }
  double* bodyInto = moments.data() + static_cast<size_t>(body) * count;
  for (int m = 0; m < count; ++m) bodyInto[m] = tetMoments.total[static_cast<size_t>(m)];
  for (int l = 0; l < labelCount; ++l) {
    if (l == body) continue;
    for (int m = 0; m < count; ++m) bodyInto[m] -= moments[static_cast<size_t>(l) * count + m];
  }
  return Ok{};
}

void FragmentSurfaceWorkspace::reserve(Eigen::Index nodes, Eigen::Index tets, Eigen::Index edges,
                                       Eigen::Index boundaryFaces) {
  // Created points: one per mixed edge, face and tet; triangles: boundary pieces and the crack
  // faces' quads (two triangles per mixed edge per side).
  points.reserve(static_cast<size_t>(nodes + edges + 2 * tets + boundaryFaces));
  edgePoint.reserve(static_cast<size_t>(edges));
  facePoint.reserve(static_cast<size_t>(4 * tets));
  triangles.reserve(static_cast<size_t>(3 * boundaryFaces + 4 * edges));
  order.reserve(triangles.capacity());
  labelStart.reserve(static_cast<size_t>(nodes) + 1);
  fill.reserve(static_cast<size_t>(nodes));
  local.reserve(points.capacity());
  used.reserve(points.capacity());
}

Result<std::vector<TriangleMesh>> buildFragmentSurfaces(const TetMesh& mesh, const TetTopology& topology,
                                                        const Eigen::VectorXi& nodeLabels, int labelCount,
                                                        const Eigen::VectorXd& edgeCuts) {
  FragmentSurfaceWorkspace workspace;
  std::vector<TriangleMesh> out;
  if (Status st = buildFragmentSurfaces(mesh, topology, nodeLabels, labelCount, edgeCuts, workspace, out); !st) {
    return st.error();
  }
  return out;
}

Status buildFragmentSurfaces(const TetMesh& mesh, const TetTopology& topology, const Eigen::VectorXi& nodeLabels,
                             int labelCount, const Eigen::VectorXd& edgeCuts, FragmentSurfaceWorkspace& w,
                             std::vector<TriangleMesh>& out) {
  if (Status st = checkLabelsAndCuts(mesh, topology, nodeLabels, labelCount, edgeCuts); !st) return st;
  Builder b(mesh, topology, nodeLabels, edgeCuts, w);
  for (size_t i = 0; i < topology.boundaryFaces.size(); ++i) b.boundaryFace(i);
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) b.interior(e);

  // The triangles grouped by label, in creation order within each (a stable counting sort).
  const auto labels = static_cast<size_t>(labelCount);
  w.labelStart.assign(labels + 1, 0);
  for (const auto& t : w.triangles) ++w.labelStart[static_cast<size_t>(t[0]) + 1];
  for (size_t l = 0; l < labels; ++l) {
    if (w.labelStart[l + 1] == 0) {
      return makeError(ErrorCode::InvalidArgument, "fragment surfaces: label " + std::to_string(l) + " has no surface");
    }
    w.labelStart[l + 1] += w.labelStart[l];
  }
  w.order.resize(w.triangles.size());
  w.fill.assign(w.labelStart.begin(), w.labelStart.end() - 1);
  for (size_t i = 0; i < w.triangles.size(); ++i) {
    w.order[static_cast<size_t>(w.fill[static_cast<size_t>(w.triangles[i][0])]++)] = static_cast<int32_t>(i);
  }
  out.resize(labels);
  w.local.assign(w.points.size(), -1);
  for (size_t l = 0; l < labels; ++l) {
    const auto first = static_cast<size_t>(w.labelStart[l]), last = static_cast<size_t>(w.labelStart[l + 1]);
    w.used.clear();
    for (size_t i = first; i < last; ++i) {
      const auto& t = w.triangles[static_cast<size_t>(w.order[i])];
      for (int k = 1; k < 4; ++k) {
        const int32_t p = t[static_cast<size_t>(k)];
        if (w.local[static_cast<size_t>(p)] < 0) {
          w.local[static_cast<size_t>(p)] = static_cast<int32_t>(w.used.size());
          w.used.push_back(p);
        }
      }
    }
    TriangleMesh& m = out[l];
    m.vertices.resize(static_cast<Eigen::Index>(w.used.size()), 3);
    for (size_t i = 0; i < w.used.size(); ++i) {
      m.vertices.row(static_cast<Eigen::Index>(i)) = w.points[static_cast<size_t>(w.used[i])].transpose();
    }
    m.faces.resize(static_cast<Eigen::Index>(last - first), 3);
    for (size_t i = first; i < last; ++i) {
      const auto& t = w.triangles[static_cast<size_t>(w.order[i])];
      for (int k = 0; k < 3; ++k) {
        m.faces(static_cast<Eigen::Index>(i - first), k) = w.local[static_cast<size_t>(t[static_cast<size_t>(k) + 1])];
      }
    }
    for (int32_t p : w.used) w.local[static_cast<size_t>(p)] = -1;
  }
  return Ok{};
}

}  // namespace brittle

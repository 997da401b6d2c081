#include "brittle/descriptors/VoxelDescriptor.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "SurfaceChecks.h"
#include "TriangleDistances.h"
#include "brittle/core/Simd.h"

namespace brittle {
namespace {

Status checkGrid(int resolution, double halfExtent) {
  if (resolution < 2 || resolution > 256) {
    return makeError(ErrorCode::InvalidArgument, "voxel resolution " + std::to_string(resolution) + " is outside [2, 256]");
  }
  if (!std::isfinite(halfExtent) || !(halfExtent > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "voxel halfExtent must be finite and positive");
  }
  return Ok{};
}

// Occupancy of the voxel centres by parity along z: for each column (i, j) of centres, the
// crossings of the line x = x_i, y = y_j with the surface, and a centre is inside when the number
// of crossings at or above it is odd. Exact for a closed surface, with one rule for a line through
// an edge or a vertex: a triangle owns a point of its projected boundary by the "top-left" rule on
// its edges, each edge's side computed with its end points in one fixed order, so that the two
// triangles at an edge agree to the bit. Where they lie on opposite sides of the edge (the surface
// crosses the line there) exactly one owns the point; where they fold over (a silhouette) both or
// neither do, and the parity does not change. Triangles whose projection has no area (walls along
// z) own no point: their neighbours' edges decide.
std::vector<float> occupancyByParity(const Points& canonical, const Triangles& faces, int k, double c) {
  const double h = 2.0 * c / k;
  auto centre = [&](int i) { return -c + (i + 0.5) * h; };
  // The side of p from the edge u → v, with u and v taken in lexicographic order and the sign
  // flipped back: the same number, bit for bit, from both triangles of the edge.
  auto side = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v, double px, double py) {
    const bool swap = v.x() < u.x() || (v.x() == u.x() && v.y() < u.y());
    const Eigen::Vector2d& a = swap ? v : u;
    const Eigen::Vector2d& b = swap ? u : v;
    const double w = (b.x() - a.x()) * (py - a.y()) - (b.y() - a.y()) * (px - a.x());
    return swap ? -w : w;
  };
  // Each triangle's crossings once, as (column, z); then grouped by column (counting sort).
  const auto columns = static_cast<size_t>(k) * static_cast<size_t>(k);
  std::vector<std::pair<uint32_t, float>> hits;
  hits.reserve(static_cast<size_t>(2 * columns));
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    Eigen::Vector2d p[3];
    double z[3];
    for (int m = 0; m < 3; ++m) {
      p[m] = canonical.row(faces(f, m)).head<2>().transpose();
      z[m] = canonical(faces(f, m), 2);
    }
    double area = (p[1] - p[0]).x() * (p[2] - p[0]).y() - (p[1] - p[0]).y() * (p[2] - p[0]).x();
    if (area == 0.0) continue;
    if (area < 0.0) {  // counter-clockwise in projection from here on
      std::swap(p[1], p[2]);
      std::swap(z[1], z[2]);
      area = -area;
    }
    const double xmin = std::min({p[0].x(), p[1].x(), p[2].x()}), xmax = std::max({p[0].x(), p[1].x(), p[2].x()});
    const double ymin = std::min({p[0].y(), p[1].y(), p[2].y()}), ymax = std::max({p[0].y(), p[1].y(), p[2].y()});
    const int i0 = std::max(0, static_cast<int>(std::ceil((xmin + c) / h - 0.5)));
    const int i1 = std::min(k - 1, static_cast<int>(std::floor((xmax + c) / h - 0.5)));
    const int j0 = std::max(0, static_cast<int>(std::ceil((ymin + c) / h - 0.5)));
    const int j1 = std::min(k - 1, static_cast<int>(std::floor((ymax + c) / h - 0.5)));
    for (int i = i0; i <= i1; ++i) {
      const double x = centre(i);
      for (int j = j0; j <= j1; ++j) {
        const double y = centre(j);
        double w[3];
        bool owned = true;
        for (int m = 0; m < 3 && owned; ++m) {
          const Eigen::Vector2d& a = p[(m + 1) % 3];
          const Eigen::Vector2d& b = p[(m + 2) % 3];
          w[m] = side(a, b, x, y);  // > 0: inside of edge a → b (the triangle is counter-clockwise)
          // Top-left rule: on the edge itself, owned when the edge is a top edge (horizontal,
          // pointing to −x) or a left edge (pointing to −y).
          const Eigen::Vector2d d = b - a;
          const bool topLeft = (d.y() == 0.0 && d.x() < 0.0) || d.y() < 0.0;
          owned = w[m] > 0.0 || (w[m] == 0.0 && topLeft);
        }
        if (!owned) continue;
        const auto q = static_cast<uint32_t>(i * k + j);
        hits.emplace_back(q, static_cast<float>((w[0] * z[0] + w[1] * z[1] + w[2] * z[2]) / area));
      }
    }
  }
  std::vector<uint32_t> start(columns + 1, 0);
  for (const auto& hit : hits) ++start[hit.first + 1];
  for (size_t q = 0; q < columns; ++q) start[q + 1] += start[q];
  std::vector<float> crossings(hits.size());
  std::vector<uint32_t> fill(start.begin(), start.end() - 1);
  for (const auto& hit : hits) crossings[fill[hit.first]++] = hit.second;
  std::vector<float> out(columns * static_cast<size_t>(k), 0.0f);
  for (size_t q = 0; q < columns; ++q) {
    const auto first = crossings.begin() + start[q], last = crossings.begin() + start[q + 1];
    std::sort(first, last);
    // Walk the centres upwards; `above` counts the crossings at or above the centre.
    auto above = static_cast<size_t>(last - first);
    auto next = first;
    for (int l = 0; l < k; ++l) {
      const auto zl = static_cast<float>(centre(l));
      while (next != last && *next < zl) {
        ++next;
        --above;
      }
      out[q * static_cast<size_t>(k) + static_cast<size_t>(l)] = (above % 2 == 1) ? 1.0f : 0.0f;
    }
  }
  return out;
}

// The signed distance at the k³ voxel centres, clamped to ±reach and divided by it (negative
// inside), in grid order. Only centres within `reach` of the surface need a distance: each triangle
// visits the centres that can be within reach of it (below), and measures one (its closest point,
// brittle/core/TriangleGeometry.h) only where the bound from its enclosing sphere (|p − m| − R)
// could beat the centre's nearest so far. A centre no triangle comes within `reach` of reads
// exactly ±1. The sign is the parity fill's (exact). Every distance is exact in double; the fixed
// face order and a minimum make it the same in any process.
//
// The visits only bound which centres are measured; a centre no bound rules out is measured. The
// box and slab bounds are widened by 1e-9 of a voxel, so rounding never leaves out a centre that the
// exact bounds keep; a centre past a bound by more than rounding is beyond reach of the triangle, so
// its distance could not replace a nearest, which is at most reach. A triangle's centres are
// gathered first, then measured several to a vector register (TriangleDistances.h, closestOnTriangle's
// bits): each centre once a triangle, so the order within a triangle changes nothing.
std::vector<float> clampedSignedDistance(const Points& canonical, const Triangles& faces, int k, double c, double reach) {
  const double h = 2.0 * c / k, perVoxel = 1.0 / h;
  constexpr double kWiden = 1e-9;  // voxels
  std::vector<double> centres(static_cast<size_t>(k));
  for (int i = 0; i < k; ++i) centres[static_cast<size_t>(i)] = -c + (i + 0.5) * h;
  // The first and last centre index at or beyond x, from x's position in voxels (centre i at i),
  // kept to [−1, k] before the conversion.
  const auto index = [&](double x) { return std::clamp((x + c) * perVoxel - 0.5, -1.0, static_cast<double>(k)); };
  const auto first = [&](double low) {
    const double x = index(low) - kWiden;
    const int i = static_cast<int>(x);
    return std::max(0, i + (i < x ? 1 : 0));
  };
  const auto last = [&](double high) {
    const double x = index(high) + kWiden;
    const int i = static_cast<int>(x);
    return std::min(k - 1, i - (i > x ? 1 : 0));
  };
  const auto cells = static_cast<size_t>(k) * static_cast<size_t>(k) * static_cast<size_t>(k);
  const std::array<int64_t, 3> stride{int64_t{k} * k, k, 1};
  std::vector<double> nearest(cells, reach);  // each centre's distance to the surface so far, at most reach
  std::vector<uint32_t> visited;              // a triangle's centres to measure, and their x, y, z
  std::vector<double> px, py, pz, measured;
  const Lanes lanes = widestLanes();
  // The centres a triangle visits: the columns along its normal's largest axis w within R + reach
  // of its centroid m, each cut to the slab of its plane (a centre within reach of the triangle lies
  // within reach of its plane: |t − t_plane| ≤ reach/|n̂_w|).
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector3d a = canonical.row(faces(f, 0)).transpose(), b = canonical.row(faces(f, 1)).transpose(),
                          v = canonical.row(faces(f, 2)).transpose();
    const Eigen::Vector3d low = a.cwiseMin(b).cwiseMin(v), high = a.cwiseMax(b).cwiseMax(v);
    const Eigen::Vector3d m = (a + b + v) / 3.0;
    const double radius = std::sqrt(std::max({(a - m).squaredNorm(), (b - m).squaredNorm(), (v - m).squaredNorm()}));
    const Eigen::Vector3d normal = (b - a).cross(v - a);
    int w = 0;
    for (int x = 1; x < 3; ++x) w = std::abs(normal[x]) > std::abs(normal[w]) ? x : w;
    const int u = (w + 1) % 3, t = (w + 2) % 3;
    const bool flat = normal[w] != 0.0;  // else no area: every centre of the box
    const double slack = flat ? reach * normal.norm() / std::abs(normal[w]) : 0.0;
    const double slopeU = flat ? -normal[u] / normal[w] : 0.0, slopeT = flat ? -normal[t] / normal[w] : 0.0;
    const int u0 = first(low[u] - reach), u1 = last(high[u] + reach), t0 = first(low[t] - reach), t1 = last(high[t] + reach);
    const int wLow = first(low[w] - reach), wHigh = last(high[w] + reach);
    if (u0 > u1 || t0 > t1 || wLow > wHigh) continue;
    const double sphere2 = (radius + reach) * (radius + reach);
    // At most a slab's worth of centres a column (2 slack / h + 1, and 2 more for the widening and
    // the rounding of its two ends): a triangle across a fine grid keeps the buffers to its slab.
    const int perColumn = flat ? std::min(wHigh - wLow + 1, static_cast<int>(2.0 * slack * perVoxel) + 3) : wHigh - wLow + 1;
    const auto most = static_cast<size_t>(u1 - u0 + 1) * static_cast<size_t>(t1 - t0 + 1) * static_cast<size_t>(perColumn);
    if (visited.size() < most) visited.resize(most), px.resize(most), py.resize(most), pz.resize(most), measured.resize(most);
    // The centres' x, y, z in px, py, pz (the order of closestOnTriangle's sums, so its bits).
    const std::array<double*, 3> axis{px.data(), py.data(), pz.data()};
    double* alongU = axis[static_cast<size_t>(u)];
    double* alongT = axis[static_cast<size_t>(t)];
    double* alongW = axis[static_cast<size_t>(w)];
    size_t count = 0;
    for (int iu = u0; iu <= u1; ++iu) {
      const double pu = centres[static_cast<size_t>(iu)], du = pu - m[u];
      for (int it = t0; it <= t1; ++it) {
        const double pt = centres[static_cast<size_t>(it)], dt = pt - m[t];
        const double column2 = du * du + dt * dt;
        if (column2 > sphere2) continue;  // the column misses the sphere
        int w0 = wLow, w1 = wHigh;
        if (flat) {
          const double plane = a[w] + slopeU * (pu - a[u]) + slopeT * (pt - a[t]);
          w0 = std::max(w0, first(plane - slack));
          w1 = std::min(w1, last(plane + slack));
        }
        assert(w1 - w0 < perColumn);
        const int64_t column = iu * stride[static_cast<size_t>(u)] + it * stride[static_cast<size_t>(t)];
        for (int iw = w0; iw <= w1; ++iw) {
          const auto n = static_cast<size_t>(column + iw * stride[static_cast<size_t>(w)]);
          const double pw = centres[static_cast<size_t>(iw)], dw = pw - m[w];
          const double reachable = radius + nearest[n];
          // Written in any case and kept where the triangle can be nearer than the centre's nearest
          // (about half are: a branch here mispredicted at that rate).
          visited[count] = static_cast<uint32_t>(n);
          alongU[count] = pu, alongT[count] = pt, alongW[count] = pw;
          count += column2 + dw * dw > reachable * reachable ? 0 : 1;
        }
      }
    }
    if (count == 0) continue;
    detail::squaredDistancesToTriangle(px.data(), py.data(), pz.data(), count, a, b, v, measured.data(), lanes);
    // The nearer of the two: min(d, √m) is (m < d² ? √m : d) to the bit, since √fl(d²) = d.
    for (size_t i = 0; i < count; ++i) {
      double& d = nearest[visited[i]];
      d = std::min(d, std::sqrt(measured[i]));
    }
  }
  const std::vector<float> inside = occupancyByParity(canonical, faces, k, c);
  std::vector<float> out(cells);
  for (size_t n = 0; n < cells; ++n) {
    const double d = nearest[n];
    const float magnitude = d >= reach ? 1.0f : static_cast<float>(d / reach);
    out[n] = inside[n] == 1.0f && magnitude > 0.0f ? -magnitude : magnitude;
  }
  return out;
}

template <typename Settings, typename Single>
Result<DescriptorMatrix> forEachFrame(const TriangleMesh& surface, const CanonicalFrames& frames,
                                      const Settings& settings, Single single) {
  if (frames.candidates.empty()) return makeError(ErrorCode::InvalidArgument, "no canonical frame given");
  const Eigen::Index k3 = static_cast<Eigen::Index>(settings.resolution) * settings.resolution * settings.resolution;
  DescriptorMatrix out;
  for (size_t c = 0; c < frames.candidates.size(); ++c) {
    auto d = single(surface, frames.candidates[c], settings);
    if (!d) return d.error();
    if (c == 0) out.resize(static_cast<Eigen::Index>(frames.candidates.size()), k3);
    out.row(static_cast<Eigen::Index>(c)) = d.value().transpose();
  }
  return out;
}

}  // namespace

Status validateVoxelDescriptorSettings(const VoxelDescriptorSettings& settings) {
  return checkGrid(settings.resolution, settings.halfExtent);
}

Status validateImprovedVoxelDescriptorSettings(const ImprovedVoxelDescriptorSettings& settings) {
  if (auto status = checkGrid(settings.resolution, settings.halfExtent); !status) return status;
  if (!std::isfinite(settings.clampVoxels) || settings.clampVoxels < 0.5 || settings.clampVoxels > settings.resolution) {
    return makeError(ErrorCode::InvalidArgument, "ImprovedVoxelDescriptorSettings.clampVoxels must be in [0.5, resolution]");
  }
  return Ok{};
}

Result<Descriptor> computeVoxelDescriptor(const TriangleMesh& surface, const CanonicalFrame& frame,
                                          const VoxelDescriptorSettings& settings) {
  if (auto status = validateVoxelDescriptorSettings(settings); !status) return status.error();
  if (auto status = detail::checkFrame(frame); !status) return status.error();
  if (auto status = detail::checkClosedSurface(surface); !status) return status.error();
  // Occupancy needs only inside or outside: a parity fill along the grid's columns, exact and
  // without OpenVDB's narrow band (measured: 16³ of a 1k-triangle fragment, see
  // docs/results/fragment-database.md).
  const std::vector<float> inside =
      occupancyByParity(frame.pointsToCanonical(surface.vertices), surface.faces, settings.resolution, settings.halfExtent);
  return Descriptor(Eigen::Map<const Descriptor>(inside.data(), static_cast<Eigen::Index>(inside.size())));
}

Result<Descriptor> computeImprovedVoxelDescriptor(const TriangleMesh& surface, const CanonicalFrame& frame,
                                                  const ImprovedVoxelDescriptorSettings& settings) {
  if (auto status = validateImprovedVoxelDescriptorSettings(settings); !status) return status.error();
  if (auto status = detail::checkFrame(frame); !status) return status.error();
  if (auto status = detail::checkClosedSurface(surface); !status) return status.error();
  // Exact distances within the clamp and the parity fill's sign, without OpenVDB's narrow band
  // (4.1 ms a 1k-triangle fragment through it; measured in docs/results/fragment-database.md).
  const double h = 2.0 * settings.halfExtent / settings.resolution;
  const std::vector<float> clamped = clampedSignedDistance(frame.pointsToCanonical(surface.vertices), surface.faces, settings.resolution,
                                                           settings.halfExtent, settings.clampVoxels * h);
  return Descriptor(Eigen::Map<const Descriptor>(clamped.data(), static_cast<Eigen::Index>(clamped.size())));
}

Result<DescriptorMatrix> computeVoxelDescriptors(const TriangleMesh& surface, const CanonicalFrames& frames,
                                                 const VoxelDescriptorSettings& settings) {
  return forEachFrame(surface, frames, settings,
                      [](const TriangleMesh& s, const CanonicalFrame& f, const VoxelDescriptorSettings& v) {
                        return computeVoxelDescriptor(s, f, v);
                      });
}

Result<DescriptorMatrix> computeImprovedVoxelDescriptors(const TriangleMesh& surface, const CanonicalFrames& frames,
                                                         const ImprovedVoxelDescriptorSettings& settings) {
  return forEachFrame(surface, frames, settings,
                      [](const TriangleMesh& s, const CanonicalFrame& f, const ImprovedVoxelDescriptorSettings& v) {
                        return computeImprovedVoxelDescriptor(s, f, v);
                      });
}

}  // namespace brittle

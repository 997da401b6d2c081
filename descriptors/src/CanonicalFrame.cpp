#include "brittle/descriptors/CanonicalFrame.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "brittle/descriptors/VolumeMoments.h"

namespace brittle {
namespace {

// Moments up to order 4 are what the frame needs: 2 for the axes, 3 for signs, 4 for symmetric
// shapes.
constexpr int kFrameOrder = 4;
// A solid whose volume is below this fraction of its bounding-box diagonal cubed is flat.
constexpr double kMinRelativeVolume = 1e-12;
// Sampling density of the direction searches, and the radius around a found extremum inside which
// further samples are taken to lead to the same extremum.
constexpr int kCircleSamples = 360;
constexpr int kSphereSamples = 2000;
constexpr double kSameBasinRad = 0.2;
// Two refined directions closer than this are the same direction.
constexpr double kSameDirectionCos = 1.0 - 1e-6;

struct DirectionChoice {
  Eigen::Vector3d direction;
  bool signFixed = false;  // true when chosen by an odd moment, which fixes the sign as well
};

// Rows are the canonical axes written in the principal (y) coordinates.
struct AxisChoice {
  Eigen::Matrix3d axes;
  std::array<bool, 3> signFixed{};
};

// The circle's cos θ_k, sin θ_k and the Fibonacci sphere's directions, made once: they are the
// same for every solid (std::cos and std::sin of the same angles, so the same bits as making them
// per call, which cost about as much as the moments' pass).
struct SampleTables {
  std::array<double, kCircleSamples> cosine{}, sine{};
  std::vector<Eigen::Vector3d> sphere;
  SampleTables() {
    for (int k = 0; k < kCircleSamples; ++k) {
      const double theta = 2.0 * std::numbers::pi * k / kCircleSamples;
      cosine[k] = std::cos(theta), sine[k] = std::sin(theta);
    }
    sphere.reserve(kSphereSamples);  // Fibonacci sphere: near-uniform, deterministic.
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (int k = 0; k < kSphereSamples; ++k) {
      const double z = 1.0 - (2.0 * k + 1.0) / kSphereSamples;
      const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
      sphere.emplace_back(r * std::cos(golden * k), r * std::sin(golden * k), z);
    }
  }
};

const SampleTables& sampleTables() {
  static const SampleTables tables;
  return tables;
}

// The circle's samples in the plane spanned by p, q.
std::vector<Eigen::Vector3d> circleDirections(const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  const SampleTables& t = sampleTables();
  std::vector<Eigen::Vector3d> out;
  out.reserve(kCircleSamples);
  for (int k = 0; k < kCircleSamples; ++k) out.push_back(t.cosine[k] * p + t.sine[k] * q);
  return out;
}

// Local maximum of sign·∫(u·y)^order on the unit sphere of the subspace with orthogonal projector
// `projector`, by projected gradient ascent with an adaptive step (radians).
Eigen::Vector3d refineMaximum(const VolumeMoments& m, int order, double sign, const Eigen::Matrix3d& projector,
                              Eigen::Vector3d u) {
  double f = sign * m.directional(u, order);
  double step = 0.05;
  for (int it = 0; it < 300 && step > 1e-13; ++it) {
    Eigen::Vector3d g = projector * (sign * m.directionalGradient(u, order));
    g -= g.dot(u) * u;
    const double gn = g.norm();
    if (!(gn > 0.0)) break;
    const Eigen::Vector3d trial = (std::cos(step) * u + std::sin(step) * (g / gn)).normalized();
    const double ft = sign * m.directional(trial, order);
    if (ft > f) {
      u = trial, f = ft, step *= 1.5;
    } else {
      step *= 0.5;
    }
  }
  return u;
}

bool sameDirection(const Eigen::Vector3d& a, const Eigen::Vector3d& b, bool lineWise, double cosTolerance) {
  const double d = a.dot(b);
  return lineWise ? std::abs(d) > cosTolerance : d > cosTolerance;
}

// Candidate directions inside a degenerate subspace (the plane spanned by p, q, or all of space),
// chosen by 3rd- then 4th-order directional moments; empty when the subspace looks symmetric.
// secondMoment is the (common) principal second moment there, used to make the test scale-free.
std::vector<DirectionChoice> chooseDirections(const VolumeMoments& m, const Eigen::Vector3d& p,
                                              const Eigen::Vector3d& q, bool plane, double secondMoment,
                                              const CanonicalFrameSettings& settings) {
  const std::vector<Eigen::Vector3d> circle = plane ? circleDirections(p, q) : std::vector<Eigen::Vector3d>();
  const std::vector<Eigen::Vector3d>& samples = plane ? circle : sampleTables().sphere;  // the sphere's, not a copy
  const Eigen::Matrix3d projector =
      plane ? Eigen::Matrix3d(p * p.transpose() + q * q.transpose()) : Eigen::Matrix3d::Identity();
  std::vector<double> values(samples.size());
  for (int order = 3; order <= 4; ++order) {
    m.directional(samples.data(), samples.size(), order, values.data());
    const auto [minIt, maxIt] = std::minmax_element(values.begin(), values.end());
    const double lo = *minIt, hi = *maxIt, range = hi - lo;
    if (!(range > settings.shapeTolerance * std::pow(secondMoment, 0.5 * order))) continue;

    // Odd order: the maximum (its sign is meaningful). Even order: the extremum farther from the
    // mean, or both when they nearly tie.
    std::vector<double> signs;
    if (order == 3) {
      signs = {1.0};
    } else {
      double mean = 0.0;
      for (double v : values) mean += v;
      mean /= static_cast<double>(values.size());
      const double dMax = hi - mean, dMin = mean - lo, dBest = std::max(dMax, dMin);
      // Minima first: for boxes they are the face normals, which makes the first frame the
      // natural one.
      if (dMin >= (1.0 - settings.tieTolerance) * dBest) signs.push_back(-1.0);
      if (dMax >= (1.0 - settings.tieTolerance) * dBest) signs.push_back(1.0);
    }
    const bool lineWise = order % 2 == 0;
    std::vector<DirectionChoice> out;
    for (double sign : signs) {
      const double best = sign > 0 ? hi : -lo;
      std::vector<size_t> order3(samples.size());
      for (size_t k = 0; k < order3.size(); ++k) order3[k] = k;
      std::stable_sort(order3.begin(), order3.end(),
                       [&](size_t a, size_t b) { return sign * values[a] > sign * values[b]; });
      std::vector<Eigen::Vector3d> found;
      std::vector<double> foundValue;
      for (size_t k : order3) {
        if (sign * values[k] < best - settings.tieTolerance * range) break;
        bool near = false;
        for (const auto& f : found) near = near || sameDirection(samples[k], f, lineWise, std::cos(kSameBasinRad));
        if (near) continue;
        const Eigen::Vector3d u = refineMaximum(m, order, sign, projector, samples[k]);
        bool duplicate = false;
        for (const auto& f : found) duplicate = duplicate || sameDirection(u, f, lineWise, kSameDirectionCos);
        if (duplicate) continue;
        found.push_back(u);
        foundValue.push_back(sign * m.directional(u, order));
      }
      const double bestRefined = *std::max_element(foundValue.begin(), foundValue.end());
      for (size_t k = 0; k < found.size(); ++k) {
        if (foundValue[k] >= bestRefined - settings.tieTolerance * range) {
          out.push_back({found[k], order == 3});
        }
      }
    }
    return out;
  }
  return {};
}

// Any unit vector orthogonal to a (deterministic).
Eigen::Vector3d orthogonalTo(const Eigen::Vector3d& a) {
  Eigen::Index k;
  a.cwiseAbs().minCoeff(&k);
  return a.cross(Eigen::Vector3d::Unit(k)).normalized();
}

}  // namespace

Status validateCanonicalFrameSettings(const CanonicalFrameSettings& s) {
  auto bad = [](const char* field) {
    return makeError(ErrorCode::InvalidArgument, std::string("CanonicalFrameSettings.") + field +
                                                     " must be finite and non-negative");
  };
  for (auto [value, name] : {std::pair{s.eigenGapTolerance, "eigenGapTolerance"},
                             std::pair{s.skewnessTolerance, "skewnessTolerance"},
                             std::pair{s.shapeTolerance, "shapeTolerance"},
                             std::pair{s.tieTolerance, "tieTolerance"},
                             std::pair{s.duplicateTolerance, "duplicateTolerance"}}) {
    if (!std::isfinite(value) || value < 0.0) return bad(name);
  }
  if (s.tieTolerance >= 1.0) return makeError(ErrorCode::InvalidArgument, "CanonicalFrameSettings.tieTolerance must be < 1");
  if (s.maxCandidates < 1) return makeError(ErrorCode::InvalidArgument, "CanonicalFrameSettings.maxCandidates must be ≥ 1");
  return Ok{};
}

Points CanonicalFrame::pointsToCanonical(const Points& pointsM) const {
  const Eigen::Matrix3d a = scalePerM * rotation;
  Points out = (pointsM.rowwise() - translationM.transpose()) * a.transpose();
  return out;
}

namespace {

// The surface's bounding-box centre (the moments' origin) and diagonal (the scale of the zero-volume test).
void boundingBox(const TriangleMesh& surface, Eigen::Vector3d& centre, double& diagonal) {
  centre.setZero();
  diagonal = 0.0;
  if (surface.vertices.rows() > 0 && surface.vertices.allFinite()) {
    const Eigen::Vector3d lo = surface.vertices.colwise().minCoeff(), hi = surface.vertices.colwise().maxCoeff();
    centre = 0.5 * (lo + hi);
    diagonal = (hi - lo).norm();
  }
}

Result<CanonicalFrames> framesFromMoments(const VolumeMoments& x, const Eigen::Vector3d& origin, double diagonal,
                                          const CanonicalFrameSettings& settings);

}  // namespace

Result<CanonicalFrames> computeCanonicalFrames(const TriangleMesh& surface, const CanonicalFrameSettings& settings) {
  if (auto status = validateCanonicalFrameSettings(settings); !status) return status.error();
  Eigen::Vector3d origin;
  double diagonal;
  boundingBox(surface, origin, diagonal);
  auto raw = computeVolumeMoments(surface, kFrameOrder, origin);
  if (!raw) return raw.error();
  return framesFromMoments(raw.value(), origin, diagonal, settings);
}

Result<CanonicalFrames> computeCanonicalFrames(const TriangleMesh& surface, const VolumeMoments& moments,
                                               const Eigen::Vector3d& momentsOriginM,
                                               const CanonicalFrameSettings& settings) {
  if (auto status = validateCanonicalFrameSettings(settings); !status) return status.error();
  if (moments.maxOrder < kFrameOrder || moments.values.size() != monomialCount(moments.maxOrder)) {
    return makeError(ErrorCode::InvalidArgument, "canonical frames need moments up to order " + std::to_string(kFrameOrder));
  }
  if (!moments.values.allFinite() || !momentsOriginM.allFinite()) {
    return makeError(ErrorCode::NonFiniteValue, "the solid's moments or their origin are not finite");
  }
  Eigen::Vector3d origin;
  double diagonal;
  boundingBox(surface, origin, diagonal);
  VolumeMoments truncated;
  truncated.maxOrder = kFrameOrder;
  truncated.values = moments.values.head(monomialCount(kFrameOrder));
  // The same origin as the pass over the surface takes (its box centre), so both give the same frames.
  return framesFromMoments(transformVolumeMoments(truncated, Eigen::Matrix3d::Identity(), origin - momentsOriginM), origin,
                           diagonal, settings);
}

namespace {

Result<CanonicalFrames> framesFromMoments(const VolumeMoments& x, const Eigen::Vector3d& origin, double diagonal,
                                          const CanonicalFrameSettings& settings) {

  const double volume = x(0, 0, 0);
  const double minVolume = kMinRelativeVolume * diagonal * diagonal * diagonal;
  if (!(std::abs(volume) > minVolume)) {
    return makeError(ErrorCode::InvalidArgument, "solid has zero volume (" + std::to_string(volume) +
                                                     " m³): the surface is flat or degenerate");
  }
  if (volume < 0.0) {
    return makeError(ErrorCode::InvalidArgument, "solid has negative volume (" + std::to_string(volume) +
                                                     " m³): the faces point inward");
  }

  const Eigen::Vector3d comLocal = Eigen::Vector3d(x(1, 0, 0), x(0, 1, 0), x(0, 0, 1)) / volume;
  Eigen::Matrix3d second;
  second << x(2, 0, 0), x(1, 1, 0), x(1, 0, 1), x(1, 1, 0), x(0, 2, 0), x(0, 1, 1), x(1, 0, 1), x(0, 1, 1), x(0, 0, 2);
  second -= volume * comLocal * comLocal.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(second);
  Eigen::Matrix3d e = eigen.eigenvectors();  // columns, ascending eigenvalues
  if (e.determinant() < 0.0) e.col(2) = -e.col(2);
  const double scale = std::cbrt(1.0 / volume);

  // y = s Eᵀ (x − t): principal axes, unit volume.
  const VolumeMoments y = transformVolumeMoments(x, scale * e.transpose(), comLocal);
  const Eigen::Vector3d mu(y(2, 0, 0), y(0, 2, 0), y(0, 0, 2));

  CanonicalFrames out;
  out.volumeM3 = volume;
  out.centerOfMassM = origin + comLocal;
  out.principalSecondMoments = std::pow(scale, 5) * eigen.eigenvalues();
  out.degenerateLowerPair = (mu[1] - mu[0]) < settings.eigenGapTolerance * mu[1];
  out.degenerateUpperPair = (mu[2] - mu[1]) < settings.eigenGapTolerance * mu[2];
  out.centralMoments = transformVolumeMoments(x, Eigen::Matrix3d::Identity(), comLocal);

  // Step 2: axis directions.
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  std::vector<AxisChoice> choices;
  if (out.degenerateLowerPair && out.degenerateUpperPair) {
    const auto firsts = chooseDirections(y, identity.col(0), identity.col(1), false, mu.mean(), settings);
    for (const auto& a : firsts) {
      const Eigen::Vector3d p = orthogonalTo(a.direction), q = a.direction.cross(p);
      const auto seconds = chooseDirections(y, p, q, true, mu.mean(), settings);
      if (seconds.empty()) {
        AxisChoice c;
        c.axes << a.direction.transpose(), p.transpose(), q.transpose();
        c.signFixed = {a.signFixed, false, false};
        choices.push_back(c);
      }
      for (const auto& b : seconds) {
        AxisChoice c;
        c.axes << a.direction.transpose(), b.direction.transpose(), a.direction.cross(b.direction).transpose();
        c.signFixed = {a.signFixed, b.signFixed, false};
        choices.push_back(c);
      }
    }
  } else if (out.degenerateLowerPair || out.degenerateUpperPair) {
    const int i = out.degenerateLowerPair ? 0 : 1, j = i + 1, k = out.degenerateLowerPair ? 2 : 0;
    const auto dirs = chooseDirections(y, identity.col(i), identity.col(j), true, 0.5 * (mu[i] + mu[j]), settings);
    for (const auto& a : dirs) {
      AxisChoice c;
      c.axes.row(i) = a.direction.transpose();
      c.axes.row(j) = identity.col(k).cross(a.direction).transpose();
      c.axes.row(k) = identity.row(k);
      c.signFixed = {false, false, false};
      c.signFixed[i] = a.signFixed;
      choices.push_back(c);
    }
  }
  if (choices.empty()) choices.push_back({identity, {false, false, false}});

  // Step 3: signs. Step 4: drop symmetric duplicates.
  std::vector<Eigen::Matrix3d> kept;
  std::vector<Eigen::VectorXd> signatures;
  std::vector<Eigen::Vector3d> skews;
  for (const AxisChoice& choice : choices) {
    Eigen::Matrix3d b = choice.axes;
    std::array<bool, 3> fixed = choice.signFixed;
    Eigen::Vector3d gamma;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d axis = b.row(a).transpose();
      gamma[a] = y.directional(axis, 3) / std::pow(y.directional(axis, 2), 1.5);
      if (!fixed[a] && std::abs(gamma[a]) >= settings.skewnessTolerance) {
        if (gamma[a] < 0.0) b.row(a) *= -1.0, gamma[a] = -gamma[a];
        fixed[a] = true;
      }
    }
    std::vector<int> freeAxes;
    for (int a = 0; a < 3; ++a) {
      if (!fixed[a]) freeAxes.push_back(a);
    }
    std::vector<Eigen::Matrix3d> patterns;
    if (freeAxes.empty()) {
      if (b.determinant() < 0.0) {
        Eigen::Index least;
        gamma.cwiseAbs().minCoeff(&least);
        b.row(least) *= -1.0;
      }
      patterns.push_back(b);
    } else {
      // The last free axis completes the right-handed frame.
      const int nFlip = static_cast<int>(freeAxes.size()) - 1;
      for (int bits = 0; bits < (1 << nFlip); ++bits) {
        Eigen::Matrix3d c = b;
        for (int f = 0; f < nFlip; ++f) {
          if (bits & (1 << f)) c.row(freeAxes[f]) *= -1.0;
        }
        if (c.determinant() < 0.0) c.row(freeAxes.back()) *= -1.0;
        patterns.push_back(c);
      }
    }
    for (const Eigen::Matrix3d& c : patterns) {
      if (static_cast<int>(kept.size()) >= settings.maxCandidates) break;
      Eigen::VectorXd signature = transformVolumeMoments(y, c).values;
      bool duplicate = false;
      for (const auto& s : signatures) {
        duplicate = duplicate || (settings.duplicateTolerance > 0.0 &&
                                  (s - signature).norm() <= settings.duplicateTolerance * signature.norm());
      }
      if (duplicate) continue;
      kept.push_back(c);
      signatures.push_back(std::move(signature));
      Eigen::Vector3d g;
      for (int a = 0; a < 3; ++a) {
        const Eigen::Vector3d axis = c.row(a).transpose();
        g[a] = y.directional(axis, 3) / std::pow(y.directional(axis, 2), 1.5);
      }
      skews.push_back(g);
    }
  }

  out.skewness = skews.front();
  for (const Eigen::Matrix3d& c : kept) {
    CanonicalFrame frame;
    frame.rotation = c * e.transpose();
    frame.translationM = out.centerOfMassM;
    frame.scalePerM = scale;
    out.candidates.push_back(frame);
  }
  return out;
}

}  // namespace

}  // namespace brittle

#include "Body.h"

#include <algorithm>
#include <exception>
#include <string>

#include "brittle/runtime/CrackPropagation.h"
#include "brittle/runtime/FragmentSurfaces.h"

namespace brittle::detail {

const Result<StaticCorrection>& Body::staticCorrection() const {
  scheduleStaticCorrection();
  return mCorrection.get([this] {
    auto built = correctionEigenvalues.size() == 0 ? StaticCorrection::build(asset, material, modes) : [&] {
      ObjectAsset entry = asset;  // the same body with the eigenvalues its correction is for
      entry.modal.eigenvaluesRad2PerS2 = correctionEigenvalues;
      return StaticCorrection::build(entry, material, modes);
    }();
    if (!built) built = Error{built.error().code, "object '" + asset.name + "': " + built.error().message};
    return built;
  });
}

void Body::adoptStaticCorrection(Result<StaticCorrection> correction) const {
  scheduleStaticCorrection();
  mCorrection.install(std::move(correction));
}

const StressBounds& Body::stressBounds() const {
  return mStressBounds.get([this] {
    return stressModeBounds(asset.stressModes, modes, omega.cwiseInverse(),
                            stressPointNodes(asset.tetMesh.tets, stressPointsPerElement(asset.elementOrder)));
  });
}

const TetMoments& Body::tetMoments() const {
  return mTetMoments.get([this] { return tetVolumeMoments(asset.tetMesh, centreM); });
}

void BodySource::abandon() const {
  for (const BodySource* s = this; s != nullptr; s = s->mLate.get()) s->mAbandoned.store(true, std::memory_order_relaxed);
}

std::shared_ptr<const BodySource> BodySource::ready(std::shared_ptr<const Body> body) {
  auto source = std::make_shared<BodySource>();
  source->mBody.install(std::move(body));
  return source;
}

std::shared_ptr<const BodySource> BodySource::deferred(Maker make) {
  auto source = std::make_shared<BodySource>();
  source->mMake = std::move(make);
  return source;
}

std::shared_ptr<const BodySource> BodySource::deferred(Maker make, std::vector<Later> laters) {
  auto source = std::make_shared<BodySource>();
  source->mMake = std::move(make);
  BodySource* previous = source.get();
  std::weak_ptr<const BodySource> base = source;
  for (Later& l : laters) {
    auto later = std::make_shared<BodySource>();
    later->mWantedSoon = l.soon;
    later->mMake = [base, late = std::move(l.make)]() -> Result<std::shared_ptr<const Body>> {
      const auto held = base.lock();
      if (!held) return makeError(ErrorCode::InvalidArgument, "the body's earlier version is gone");
      return late(held->get());
    };
    previous->mLate = later;
    previous->mLateDueS = l.dueS;
    previous = later.get();
    base = later;
  }
  return source;
}

const Result<std::shared_ptr<const Body>>& BodySource::get() const {
  return mBody.get(
      [this]() -> Result<std::shared_ptr<const Body>> {
        try {
          return mMake();
        } catch (const std::exception& e) {
          return makeError(ErrorCode::InvalidArgument, std::string("making the body failed: ") + e.what());
        }
      },
      [this] { mMake = nullptr; });
}

namespace {

// ω and ζ of the first `modes` modes (makeBody and withFrequencies: the same bits).
Status setModalRates(Body& body, const ModalBasis& modal, const Material& material, const std::string& name) {
  body.omega = modal.eigenvaluesRad2PerS2.head(body.modes).cwiseMax(0.0).cwiseSqrt();
  if (!(body.omega.minCoeff() > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "object '" + name + "' has a zero-frequency elastic mode");
  }
  body.zeta.resize(body.modes);
  for (int j = 0; j < body.modes; ++j) body.zeta[j] = rayleighDampingRatio(material, body.omega[j]);
  return Ok{};
}

}  // namespace

Result<std::shared_ptr<Body>> withFrequencies(const Body& base, const ModalBasis& rates) {
  const Eigen::Index r = base.asset.modal.eigenvaluesRad2PerS2.size();
  if (base.correctionEigenvalues.size() == 0 || rates.frequenciesHz.size() != r || rates.eigenvaluesRad2PerS2.size() != r ||
      rates.residuals.size() != r) {
    return makeError(ErrorCode::InvalidArgument, "object '" + base.asset.name + "': new frequencies need " + std::to_string(r) +
                                                     " of each and a body with correctionEigenvalues");
  }
  auto body = std::make_shared<Body>();
  body->modes = base.modes;
  if (Status st = setModalRates(*body, rates, base.material, base.asset.name); !st) return st.error();
  body->asset = base.asset;
  body->asset.modal.frequenciesHz = rates.frequenciesHz;
  body->asset.modal.eigenvaluesRad2PerS2 = rates.eigenvaluesRad2PerS2;
  body->asset.modal.residuals = rates.residuals;
  body->material = base.material;
  body->topology = base.topology;
  body->nodeNormals = base.nodeNormals;
  body->ring = base.ring;
  body->boundaryNodes = base.boundaryNodes;
  body->boundaryTree = base.boundaryTree;
  body->sizeM = base.sizeM;
  body->centreM = base.centreM;
  body->correctionEigenvalues = base.correctionEigenvalues;
  body->frequencyError = base.frequencyError;
  body->ritzFrequenciesHz = base.ritzFrequenciesHz;
  if (base.staticCorrectionScheduled()) body->adoptStaticCorrection(base.staticCorrection());
  return body;
}

Result<std::shared_ptr<const Body>> makeBody(ObjectAsset asset, const Material& material, int modeCount,
                                             const ExactModesFactor* factor, Eigen::VectorXd correctionEigenvalues,
                                             const TetTopology* sameTets) {
  const int points = stressPointsPerElement(asset.elementOrder);
  if (asset.modal.modes.cols() == 0 || asset.stressModes.rows() != 6 * points * asset.tetMesh.tets.rows()) {
    return makeError(ErrorCode::InvalidArgument,
                     "object '" + asset.name + "' has no modal data or stress modes of the wrong size");
  }
  auto topo = sameTets ? buildTetTopology(asset.tetMesh, *sameTets) : buildTetTopology(asset.tetMesh);
  if (!topo) return Error{topo.error().code, "object '" + asset.name + "': " + topo.error().message};
  // P2 modes cover the corners and one node per edge (ObjectAsset.h).
  const Eigen::Index femNodes =
      asset.tetMesh.nodes.rows() + (asset.elementOrder == ElementOrder::P2 ? topo.value().edges.rows() : 0);
  if (asset.modal.modes.rows() != 3 * femNodes) {
    return makeError(ErrorCode::InvalidArgument, "object '" + asset.name + "' (" + elementOrderName(asset.elementOrder) +
                                                     ") has modes of " + std::to_string(asset.modal.modes.rows()) +
                                                     " rows, expected " + std::to_string(3 * femNodes));
  }
  if (!isContactSpreadFraction(asset.contactSpreadFraction)) {
    return makeError(ErrorCode::InvalidArgument, "object '" + asset.name + "': contactSpreadFraction " +
                                                     std::to_string(asset.contactSpreadFraction) + " is outside [0, 1)");
  }
  if (asset.elementOrder == ElementOrder::P2) {
    // The pack holds each element's own corner stresses; the runtime reads their nodal means
    // (CornerStressMeans, FemAssembly.h), as the static correction's recovery does.
    auto means = CornerStressMeans::make(asset.tetMesh);
    if (!means) return Error{means.error().code, "object '" + asset.name + "': " + means.error().message};
    means.value().apply(asset.stressModes.data(), asset.stressModes.cols());
  }
  auto body = std::make_shared<Body>();
  body->topology = std::move(topo).value();
  body->material = material;
  const auto available = static_cast<int>(asset.modal.modes.cols());
  body->modes = keptModeCount(modeCount, available);
  if (Status st = setModalRates(*body, asset.modal, material, asset.name); !st) return st.error();
  const auto n = asset.tetMesh.nodes.rows();
  body->nodeNormals.setZero(n, 3);
  body->ring.assign(static_cast<size_t>(n), {});
  const Triangles& tri = body->topology.boundaryTriangles;
  for (Eigen::Index f = 0; f < tri.rows(); ++f) {
    const Eigen::Vector3d a = asset.tetMesh.nodes.row(tri(f, 0)), b = asset.tetMesh.nodes.row(tri(f, 1)),
                          c = asset.tetMesh.nodes.row(tri(f, 2));
    const Eigen::Vector3d areaNormal = 0.5 * (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) {
      body->nodeNormals.row(tri(f, k)) += areaNormal.transpose();
      auto& r = body->ring[static_cast<size_t>(tri(f, k))];
      for (int m = 1; m < 3; ++m) {
        const int32_t other = tri(f, (k + m) % 3);
        if (std::find(r.begin(), r.end(), other) == r.end()) r.push_back(other);
      }
    }
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    const double len = body->nodeNormals.row(i).norm();
    if (len > 0.0) {
      body->nodeNormals.row(i) /= len;
      body->boundaryNodes.push_back(static_cast<int32_t>(i));
    }
  }
  body->boundaryTree = TriangleBoxTree::build(asset.tetMesh.nodes, tri);
  const Eigen::Vector3d lo = asset.tetMesh.nodes.colwise().minCoeff(), hi = asset.tetMesh.nodes.colwise().maxCoeff();
  body->sizeM = (hi - lo).norm();
  body->centreM = 0.5 * (lo + hi);
  body->asset = std::move(asset);
  body->correctionEigenvalues = std::move(correctionEigenvalues);
  if (factor && factor->factor) {
    auto built = StaticCorrection::build(body->asset, material, body->modes, factor->fem, factor->factor,
                                         -factor->shiftRad2PerS2);
    if (!built) built = Error{built.error().code, "object '" + body->asset.name + "': " + built.error().message};
    body->adoptStaticCorrection(std::move(built));
  }
  return std::shared_ptr<const Body>(std::move(body));
}

}  // namespace brittle::detail

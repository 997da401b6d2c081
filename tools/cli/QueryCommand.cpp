// query: the database entries nearest to a closed mesh, with rescaled physical data.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "CliSupport.h"
#include "Commands.h"
#include "brittle/core/Timing.h"
#include "brittle/database/FragmentMatcher.h"
#include "brittle/database/Pack.h"
#include "brittle/database/ScalingLaws.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/MeshIO.h"
#include "brittle/precompute/MeshValidation.h"
#include "brittle/runtime/Fingerprint.h"

namespace brittle::cli {
namespace {

struct QueryOptions {
  std::string pack;
  std::string mesh;
  std::string descriptor = "moment";
  std::string index;
  std::string material;
  int k = 3;
  bool json = false;
  bool digest = false;
};

nlohmann::json matrixJson(const Eigen::Matrix3d& m) {
  return {{m(0, 0), m(0, 1), m(0, 2)}, {m(1, 0), m(1, 1), m(1, 2)}, {m(2, 0), m(2, 1), m(2, 2)}};
}

}  // namespace

Runner addQueryCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("query", "Find the database entries nearest to a closed mesh, with rescaled physical data");
  auto o = std::make_shared<QueryOptions>();
  cmd->add_option("pack", o->pack, "Pack with a fragment database")->required();
  cmd->add_option("--mesh", o->mesh, "Query surface (OFF, OBJ, PLY, STL), closed and outward, in metres")->required();
  cmd->add_option("--descriptor", o->descriptor, "Descriptor kind")
      ->check(CLI::IsMember({"moment", "voxel", "voxel-improved"}))->capture_default_str();
  cmd->add_option("--k", o->k, "Number of matches")->capture_default_str()->check(CLI::Range(1, 1000));
  std::vector<std::string> backends;
  for (auto kind : kAllDescriptorIndexKinds) backends.push_back(descriptorIndexKindName(kind));
  cmd->add_option("--index", o->index,
                  "Override the stored index: brute-force (exact), kd-forest, autotuned, hnsw, hnsw-binary, hnsw-pooled, hnsw-principal, ivf, ivf-binary, faiss-hnsw, "
                  "faiss-ivf, faiss-binary-flat or faiss-binary-hnsw (kd-forest: 4 trees, 64 checks; graphs: M 16, ef 64; ivf: "
                  "as a bake sizes it, the moments n/390 lists, 4 probed, the voxel grids n/10, 40; faiss-ivf: √n lists, a quarter probed; the binary kinds: voxel only)")
      ->check(CLI::IsMember(backends));
  cmd->add_option("--material", o->material,
                  "Material of the query (preset or JSON file) to rescale the physics to; default: the reference");
  cmd->add_flag("--json", o->json, "Print the matches as JSON");
  cmd->add_flag("--digest", o->digest,
                "Also print the built index's digest (its settings, data and what its build made: equal digests, the same index "
                "bit for bit, in any process or on any machine; it reads the whole index)");

  return [o]() -> int {
    auto pack = readPack(o->pack);
    if (!pack) return reportError(pack.error());
    const FragmentDatabase& db = pack.value().database;
    auto surface = readSurfaceMesh(o->mesh);
    if (!surface) return reportError(surface.error());
    if (Status valid = validateSurfaceMesh(surface.value()); !valid) return reportError(valid.error());
    const DescriptorKind kind = parseDescriptorKind(o->descriptor).value();
    Material material = db.referenceMaterial;
    if (!o->material.empty()) {
      auto m = resolveMaterial(o->material);
      if (!m) return reportError(m.error());
      material = std::move(m).value();
    }
    FragmentMatcherSettings settings;
    for (DescriptorKind other : kAllDescriptorKinds) settings.enabled[static_cast<size_t>(other)] = other == kind;
    if (!o->index.empty()) {
      DescriptorIndexSettings index = db.indexSettings[static_cast<size_t>(kind)];
      using Kind = DescriptorIndexSettings::Kind;
      if (const Kind wanted = parseDescriptorIndexKind(o->index).value(); wanted != index.kind) {
        // The stored numbers are another kind's: this kind's own defaults instead (the seed kept).
        const uint64_t seed = index.seed;
        index = DescriptorIndexSettings{};
        index.kind = wanted;
        index.seed = seed;
        const auto entries = static_cast<int64_t>(db.entries.size());
        if (index.kind == Kind::Ivf) {
          const DescriptorIndexSettings sized = sizedInvertedFile(entries, kind);
          index.trees = sized.trees;
          index.checks = sized.checks;
        } else if (index.kind == Kind::FaissIvf) {
          index.trees = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(entries))));
          index.checks = std::max(1, index.trees / 4);
        } else if (index.kind == Kind::Hnsw || index.kind == Kind::HnswBinary || index.kind == Kind::HnswPooled || index.kind == Kind::HnswPrincipal || index.kind == Kind::FaissHnsw ||
                   index.kind == Kind::FaissBinaryHnsw) {
          index.trees = 16;  // M and ef: hnswlib's and FAISS's usual defaults
          index.checks = 64;
        }
      }
      settings.indexOverride[static_cast<size_t>(kind)] = index;
    }
    auto matcher = FragmentMatcher::build(db, settings);
    if (!matcher) return reportError(matcher.error());
    const int k = static_cast<int>(std::min<int64_t>(o->k, static_cast<int64_t>(db.entries.size())));
    const auto start = SteadyClock::now();
    auto matches = matcher.value().match(surface.value(), kind, k);
    const double matchS = secondsSince(start);
    if (!matches) return reportError(matches.error());

    nlohmann::json doc;
    doc["query"] = {{"mesh", std::filesystem::path(o->mesh).filename().string()},
                    {"descriptor", o->descriptor},
                    {"index", descriptorIndexKindName(matcher.value().index(kind)->settings().kind)},
                    {"material", material.name},
                    {"match_time_s", matchS}};
    if (o->digest) {
      const Result<uint64_t> digest = matcher.value().index(kind)->digest();
      if (!digest) return reportError(digest.error());
      doc["query"]["index_digest"] = fingerprintHex(digest.value());
    }
    doc["matches"] = nlohmann::json::array();
    for (const FragmentMatch& m : matches.value()) {
      const FragmentEntry& e = db.entries[static_cast<size_t>(m.entry)];
      nlohmann::json j = {{"entry", m.entry},
                          {"name", e.asset.name},
                          {"base_shape", e.baseShape},
                          {"cut", e.cut},
                          {"distance", m.distance},
                          {"candidate_frame", m.candidate},
                          // entry point x̂ maps to rotationᵀ x̂ · scale_m + translation_m
                          {"entry_to_query", {{"rotation_transposed", matrixJson(m.queryFrame.rotation.transpose())},
                                              {"scale_m", 1.0 / m.queryFrame.scalePerM},
                                              {"translation_m", {m.queryFrame.translationM.x(), m.queryFrame.translationM.y(),
                                                                 m.queryFrame.translationM.z()}}}}};
      if (db.hasPhysics()) {
        InstantiateReport report;
        auto placed = instantiateEntry(e, db.referenceMaterial, material, m.queryFrame, &report);
        if (!placed) return reportError(placed.error());
        const ObjectAsset& a = placed.value();
        const Eigen::VectorXd& f = a.modal.frequenciesHz;
        j["physics"] = {{"mass_kg", a.massProperties.massKg},
                        {"volume_m3", a.massProperties.volumeM3},
                        {"frequencies_hz", std::vector<double>(f.data(), f.data() + f.size())},
                        {"poisson_corrected", report.poissonCorrected}};
      }
      doc["matches"].push_back(std::move(j));
    }
    if (o->json) {
      std::cout << doc.dump(2) << "\n";
      return kExitOk;
    }
    std::cout << std::setprecision(4) << "query " << doc["query"]["mesh"].get<std::string>() << ": " << o->descriptor
              << " descriptor, " << doc["query"]["index"].get<std::string>() << " index, " << db.entries.size()
              << " entries, " << 1e3 * matchS << " ms\n";
    if (o->digest) std::cout << "  index digest " << doc["query"]["index_digest"].get<std::string>() << "\n";
    for (const auto& j : doc["matches"]) {
      std::cout << "  " << std::setw(4) << j["entry"].get<int64_t>() << "  " << std::setw(16) << std::left
                << j["name"].get<std::string>() << std::right << "  distance " << j["distance"].get<double>()
                << "  scale " << j["entry_to_query"]["scale_m"].get<double>() << " m";
      if (j.contains("physics")) {
        const auto& f = j["physics"]["frequencies_hz"];
        std::cout << "  mass " << j["physics"]["mass_kg"].get<double>() << " kg  f1-3 (Hz)";
        for (size_t i = 0; i < std::min<size_t>(3, f.size()); ++i) std::cout << " " << f[i].get<double>();
      }
      std::cout << "\n";
    }
    return kExitOk;
  };
}

}  // namespace brittle::cli

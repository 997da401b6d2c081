// bake-db and query: the fragment shape database from the command line.
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

#include "../bench/ExactModesBench.h"
#include "../bench/FractureStatsBench.h"
#include "../bench/ImpactBench.h"
#include "../bench/IntegratorBench.h"
#include "../bench/ModeCountBench.h"
#include "../bench/ResolutionBench.h"
#include "../bench/SearchBench.h"
#include "CliSupport.h"
#include "Commands.h"
#include "Distributed.h"
#include "brittle/core/Timing.h"
#include "brittle/database/FragmentMatcher.h"
#include "brittle/database/ScalingLaws.h"
#include "brittle/precompute/FragmentDatabaseBake.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/MeshIO.h"
#include "brittle/precompute/MeshValidation.h"

namespace brittle::cli {
namespace {

struct BakeDbOptions {
  std::string shapesFile = "assets/shapes/base-shapes.json";
  std::vector<std::string> only;
  std::string out;
  int64_t entries = 48;
  uint64_t seed = 1;
  int64_t tets = 1000;
  int modes = 12;
  bool descriptorsOnly = false;
  int momentOrder = 4;
  int voxelResolution = 16;
  int threads = 0;
  double runtimeFraction = 0.0;
  std::string checkpointDir;  // default: <out>.checkpoints
  int64_t checkpointEvery = 64;
  bool resume = false;
  bool keepCheckpoints = false;
  bool quiet = false;
  bool json = false;
};

struct QueryOptions {
  std::string pack;
  std::string mesh;
  std::string descriptor = "moment";
  std::string index;
  std::string material;
  int k = 3;
  bool json = false;
};

nlohmann::json matrixJson(const Eigen::Matrix3d& m) {
  return {{m(0, 0), m(0, 1), m(0, 2)}, {m(1, 0), m(1, 1), m(1, 2)}, {m(2, 0), m(2, 1), m(2, 2)}};
}

}  // namespace

Runner addBakeDbCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "bake-db", "Bake a fragment shape database (fragments of base shapes, descriptors, tet meshes, modes) into a pack");
  auto o = std::make_shared<BakeDbOptions>();
  cmd->add_option("--shapes", o->shapesFile, "Base shape definitions (JSON, see assets/shapes/README.md)")
      ->capture_default_str();
  cmd->add_option("--only", o->only, "Use only these base shapes (names from the shapes file)")->delimiter(',');
  cmd->add_option("--entries", o->entries, "Number of fragments")->capture_default_str()->check(CLI::Range(int64_t{1}, int64_t{10000000}));
  cmd->add_option("--seed", o->seed, "Seed of the fragment cuts (the bake is reproducible from it)")->capture_default_str();
  cmd->add_option("--tets", o->tets, "Target tetrahedra per fragment")->capture_default_str()->check(CLI::Range(int64_t{100}, int64_t{1000000}));
  cmd->add_option("--modes", o->modes, "Elastic modes per fragment")->capture_default_str()->check(CLI::Range(1, 200));
  cmd->add_flag("--descriptors-only", o->descriptorsOnly, "Skip tet meshes and modes (search benchmarks on large databases)");
  cmd->add_option("--moment-order", o->momentOrder, "Highest moment order of the moment descriptor")->capture_default_str()->check(CLI::Range(2, 10));
  cmd->add_option("--voxel-resolution", o->voxelResolution, "Voxels per axis k of both voxel descriptors")->capture_default_str()->check(CLI::Range(2, 64));
  cmd->add_option("--runtime-fraction", o->runtimeFraction,
                  "Share of entries broken off base shapes by the runtime instead of cut (a second source)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--threads", o->threads, "Worker threads (0 = all cores); the result does not depend on it")->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--out", o->out, "Output pack (.h5), written atomically")->required();
  cmd->add_option("--checkpoint-dir", o->checkpointDir,
                  "Where finished chunks of entries are kept while the bake runs (default: OUT.checkpoints)");
  cmd->add_option("--checkpoint-every", o->checkpointEvery, "Entries per checkpoint chunk")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{1}, int64_t{10000000}));
  cmd->add_flag("--resume", o->resume,
                "Continue an interrupted bake: reuse its finished chunks (same settings required); the pack equals an "
                "uninterrupted bake's");
  cmd->add_flag("--keep-checkpoints", o->keepCheckpoints, "Keep the checkpoint directory after the pack is written");
  cmd->add_flag("--quiet", o->quiet, "No progress display");
  cmd->add_flag("--json", o->json, "Print the inspection of the new pack as JSON");
  cmd->footer(
      "Distributed: `mpirun -np N brittle bake-db ...` splits the chunks across N ranks (chunk c goes to rank c mod "
      "N); rank 0 gathers them over MPI, so the ranks need not share a file system, and writes the pack. The pack "
      "equals a single-process bake's.");

  return [o]() -> int {
    auto group = ProcessGroup::join();
    if (!group) return reportError(group.error());
    auto shapes = loadBaseShapes(o->shapesFile);
    if (!shapes) return reportError(shapes.error());
    DatabaseBakeSettings s;
    s.shapes = std::move(shapes).value();
    if (!o->only.empty()) {
      auto picked = selectBaseShapes(s.shapes, o->only);
      if (!picked) return reportError(picked.error());
      s.shapes = std::move(picked).value();
    }
    s.entryCount = o->entries;
    s.seed = o->seed;
    s.tetMesh.targetTets = o->tets;
    s.tetMesh.seed = o->seed;
    s.modeCount = o->modes;
    s.physics = !o->descriptorsOnly;
    s.descriptors.moment.maxOrder = o->momentOrder;
    s.descriptors.voxel.resolution = s.descriptors.voxelImproved.resolution = o->voxelResolution;
    s.threads = o->threads;
    s.runtimeFragments.fraction = o->runtimeFraction;
    DatabaseCheckpointSettings checkpoints;
    checkpoints.directory = o->checkpointDir.empty() ? o->out + ".checkpoints" : o->checkpointDir;
    checkpoints.chunkEntries = o->checkpointEvery;
    checkpoints.resume = o->resume;
    checkpoints.rank = group.value().rank();
    checkpoints.ranks = group.value().size();
    const bool root = checkpoints.rank == 0;

    // Every rank prepares its own directory (they may not share a file system; where they do,
    // preparing twice is harmless), then bakes its chunks; all stop if one fails.
    Status prepared = prepareFragmentDatabaseCheckpoints(s, checkpoints);
    if (!group.value().allSucceeded(prepared.ok())) return prepared ? kExitPack : reportError(prepared.error());
    Result<DatabaseCheckpointReport> baked = [&] {
      TerminalProgress progress(o->quiet || !root);
      return bakeFragmentDatabaseChunks(s, checkpoints, &progress);
    }();
    if (!group.value().allSucceeded(baked.ok())) return baked ? kExitPack : reportError(baked.error());
    const int64_t chunks = fragmentDatabaseChunkCount(s, checkpoints);
    for (int64_t c = 0; c < chunks; ++c) {
      const Status sent = group.value().sendToRoot(static_cast<int>(c % checkpoints.ranks),
                                                   fragmentDatabaseChunkPath(s, checkpoints, c));
      if (!sent) return reportError(sent.error());
    }
    // One write per line: std::cerr is unbuffered, and the ranks share the terminal.
    std::cerr << ("bake-db: rank " + std::to_string(checkpoints.rank) + " of " + std::to_string(checkpoints.ranks) +
                  ": " + std::to_string(baked.value().entriesBaked) + " entries baked, " +
                  std::to_string(baked.value().entriesReused) + " reused from checkpoints\n");
    if (!root) return kExitOk;

    auto db = assembleFragmentDatabase(s, checkpoints);
    if (!db) return reportError(db.error());
    Pack pack;
    pack.database = std::move(db).value();
    const int code = writeAndPrintPack(pack, o->out, o->json);
    if (code == kExitOk && !o->keepCheckpoints) {
      std::error_code ignored;
      std::filesystem::remove_all(checkpoints.directory, ignored);
    }
    return code;
  };
}

Runner addQueryCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("query", "Find the database entries nearest to a closed mesh, with rescaled physical data");
  auto o = std::make_shared<QueryOptions>();
  cmd->add_option("pack", o->pack, "Pack with a fragment database")->required();
  cmd->add_option("--mesh", o->mesh, "Query surface (OFF, OBJ, PLY, STL), closed and outward, in metres")->required();
  cmd->add_option("--descriptor", o->descriptor, "Descriptor kind")
      ->check(CLI::IsMember({"moment", "voxel", "voxel-improved"}))->capture_default_str();
  cmd->add_option("--k", o->k, "Number of matches")->capture_default_str()->check(CLI::Range(1, 1000));
  cmd->add_option("--index", o->index, "Override the stored index: brute-force (exact), kd-forest, autotuned or hnsw (M 16, ef 64)")
      ->check(CLI::IsMember({"brute-force", "kd-forest", "autotuned", "hnsw"}));
  cmd->add_option("--material", o->material,
                  "Material of the query (preset or JSON file) to rescale the physics to; default: the reference");
  cmd->add_flag("--json", o->json, "Print the matches as JSON");

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
      index.kind = parseDescriptorIndexKind(o->index).value();
      if (index.kind == DescriptorIndexSettings::Kind::Hnsw &&
          db.indexSettings[static_cast<size_t>(kind)].kind != DescriptorIndexSettings::Kind::Hnsw) {
        index.trees = 16;  // M and ef: hnswlib's usual defaults, not the stored kd-forest's numbers
        index.checks = 64;
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

Runner addBenchCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "bench", "Benchmarks that write CSV (charts: tools/scripts/plot_*.py, all redrawn by tools/run-charts.sh)");
  cmd->require_subcommand(1);
  auto* search = cmd->add_subcommand(
      "search", "Descriptor search: recall@1, query time, build time, memory and physical error per setting");
  auto s = std::make_shared<bench::SearchBenchSettings>();
  auto shapes = std::make_shared<std::string>("assets/shapes/base-shapes.json");
  auto kinds = std::make_shared<std::vector<std::string>>(std::vector<std::string>{"moment", "voxel", "voxel-improved"});
  auto indices = std::make_shared<std::vector<std::string>>(
      std::vector<std::string>{"kd-forest:1:8", "kd-forest:4:32", "kd-forest:4:128", "kd-forest:8:512"});
  search->add_option("--shapes", *shapes, "Base shape definitions (JSON)")->capture_default_str();
  search->add_option("--sizes", s->sizes, "Database sizes")->delimiter(',')->capture_default_str();
  search->add_option("--kinds", *kinds, "Descriptor kinds")->delimiter(',')->capture_default_str()
      ->check(CLI::IsMember({"moment", "voxel", "voxel-improved"}));
  search->add_option("--voxel-size-limit", s->voxelSizeLimit, "Largest database size for the voxel kinds")->capture_default_str();
  search->add_option("--index", *indices, "Index settings: kd-forest:TREES:CHECKS, hnsw:M:EF, autotuned:PRECISION")
      ->delimiter(',')->capture_default_str();
  search->add_option("--queries", s->queries, "Query fragments")->capture_default_str()->check(CLI::Range(1, 100000));
  search->add_option("--physics-queries", s->physicsQueries, "Queries with a direct bake as ground truth")
      ->capture_default_str()->check(CLI::Range(0, 10000));
  search->add_option("--physics-tets", s->physicsTets, "Tetrahedra per fragment for the physical error")->capture_default_str();
  search->add_option("--min-query-triangles", s->minQueryTriangles,
                     "Query fragments are refined by midpoint subdivision (same solid) to at least this many triangles")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{0}, int64_t{1} << 20));
  search->add_option("--runtime-fraction", s->runtimeFraction,
                     "Share of database entries broken off base shapes by the runtime (a second source)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  search->add_flag("--runtime-queries", s->runtimeQueries,
                   "Query with fragments broken off by the runtime instead of exact cuts");
  search->add_option("--voxel-resolution", s->voxelResolution, "Voxels per axis")->capture_default_str()->check(CLI::Range(2, 64));
  search->add_option("--moment-order", s->momentOrder, "Highest order of the moment descriptor")->capture_default_str()->check(CLI::Range(2, 10));
  search->add_option("--seed", s->seed, "Seed of the database and the queries")->capture_default_str();
  search->add_option("--csv", s->searchCsv, "Search results CSV")->capture_default_str();
  search->add_option("--cost-csv", s->descriptorCsv, "Descriptor cost CSV")->capture_default_str();
  search->add_flag("--quiet", s->quiet, "No progress lines");
  auto* impact = cmd->add_subcommand(
      "impact", "Impact latency per stage on glass panes of several sizes and mode counts, pruned and unpruned");
  auto is = std::make_shared<bench::ImpactBenchSettings>();
  impact->add_option("--tets", is->tets, "Target tet counts")->delimiter(',')->capture_default_str();
  impact->add_option("--modes", is->modes, "Mode counts")->delimiter(',')->capture_default_str();
  impact->add_option("--impacts", is->impacts, "Impacts per setting")->capture_default_str()->check(CLI::Range(1, 100000));
  impact->add_option("--speed", is->speedMps, "Impact speed (m/s)")->capture_default_str();
  impact->add_option("--seed", is->seed, "Seed of the impact points and cracks")->capture_default_str();
  impact->add_option("--csv", is->csv, "Output CSV")->capture_default_str();
  auto pb = std::make_shared<bench::PlacementBenchSettings>();
  auto* place = cmd->add_subcommand("place", "Placing each object of a pack against reading its bytes (and its background preparation)");
  place->add_option("pack", pb->pack, "The pack")->required()->check(CLI::ExistingFile);
  place->add_option("--repeats", pb->repeats, "Fresh worlds per object (medians)")->capture_default_str()->check(CLI::Range(1, 1000));
  place->add_option("--csv", pb->csv, "Output CSV")->capture_default_str();
  impact->add_option("--database", is->databasePack,
                     "A pack whose fragment database the fragments are matched against (none: they stay surfaces)");
  impact->add_option("--exact-max-tets", is->exactModesMaxTets,
                     "With a database: fragments of at most this many parent tets get their own modes (0: all matched)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  impact->add_flag("--quiet", is->quiet, "No progress lines");
  auto* integrators = cmd->add_subcommand(
      "integrators", "Error and stability of the modal time integrators against the time step (ωh from 0.01 to 100)");
  auto ib = std::make_shared<bench::IntegratorBenchSettings>();
  integrators->add_option("--zeta", ib->dampingRatios, "Damping ratios")->delimiter(',')->capture_default_str();
  integrators->add_option("--pulse-steps", ib->pulseSteps, "Steps over the 100 us pulse")->capture_default_str()->check(CLI::Range(2, 10000));
  integrators->add_option("--points", ib->points, "Values of ωh")->capture_default_str()->check(CLI::Range(2, 1000));
  integrators->add_option("--csv", ib->csv, "Error CSV")->capture_default_str();
  integrators->add_option("--timing-csv", ib->timingCsv, "Timing CSV")->capture_default_str();
  auto* modes = cmd->add_subcommand(
      "modes", "Mode count against peak-stress error (full-FEM reference) and impact time, with and without the static correction");
  auto mb = std::make_shared<bench::ModeCountBenchSettings>();
  modes->add_option("--modes", mb->modes, "Mode counts")->delimiter(',')->capture_default_str();
  modes->add_option("--tets", mb->tets, "Target tet count of the plate")->capture_default_str();
  modes->add_option("--points", mb->points, "Impact points")->capture_default_str()->check(CLI::Range(1, 1000));
  modes->add_option("--speed", mb->speedMps, "Impact speed (m/s)")->capture_default_str();
  modes->add_option("--repeats", mb->repeats, "Impacts timed per setting")->capture_default_str()->check(CLI::Range(1, 1000));
  modes->add_option("--reference-steps", mb->referenceStepsPerContact, "Newmark steps per contact time")
      ->capture_default_str()->check(CLI::Range(10, 100000));
  modes->add_option("--seed", mb->seed, "Seed of the impact points")->capture_default_str();
  modes->add_option("--csv", mb->csv, "Output CSV")->capture_default_str();
  modes->add_flag("--quiet", mb->quiet, "No progress lines");
  auto* resolution = cmd->add_subcommand("resolution", "Tet resolution against frequency error and bake time");
  auto rb = std::make_shared<bench::ResolutionBenchSettings>();
  resolution->add_option("--mesh", rb->mesh, "Surface mesh")->capture_default_str();
  resolution->add_option("--material", rb->material, "Material: preset or JSON file")->capture_default_str();
  resolution->add_option("--tets", rb->tets, "Target tet counts (two or more)")->delimiter(',')->capture_default_str();
  resolution->add_option("--modes", rb->modes, "Elastic modes compared")->capture_default_str()->check(CLI::Range(1, 500));
  resolution->add_option("--csv", rb->csv, "Output CSV")->capture_default_str();
  resolution->add_flag("--quiet", rb->quiet, "No progress lines");
  auto* fracture = cmd->add_subcommand(
      "fracture", "Fragment count and largest fragment's mass share against impact speed, over many seeds");
  auto fb = std::make_shared<bench::FractureStatsBenchSettings>();
  fracture->add_option("--plate-speeds", fb->plateSpeedsMps, "Speeds of the ball on the glass plate (m/s)")
      ->delimiter(',')->capture_default_str();
  fracture->add_option("--brick-speeds", fb->brickSpeedsMps, "Speeds of the brick dropped on a corner (m/s)")
      ->delimiter(',')->capture_default_str();
  fracture->add_option("--seeds", fb->seeds, "Seeds per speed")->capture_default_str()->check(CLI::Range(1, 100000));
  fracture->add_option("--plate-tets", fb->plateTets, "Target tet count of the plate")->capture_default_str();
  fracture->add_option("--brick-tets", fb->brickTets, "Target tet count of the brick")->capture_default_str();
  fracture->add_option("--modes", fb->modes, "Modes per object")->capture_default_str()->check(CLI::Range(1, 500));
  fracture->add_option("--brick-mesh", fb->brickMesh, "Surface mesh of the brick")->capture_default_str();
  fracture->add_option("--csv", fb->csv, "Output CSV")->capture_default_str();
  fracture->add_flag("--quiet", fb->quiet, "No progress lines");
  auto* exact = cmd->add_subcommand(
      "exact-modes", "A fragment's database match against its own modal analysis at runtime, per fragment size");
  auto xb = std::make_shared<bench::ExactModesBenchSettings>();
  exact->add_option("pack", xb->pack, "A pack with a fragment database")->capture_default_str();
  exact->add_option("--objects", xb->objects, "Objects to break (default: all)")->delimiter(',');
  exact->add_option("--speeds", xb->speedsMps, "Ball speeds (m/s)")->delimiter(',')->capture_default_str();
  exact->add_option("--seeds", xb->seeds, "Seeds per speed (impact point and cracks)")->capture_default_str()->check(CLI::Range(1, 10000));
  exact->add_option("--max-fragments", xb->maxFragmentsPerImpact, "Largest fragments measured per impact")
      ->capture_default_str()->check(CLI::Range(1, 1000));
  exact->add_option("--reference-max-tets", xb->referenceMaxTets,
                    "Largest exact mesh that also gets the reference (the same mesh split 1:8)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  exact->add_option("--exact-modes", xb->exactModes, "Modes of the exact path")->capture_default_str()->check(CLI::Range(1, 500));
  exact->add_option("--repeats", xb->repeats, "Timing repeats (median)")->capture_default_str()->check(CLI::Range(1, 100));
  exact->add_option("--csv", xb->csv, "Output CSV")->capture_default_str();
  exact->add_flag("--quiet", xb->quiet, "No progress lines");
  return [s, shapes, kinds, indices, impact, is, place, pb, integrators, ib, modes, mb, resolution, rb, fracture, fb, exact, xb]() -> int {
    if (exact->parsed()) {
      if (xb->csv.has_parent_path()) std::filesystem::create_directories(xb->csv.parent_path());
      if (Status st = bench::runExactModesBench(*xb); !st) return reportError(st.error());
      std::cout << "wrote " << xb->csv.string() << "\n";
      return kExitOk;
    }
    if (fracture->parsed()) {
      if (fb->csv.has_parent_path()) std::filesystem::create_directories(fb->csv.parent_path());
      if (Status st = bench::runFractureStatsBench(*fb); !st) return reportError(st.error());
      std::cout << "wrote " << fb->csv.string() << "\n";
      return kExitOk;
    }
    if (resolution->parsed()) {
      if (rb->csv.has_parent_path()) std::filesystem::create_directories(rb->csv.parent_path());
      if (Status st = bench::runResolutionBench(*rb); !st) return reportError(st.error());
      std::cout << "wrote " << rb->csv.string() << "\n";
      return kExitOk;
    }
    if (modes->parsed()) {
      if (mb->csv.has_parent_path()) std::filesystem::create_directories(mb->csv.parent_path());
      if (Status st = bench::runModeCountBench(*mb); !st) return reportError(st.error());
      std::cout << "wrote " << mb->csv.string() << "\n";
      return kExitOk;
    }
    if (integrators->parsed()) {
      for (const auto& path : {ib->csv, ib->timingCsv}) {
        if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
      }
      for (double z : ib->dampingRatios) {
        if (!(z >= 0.0 && z < 1.0)) return reportError(makeError(ErrorCode::InvalidArgument, "--zeta values must be in [0, 1)"));
      }
      if (Status st = bench::runIntegratorBench(*ib); !st) return reportError(st.error());
      std::cout << "wrote " << ib->csv.string() << " and " << ib->timingCsv.string() << "\n";
      return kExitOk;
    }
    if (place->parsed()) {
      if (pb->csv.has_parent_path()) std::filesystem::create_directories(pb->csv.parent_path());
      if (Status st = bench::runPlacementBench(*pb); !st) return reportError(st.error());
      std::cout << "wrote " << pb->csv.string() << "\n";
      return kExitOk;
    }
    if (impact->parsed()) {
      if (is->csv.has_parent_path()) std::filesystem::create_directories(is->csv.parent_path());
      if (Status st = bench::runImpactBench(*is); !st) return reportError(st.error());
      std::cout << "wrote " << is->csv.string() << "\n";
      return kExitOk;
    }
    auto loaded = loadBaseShapes(*shapes);
    if (!loaded) return reportError(loaded.error());
    s->shapes = std::move(loaded).value();
    s->kinds.clear();
    for (const auto& k : *kinds) s->kinds.push_back(parseDescriptorKind(k).value());
    s->indices.clear();
    for (const auto& text : *indices) {
      auto choice = bench::parseIndexChoice(text);
      if (!choice) return reportError(choice.error());
      s->indices.push_back(std::move(choice).value());
    }
    for (const auto& path : {s->searchCsv, s->descriptorCsv}) {
      if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    }
    if (Status st = bench::runSearchBench(*s); !st) return reportError(st.error());
    std::cout << "wrote " << s->searchCsv.string() << " and " << s->descriptorCsv.string() << "\n";
    return kExitOk;
  };
}

}  // namespace brittle::cli

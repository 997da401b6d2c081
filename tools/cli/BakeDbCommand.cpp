// bake-db: the fragment shape database from the command line, on one process or many (MPI).
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "CliSupport.h"
#include "Commands.h"
#include "Distributed.h"
#include "brittle/precompute/BaseShapes.h"
#include "brittle/precompute/FragmentDatabaseBake.h"

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
  std::string element = "p1";
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
  cmd->add_option("--element", o->element,
                  "Finite element of the entries: p1 (4-node tets) or p2 (10-node tets; pieces of thin parts, which "
                  "lock in bending with p1)")
      ->capture_default_str()
      ->check(CLI::IsMember({"p1", "p2"}));
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
    s.elementOrder = *parseElementOrder(o->element);
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

}  // namespace brittle::cli

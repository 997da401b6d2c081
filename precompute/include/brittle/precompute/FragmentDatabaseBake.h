// FragmentDatabaseBake.h — bakes the fragment shape database (FragmentDatabase.h): fragments cut
// from procedural base shapes (BaseShapes.h, FragmentGenerator.h), each normalised to its
// canonical frame at unit volume, described by every descriptor kind and, unless descriptors only
// are asked for, tetrahedralised and solved for its modes at the reference material.
//
// Parallel and reproducible: entries are baked concurrently (TBB), but entry i depends only on
// the settings and its own seed, seed_i = splitmix64(seed + i), and results are gathered in entry
// order, so the database is the same for any thread count. Entry i comes from base shape
// i mod #shapes: cut (FragmentGenerator.h) or, for a seeded share runtimeFragments.fraction of
// the entries, broken off by the runtime (RuntimeFragments.h). A cut entry is tet-meshed by
// Mesh_3; a runtime entry keeps the tets the runtime cut it out with (Mesh_3 split most thin
// shards of a plate into pieces). An entry whose fragment, tet meshing or modal solve fails is
// made again from the next seed of the same stream (at most kEntryAttempts times) before the
// bake fails.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "brittle/database/FragmentDatabase.h"
#include "brittle/precompute/BaseShapes.h"
#include "brittle/precompute/FragmentGenerator.h"
#include "brittle/precompute/ModalAnalysis.h"
#include "brittle/precompute/Progress.h"
#include "brittle/precompute/RuntimeFragments.h"
#include "brittle/precompute/TetMesher.h"

namespace brittle {

inline constexpr int kEntryAttempts = 4;

struct DatabaseBakeSettings {
  std::vector<BaseShapeDefinition> shapes;  ///< at least one
  int64_t entryCount = 48;
  uint64_t seed = 1;
  FragmentSettings fragments;
  /// The material every entry is baked with; queries rescale from it (ScalingLaws.h).
  Material referenceMaterial = referenceFragmentMaterial();
  /// false: descriptors only (no tets, no modes); for search benchmarks on large databases.
  bool physics = true;
  TetMeshSettings tetMesh = defaultFragmentTetMeshSettings();
  int modeCount = 12;
  /// The entries' finite element. P2 for pieces of thin parts (shards of a plate or a vase wall),
  /// which P1 tets make too stiff in bending; P1 (the default) for chunky pieces.
  ElementOrder elementOrder = ElementOrder::P1;
  ShapeDescriptorSettings descriptors;
  /// Kinds to compute. A disabled kind leaves a 0-column matrix, which FragmentMatcher cannot
  /// search and writePack rejects: for benchmarks that need one kind on a huge database.
  std::array<bool, kDescriptorKindCount> kinds = {true, true, true};
  /// Per kind, the index the database stores; unset: defaultIndexSettings(kind, entries).
  std::array<std::optional<DescriptorIndexSettings>, kDescriptorKindCount> index;
  int threads = 0;  ///< worker threads; 0 = TBB's default (all cores)
  /// Runtime fracture as a second source of fragments (fraction 0: every entry is cut).
  RuntimeFragmentSettings runtimeFragments;

  /// The glass preset (E 70 GPa, ν 0.2, ρ 2500 kg/m³): a query of the same ν rescales exactly,
  /// another ν goes through the Rayleigh–Ritz correction of ScalingLaws.h.
  static Material referenceFragmentMaterial();
  /// ~1000 tets per fragment, sharp features kept (cut faces meet at sharp edges).
  static TetMeshSettings defaultFragmentTetMeshSettings();
};

/// Seed of entry i: splitmix64(seed + i).
uint64_t fragmentEntrySeed(uint64_t seed, int64_t entry);

/// Whether the entry with first seed `entrySeed` comes from runtime fracture: a uniform draw from
/// the seed below `fraction` (so about that share of entries, the same ones for any thread count).
bool isRuntimeFragmentEntry(uint64_t entrySeed, double fraction);

/// One entry from any closed fragment surface (metres, any pose): canonical surface, descriptors
/// of every kind (written to `descriptors`, one row each, in kind order) and, when
/// settings.physics, the tet mesh and modes. name must be unique in the database. The tets are
/// Mesh_3's of the surface, or, when `solid` is given (the fragment's own tets in the surface's
/// frame, as a runtime fragment has them), those tets moved to the canonical frame, whose modes
/// are solved as the exact path solves them (exactFragmentAsset, FragmentModes.h).
/// Errors: those of computeCanonicalFrames, validateSurfaceMesh, bakeSurface, exactFragmentAsset.
Result<FragmentEntry> bakeFragmentEntry(const TriangleMesh& fragment, const std::string& name,
                                        const DatabaseBakeSettings& settings,
                                        std::array<Descriptor, kDescriptorKindCount>& descriptors,
                                        ProgressSink* progress = nullptr, const TetMesh* solid = nullptr);

/// The whole database. Progress reports "fragment database" with the fraction of entries done.
/// Errors: InvalidArgument (no shapes, entryCount < 1, bad descriptor settings), the first
/// failing entry's error after kEntryAttempts, Cancelled.
Result<FragmentDatabase> bakeFragmentDatabase(const DatabaseBakeSettings& settings, ProgressSink* progress = nullptr);

/// Checkpoints of a database bake. The entries are baked in chunks of chunkEntries consecutive
/// entries; each finished chunk is written whole (writePack: temporary file and rename) as
/// `<directory>/entries-<first>-<end>.h5`, a pack holding just those entries, beside `bake.json`,
/// which records the settings (describeDatabaseBake) and the chunking. A bake killed at any point
/// keeps its finished chunks and never a partial one. With resume, the next bake reads the
/// finished chunks back instead of baking them again; the database then equals an uninterrupted
/// bake's bit for bit, because entry i depends only on the settings and i. A distributed bake
/// gives process `rank` of `ranks` the chunks c with c mod ranks = rank.
struct DatabaseCheckpointSettings {
  std::filesystem::path directory;  ///< where the chunks live; required
  int64_t chunkEntries = 64;        ///< entries per chunk, ≥ 1
  bool resume = false;              ///< reuse finished chunks; false: remove them and bake afresh
  int rank = 0;                     ///< this process, in [0, ranks)
  int ranks = 1;                    ///< processes sharing the bake
};

/// What a checkpointed bake did on this rank.
struct DatabaseCheckpointReport {
  int64_t chunksReused = 0, entriesReused = 0;  ///< read back from the directory
  int64_t chunksBaked = 0, entriesBaked = 0;    ///< baked and written now
};

/// The settings that decide the entries, as one line of JSON (every field, doubles round-trip).
std::string describeDatabaseBake(const DatabaseBakeSettings& settings);

/// Number of chunks, ceil(entryCount / chunkEntries), and the file of chunk c.
int64_t fragmentDatabaseChunkCount(const DatabaseBakeSettings& settings, const DatabaseCheckpointSettings& checkpoints);
std::filesystem::path fragmentDatabaseChunkPath(const DatabaseBakeSettings& settings,
                                                const DatabaseCheckpointSettings& checkpoints, int64_t chunk);

/// Creates the directory and its bake.json. Afresh (no resume) it first removes every chunk file
/// found there. Errors: InvalidArgument (bad chunking or rank, a disabled descriptor kind, resume
/// over the checkpoints of a bake with other settings), PackIoError.
Status prepareFragmentDatabaseCheckpoints(const DatabaseBakeSettings& settings,
                                          const DatabaseCheckpointSettings& checkpoints);

/// Bakes this rank's chunks that the directory does not hold whole (with resume) or all of them.
/// Progress counts this rank's entries, reused ones included. Call after
/// prepareFragmentDatabaseCheckpoints. Errors: those of prepare (FileNotFound without bake.json),
/// bakeFragmentDatabase and writePack.
Result<DatabaseCheckpointReport> bakeFragmentDatabaseChunks(const DatabaseBakeSettings& settings,
                                                            const DatabaseCheckpointSettings& checkpoints,
                                                            ProgressSink* progress = nullptr);

/// The database from a directory that holds every chunk. Errors: those of readPack for a missing
/// or damaged chunk (naming it), PackCorrupt for a chunk holding other entries.
Result<FragmentDatabase> assembleFragmentDatabase(const DatabaseBakeSettings& settings,
                                                  const DatabaseCheckpointSettings& checkpoints);

/// One process, checkpointed: prepare, bake the chunks, assemble. Equal to the uncheckpointed
/// bake for any chunking and thread count.
Result<FragmentDatabase> bakeFragmentDatabase(const DatabaseBakeSettings& settings,
                                              const DatabaseCheckpointSettings& checkpoints,
                                              ProgressSink* progress = nullptr,
                                              DatabaseCheckpointReport* report = nullptr);

/// The optional "database" section of a bake manifest (BakePipeline.h):
///   "database": { "shapes": "shapes/base-shapes.json", "only": ["box", "plate"], "entries": 48,
///                 "seed": 1, "tets": 1000, "modes": 12, "descriptors_only": false,
///                 "moment_order": 4, "voxel_resolution": 16, "runtime_fraction": 0.5 }
/// Every key is optional except "shapes" (relative to the manifest's directory); "only" picks
/// shapes by name. nullopt when the manifest has no "database" key.
/// Errors: FileNotFound, ParseError (naming the key), those of loadBaseShapes.
Result<std::optional<DatabaseBakeSettings>> loadDatabaseManifest(const std::filesystem::path& manifestPath);

/// Keeps the shapes whose names are listed (in the listed order). Error: InvalidArgument naming
/// an unknown shape and listing the known ones.
Result<std::vector<BaseShapeDefinition>> selectBaseShapes(const std::vector<BaseShapeDefinition>& shapes,
                                                          const std::vector<std::string>& names);

}  // namespace brittle

// FragmentDatabase.h — the precomputed fragment shape database a pack carries (schema v2,
// database/PACK_SCHEMA.md): fragments of base shapes, each with its own tet mesh, modal basis and
// stress modes, and a descriptor matrix per kind for nearest-neighbour search.
//
// Frame and scale of an entry. Every entry is stored in its own primary canonical frame
// (CanonicalFrame.h): centre of mass at the origin, principal axes along x, y, z, unit volume
// (1 m³). Its physical data is baked at the database's reference material. A query fragment of
// any size, pose and material is matched in its canonical frame, and the entry's data is mapped
// back by the scaling laws of ScalingLaws.h.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "brittle/database/DescriptorIndex.h"
#include "brittle/database/MatchErrors.h"
#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/descriptors/DescriptorTypes.h"
#include "brittle/core/MeshTypes.h"
#include "brittle/descriptors/ShapeDescriptors.h"

namespace brittle {

struct FragmentEntry {
  /// Tet mesh, mass properties, modal basis and stress modes in the canonical frame, at unit
  /// volume and the reference material. asset.name is unique in the database; asset.materialName
  /// is the reference material's name. An entry baked with descriptors only has no tets (0 rows).
  ObjectAsset asset;
  /// The exact fragment surface (closed, outward) in the canonical frame; the descriptors are
  /// computed from it.
  TriangleMesh surface;
  std::string baseShape;             ///< name of the base shape it was cut from
  std::string cut;                   ///< how: "voronoi", "planes", or kRuntimeCutPrefix and the impact
  uint64_t seed = 0;                 ///< the seed that reproduces the cut
  double baseVolumeFraction = 0.0;   ///< fragment volume / base shape volume, before normalising
};

/// How `FragmentEntry::cut` starts for an entry broken off a base shape by the runtime
/// (RuntimeFragments.h) instead of cut; the rest names the impact's speed and the piece.
inline constexpr std::string_view kRuntimeCutPrefix = "runtime:";
inline bool brokenByTheRuntime(const FragmentEntry& entry) { return entry.cut.rfind(kRuntimeCutPrefix, 0) == 0; }

/// Reads the arrays of entries that a database does not hold: a pack read with
/// EntryReading::OnDemand (Pack.h). Thread-safe; every call reads and checks the entry anew.
class FragmentEntrySource {
 public:
  virtual ~FragmentEntrySource() = default;
  /// Entry `entry` whole, its arrays read and checked as a whole read checks them (indices,
  /// block sizes, checksums, finite values, its surface by validateFragmentEntry). Errors: the
  /// pack's typed read errors (PackCorrupt, PackShapeMismatch, PackIoError), InvalidArgument (an
  /// entry out of range).
  virtual Result<FragmentEntry> load(int64_t entry) const = 0;
  /// Entry `entry`'s number of tets, known without reading its arrays; 0 out of range.
  virtual int64_t tetCount(int64_t entry) const = 0;
  /// The descriptor matrix of `kind` (#entries by descriptorSize), read and checked (finite).
  /// Errors: the pack's typed read errors.
  virtual Result<DescriptorMatrix> descriptors(DescriptorKind kind) const = 0;
};

struct FragmentDatabase {
  Material referenceMaterial;          ///< the material every entry's physics was baked with
  ShapeDescriptorSettings descriptorSettings;
  uint64_t seed = 0;                  ///< the bake seed (entry i's seed derives from it)
  std::vector<FragmentEntry> entries;
  /// Per kind (indexed by DescriptorKind): #entries by descriptorSize(kind), row i for entry i in
  /// its primary frame. Empty when read on demand (entrySource).
  std::array<DescriptorMatrix, kDescriptorKindCount> descriptors;
  /// Per kind: how the runtime builds the search index at load.
  std::array<DescriptorIndexSettings, kDescriptorKindCount> indexSettings;
  /// Per kind: the match error against the descriptor distance, calibrated when the database was
  /// baked with physics (MatchErrors.h); empty without physics and in packs baked before it.
  std::array<MatchErrorModel, kDescriptorKindCount> matchErrors;
  /// A matched body's own frequencies' error against the runtime's indicators (MatchErrors.h),
  /// calibrated on the pack's objects' runtime fragments; empty when not calibrated.
  FrequencyErrorModels frequencyErrors;
  /// Null: `entries` are whole. Set: the pack was read with EntryReading::OnDemand, `entries` hold
  /// every field but the arrays (asset.tetMesh, asset.surfaceFaces, asset.modal.modes,
  /// asset.stressModes, asset.eliminationOrder, surface), `descriptors` are empty (0 rows), and
  /// this reads them (FragmentMatcher::build reads the kinds it indexes). Such a database cannot
  /// be written (writePack refuses it).
  std::shared_ptr<const FragmentEntrySource> entrySource;

  bool empty() const { return entries.empty(); }
  bool hasPhysics() const;  ///< every entry has a tet mesh and at least one mode (read whole or not)
  const DescriptorMatrix& descriptorsOf(DescriptorKind kind) const {
    return descriptors[static_cast<size_t>(kind)];
  }
};

/// The index a baked database stores for `kind` when its bake names none.
/// - The moments: the inverted file (`ivf`), about kIvfRowsPerList rows a list and 4 lists probed,
///   so a query compares about 1 600 rows at any size. At 10⁵ entries that is 256 / 4, recall@1
///   0.995 at 8.9 µs in `bench search` (docs/results/fragment-database.md). Below 780 entries it is
///   one list, which is every row ranked by the key's bounds, so exact. Lists are capped at 1 024
///   (the pack's limit on trees), so past ~4·10⁵ entries a query compares more rows.
/// - The occupancy voxels (0/1): the inverted file over their bit codes (`ivf-binary`), about
///   kIvfBinaryRowsPerList rows a list (at most 1 024 lists) and 32 probed: in `bench search` at 10⁴
///   entries recall@1 0.995 at 9.2–10.9 µs, at 10⁵ 0.995 at 15.3–16.6 µs, where the graph over the
///   codes stored before (`hnsw-binary`, M 16, ef 32) took 21.4–24.2 and 45.6–71.7 µs for 0.993 and
///   0.990 in the same runs (docs/results/fragment-database.md). Below 330 entries every list is probed, which
///   is exact.
/// - The improved voxels (a clamped distance): the inverted file (`ivf`) over their first 64
///   principal components and bounds of the rest, about kIvfWideRowsPerList rows a list (at most
///   1 024 lists) and 40 probed: in `bench search` at 10⁴ entries recall@1 0.993 at 37.8 µs, at 10⁵
///   0.998 at 75.2–81.5 µs (two runs), where the graph over their block sums' principal components
///   stored before (`hnsw-principal`, M 32, ef 32) took 93.5 and 138.0 µs for 0.998 and 0.995 in the
///   same run, and builds 5× slower (4.7 against 22.8 s at 10⁵). Below 410 entries every list is
///   probed, which is exact. It takes a grid of any resolution (the graph needed multiples of 8).
/// Every build is deterministic (the same data give the same index in any process).
DescriptorIndexSettings defaultIndexSettings(DescriptorKind kind, int64_t entries);
/// The inverted file (`ivf`) sized to `entries` rows of `kind`, as defaultIndexSettings gives it to
/// the moments and the improved voxels (also what `query --index ivf` builds, the occupancy grids
/// sized as the improved ones: both are 4 096-value rows, filed by 64 components).
DescriptorIndexSettings sizedInvertedFile(int64_t entries, DescriptorKind kind = DescriptorKind::Moment);
inline constexpr int64_t kIvfRowsPerList = 390;
/// Rows a list of the occupancy voxels' default inverted file (defaultIndexSettings).
inline constexpr int64_t kIvfBinaryRowsPerList = 10;
/// Rows a list of the improved voxels' default inverted file (defaultIndexSettings).
inline constexpr int64_t kIvfWideRowsPerList = 10;

/// Checks one entry against the database's reference material: its material, its base volume
/// fraction and its surface (at least 4 vertices and faces, finite, indices in range). Error:
/// InvalidArgument naming the entry.
Status validateFragmentEntry(const FragmentEntry& entry, const Material& referenceMaterial);

/// Checks sizes and values: descriptor matrices have one finite row per entry and the width of
/// their settings, unique entry names, every entry's material is the reference material, and
/// valid surfaces (of entries it holds whole) and settings. Error: InvalidArgument naming the
/// entry or field.
Status validateFragmentDatabase(const FragmentDatabase& database);

}  // namespace brittle

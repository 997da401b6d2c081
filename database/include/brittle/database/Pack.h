// Pack.h — the brittle pack: one HDF5 file holding materials, baked objects and, optionally, the
// fragment shape database (FragmentDatabase.h).
//
// The schema (groups, datasets, attributes, units) is documented in database/PACK_SCHEMA.md, next
// to the code that writes it. Writing is atomic: the pack goes to a temporary file in the target
// directory, which is renamed over the target only once it is complete, so a pack on disk is
// always whole. Reading validates the format name, the version, every dataset's shape, every
// checksum (HDF5 Fletcher-32 filter) and that every floating-point value is finite.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "brittle/database/FragmentDatabase.h"
#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/core/Result.h"

namespace brittle {

inline constexpr const char* kPackFormatName = "brittle-pack";
/// Version 2 added the fragment database (/database). Version 3 added each object's element order
/// (element_order: 1 = P1, 2 = P2; ObjectAsset.h). The reader also reads versions 1 and 2: their
/// objects are P1, and version 1 packs have no database. The database's match-error models
/// (/database/match_errors, MatchErrors.h) are an optional group (PACK_SCHEMA.md's policy: no new
/// version): a pack without them reads with none, and its matches carry no predicted error until
/// the database is baked again (brittle bake-db).
inline constexpr int kPackVersion = 3;
inline constexpr int kOldestReadablePackVersion = 1;

struct Pack {
  std::vector<Material> materials;
  std::vector<ObjectAsset> objects;  ///< each objects[i].materialName names one of materials
  FragmentDatabase database;         ///< empty: the pack has no fragment database
};

/// Writes pack to path atomically (temporary file + rename). On any error no file is left at
/// path (an existing pack there is untouched) and no temporary file remains.
/// Errors: InvalidArgument (object names a missing material, inconsistent array sizes),
/// PackIoError (cannot create, write or rename).
Status writePack(const Pack& pack, const std::filesystem::path& path);

/// Reads and validates a whole pack.
/// Errors: FileNotFound, PackIoError (not HDF5, unreadable), PackFormatMismatch (format attribute
/// is not "brittle-pack"), PackVersionMismatch, PackShapeMismatch (a dataset's size disagrees with
/// its offsets or counts, a missing group or dataset), PackCorrupt (checksum failure, non-finite
/// value, index out of range).
/// How readPack reads the fragment database's entries.
enum class EntryReading {
  /// Every entry whole, read and checked before readPack returns: for tools that walk the entries
  /// (query, inspect, benchmarks, a resumed bake) and for writing the pack back.
  Whole,
  /// Only what a World needs before its first match: the index settings, the match-error models
  /// and every entry's small fields (name, mass properties, frequencies, quality, bake record).
  /// The descriptor matrices and each entry's arrays (tet mesh, modes, stress modes, exact
  /// surface) stay in the file, and database.entrySource reads and checks them when they are
  /// needed: a kind's matrix when an index is built over it (FragmentMatcher::build), an entry
  /// when it is matched (FragmentDatabase.h). The pack keeps its file open while it (or a copy)
  /// lives. A World made from it matches to the same bits; a damaged entry is found when it is
  /// read, as that fragment's error, instead of failing the whole read. The objects are read
  /// whole either way.
  OnDemand,
};

Result<Pack> readPack(const std::filesystem::path& path, EntryReading entries = EntryReading::Whole);

}  // namespace brittle

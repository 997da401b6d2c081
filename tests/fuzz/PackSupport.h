// PackSupport.h — what the pack fuzz targets share: the small, valid pack they start from, and
// the checks on what readPack returns.
#pragma once

#include <filesystem>

#include "brittle/database/Pack.h"

namespace brittle::fuzz {

/// Two materials, two objects (one tetrahedron with two modes, two tetrahedra with one mode) and
/// a fragment database of two entries (one with physics, one descriptors only) at the smallest
/// descriptor settings. Every value is finite and every index in range, so writePack accepts it.
/// It reaches every group, dataset and attribute readPack reads, in a file of a few tens of KB.
Pack makeSeedPack();

/// Aborts (a finding) unless readPack's result is a documented error, or a pack that passes
/// what the runtime relies on: writePack's validation (which rejects everything the reader must
/// reject), the fragment database's, and a material for every object. Also aborts when the read
/// left an HDF5 object open.
void checkReadResult(const Result<Pack>& result);

/// Reads the pack at `path` on demand (EntryReading::OnDemand), then every entry and descriptor
/// matrix of it, and aborts unless each result is a documented error or checked data, the reads
/// agree with the whole read (`wholeReadOk`: the file passes read whole iff it passes on demand
/// with everything read), and nothing is left open once the pack is gone.
void checkOnDemandRead(const std::filesystem::path& path, bool wholeReadOk);

}  // namespace brittle::fuzz

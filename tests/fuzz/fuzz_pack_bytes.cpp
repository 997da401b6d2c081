// Fuzz target: readPack (Pack.h) on arbitrary files. The seed is a real pack (PackSupport.h), so
// the mutations land in HDF5's superblock, object headers, B-trees, heaps and checksummed chunks.
// readPack must refuse a damaged file with one of its documented codes, and never crash, hang,
// allocate beyond the file's size or leave an HDF5 object open (checkReadResult). Read on demand
// with every entry read, it must agree with the whole read (checkOnDemandRead).
#include <cstddef>
#include <cstdint>

#include "FuzzSupport.h"
#include "PackSupport.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = brittle::fuzz::writeScratchFile("pack.h5", data, size);
  bool wholeOk = false;
  {
    auto whole = brittle::readPack(path);
    wholeOk = whole.ok();
    brittle::fuzz::checkReadResult(whole);
  }
  brittle::fuzz::checkOnDemandRead(path, wholeOk);
  return 0;
}

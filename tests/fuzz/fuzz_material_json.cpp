// Fuzz target: loadMaterialFile (MaterialLibrary.h) on arbitrary bytes. A material that loads
// must pass validateMaterial: the runtime trusts it from then on.
#include <cstddef>
#include <cstdint>

#include "FuzzSupport.h"
#include "brittle/precompute/MaterialLibrary.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace brittle;
  const auto path = fuzz::writeScratchFile("material.json", data, size);
  const Result<Material> material = loadMaterialFile(path);
  fuzz::expectDocumentedError(material, {ErrorCode::FileNotFound, ErrorCode::ParseError, ErrorCode::InvalidMaterial});
  if (material.ok() && !validateMaterial(material.value()).ok()) fuzz::finding("an invalid material was loaded");
  return 0;
}

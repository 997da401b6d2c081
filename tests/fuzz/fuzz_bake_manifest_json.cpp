// Fuzz target: loadBakeManifest (BakeManifest.h) on arbitrary bytes. The manifest sits next to a
// valid custom material file, "custom.json", so that inputs can reach the material-file branch;
// the meshes it names are not read by the loader. Every object it returns must carry a valid
// material and settings inside the documented ranges.
#include <cstddef>
#include <cstdint>

#include "FuzzSupport.h"
#include "brittle/precompute/BakeManifest.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  brittle::fuzz::writeCustomMaterialFile();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace brittle;
  const auto path = fuzz::writeScratchFile("manifest.json", data, size);
  const Result<std::vector<ObjectBakeSettings>> objects = loadBakeManifest(path);
  fuzz::expectDocumentedError(objects, {ErrorCode::FileNotFound, ErrorCode::ParseError, ErrorCode::UnknownMaterial,
                                        ErrorCode::InvalidMaterial});
  if (!objects.ok()) return 0;
  for (const ObjectBakeSettings& s : objects.value()) {
    if (!validateMaterial(s.material).ok()) fuzz::finding("an object with an invalid material was loaded");
    if (s.tetMesh.targetTets < 0 || s.tetMesh.targetTets > 5000000) fuzz::finding("\"tets\" out of range");
    if (s.modal.modeCount < 1 || s.modal.modeCount > 2000) fuzz::finding("\"modes\" out of range");
    if (!(s.tetMesh.sliverBoundDeg >= 0.0 && s.tetMesh.sliverBoundDeg <= 30.0)) fuzz::finding("\"sliver_bound\" out of range");
  }
  return 0;
}

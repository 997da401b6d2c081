// Fuzz target: parseRuntimeSettings (RuntimeSettingsFile.h) on arbitrary bytes. Whatever it
// accepts must be inside the ranges validateWorldSettings checks (this target does not link the
// runtime), and written back out it must read to the same settings.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "FuzzSupport.h"
#include "brittle/precompute/RuntimeSettingsFile.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace brittle;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const Result<FractureSettings> r = parseRuntimeSettings(text, "fuzz");
  fuzz::expectDocumentedError(r, {ErrorCode::ParseError, ErrorCode::InvalidArgument});
  if (!r.ok()) return 0;
  const FractureSettings& f = r.value();
  if (!(f.debrisVolumeFraction >= 0.0 && f.debrisVolumeFraction < 1.0) || f.modeCount < 0 || f.exactModesMaxTets < 0 ||
      f.exactModeCount < 1) {
    fuzz::finding("accepted settings the World refuses");
  }
  const Result<FractureSettings> again = parseRuntimeSettings(runtimeSettingsJson(r.value()), "fuzz (written back)");
  if (!again.ok()) fuzz::finding("written settings do not read back");
  const FractureSettings& a = r.value();
  const FractureSettings& b = again.value();
  if (a.descriptor != b.descriptor || a.debrisVolumeFraction != b.debrisVolumeFraction ||
      a.exactModesMaxTets != b.exactModesMaxTets || a.exactModeCount != b.exactModeCount || a.modeCount != b.modeCount) {
    fuzz::finding("settings changed on the way back");
  }
  return 0;
}

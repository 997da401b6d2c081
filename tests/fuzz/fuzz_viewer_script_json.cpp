// Fuzz target: parseViewerScript (the viewer's ViewerScript.h) on arbitrary bytes. Whatever it
// accepts must be in frame order, with non-negative frames, throws of positive finite speed,
// radius and mass between two different points, and non-empty screenshot names.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "FuzzSupport.h"
#include "brittle/viewer/ViewerScript.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace brittle;
  const Result<ViewerScript> r = parseViewerScript(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz");
  fuzz::expectDocumentedError(r, {ErrorCode::ParseError, ErrorCode::InvalidArgument, ErrorCode::UnknownMaterial});
  if (!r.ok()) return 0;
  int64_t previous = 0;
  for (const ScriptEvent& e : r.value().events) {
    if (e.frame < previous) fuzz::finding("events out of frame order");
    previous = e.frame;
    if (e.action == ScriptAction::Throw) {
      const bool ok = e.speedMps > 0.0 && std::isfinite(e.speedMps) && e.radiusM > 0.0 && std::isfinite(e.radiusM) &&
                      e.massKg > 0.0 && std::isfinite(e.massKg) && e.from.allFinite() && e.to.allFinite() && e.from != e.to;
      if (!ok) fuzz::finding("a throw out of range");
    }
    if (e.action == ScriptAction::Screenshot && e.file.empty()) fuzz::finding("a screenshot without a file");
    if (e.distanceM && !(*e.distanceM > 0.0)) fuzz::finding("a camera distance ≤ 0");
  }
  return 0;
}

// Progress.h — progress and cancellation for long offline operations (after OpenVDB's
// util::NullInterrupter): long functions take a ProgressSink* (may be null) and report stages.
#pragma once

#include <string_view>

namespace brittle {

class ProgressSink {
 public:
  virtual ~ProgressSink() = default;
  /// Called when work on stage advances; fraction in [0, 1] within that stage.
  virtual void report(std::string_view stage, double fraction) = 0;
  /// Polled between steps; returning true makes the operation stop with ErrorCode::Cancelled.
  virtual bool wasInterrupted() { return false; }
};

/// Null-safe helpers so call sites need no checks.
inline void reportProgress(ProgressSink* sink, std::string_view stage, double fraction) {
  if (sink) sink->report(stage, fraction);
}
inline bool isInterrupted(ProgressSink* sink) { return sink && sink->wasInterrupted(); }

}  // namespace brittle

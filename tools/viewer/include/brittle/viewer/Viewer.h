// Viewer.h — `brittle view`: a scene playing in a window (GLFW, OpenGL, Dear ImGui), and the
// off-screen frames of `brittle play --frames`.
//
// Interactive: the scene plays in real time (frames of the scene's time step, at most four per
// drawn frame); left drag orbits, right drag pans, the wheel zooms; a left click throws a steel
// ball from the camera through the clicked point, B throws one at the view's centre; Space
// pauses, N (or →) steps one frame while paused, R restarts, Esc quits. A panel shows the time,
// the bodies by kind, the impacts (breaks, deferred, budget waits, simplified, refused), the last
// frame's Bullet and fracture times, and the last impact's stage times and modes.
// Scripted (ViewerScript.h): one scene frame per drawn frame, as fast as it draws, so a script
// gives the same play every time.
//
// A window needs a display: without one, runViewer and FrameWriter::create return an error that
// says to run under `xvfb-run` (Mesa's software renderer draws there).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "brittle/database/Pack.h"
#include "brittle/core/Result.h"
#include "brittle/player/Player.h"
#include "brittle/viewer/ViewerScript.h"

namespace brittle {

struct ViewerSettings {
  int width = 1280, height = 800;
  std::optional<ViewerScript> script;    ///< scripted mode
  std::filesystem::path screenshot;      ///< PNG of the last drawn frame (empty: none)
  int64_t maxFrames = 0;                 ///< stop after this many scene frames (0: scripted, the script's
                                         ///< last event or the scene's duration; interactive, never)
  double throwSpeedMps = 10.0;           ///< what a click or B throws
  double throwRadiusM = 0.025, throwMassKg = 0.3;
};

/// What a (scripted) run saw, in the viewer's own counts.
struct ViewerEventRecord {
  int64_t frame = 0;
  std::string action;
  int32_t bodies = 0;                    ///< live bodies when it fired (before a throw adds its ball)
  std::string file;                      ///< screenshots
};

struct ViewerReport {
  int64_t frames = 0;
  int32_t bodiesStart = 0, bodiesEnd = 0;
  int64_t impacts = 0, breaks = 0, throws = 0;
  std::vector<ViewerEventRecord> events;
};

/// Runs the viewer until Esc, a window close, a script's "quit" or maxFrames. Errors:
/// InvalidArgument (no display, no OpenGL 2.1 context; the message says what GLFW said), those
/// of PlaySession::create and of writing screenshots (PackIoError).
Result<ViewerReport> runViewer(const Pack& pack, const Scene& scene, const PlayerSettings& settings,
                               const ViewerSettings& viewer);

/// `brittle play --frames DIR`: a hidden window that draws frames of a play into PNG files
/// (DIR/frame_000123.png), the camera framed on the scene's first frame.
class FrameWriter {
 public:
  /// Errors: InvalidArgument (no display, bad size), PackIoError (the directory cannot be made).
  static Result<std::unique_ptr<FrameWriter>> create(const std::filesystem::path& dir, int width, int height);
  ~FrameWriter();
  /// Draws the session's bodies and writes the picture of its current frame. Error: PackIoError.
  Status write(const PlaySession& session);
  int64_t written() const { return mWritten; }

 private:
  FrameWriter() = default;
  struct Impl;
  std::unique_ptr<Impl> mImpl;
  int64_t mWritten = 0;
};

}  // namespace brittle

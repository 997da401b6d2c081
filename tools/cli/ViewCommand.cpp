// brittle view — a scene in a window (Viewer.h), and the frames of `brittle play --frames`.
// Without the viewer's libraries (GLFW, OpenGL, ImGui, stb) both say so and exit non-zero.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "CliSupport.h"
#include "Commands.h"
#include "brittle/database/Pack.h"
#include "brittle/player/Player.h"
#include "brittle/player/Scene.h"
#ifdef BRITTLE_WITH_VIEWER
#include "brittle/viewer/Viewer.h"
#endif

namespace brittle::cli {
namespace {

struct ViewOptions {
  std::string pack, scene, script, screenshot, report, size = "1280x800";
  int64_t frames = 0;
  int modes = 0;
  double frameBudgetMs = 0.0;
  int latencyFrames = PlayerSettings{}.fractureLatencyFrames;
};

// "WxH" → (W, H). Error: InvalidArgument.
Result<std::pair<int, int>> parseSize(const std::string& text) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') || w < 16 || h < 16 ||
      w > 16384 || h > 16384) {
    return makeError(ErrorCode::InvalidArgument, "size must be WxH with 16 ≤ W, H ≤ 16384, e.g. 1280x800 (got \"" + text + "\")");
  }
  return std::pair{w, h};
}

#ifndef BRITTLE_WITH_VIEWER
Error noViewer() {
  return makeError(ErrorCode::InvalidArgument,
                   "this brittle was built without the viewer (install libglfw3-dev libgl-dev libimgui-dev libstb-dev and rebuild)");
}
#endif

}  // namespace

Result<PlayResult> playWithFrames(Pack pack, const Scene& scene, const PlayerSettings& settings, const std::string& dir,
                                  int every, const std::string& size) {
  auto wh = parseSize(size);
  if (!wh) return wh.error();
#ifdef BRITTLE_WITH_VIEWER
  auto session = PlaySession::create(std::move(pack), scene, settings);
  if (!session) return session.error();
  auto writer = FrameWriter::create(dir, wh.value().first, wh.value().second);
  if (!writer) return writer.error();
  PlaySession& s = *session.value();
  if (Status st = writer.value()->write(s); !st) return st.error();  // frame 0: the start
  while (s.frame() < s.frameCount()) {
    s.stepFrame();
    if (s.frame() % every == 0 || s.frame() == s.frameCount()) {
      if (Status st = writer.value()->write(s); !st) return st.error();
    }
  }
  return s.finish();
#else
  (void)pack, (void)scene, (void)settings, (void)dir, (void)every;
  return noViewer();
#endif
}

Runner addViewCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "view",
      "Play a scene in a window (GLFW, OpenGL, ImGui). Drag: orbit; right drag: pan; wheel: zoom; click: throw a ball "
      "there; B: throw at the centre; Space: pause; N: step; R: restart; Esc: quit. Needs a display (or xvfb-run).");
  auto o = std::make_shared<ViewOptions>();
  cmd->add_option("pack", o->pack, "Pack (.h5)")->required();
  cmd->add_option("scene", o->scene, "Scene (.json, see assets/scenes/)")->required();
  cmd->add_option("--script", o->script, "Timed inputs (JSON: throw, screenshot, camera, pause, step, resume, quit); "
                                         "the scene then plays one frame per drawn frame");
  cmd->add_option("--screenshot", o->screenshot, "PNG of the last drawn frame");
  cmd->add_option("--report", o->report, "JSON of what the viewer counted (bodies at each event, impacts, breaks)");
  cmd->add_option("--frames-to-run", o->frames, "Stop after this many scene frames (0: the script's end, or never)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--size", o->size, "Window size, WxH")->capture_default_str();
  cmd->add_option("--modes", o->modes, "Modes used per impact (0: all stored)")->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--frame-budget-ms", o->frameBudgetMs, "Fracture time per frame (as for play; 0: none)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--latency-frames", o->latencyFrames,
                  "Frames from a contact to its fracture, computed on worker threads meanwhile (0: at once, on the "
                  "player's thread; -1: the frames nearest to 33 ms)")
      ->capture_default_str()->check(CLI::Range(-1, 600));
  return [o]() -> int {
    auto size = parseSize(o->size);
    if (!size) return reportError(size.error());
    auto scene = loadScene(o->scene);
    if (!scene) return reportError(scene.error());
#ifdef BRITTLE_WITH_VIEWER
    ViewerSettings v;
    v.width = size.value().first;
    v.height = size.value().second;
    v.screenshot = o->screenshot;
    v.maxFrames = o->frames;
    if (!o->script.empty()) {
      auto script = loadViewerScript(o->script);
      if (!script) return reportError(script.error());
      v.script = std::move(script).value();
    }
    auto pack = readPack(o->pack, EntryReading::OnDemand);  // a World reads entries as it matches them
    if (!pack) return reportError(pack.error());
    PlayerSettings settings;
    settings.world.fracture.modeCount = o->modes;
    settings.fractureBudgetS = 1e-3 * o->frameBudgetMs;
    settings.fractureLatencyFrames = o->latencyFrames;
    auto report = runViewer(pack.value(), scene.value(), settings, v);
    if (!report) return reportError(report.error());
    const ViewerReport& r = report.value();
    nlohmann::json events = nlohmann::json::array();
    for (const auto& e : r.events) {
      nlohmann::json j = {{"frame", e.frame}, {"action", e.action}, {"bodies", e.bodies}};
      if (!e.file.empty()) j["file"] = e.file;
      events.push_back(j);
    }
    const nlohmann::json doc = {{"scene", scene.value().name}, {"frames", r.frames}, {"bodies_start", r.bodiesStart},
                                {"bodies_end", r.bodiesEnd}, {"impacts", r.impacts}, {"breaks", r.breaks},
                                {"throws", r.throws}, {"events", events}};
    if (!o->report.empty()) {
      std::ofstream file(o->report);
      file << doc.dump(2) << "\n";
      if (!file) return reportError(makeError(ErrorCode::PackIoError, "cannot write " + o->report));
    }
    std::printf("%s: %lld frames, %d -> %d bodies, %lld impacts, %lld breaks, %lld balls thrown\n", scene.value().name.c_str(),
                static_cast<long long>(r.frames), r.bodiesStart, r.bodiesEnd, static_cast<long long>(r.impacts),
                static_cast<long long>(r.breaks), static_cast<long long>(r.throws));
    return kExitOk;
#else
    return reportError(noViewer());
#endif
  };
}

}  // namespace brittle::cli

// Viewer.cpp — the window, the loop, the panel and the off-screen frames (Viewer.h).
#include "brittle/viewer/Viewer.h"

#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl2.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "brittle/core/Timing.h"
#include "brittle/viewer/Renderer.h"

namespace brittle {
namespace {


std::string& glfwMessage() {
  static std::string message;
  return message;
}

void onGlfwError(int, const char* description) { glfwMessage() = description ? description : "unknown error"; }

// GLFW for the whole process: initialised once, terminated at exit.
Status initGlfw() {
  static bool ready = false;
  if (ready) return Ok{};
  glfwSetErrorCallback(onGlfwError);
  if (!glfwInit()) {
    return makeError(ErrorCode::InvalidArgument,
                     "no display for a window (GLFW: " + glfwMessage() + "); run under xvfb-run, e.g. xvfb-run -a brittle view ...");
  }
  std::atexit(glfwTerminate);
  ready = true;
  return Ok{};
}

Result<GLFWwindow*> openWindow(int width, int height, bool visible, const char* title) {
  if (width < 16 || height < 16 || width > 16384 || height > 16384) {
    return makeError(ErrorCode::InvalidArgument, "window size must be within 16..16384 pixels per side");
  }
  if (Status st = initGlfw(); !st) return st.error();
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 2);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 1);
  glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
  glfwWindowHint(GLFW_DEPTH_BITS, 24);
  GLFWwindow* w = glfwCreateWindow(width, height, title, nullptr, nullptr);
  if (!w) return makeError(ErrorCode::InvalidArgument, "no OpenGL 2.1 window (GLFW: " + glfwMessage() + ")");
  glfwMakeContextCurrent(w);
  glfwSwapInterval(visible ? 1 : 0);
  return w;
}

std::optional<double> floorOf(const Scene& scene) {
  return scene.floor ? std::optional<double>(scene.floor->heightM) : std::nullopt;
}

// The wheel, from GLFW's callback (installed before ImGui's, which chains to it).
double& scrollAccumulator() {
  static double scroll = 0.0;
  return scroll;
}
void onScroll(GLFWwindow*, double, double dy) { scrollAccumulator() += dy; }

RigidImpactor ballThrough(const Eigen::Vector3d& from, const Eigen::Vector3d& direction, double speed, double radius,
                          double mass, const std::string& material) {
  RigidImpactor b;
  b.name = "thrown";
  b.shape = ImpactorShape::Sphere;
  b.radiusM = radius;
  b.massKg = mass;
  b.material = material;
  b.positionWorldM = from;
  b.velocityMps = speed * direction.normalized();
  return b;
}

void panel(const PlaySession& s, const FrameStats& last, bool paused, bool scripted) {
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::Begin("brittle", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  ImGui::Text("%s  t = %.3f s  frame %lld%s", s.scene().name.c_str(), s.timeS(), static_cast<long long>(s.frame()),
              paused ? "  (paused)" : "");
  std::map<BodyKind, int> kinds;
  for (const BodyView& b : s.bodies()) ++kinds[b.kind];
  ImGui::Text("bodies %d: objects %d, fragments %d, debris %d, impactors %d",
              kinds[BodyKind::Object] + kinds[BodyKind::Fragment] + kinds[BodyKind::Debris] + kinds[BodyKind::Impactor],
              kinds[BodyKind::Object], kinds[BodyKind::Fragment], kinds[BodyKind::Debris], kinds[BodyKind::Impactor]);
  const PlayResult& p = s.progress();
  ImGui::Text("impacts %lld, breaks %lld", static_cast<long long>(p.impacts), static_cast<long long>(p.breaks));
  ImGui::Text("deferred %lld, budget waits %lld, simplified %lld, refused %lld", static_cast<long long>(p.deferredImpacts),
              static_cast<long long>(p.budgetDeferredImpacts), static_cast<long long>(p.simplifiedImpacts),
              static_cast<long long>(p.failedImpacts));
  ImGui::Separator();
  ImGui::Text("last frame: Bullet %.2f ms, fracture %.2f ms", 1e3 * last.bulletS, 1e3 * last.fractureS);
  if (!p.events.empty()) {
    const ImpactEvent& e = p.events.back();
    ImGui::Text("last impact: %s at %.2f m/s, %s", e.object.c_str(), e.speedMps,
                !e.error.empty() ? "refused" : (e.broken ? "broke" : "held"));
    ImGui::Text("  %d modes%s%s, %d fragments (%d debris)", e.modesUsed, e.staticCorrection ? " + static correction" : "",
                e.simplified ? ", simplified" : "", e.fragments, e.debris);
    const StageTimes& t = e.times;
    ImGui::Text("  ms: contact %.2f, prepare %.2f, modal %.2f", 1e3 * t.contactS, 1e3 * t.prepareS, 1e3 * t.modalS);
    ImGui::Text("      stress %.2f, cracks %.2f, surfaces %.2f", 1e3 * t.stressS, 1e3 * t.propagationS, 1e3 * t.surfacesS);
    ImGui::Text("      new objects %.2f, total %.2f", 1e3 * t.matchingS, 1e3 * t.totalS());
  }
  if (!scripted) {
    ImGui::Separator();
    ImGui::TextUnformatted("drag: orbit, right drag: pan, wheel: zoom");
    ImGui::TextUnformatted("click: throw a ball there, B: at the centre");
    ImGui::TextUnformatted("Space: pause, N: step, R: restart, Esc: quit");
  }
  ImGui::End();
}

}  // namespace

Result<ViewerReport> runViewer(const Pack& pack, const Scene& scene, const PlayerSettings& settings, const ViewerSettings& v) {
  auto session = PlaySession::create(Pack(pack), scene, settings);
  if (!session) return session.error();
  auto window = openWindow(v.width, v.height, true, ("brittle view: " + scene.name).c_str());
  if (!window) return window.error();
  GLFWwindow* w = window.value();
  glfwSetScrollCallback(w, onScroll);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini beside the user's files
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(w, true);
  ImGui_ImplOpenGL2_Init();
  struct Cleanup {
    GLFWwindow* w;
    ~Cleanup() {
      ImGui_ImplOpenGL2_Shutdown();
      ImGui_ImplGlfw_Shutdown();
      ImGui::DestroyContext();
      glfwDestroyWindow(w);
    }
  } cleanup{w};

  Renderer renderer;
  const std::optional<double> floor = floorOf(scene);
  OrbitCamera camera = OrbitCamera::framing(session.value()->bodies(), floor);
  const bool scripted = v.script.has_value();
  ViewerReport report;
  report.bodiesStart = static_cast<int32_t>(session.value()->bodies().size());
  int64_t lastFrame = v.maxFrames;
  if (lastFrame <= 0 && scripted) {
    lastFrame = session.value()->frameCount();
    for (const ScriptEvent& e : v.script->events) lastFrame = std::max(lastFrame, e.frame + 1);
  }
  size_t next = 0;  // the next script event
  bool paused = false, quit = false, stepOnce = false;
  FrameStats last;
  double accumulated = 0.0;
  auto previous = SteadyClock::now();
  Eigen::Vector2d pressAt(-1, -1), lastCursor(0, 0);
  bool leftDown = false, dragged = false;

  auto throwBall = [&](const RigidImpactor& ball) -> Status {
    report.events.push_back({session.value()->frame(), "throw", static_cast<int32_t>(session.value()->bodies().size()), {}});
    ++report.throws;
    return session.value()->throwSphere(ball);
  };

  while (!quit && !glfwWindowShouldClose(w)) {
    glfwPollEvents();
    int width = 0, height = 0;
    glfwGetFramebufferSize(w, &width, &height);
    PlaySession& s = *session.value();
    std::vector<const ScriptEvent*> shots;

    // Inputs: the script's due events, or the user's.
    if (scripted) {
      while (next < v.script->events.size() && (v.script->events[next].frame <= s.frame() || paused)) {
        const ScriptEvent& e = v.script->events[next++];
        if (e.action == ScriptAction::Throw) {
          const RigidImpactor ball = ballThrough(e.from, e.to - e.from, e.speedMps, e.radiusM, e.massKg, e.material);
          if (Status st = throwBall(ball); !st) return st.error();
        } else if (e.action == ScriptAction::Screenshot) {
          shots.push_back(&e);
        } else if (e.action == ScriptAction::Camera) {
          if (e.yawDeg) camera.yawDeg = *e.yawDeg;
          if (e.pitchDeg) camera.pitchDeg = *e.pitchDeg;
          if (e.distanceM) camera.distanceM = *e.distanceM;
        } else if (e.action == ScriptAction::Pause) {
          paused = true;
        } else if (e.action == ScriptAction::Resume) {
          paused = false;
        } else if (e.action == ScriptAction::Step) {
          stepOnce = true;
        } else if (e.action == ScriptAction::Quit) {
          quit = true;
        }
        if (e.action != ScriptAction::Throw && e.action != ScriptAction::Screenshot) {
          report.events.push_back({s.frame(), std::string(scriptActionName(e.action)), static_cast<int32_t>(s.bodies().size()), {}});
        }
        if (paused || stepOnce || quit || !shots.empty()) break;  // one paused event per drawn frame
      }
    } else {
      const ImGuiIO& io = ImGui::GetIO();
      double cx = 0.0, cy = 0.0;
      glfwGetCursorPos(w, &cx, &cy);
      const Eigen::Vector2d cursor(cx, cy), delta = cursor - lastCursor;
      lastCursor = cursor;
      if (!io.WantCaptureMouse) {
        const bool left = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
        const bool right = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
                           glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS;
        if (left && !leftDown) pressAt = cursor, dragged = false;
        if (left && (cursor - pressAt).norm() > 3.0) dragged = true;
        if (left && dragged) {
          camera.yawDeg -= 0.3 * delta.x();
          camera.pitchDeg = std::clamp(camera.pitchDeg + 0.3 * delta.y(), -85.0, 85.0);
        }
        if (!left && leftDown && !dragged) {  // a click: throw through the clicked point
          Eigen::Vector3d origin, direction;
          int ww = 0, wh = 0;
          glfwGetWindowSize(w, &ww, &wh);
          camera.ray(cursor.x(), cursor.y(), ww, wh, origin, direction);
          if (Status st = throwBall(ballThrough(origin + 0.2 * camera.distanceM * direction, direction, v.throwSpeedMps,
                                                v.throwRadiusM, v.throwMassKg, "steel"));
              !st) {
            return st.error();
          }
        }
        leftDown = left;
        if (right) {
          const Eigen::Vector3d f = (camera.target - camera.eye()).normalized();
          const Eigen::Vector3d side = f.cross(Eigen::Vector3d::UnitZ()).normalized(), up = side.cross(f);
          camera.target += 0.0015 * camera.distanceM * (-delta.x() * side + delta.y() * up);
        }
        camera.distanceM *= std::pow(0.9, scrollAccumulator());
      }
      scrollAccumulator() = 0.0;
      if (!io.WantCaptureKeyboard) {
        static std::map<int, bool> was;
        auto pressed = [&](int key) {
          const bool down = glfwGetKey(w, key) == GLFW_PRESS;
          const bool edge = down && !was[key];
          was[key] = down;
          return edge;
        };
        if (pressed(GLFW_KEY_ESCAPE)) quit = true;
        if (pressed(GLFW_KEY_SPACE)) paused = !paused;
        if (pressed(GLFW_KEY_N) || pressed(GLFW_KEY_RIGHT)) stepOnce = true;
        if (pressed(GLFW_KEY_B)) {
          const Eigen::Vector3d eye = camera.eye();
          if (Status st = throwBall(ballThrough(eye + 0.2 * (camera.target - eye), camera.target - eye, v.throwSpeedMps,
                                                v.throwRadiusM, v.throwMassKg, "steel"));
              !st) {
            return st.error();
          }
        }
        if (pressed(GLFW_KEY_R)) {
          auto fresh = PlaySession::create(Pack(pack), scene, settings);
          if (!fresh) return fresh.error();
          session = std::move(fresh);
          renderer.forget();  // the new play numbers its bodies from 0 again
          continue;
        }
      }
    }

    // The simulation: one frame per drawn frame when scripted, real time otherwise.
    PlaySession& sim = *session.value();
    const auto now = SteadyClock::now();
    const double elapsed = secondsBetween(previous, now);
    previous = now;
    if (stepOnce || (!paused && scripted)) {
      last = sim.stepFrame();
    } else if (!paused) {
      accumulated += elapsed;
      int steps = 0;
      while (accumulated >= sim.scene().timeStepS && steps < 4) {
        last = sim.stepFrame();
        accumulated -= sim.scene().timeStepS;
        ++steps;
      }
      if (steps == 4) accumulated = 0.0;  // behind: slow down rather than spiral
    }
    stepOnce = false;

    // Draw: the scene, then the panel.
    renderer.draw(sim.bodies(), camera, floor, width, height);
    ImGui_ImplOpenGL2_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    panel(sim, last, paused, scripted);
    ImGui::Render();
    ImGui_ImplOpenGL2_RenderDrawData(ImGui::GetDrawData());
    for (const ScriptEvent* e : shots) {
      if (Status st = Renderer::writePng(e->file, renderer.readPixels(width, height), width, height); !st) return st.error();
      report.events.push_back({sim.frame(), "screenshot", static_cast<int32_t>(sim.bodies().size()), e->file.string()});
    }
    const bool end = quit || (lastFrame > 0 && sim.frame() >= lastFrame);
    if (end && !v.screenshot.empty()) {
      if (Status st = Renderer::writePng(v.screenshot, renderer.readPixels(width, height), width, height); !st) return st.error();
      report.events.push_back({sim.frame(), "screenshot", static_cast<int32_t>(sim.bodies().size()), v.screenshot.string()});
    }
    glfwSwapBuffers(w);
    if (end) break;
  }
  const PlaySession& s = *session.value();
  report.frames = s.frame();
  report.bodiesEnd = static_cast<int32_t>(s.bodies().size());
  report.impacts = s.progress().impacts;
  report.breaks = s.progress().breaks;
  return report;
}

struct FrameWriter::Impl {
  GLFWwindow* window = nullptr;
  std::filesystem::path dir;
  int width = 0, height = 0;
  Renderer renderer;
  std::optional<OrbitCamera> camera;
  ~Impl() {
    if (window) glfwDestroyWindow(window);
  }
};

Result<std::unique_ptr<FrameWriter>> FrameWriter::create(const std::filesystem::path& dir, int width, int height) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return makeError(ErrorCode::PackIoError, "cannot make the frame directory " + dir.string() + ": " + ec.message());
  auto window = openWindow(width, height, false, "brittle frames");
  if (!window) return window.error();
  std::unique_ptr<FrameWriter> f(new FrameWriter());
  f->mImpl = std::make_unique<Impl>();
  f->mImpl->window = window.value();
  f->mImpl->dir = dir;
  glfwGetFramebufferSize(window.value(), &f->mImpl->width, &f->mImpl->height);
  return f;
}

FrameWriter::~FrameWriter() = default;

Status FrameWriter::write(const PlaySession& session) {
  Impl& m = *mImpl;
  glfwMakeContextCurrent(m.window);
  const std::vector<BodyView> bodies = session.bodies();
  const std::optional<double> floor = floorOf(session.scene());
  if (!m.camera) m.camera = OrbitCamera::framing(bodies, floor);
  m.renderer.draw(bodies, *m.camera, floor, m.width, m.height);
  glFinish();
  char name[64];
  std::snprintf(name, sizeof name, "frame_%06lld.png", static_cast<long long>(session.frame()));
  if (Status st = Renderer::writePng(m.dir / name, m.renderer.readPixels(m.width, m.height), m.width, m.height); !st) return st;
  ++mWritten;
  return Ok{};
}

}  // namespace brittle

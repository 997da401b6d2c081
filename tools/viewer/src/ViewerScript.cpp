// ViewerScript.cpp — the viewer's script reader (ViewerScript.h). No GL here: the tests and the
// fuzz target build it alone.
#include "brittle/viewer/ViewerScript.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "brittle/core/JsonChecks.h"
#include "brittle/precompute/MaterialLibrary.h"

namespace brittle {
namespace {

Error scriptError(std::string_view source, const std::string& where, const std::string& what) {
  return parseError("script " + std::string(source) + ": " + where, what);
}

Result<double> number(const nlohmann::json& o, const char* key, std::string_view source, const std::string& where) {
  const auto& v = o.at(key);
  if (!v.is_number()) return scriptError(source, where + "." + key, "must be a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) return makeError(ErrorCode::InvalidArgument, "script " + std::string(source) + ": " + where + "." + key + " must be finite");
  return x;
}

Result<Eigen::Vector3d> vector3(const nlohmann::json& o, const char* key, std::string_view source, const std::string& where) {
  const auto& v = o.at(key);
  if (!v.is_array() || v.size() != 3) return scriptError(source, where + "." + key, "must be [x, y, z]");
  Eigen::Vector3d x;
  for (int i = 0; i < 3; ++i) {
    if (!v[static_cast<size_t>(i)].is_number()) return scriptError(source, where + "." + key, "must hold numbers");
    x[i] = v[static_cast<size_t>(i)].get<double>();
  }
  if (!x.allFinite()) return makeError(ErrorCode::InvalidArgument, "script " + std::string(source) + ": " + where + "." + key + " must be finite");
  return x;
}

}  // namespace

std::string_view scriptActionName(ScriptAction action) {
  switch (action) {
    case ScriptAction::Throw: return "throw";
    case ScriptAction::Screenshot: return "screenshot";
    case ScriptAction::Camera: return "camera";
    case ScriptAction::Pause: return "pause";
    case ScriptAction::Resume: return "resume";
    case ScriptAction::Step: return "step";
    case ScriptAction::Quit: return "quit";
  }
  return "quit";
}

Result<ViewerScript> parseViewerScript(std::string_view json, std::string_view source) {
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(json);
  } catch (const std::exception& e) {
    return scriptError(source, "document", e.what());
  }
  if (!doc.is_object()) return scriptError(source, "document", "not a JSON object");
  if (auto key = findUnknownKey(doc, {"events"})) return scriptError(source, "document", unknownKeyMessage(*key));
  if (!doc.contains("events") || !doc["events"].is_array()) return scriptError(source, "events", "must be an array");
  const std::vector<std::pair<std::string, ScriptAction>> actions = {
      {"throw", ScriptAction::Throw}, {"screenshot", ScriptAction::Screenshot}, {"camera", ScriptAction::Camera},
      {"pause", ScriptAction::Pause}, {"resume", ScriptAction::Resume},         {"step", ScriptAction::Step},
      {"quit", ScriptAction::Quit}};
  const std::map<ScriptAction, std::set<std::string>> allowed = {
      {ScriptAction::Throw, {"frame", "action", "from", "to", "speed", "radius", "mass", "material"}},
      {ScriptAction::Screenshot, {"frame", "action", "file"}},
      {ScriptAction::Camera, {"frame", "action", "yaw_deg", "pitch_deg", "distance"}},
      {ScriptAction::Pause, {"frame", "action"}},
      {ScriptAction::Resume, {"frame", "action"}},
      {ScriptAction::Step, {"frame", "action"}},
      {ScriptAction::Quit, {"frame", "action"}}};
  ViewerScript script;
  const auto& events = doc["events"];
  for (size_t i = 0; i < events.size(); ++i) {
    const std::string where = "events[" + std::to_string(i) + "]";
    const auto& e = events[i];
    if (!e.is_object()) return scriptError(source, where, "not an object");
    if (!e.contains("action") || !e["action"].is_string()) return scriptError(source, where + ".action", "missing or not a string");
    const std::string name = e["action"].get<std::string>();
    const auto found = std::find_if(actions.begin(), actions.end(), [&](const auto& a) { return a.first == name; });
    if (found == actions.end()) return scriptError(source, where + ".action", "unknown action \"" + name + "\"");
    ScriptEvent ev;
    ev.action = found->second;
    if (auto key = findUnknownKey(e, allowed.at(ev.action))) {
      return scriptError(source, where, unknownKeyMessage(*key) + " for " + name);
    }
    if (!e.contains("frame") || !e["frame"].is_number_integer()) return scriptError(source, where + ".frame", "missing or not an integer");
    ev.frame = e["frame"].get<int64_t>();
    if (ev.frame < 0) return makeError(ErrorCode::InvalidArgument, "script " + std::string(source) + ": " + where + ".frame must be ≥ 0");
    try {
      if (ev.action == ScriptAction::Throw) {
        if (!e.contains("from") || !e.contains("to")) return scriptError(source, where, "a throw needs \"from\" and \"to\"");
        auto from = vector3(e, "from", source, where);
        if (!from) return from.error();
        auto to = vector3(e, "to", source, where);
        if (!to) return to.error();
        ev.from = from.value();
        ev.to = to.value();
        if ((ev.to - ev.from).norm() == 0.0) return makeError(ErrorCode::InvalidArgument, "script " + std::string(source) + ": " + where + ": \"from\" equals \"to\"");
        for (auto [key, out] : {std::pair{"speed", &ev.speedMps}, std::pair{"radius", &ev.radiusM}, std::pair{"mass", &ev.massKg}}) {
          if (!e.contains(key)) continue;
          auto x = number(e, key, source, where);
          if (!x) return x.error();
          if (!(x.value() > 0.0)) return makeError(ErrorCode::InvalidArgument, "script " + std::string(source) + ": " + where + "." + key + " must be > 0");
          *out = x.value();
        }
        if (e.contains("material")) {
          if (!e["material"].is_string()) return scriptError(source, where + ".material", "must be a string");
          ev.material = e["material"].get<std::string>();
        }
        if (auto m = materialPreset(ev.material); !m) return Error{ErrorCode::UnknownMaterial, "script " + std::string(source) + ": " + where + ": " + m.error().message};
      } else if (ev.action == ScriptAction::Screenshot) {
        if (!e.contains("file") || !e["file"].is_string()) return scriptError(source, where + ".file", "missing or not a string");
        ev.file = e["file"].get<std::string>();
        if (ev.file.empty()) return makeError(ErrorCode::InvalidArgument, "script " + std::string(source) + ": " + where + ".file is empty");
      } else if (ev.action == ScriptAction::Camera) {
        for (auto [key, out] : {std::pair{"yaw_deg", &ev.yawDeg}, std::pair{"pitch_deg", &ev.pitchDeg}, std::pair{"distance", &ev.distanceM}}) {
          if (!e.contains(key)) continue;
          auto x = number(e, key, source, where);
          if (!x) return x.error();
          *out = x.value();
        }
        if (ev.distanceM && !(*ev.distanceM > 0.0)) return makeError(ErrorCode::InvalidArgument, "script " + std::string(source) + ": " + where + ".distance must be > 0");
        if (ev.pitchDeg && !(std::abs(*ev.pitchDeg) < 90.0)) return makeError(ErrorCode::InvalidArgument, "script " + std::string(source) + ": " + where + ".pitch_deg must be in (−90, 90)");
      }
    } catch (const std::exception& ex) {
      return scriptError(source, where, ex.what());
    }
    script.events.push_back(std::move(ev));
  }
  std::stable_sort(script.events.begin(), script.events.end(), [](const ScriptEvent& a, const ScriptEvent& b) { return a.frame < b.frame; });
  return script;
}

Result<ViewerScript> loadViewerScript(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(ErrorCode::FileNotFound, "script not found: " + path.string());
  std::ostringstream text;
  text << in.rdbuf();
  return parseViewerScript(text.str(), path.filename().string());
}

}  // namespace brittle

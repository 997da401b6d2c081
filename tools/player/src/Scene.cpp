// Scene.cpp — the scene reader: strict JSON (unknown keys refused), key paths in every message.
#include "brittle/player/Scene.h"

#include <cmath>
#include <fstream>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "brittle/core/JsonChecks.h"
#include "brittle/precompute/MaterialLibrary.h"

namespace brittle {
namespace {

using Json = nlohmann::json;

// The first error wins; later reads become no-ops so parsing code stays linear.
class Reader {
 public:
  explicit Reader(std::string source) : mSource(std::move(source)) {}

  bool failed() const { return mError.has_value(); }
  Error error() const { return *mError; }

  void fail(ErrorCode code, const std::string& path, const std::string& what) {
    if (!mError) mError = makeError(code, mSource + ": " + path + ": " + what);
  }

  // Refuses keys outside `allowed`.
  bool object(const Json& j, const std::string& path, std::initializer_list<std::string_view> allowed) {
    if (failed()) return false;
    if (!j.is_object()) {
      fail(ErrorCode::ParseError, path, "expected an object");
      return false;
    }
    if (auto key = findUnknownKey(j, allowed)) {
      fail(ErrorCode::ParseError, join(path, *key), "unknown key");
      return false;
    }
    return true;
  }

  static std::string join(const std::string& path, std::string_view key) {
    return path.empty() ? std::string(key) : path + "." + std::string(key);
  }

  const Json* find(const Json& j, std::string_view key, const std::string& path, bool required) {
    if (failed()) return nullptr;
    auto it = j.find(std::string(key));
    if (it == j.end()) {
      if (required) fail(ErrorCode::ParseError, join(path, key), "missing key");
      return nullptr;
    }
    return &*it;
  }

  void number(const Json& j, std::string_view key, const std::string& path, bool required, double& out) {
    const Json* v = find(j, key, path, required);
    if (!v) return;
    if (!v->is_number()) return fail(ErrorCode::ParseError, join(path, key), "expected a number");
    out = v->get<double>();
    if (!std::isfinite(out)) fail(ErrorCode::InvalidArgument, join(path, key), "must be finite");
  }

  void integer(const Json& j, std::string_view key, const std::string& path, bool required, int64_t& out) {
    const Json* v = find(j, key, path, required);
    if (!v) return;
    if (!v->is_number_integer()) return fail(ErrorCode::ParseError, join(path, key), "expected an integer");
    out = v->get<int64_t>();
  }

  void boolean(const Json& j, std::string_view key, const std::string& path, bool& out) {
    const Json* v = find(j, key, path, false);
    if (!v) return;
    if (!v->is_boolean()) return fail(ErrorCode::ParseError, join(path, key), "expected true or false");
    out = v->get<bool>();
  }

  void string(const Json& j, std::string_view key, const std::string& path, bool required, std::string& out) {
    const Json* v = find(j, key, path, required);
    if (!v) return;
    if (!v->is_string()) return fail(ErrorCode::ParseError, join(path, key), "expected a string");
    out = v->get<std::string>();
  }

  template <int N>
  void vector(const Json& j, std::string_view key, const std::string& path, bool required, Eigen::Matrix<double, N, 1>& out) {
    const Json* v = find(j, key, path, required);
    if (!v) return;
    if (!v->is_array() || v->size() != N) {
      return fail(ErrorCode::ParseError, join(path, key), "expected an array of " + std::to_string(N) + " numbers");
    }
    for (int i = 0; i < N; ++i) {
      if (!(*v)[i].is_number()) {
        return fail(ErrorCode::ParseError, join(path, key), "expected an array of " + std::to_string(N) + " numbers");
      }
      out[i] = (*v)[i].get<double>();
      if (!std::isfinite(out[i])) return fail(ErrorCode::InvalidArgument, join(path, key), "must be finite");
    }
  }

  // { "axis": [x, y, z], "angle_deg": a } or { "quaternion": [w, x, y, z] }.
  void rotation(const Json& j, const std::string& path, Eigen::Quaterniond& out) {
    const Json* r = find(j, "rotation", path, false);
    if (!r) return;
    const std::string p = join(path, "rotation");
    if (!object(*r, p, {"axis", "angle_deg", "quaternion"})) return;
    if (r->contains("quaternion")) {
      if (r->contains("axis") || r->contains("angle_deg")) {
        return fail(ErrorCode::ParseError, p, "give either quaternion or axis and angle_deg, not both");
      }
      Eigen::Vector4d q;
      vector<4>(*r, "quaternion", p, true, q);
      if (failed()) return;
      if (!(q.norm() > 1e-12)) return fail(ErrorCode::InvalidArgument, join(p, "quaternion"), "must not be zero");
      out = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
      return;
    }
    Eigen::Vector3d axis;
    double angleDeg = 0.0;
    vector<3>(*r, "axis", p, true, axis);
    number(*r, "angle_deg", p, true, angleDeg);
    if (failed()) return;
    if (!(axis.norm() > 1e-12)) return fail(ErrorCode::InvalidArgument, join(p, "axis"), "must not be zero");
    out = Eigen::Quaterniond(Eigen::AngleAxisd(angleDeg * std::numbers::pi / 180.0, axis.normalized()));
  }

  void positive(double value, const std::string& path, double max = 1e6) {
    if (!failed() && !(value > 0.0 && value <= max)) {
      fail(ErrorCode::InvalidArgument, path, "must be > 0 and ≤ " + shortNumber(max) + " (got " + shortNumber(value) + ")");
    }
  }

  void material(const std::string& name, const std::string& path) {
    if (failed()) return;
    if (auto m = materialPreset(name); !m) fail(m.error().code, path, m.error().message);
  }

  static std::string shortNumber(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  }

 private:
  std::string mSource;
  std::optional<Error> mError;
};

}  // namespace

Result<Scene> parseScene(std::string_view text, std::string_view sourceName) {
  Json root;
  try {
    root = Json::parse(text.begin(), text.end());
  } catch (const Json::exception& e) {  // syntax, and numbers out of double's range (out_of_range)
    return makeError(ErrorCode::ParseError, std::string(sourceName) + ": invalid JSON: " + e.what());
  }
  Reader in{std::string(sourceName)};
  Scene scene;
  scene.name = std::string(sourceName);
  if (!in.object(root, "", {"name", "gravity", "duration", "time_step", "substeps", "seed", "floor", "objects", "impactors"})) {
    return in.error();
  }
  in.string(root, "name", "", false, scene.name);
  in.vector<3>(root, "gravity", "", false, scene.gravityMps2);
  in.number(root, "duration", "", true, scene.durationS);
  in.number(root, "time_step", "", true, scene.timeStepS);
  int64_t substeps = 1, seed = 1;
  in.integer(root, "substeps", "", false, substeps);
  in.integer(root, "seed", "", false, seed);
  in.positive(scene.durationS, "duration", 600.0);
  in.positive(scene.timeStepS, "time_step", 0.1);
  if (!in.failed() && scene.timeStepS > scene.durationS) in.fail(ErrorCode::InvalidArgument, "time_step", "exceeds the duration");
  if (!in.failed() && scene.durationS / scene.timeStepS > 100000.0) {
    in.fail(ErrorCode::InvalidArgument, "duration", "more than 100000 frames of time_step");
  }
  if (!in.failed() && (substeps < 1 || substeps > 64)) in.fail(ErrorCode::InvalidArgument, "substeps", "must be in [1, 64]");
  if (!in.failed() && seed < 0) in.fail(ErrorCode::InvalidArgument, "seed", "must be ≥ 0");
  scene.substeps = static_cast<int>(substeps);
  scene.seed = static_cast<uint64_t>(seed);

  if (const Json* f = in.find(root, "floor", "", false)) {
    SceneFloor floor;
    if (in.object(*f, "floor", {"height", "material"})) {
      in.number(*f, "height", "floor", false, floor.heightM);
      in.string(*f, "material", "floor", false, floor.material);
      in.material(floor.material, "floor.material");
    }
    scene.floor = floor;
  }

  if (const Json* objects = in.find(root, "objects", "", true)) {
    if (!objects->is_array()) in.fail(ErrorCode::ParseError, "objects", "expected an array");
    for (size_t i = 0; !in.failed() && i < objects->size(); ++i) {
      const Json& o = (*objects)[i];
      const std::string p = "objects[" + std::to_string(i) + "]";
      SceneObject obj;
      if (!in.object(o, p, {"name", "asset", "position", "rotation", "static", "velocity", "angular_velocity"})) break;
      in.string(o, "asset", p, true, obj.asset);
      obj.name = obj.asset;
      in.string(o, "name", p, false, obj.name);
      in.vector<3>(o, "position", p, true, obj.positionWorldM);
      in.rotation(o, p, obj.rotation);
      in.boolean(o, "static", p, obj.isStatic);
      in.vector<3>(o, "velocity", p, false, obj.velocityMps);
      in.vector<3>(o, "angular_velocity", p, false, obj.angularVelocityRadPerS);
      if (!in.failed() && obj.asset.empty()) in.fail(ErrorCode::InvalidArgument, p + ".asset", "must not be empty");
      scene.objects.push_back(std::move(obj));
    }
  }

  if (const Json* impactors = in.find(root, "impactors", "", false)) {
    if (!impactors->is_array()) in.fail(ErrorCode::ParseError, "impactors", "expected an array");
    for (size_t i = 0; !in.failed() && i < impactors->size(); ++i) {
      const Json& o = (*impactors)[i];
      const std::string p = "impactors[" + std::to_string(i) + "]";
      RigidImpactor imp;
      imp.name = "impactor-" + std::to_string(i);
      if (!in.object(o, p, {"name", "shape", "radius", "half_extents", "mass", "material", "position", "rotation", "velocity",
                            "angular_velocity"})) {
        break;
      }
      std::string shape;
      in.string(o, "name", p, false, imp.name);
      in.string(o, "shape", p, true, shape);
      if (!in.failed()) {
        if (shape == "sphere") {
          imp.shape = ImpactorShape::Sphere;
          if (o.contains("half_extents")) in.fail(ErrorCode::ParseError, p + ".half_extents", "not a key of a sphere");
          in.number(o, "radius", p, true, imp.radiusM);
          in.positive(imp.radiusM, p + ".radius", 100.0);
        } else if (shape == "box") {
          imp.shape = ImpactorShape::Box;
          if (o.contains("radius")) in.fail(ErrorCode::ParseError, p + ".radius", "not a key of a box");
          in.vector<3>(o, "half_extents", p, true, imp.halfExtentsM);
          for (int k = 0; k < 3; ++k) in.positive(imp.halfExtentsM[k], p + ".half_extents", 100.0);
        } else {
          in.fail(ErrorCode::ParseError, p + ".shape", "expected \"sphere\" or \"box\", got \"" + shape + "\"");
        }
      }
      in.number(o, "mass", p, true, imp.massKg);
      in.positive(imp.massKg, p + ".mass", 1e6);
      in.string(o, "material", p, false, imp.material);
      in.material(imp.material, p + ".material");
      in.vector<3>(o, "position", p, true, imp.positionWorldM);
      in.rotation(o, p, imp.rotation);
      in.vector<3>(o, "velocity", p, false, imp.velocityMps);
      in.vector<3>(o, "angular_velocity", p, false, imp.angularVelocityRadPerS);
      scene.impactors.push_back(std::move(imp));
    }
  }
  if (!in.failed() && scene.objects.empty() && scene.impactors.empty()) {
    in.fail(ErrorCode::InvalidArgument, "objects", "the scene has no objects and no impactors");
  }
  if (in.failed()) return in.error();
  return scene;
}

Result<Scene> loadScene(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return makeError(ErrorCode::FileNotFound, "cannot open scene file " + path.string());
  std::ostringstream text;
  text << file.rdbuf();
  auto scene = parseScene(text.str(), path.filename().string());
  if (!scene) return scene;
  // The file stem names the scene unless the file says otherwise.
  if (scene.value().name == path.filename().string()) scene.value().name = path.stem().string();
  return scene;
}

}  // namespace brittle

#include "brittle/precompute/BaseShapes.h"

#include "brittle/core/JsonChecks.h"
#include "brittle/descriptors/MeshRefinement.h"
#include "brittle/precompute/MeshIO.h"
#include "brittle/precompute/MeshValidation.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>
#include <set>

namespace brittle {
namespace {

struct Builder {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;
  int add(const Eigen::Vector3d& p) {
    vertices.push_back(p);
    return static_cast<int>(vertices.size()) - 1;
  }
  void tri(int a, int b, int c) { faces.emplace_back(a, b, c); }
  void quad(int a, int b, int c, int d) {  // counter-clockwise a, b, c, d
    tri(a, b, c);
    tri(a, c, d);
  }
  TriangleMesh mesh() const {
    TriangleMesh m;
    m.vertices.resize(static_cast<Eigen::Index>(vertices.size()), 3);
    m.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
    for (size_t i = 0; i < vertices.size(); ++i) m.vertices.row(static_cast<Eigen::Index>(i)) = vertices[i].transpose();
    for (size_t i = 0; i < faces.size(); ++i) m.faces.row(static_cast<Eigen::Index>(i)) = faces[i].transpose();
    return m;
  }
};

TriangleMesh box(const Eigen::Vector3d& size) {
  Builder b;
  const Eigen::Vector3d h = 0.5 * size;
  for (int i = 0; i < 8; ++i) b.add({(i & 1 ? h.x() : -h.x()), (i & 2 ? h.y() : -h.y()), (i & 4 ? h.z() : -h.z())});
  b.quad(0, 2, 3, 1);  // z−
  b.quad(4, 5, 7, 6);  // z+
  b.quad(0, 1, 5, 4);  // y−
  b.quad(2, 6, 7, 3);  // y+
  b.quad(0, 4, 6, 2);  // x−
  b.quad(1, 3, 7, 5);  // x+
  return b.mesh();
}

// Rod (a ring of n points at each end) or cone (a ring at z = −L/2, the apex at z = +L/2), both
// on the inscribed regular n-gon, with fan caps around a centre vertex.
TriangleMesh lathe(const Eigen::Vector3d& size, int n, bool cone) {
  Builder b;
  const double rx = 0.5 * size.x(), ry = 0.5 * size.y(), hz = 0.5 * size.z();
  std::vector<int> bottom, top;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * std::numbers::pi * i / n;
    bottom.push_back(b.add({rx * std::cos(a), ry * std::sin(a), -hz}));
  }
  const int bottomCentre = b.add({0.0, 0.0, -hz});
  if (cone) {
    const int apex = b.add({0.0, 0.0, hz});
    for (int i = 0; i < n; ++i) b.tri(bottom[i], bottom[(i + 1) % n], apex);
  } else {
    for (int i = 0; i < n; ++i) {
      const double a = 2.0 * std::numbers::pi * i / n;
      top.push_back(b.add({rx * std::cos(a), ry * std::sin(a), hz}));
    }
    const int topCentre = b.add({0.0, 0.0, hz});
    for (int i = 0; i < n; ++i) {
      const int j = (i + 1) % n;
      b.quad(bottom[i], bottom[j], top[j], top[i]);
      b.tri(top[i], top[j], topCentre);
    }
  }
  for (int i = 0; i < n; ++i) b.tri(bottom[(i + 1) % n], bottom[i], bottomCentre);
  return b.mesh();
}

// Right-angled triangle (0,0), (a,0), (0,c) in x–z, extruded along y; centred on its bounding box.
TriangleMesh wedge(const Eigen::Vector3d& size) {
  Builder b;
  const double a = size.x(), w = size.y(), c = size.z();
  const Eigen::Vector3d o(-0.5 * a, -0.5 * w, -0.5 * c);
  const int p0 = b.add(o + Eigen::Vector3d(0, 0, 0)), p1 = b.add(o + Eigen::Vector3d(a, 0, 0)),
            p2 = b.add(o + Eigen::Vector3d(0, 0, c));
  const int q0 = b.add(o + Eigen::Vector3d(0, w, 0)), q1 = b.add(o + Eigen::Vector3d(a, w, 0)),
            q2 = b.add(o + Eigen::Vector3d(0, w, c));
  b.tri(p0, p1, p2);        // y− (normal −y)
  b.tri(q0, q2, q1);        // y+
  b.quad(p0, q0, q1, p1);   // z− bottom
  b.quad(p0, p2, q2, q0);   // x− back
  b.quad(p1, q1, q2, p2);   // hypotenuse
  return b.mesh();
}

}  // namespace

const char* baseShapeKindName(BaseShapeKind kind) {
  switch (kind) {
    case BaseShapeKind::Box: return "box";
    case BaseShapeKind::Plate: return "plate";
    case BaseShapeKind::Rod: return "rod";
    case BaseShapeKind::Sphere: return "sphere";
    case BaseShapeKind::Cone: return "cone";
    case BaseShapeKind::Wedge: return "wedge";
    case BaseShapeKind::Blob: return "blob";
    case BaseShapeKind::Mesh: return "mesh";
  }
  return "unknown";
}

Result<BaseShapeKind> parseBaseShapeKind(std::string_view name) {
  for (BaseShapeKind k : {BaseShapeKind::Box, BaseShapeKind::Plate, BaseShapeKind::Rod, BaseShapeKind::Sphere,
                          BaseShapeKind::Cone, BaseShapeKind::Wedge, BaseShapeKind::Blob, BaseShapeKind::Mesh}) {
    if (name == baseShapeKindName(k)) return k;
  }
  return makeError(ErrorCode::InvalidArgument, "unknown base shape kind '" + std::string(name) +
                                                   "' (expected box, plate, rod, sphere, cone, wedge, blob or mesh)");
}

namespace {

// Everything makeBaseShape can refuse: once a definition passes, building it cannot fail.
Status checkDefinition(const BaseShapeDefinition& d) {
  const std::string label = "base shape '" + d.name + "': ";
  if (d.kind == BaseShapeKind::Mesh) {
    if (d.meshPath.empty()) return makeError(ErrorCode::InvalidArgument, label + "a mesh shape needs a mesh file");
    return Ok{};
  }
  if (!d.sizeM.allFinite() || !(d.sizeM.minCoeff() > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, label + "size must be finite and positive");
  }
  const bool round = d.kind == BaseShapeKind::Rod || d.kind == BaseShapeKind::Cone;
  const bool spherical = d.kind == BaseShapeKind::Sphere || d.kind == BaseShapeKind::Blob;
  if (round && (d.segments < 3 || d.segments > 256)) {
    return makeError(ErrorCode::InvalidArgument, label + "segments must be in [3, 256]");
  }
  if (spherical && (d.segments < 0 || d.segments > 6)) {
    return makeError(ErrorCode::InvalidArgument, label + "segments (subdivision level) must be in [0, 6]");
  }
  if (!std::isfinite(d.noiseAmplitude) || d.noiseAmplitude < 0.0 || d.noiseAmplitude >= 0.9) {
    return makeError(ErrorCode::InvalidArgument, label + "noise must be in [0, 0.9)");
  }
  return Ok{};
}

}  // namespace

Result<TriangleMesh> makeBaseShape(const BaseShapeDefinition& d) {
  if (Status valid = checkDefinition(d); !valid) return valid.error();
  switch (d.kind) {
    case BaseShapeKind::Box:
    case BaseShapeKind::Plate: return box(d.sizeM);
    case BaseShapeKind::Rod: return lathe(d.sizeM, d.segments, false);
    case BaseShapeKind::Cone: return lathe(d.sizeM, d.segments, true);
    case BaseShapeKind::Wedge: return wedge(d.sizeM);
    case BaseShapeKind::Mesh: {
      auto mesh = readSurfaceMesh(d.meshPath);
      if (!mesh) return Error{mesh.error().code, "base shape '" + d.name + "': " + mesh.error().message};
      if (Status valid = validateSurfaceMesh(mesh.value()); !valid) {
        return Error{valid.error().code, "base shape '" + d.name + "': " + valid.error().message};
      }
      TriangleMesh m = std::move(mesh).value();
      const Eigen::RowVector3d centre = 0.5 * (m.vertices.colwise().minCoeff() + m.vertices.colwise().maxCoeff());
      m.vertices.rowwise() -= centre;
      return m;
    }
    case BaseShapeKind::Sphere:
    case BaseShapeKind::Blob: {
      TriangleMesh m = unitIcosphere(d.segments);
      // Blob: see the header. tanh bounds the bump sum smoothly, so r ≥ 1 − noise > 0.
      std::vector<Eigen::Vector3d> centres;
      std::vector<double> weights;
      if (d.kind == BaseShapeKind::Blob && d.noiseAmplitude > 0.0) {
        std::mt19937_64 rng(d.seed);
        auto unit = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
        for (int k = 0; k < 6; ++k) {
          const double z = 2.0 * unit() - 1.0;
          const double phi = 2.0 * std::numbers::pi * unit();
          const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
          centres.emplace_back(s * std::cos(phi), s * std::sin(phi), z);
          weights.push_back(2.0 * unit() - 1.0);
        }
      }
      for (Eigen::Index v = 0; v < m.vertices.rows(); ++v) {
        const Eigen::Vector3d u = m.vertices.row(v).transpose();
        double bump = 0.0;
        for (size_t k = 0; k < centres.size(); ++k) bump += weights[k] * std::exp(-(u - centres[k]).squaredNorm() / 0.5);
        const double r = 1.0 + d.noiseAmplitude * std::tanh(bump);
        m.vertices.row(v) = (0.5 * r * u.cwiseProduct(d.sizeM)).transpose();
      }
      return m;
    }
  }
  return makeError(ErrorCode::InvalidArgument, "base shape '" + d.name + "': unknown kind");
}

Result<std::vector<BaseShapeDefinition>> loadBaseShapes(const std::filesystem::path& jsonPath) {
  std::ifstream in(jsonPath);
  if (!in) return makeError(ErrorCode::FileNotFound, "base shapes file not found: " + jsonPath.string());
  const std::string file = jsonPath.filename().string();
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    return makeError(ErrorCode::ParseError, file + ": not valid JSON: " + e.what());
  }
  if (!doc.is_object() || !doc.contains("shapes") || !doc["shapes"].is_array() || doc["shapes"].empty()) {
    return makeError(ErrorCode::ParseError, file + ": needs a non-empty \"shapes\" array");
  }
  static const std::set<std::string> kKeys = {"name", "kind", "size", "segments", "noise", "seed", "mesh"};
  std::set<std::string> names;
  std::vector<BaseShapeDefinition> out;
  for (size_t i = 0; i < doc["shapes"].size(); ++i) {
    const nlohmann::json& j = doc["shapes"][i];
    const std::string where = file + ", shape " + std::to_string(i);
    auto bad = [&](const std::string& key, const std::string& what) {
      return makeError(ErrorCode::ParseError, where + ": \"" + key + "\" " + what);
    };
    if (!j.is_object()) return makeError(ErrorCode::ParseError, where + ": not an object");
    if (auto key = findUnknownKey(j, kKeys)) return bad(*key, "is not a known key");
    for (const char* key : {"name", "kind"}) {
      if (!j.contains(key)) return bad(key, "is required");
    }
    BaseShapeDefinition d;
    if (!j["name"].is_string() || j["name"].get<std::string>().empty()) return bad("name", "must be a non-empty string");
    d.name = j["name"].get<std::string>();
    if (!names.insert(d.name).second) return bad("name", "repeats '" + d.name + "'");
    if (!j["kind"].is_string()) return bad("kind", "must be a string");
    auto kind = parseBaseShapeKind(j["kind"].get<std::string>());
    if (!kind) return bad("kind", kind.error().message);
    d.kind = kind.value();
    if (d.kind == BaseShapeKind::Mesh) {
      // A surface mesh keeps its own size: the procedural keys do not apply to it.
      for (const char* key : {"size", "segments", "noise", "seed"}) {
        if (j.contains(key)) return bad(key, "does not apply to a mesh shape (it keeps its own size)");
      }
      if (!j.contains("mesh")) return bad("mesh", "is required for a mesh shape");
      if (!j["mesh"].is_string() || j["mesh"].get<std::string>().empty()) return bad("mesh", "must be a non-empty path");
      const std::filesystem::path mesh = j["mesh"].get<std::string>();
      d.meshPath = mesh.is_absolute() ? mesh : jsonPath.parent_path() / mesh;
      if (!std::filesystem::is_regular_file(d.meshPath)) {
        return makeError(ErrorCode::FileNotFound, where + ": mesh file not found: " + d.meshPath.string());
      }
      out.push_back(std::move(d));
      continue;
    }
    if (j.contains("mesh")) return bad("mesh", "applies to mesh shapes only");
    if (!j.contains("size")) return bad("size", "is required");
    const nlohmann::json& size = j["size"];
    if (!size.is_array() || size.size() != 3 || !size[0].is_number() || !size[1].is_number() || !size[2].is_number()) {
      return bad("size", "must be 3 numbers (m)");
    }
    d.sizeM = Eigen::Vector3d(size[0].get<double>(), size[1].get<double>(), size[2].get<double>());
    if (d.kind == BaseShapeKind::Sphere || d.kind == BaseShapeKind::Blob) d.segments = 3;
    if (j.contains("segments")) {
      if (!j["segments"].is_number_integer()) return bad("segments", "must be an integer");
      const auto segments = j["segments"].get<int64_t>();
      if (segments < 0 || segments > 1024) return bad("segments", "is out of range");
      d.segments = static_cast<int>(segments);
    }
    if (j.contains("noise")) {
      if (!j["noise"].is_number()) return bad("noise", "must be a number");
      d.noiseAmplitude = j["noise"].get<double>();
    }
    if (j.contains("seed")) {
      if (!j["seed"].is_number_unsigned()) return bad("seed", "must be an unsigned integer");
      d.seed = j["seed"].get<uint64_t>();
    }
    // Checked, not built: building is what takes time (4 KB of level-6 spheres are 5 million
    // faces), and a definition that checks out always builds.
    if (Status valid = checkDefinition(d); !valid) return makeError(ErrorCode::ParseError, where + ": " + valid.error().message);
    out.push_back(std::move(d));
  }
  return out;
}

}  // namespace brittle

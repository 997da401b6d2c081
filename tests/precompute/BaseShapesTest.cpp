#include "brittle/precompute/BaseShapes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <set>
#include <tuple>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/MeshIO.h"
#include "brittle/precompute/MeshValidation.h"
#include "brittle/testing/Fixtures.h"
#include "SurfaceExpectations.h"

namespace brittle {
namespace {

using testing::expectValid;
using testing::volumeOf;

constexpr double kPi = std::numbers::pi;

// Area of the regular n-gon inscribed in the ellipse of diameters sx, sy.
double inscribedPolygonArea(int n, double sx, double sy) { return 0.5 * n * std::sin(2.0 * kPi / n) * 0.25 * sx * sy; }

BaseShapeDefinition shape(BaseShapeKind kind, Eigen::Vector3d size, int segments) {
  BaseShapeDefinition d;
  d.name = baseShapeKindName(kind);
  d.kind = kind;
  d.sizeM = size;
  d.segments = segments;
  return d;
}

TEST(BaseShapes, ShippedShapesAreValidSolidsWithTheirVolumes) {
  auto shapes = loadBaseShapes(testing::sourceDir() / "assets" / "shapes" / "base-shapes.json");
  ASSERT_TRUE(shapes) << shapes.error().message;
  std::set<BaseShapeKind> kinds;
  for (const BaseShapeDefinition& d : shapes.value()) {
    SCOPED_TRACE(d.name);
    kinds.insert(d.kind);
    auto mesh = makeBaseShape(d);
    ASSERT_TRUE(mesh) << mesh.error().message;
    expectValid(mesh.value());
    const Eigen::Vector3d s = d.sizeM;
    const double v = volumeOf(mesh.value());
    switch (d.kind) {
      case BaseShapeKind::Box:
      case BaseShapeKind::Plate: EXPECT_NEAR(v, s.prod(), 1e-12 * s.prod()); break;
      case BaseShapeKind::Wedge: EXPECT_NEAR(v, 0.5 * s.prod(), 1e-12 * s.prod()); break;
      // Prism and pyramid on the inscribed n-gon: exact up to rounding.
      case BaseShapeKind::Rod:
        EXPECT_NEAR(v, inscribedPolygonArea(d.segments, s.x(), s.y()) * s.z(), 1e-12 * s.prod());
        break;
      case BaseShapeKind::Cone:
        EXPECT_NEAR(v, inscribedPolygonArea(d.segments, s.x(), s.y()) * s.z() / 3.0, 1e-12 * s.prod());
        break;
      // Inscribed in the ellipsoid, so below it; level 3 loses 1.1 %.
      case BaseShapeKind::Sphere:
        EXPECT_LT(v, kPi / 6.0 * s.prod());
        EXPECT_GT(v, 0.985 * kPi / 6.0 * s.prod());
        break;
      case BaseShapeKind::Blob: EXPECT_GT(v, 0.2 * kPi / 6.0 * s.prod()); break;
      case BaseShapeKind::Mesh: ADD_FAILURE() << "no mesh shape is shipped in base-shapes.json"; break;
    }
    // Centred on its bounding box, with the extents of sizeM (blob: radii vary by the noise).
    const Eigen::Vector3d lo = mesh.value().vertices.colwise().minCoeff(), hi = mesh.value().vertices.colwise().maxCoeff();
    if (d.kind == BaseShapeKind::Box || d.kind == BaseShapeKind::Plate || d.kind == BaseShapeKind::Wedge) {
      EXPECT_LT((hi - lo - s).norm(), 1e-12);
      EXPECT_LT((hi + lo).norm(), 1e-12);
    }
  }
  EXPECT_EQ(kinds.size(), 7u);  // every kind is shipped
  for (const BaseShapeDefinition& d : shapes.value()) {
    if (d.name == "box") {
      EXPECT_EQ(d.sizeM, Eigen::Vector3d(1, 0.8, 0.6));
    }
    if (d.name == "plate") {
      EXPECT_EQ(d.sizeM, Eigen::Vector3d(1, 1, 0.1));
    }
    if (d.name == "rod") {
      EXPECT_EQ(d.sizeM, Eigen::Vector3d(0.2, 0.2, 1));
    }
  }
}

TEST(BaseShapes, RoundShapesConvergeToTheirAnalyticVolumes) {
  const Eigen::Vector3d s(0.6, 0.4, 1.2);
  // An ellipsoid of level L has 20·4^L faces and 10·4^L + 2 vertices; the inscribed volume deficit
  // shrinks about 4× per level.
  double previousGap = 1.0;
  for (int level = 0; level <= 5; ++level) {
    SCOPED_TRACE(level);
    const TriangleMesh m = makeBaseShape(shape(BaseShapeKind::Sphere, s, level)).value();
    EXPECT_EQ(m.faces.rows(), 20 * (1 << (2 * level)));
    EXPECT_EQ(m.vertices.rows(), 10 * (1 << (2 * level)) + 2);
    expectValid(m);
    const double gap = 1.0 - volumeOf(m) / (kPi / 6.0 * s.prod());
    EXPECT_GT(gap, 0.0);
    EXPECT_LT(gap, 0.6 * previousGap);
    previousGap = gap;
  }
  EXPECT_LT(previousGap, 1e-3);  // level 5
  // 256 segments: the inscribed polygon's area is n/(2π)·sin(2π/n) ≈ 1 − (2π/n)²/6 = 1 − 1.004e-4
  // of the circle's.
  const TriangleMesh rod = makeBaseShape(shape(BaseShapeKind::Rod, s, 256)).value();
  const TriangleMesh cone = makeBaseShape(shape(BaseShapeKind::Cone, s, 256)).value();
  expectValid(rod);
  expectValid(cone);
  const double polygon = 256.0 / (2.0 * kPi) * std::sin(2.0 * kPi / 256.0);
  EXPECT_NEAR(volumeOf(rod) / (kPi / 4.0 * s.prod()), polygon, 1e-12);
  EXPECT_NEAR(volumeOf(cone) / (kPi / 12.0 * s.prod()), polygon, 1e-12);
  EXPECT_NEAR(polygon, 1.0, 1.1e-4);
  // The smallest round shapes are still valid.
  expectValid(makeBaseShape(shape(BaseShapeKind::Rod, s, 3)).value());
  expectValid(makeBaseShape(shape(BaseShapeKind::Cone, s, 3)).value());
}

TEST(BaseShapes, BlobIsSeededBumpyAndValidForEverySeed) {
  BaseShapeDefinition d = shape(BaseShapeKind::Blob, Eigen::Vector3d(1.0, 0.8, 0.7), 3);
  d.noiseAmplitude = 0.3;
  d.seed = 7;
  const TriangleMesh a = makeBaseShape(d).value(), b = makeBaseShape(d).value();
  EXPECT_EQ(a.vertices, b.vertices);
  expectValid(a);
  const Eigen::VectorXd r = a.vertices.cwiseQuotient(Eigen::RowVector3d(0.5, 0.4, 0.35).replicate(a.vertices.rows(), 1))
                                .rowwise()
                                .norm();
  EXPECT_GT(r.maxCoeff() / r.minCoeff(), 1.2);  // bumpy
  EXPECT_GE(r.minCoeff(), 1.0 - 0.3 - 1e-12);    // r ≥ 1 − noise
  EXPECT_LE(r.maxCoeff(), 1.0 + 0.3 + 1e-12);
  d.noiseAmplitude = 0.89;  // the largest allowed amplitude stays a valid (star-shaped) solid
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    SCOPED_TRACE(seed);
    d.seed = seed;
    const TriangleMesh m = makeBaseShape(d).value();
    EXPECT_NE(m.vertices, a.vertices);
    expectValid(m);
  }
  d.noiseAmplitude = 0.0;  // no noise: the sphere
  BaseShapeDefinition sphere = d;
  sphere.kind = BaseShapeKind::Sphere;
  EXPECT_EQ(makeBaseShape(d).value().vertices, makeBaseShape(sphere).value().vertices);
}

TEST(BaseShapes, KindNamesRoundTrip) {
  for (BaseShapeKind k : {BaseShapeKind::Box, BaseShapeKind::Plate, BaseShapeKind::Rod, BaseShapeKind::Sphere,
                          BaseShapeKind::Cone, BaseShapeKind::Wedge, BaseShapeKind::Blob, BaseShapeKind::Mesh}) {
    auto parsed = parseBaseShapeKind(baseShapeKindName(k));
    ASSERT_TRUE(parsed);
    EXPECT_EQ(parsed.value(), k);
  }
  EXPECT_EQ(parseBaseShapeKind("torus").error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(parseBaseShapeKind("Box").error().code, ErrorCode::InvalidArgument);
}

TEST(BaseShapes, BadDefinitionsGiveTypedErrors) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto code = [](const BaseShapeDefinition& d) { return makeBaseShape(d).error().code; };
  EXPECT_EQ(code(shape(BaseShapeKind::Box, {1, -1, 1}, 24)), ErrorCode::InvalidArgument);
  EXPECT_EQ(code(shape(BaseShapeKind::Plate, {1, 1, 0}, 24)), ErrorCode::InvalidArgument);
  EXPECT_EQ(code(shape(BaseShapeKind::Wedge, {1, nan, 1}, 24)), ErrorCode::InvalidArgument);
  EXPECT_EQ(code(shape(BaseShapeKind::Cone, {1, 1, std::numeric_limits<double>::infinity()}, 24)),
            ErrorCode::InvalidArgument);
  EXPECT_EQ(code(shape(BaseShapeKind::Rod, {1, 1, 1}, 2)), ErrorCode::InvalidArgument);
  EXPECT_EQ(code(shape(BaseShapeKind::Rod, {1, 1, 1}, 257)), ErrorCode::InvalidArgument);
  EXPECT_EQ(code(shape(BaseShapeKind::Sphere, {1, 1, 1}, 24)), ErrorCode::InvalidArgument);  // level 24
  EXPECT_EQ(code(shape(BaseShapeKind::Sphere, {1, 1, 1}, -1)), ErrorCode::InvalidArgument);
  BaseShapeDefinition blob = shape(BaseShapeKind::Blob, {1, 1, 1}, 3);
  blob.noiseAmplitude = 0.9;
  EXPECT_EQ(code(blob), ErrorCode::InvalidArgument);
  blob.noiseAmplitude = -0.1;
  EXPECT_EQ(code(blob), ErrorCode::InvalidArgument);
  blob.noiseAmplitude = nan;
  EXPECT_EQ(code(blob), ErrorCode::InvalidArgument);
}

TEST(BaseShapes, BadFilesGiveTypedErrorsNamingShapeAndKey) {
  const auto dir = testing::makeTempDir("shapes");
  EXPECT_EQ(loadBaseShapes(dir / "missing.json").error().code, ErrorCode::FileNotFound);
  auto load = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return loadBaseShapes(dir / name);
  };
  const std::string box = R"({"name": "a", "kind": "box", "size": [1, 1, 1]})";
  auto ok = load("ok.json", R"({"shapes": [)" + box + R"(, {"name": "s", "kind": "sphere", "size": [1, 1, 1]}]})");
  ASSERT_TRUE(ok) << ok.error().message;
  EXPECT_EQ(ok.value()[1].segments, 3);  // sphere default level
  EXPECT_EQ(ok.value()[0].segments, 24);
  // (file body, text the message must contain)
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"shapes": [)", "not valid JSON"},
      {R"({"shape": []})", "\"shapes\""},
      {R"({"shapes": []})", "\"shapes\""},
      {R"({"shapes": [)" + box + R"(, {"name": "b", "kind": "box", "size": [1, 1]}]})", "shape 1: \"size\""},
      {R"({"shapes": [)" + box + R"(, {"name": "b", "kind": "box", "size": "big"}]})", "shape 1: \"size\""},
      {R"({"shapes": [)" + box + R"(, {"name": "b", "kind": "box", "size": [1, 1, 1], "colour": 3}]})",
       "shape 1: \"colour\""},
      {R"({"shapes": [)" + box + R"(, {"name": "b", "size": [1, 1, 1]}]})", "shape 1: \"kind\" is required"},
      {R"({"shapes": [)" + box + R"(, {"name": "b", "kind": "torus", "size": [1, 1, 1]}]})", "shape 1: \"kind\""},
      {R"({"shapes": [)" + box + R"(, {"name": 3, "kind": "box", "size": [1, 1, 1]}]})", "shape 1: \"name\""},
      {R"({"shapes": [)" + box + "," + box + "]}", "shape 1: \"name\" repeats"},
      {R"({"shapes": [)" + box + R"(, {"name": "b", "kind": "rod", "size": [1, 1, 1], "segments": 2.5}]})",
       "shape 1: \"segments\""},
      {R"({"shapes": [)" + box + R"(, {"name": "b", "kind": "blob", "size": [1, 1, 1], "seed": -4}]})",
       "shape 1: \"seed\""},
      {R"({"shapes": [)" + box + R"(, {"name": "b", "kind": "blob", "size": [1, 1, 1], "noise": "x"}]})",
       "shape 1: \"noise\""},
      {R"({"shapes": [)" + box + R"(, {"name": "b", "kind": "blob", "size": [1, 1, 1], "noise": 0.95}]})",
       "shape 1: base shape 'b': noise"},
      {R"({"shapes": [)" + box + R"(, {"name": "b", "kind": "box", "size": [1, 0, 1]}]})", "shape 1: base shape 'b': size"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(cases[i].first);
    auto r = load("case" + std::to_string(i) + ".json", cases[i].first);
    ASSERT_FALSE(r);
    EXPECT_EQ(r.error().code, ErrorCode::ParseError);
    EXPECT_NE(r.error().message.find(cases[i].second), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find("case" + std::to_string(i) + ".json"), std::string::npos) << r.error().message;
  }
}

TEST(BaseShapes, MeshShapesAreTheirFilesCentredAtTheirOwnSize) {
  // The default objects as base shapes (assets/shapes/default-objects.json): a database of their
  // own pieces. Each is its file's solid, moved to centre its bounding box: the same volume and
  // extents, and valid.
  auto shapes = loadBaseShapes(testing::sourceDir() / "assets" / "shapes" / "default-objects.json");
  ASSERT_TRUE(shapes) << shapes.error().message;
  ASSERT_EQ(shapes.value().size(), 4u);
  for (const BaseShapeDefinition& d : shapes.value()) {
    SCOPED_TRACE(d.name);
    EXPECT_EQ(d.kind, BaseShapeKind::Mesh);
    EXPECT_TRUE(d.meshPath.is_absolute() || d.meshPath.has_parent_path());
    auto mesh = makeBaseShape(d);
    ASSERT_TRUE(mesh) << mesh.error().message;
    expectValid(mesh.value());
    const TriangleMesh file = readSurfaceMesh(d.meshPath).value();
    const double v = volumeOf(file);
    EXPECT_GT(v, 0.0);
    EXPECT_NEAR(volumeOf(mesh.value()), v, 1e-12 * v);
    const Eigen::Vector3d lo = mesh.value().vertices.colwise().minCoeff(), hi = mesh.value().vertices.colwise().maxCoeff();
    const Eigen::Vector3d extent = file.vertices.colwise().maxCoeff() - file.vertices.colwise().minCoeff();
    EXPECT_LT((hi - lo - extent).norm(), 1e-12 * extent.norm());
    EXPECT_LT((hi + lo).norm(), 1e-12 * extent.norm());
  }
}

TEST(BaseShapes, BadMeshShapesGiveTypedErrors) {
  const auto dir = testing::makeTempDir("mesh-shapes");
  const std::filesystem::path plate = testing::sourceDir() / "assets" / "meshes" / "plate.off";
  auto load = [&](const std::string& name, const std::string& shape) {
    std::ofstream(dir / name) << R"({"shapes": [)" + shape + "]}";
    return loadBaseShapes(dir / name);
  };
  const std::string path = "\"" + plate.generic_string() + "\"";
  ASSERT_TRUE(load("ok.json", R"({"name": "p", "kind": "mesh", "mesh": )" + path + "}"));
  // (shape, code, text the message must contain)
  const std::vector<std::tuple<std::string, ErrorCode, std::string>> cases = {
      {R"({"name": "p", "kind": "mesh"})", ErrorCode::ParseError, "\"mesh\" is required"},
      {R"({"name": "p", "kind": "mesh", "mesh": 3})", ErrorCode::ParseError, "\"mesh\" must be"},
      {R"({"name": "p", "kind": "mesh", "mesh": )" + path + R"(, "size": [1, 1, 1]})", ErrorCode::ParseError,
       "\"size\" does not apply"},
      {R"({"name": "p", "kind": "box", "size": [1, 1, 1], "mesh": )" + path + "}", ErrorCode::ParseError,
       "\"mesh\" applies to mesh shapes only"},
      {R"({"name": "p", "kind": "mesh", "mesh": "nowhere.off"})", ErrorCode::FileNotFound, "nowhere.off"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(std::get<0>(cases[i]));
    auto r = load("case" + std::to_string(i) + ".json", std::get<0>(cases[i]));
    ASSERT_FALSE(r);
    EXPECT_EQ(r.error().code, std::get<1>(cases[i]));
    EXPECT_NE(r.error().message.find(std::get<2>(cases[i])), std::string::npos) << r.error().message;
  }
  // A file that is there but not a closed solid: refused when the shape is built, naming it.
  TriangleMesh open = readSurfaceMesh(plate).value();
  open.faces.conservativeResize(open.faces.rows() - 1, 3);
  ASSERT_TRUE(writeSurfaceMesh(open, dir / "open.off"));
  auto shapes = load("open.json", R"({"name": "holed", "kind": "mesh", "mesh": "open.off"})");
  ASSERT_TRUE(shapes) << shapes.error().message;
  auto built = makeBaseShape(shapes.value()[0]);
  ASSERT_FALSE(built);
  EXPECT_EQ(built.error().code, ErrorCode::OpenMesh);
  EXPECT_NE(built.error().message.find("base shape 'holed'"), std::string::npos) << built.error().message;
  BaseShapeDefinition none;
  none.name = "none";
  none.kind = BaseShapeKind::Mesh;
  EXPECT_EQ(makeBaseShape(none).error().code, ErrorCode::InvalidArgument);
}

TEST(BaseShapes, FineShapesAreCheckedNotBuiltWhenLoaded) {
  // 66 level-6 spheres fit in 4 KB, the size of a fuzz input, and the loader built all 5.4 million
  // faces to check them: seconds per file, past the fuzz timeout under the sanitizers. It now
  // checks the parameters only (tests/fuzz/corpus keeps this input); each definition still builds.
  const auto dir = testing::makeTempDir("shapes");
  std::string text = R"({"shapes": [)";
  for (int i = 0; i < 66; ++i) {
    text += std::string(i ? "," : "") + R"({"name": "s)" + std::to_string(i) +
            R"(", "kind": "sphere", "size": [1, 1, 1], "segments": 6})";
  }
  std::ofstream(dir / "fine.json") << text + "]}";
  const auto shapes = loadBaseShapes(dir / "fine.json");
  ASSERT_TRUE(shapes.ok()) << shapes.error().message;
  ASSERT_EQ(shapes.value().size(), 66u);
  EXPECT_EQ(shapes.value().back().segments, 6);
  const auto mesh = makeBaseShape(shapes.value().back());
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(mesh.value().faces.rows(), 20 * 4096);
}

}  // namespace
}  // namespace brittle

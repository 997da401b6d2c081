#include "brittle/precompute/MeshIO.h"

#include <CGAL/IO/OBJ.h>
#include <CGAL/IO/OFF.h>  // writing only
#include <CGAL/IO/PLY.h>  // writing only
#include <CGAL/IO/STL.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "MeshReaders.h"

namespace brittle {
namespace {

using detail::PolygonSoup;
using IoKernel = CGAL::Simple_cartesian<double>;
using IoPoint = IoKernel::Point_3;

std::string lowerExtension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// CGAL's OBJ reader stops at a "nan" or "inf" token without saying why; find the first one so
// the error can name it. Returns the 1-based line, or 0 if the file has none.
size_t findNonFiniteToken(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line;
  for (size_t lineNo = 1; std::getline(in, line); ++lineNo) {
    if (!line.empty() && line[0] == '#') continue;
    std::istringstream tokens(line);
    std::string token;
    while (tokens >> token) {
      std::string lower = token;
      std::transform(lower.begin(), lower.end(), lower.begin(),
                     [](unsigned char c) { return std::tolower(c); });
      if (!lower.empty() && (lower[0] == '-' || lower[0] == '+')) lower.erase(0, 1);
      // Whole numeric tokens only ("nan", "nan(0x1)", "inf", "infinity"), not names like "banana".
      if (lower == "nan" || lower.rfind("nan(", 0) == 0 || lower == "inf" || lower == "infinity") {
        return lineNo;
      }
    }
  }
  return 0;
}

// OBJ and STL, parsed by CGAL.
Result<PolygonSoup> readWithCgal(const std::filesystem::path& path, const std::string& ext) {
  PolygonSoup soup;
  std::vector<IoPoint> points;
  bool ok = false;
  try {
    const std::string name = path.string();
    if (ext == "obj") ok = CGAL::IO::read_OBJ(name, points, soup.polygons);
    if (ext == "stl") {
      std::vector<std::array<std::size_t, 3>> triangles;
      ok = CGAL::IO::read_STL(name, points, triangles);
      for (const auto& t : triangles) soup.polygons.push_back({t[0], t[1], t[2]});
    }
  } catch (const std::exception&) {
    ok = false;
  }
  if (!ok) {
    // Binary STL cannot hold a text token; for OBJ, say which line broke parsing.
    if (const size_t line = ext == "stl" ? 0 : findNonFiniteToken(path); line != 0) {
      return makeError(ErrorCode::NonFiniteValue, "non-finite coordinate in " + path.filename().string() +
                                                      " at line " + std::to_string(line));
    }
    return makeError(ErrorCode::ParseError, "cannot parse " + ext + " mesh " + path.filename().string());
  }
  soup.points.reserve(points.size());
  for (const IoPoint& p : points) soup.points.push_back({p.x(), p.y(), p.z()});
  return soup;
}

}  // namespace

Result<TriangleMesh> readSurfaceMesh(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return makeError(ErrorCode::FileNotFound, "mesh file not found: " + path.string());
  }
  const std::string ext = lowerExtension(path);
  if (ext != "off" && ext != "obj" && ext != "ply" && ext != "stl") {
    return makeError(ErrorCode::UnknownFormat, "unknown mesh format '" + ext + "' for " +
                                                   path.filename().string() +
                                                   " (supported: off, obj, ply, stl)");
  }
  if (std::filesystem::file_size(path, ec) == 0) {
    return makeError(ErrorCode::EmptyMesh, "mesh file is empty: " + path.filename().string());
  }

  PolygonSoup soup;
  if (ext == "off" || ext == "ply") {
    auto read = ext == "off" ? detail::readOff(path) : detail::readPly(path);
    if (!read) return read.error();
    soup = std::move(read).value();
  } else if (Result<PolygonSoup> read = readWithCgal(path, ext); read.ok()) {
    soup = std::move(read).value();
  } else {
    return read.error();
  }
  const std::vector<std::array<double, 3>>& points = soup.points;
  const std::vector<std::vector<std::size_t>>& polygons = soup.polygons;
  if (points.empty() || polygons.empty()) {
    return makeError(ErrorCode::EmptyMesh, "mesh has no " + std::string(points.empty() ? "vertices" : "faces") +
                                               ": " + path.filename().string());
  }

  TriangleMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    mesh.vertices.row(row) << points[i][0], points[i][1], points[i][2];
    if (!mesh.vertices.row(row).allFinite()) {
      return makeError(ErrorCode::NonFiniteValue, "non-finite coordinate at vertex " +
                                                      std::to_string(i) + " of " +
                                                      path.filename().string());
    }
  }
  std::vector<std::array<int32_t, 3>> triangles;
  for (size_t f = 0; f < polygons.size(); ++f) {
    const auto& poly = polygons[f];
    if (poly.size() < 3) {
      return makeError(ErrorCode::ParseError,
                       "face " + std::to_string(f) + " has fewer than 3 corners in " + path.filename().string());
    }
    for (size_t index : poly) {
      if (index >= points.size()) {
        return makeError(ErrorCode::ParseError, "face " + std::to_string(f) + " refers to vertex " +
                                                    std::to_string(index) + " of " +
                                                    std::to_string(points.size()));
      }
    }
    for (size_t k = 1; k + 1 < poly.size(); ++k) {
      triangles.push_back({static_cast<int32_t>(poly[0]), static_cast<int32_t>(poly[k]),
                           static_cast<int32_t>(poly[k + 1])});
    }
  }
  mesh.faces.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (size_t f = 0; f < triangles.size(); ++f) {
    mesh.faces.row(static_cast<Eigen::Index>(f)) << triangles[f][0], triangles[f][1], triangles[f][2];
  }
  return mesh;
}

Status writeSurfaceMesh(const TriangleMesh& mesh, const std::filesystem::path& path) {
  const std::string ext = lowerExtension(path);
  std::vector<IoPoint> points;
  std::vector<std::array<std::size_t, 3>> polygons;
  for (Eigen::Index i = 0; i < mesh.vertices.rows(); ++i) {
    points.emplace_back(mesh.vertices(i, 0), mesh.vertices(i, 1), mesh.vertices(i, 2));
  }
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
    polygons.push_back({static_cast<std::size_t>(mesh.faces(f, 0)), static_cast<std::size_t>(mesh.faces(f, 1)),
                        static_cast<std::size_t>(mesh.faces(f, 2))});
  }
  bool ok = false;
  const std::string name = path.string();
  const auto precision = CGAL::parameters::stream_precision(17);
  if (ext == "off") ok = CGAL::IO::write_OFF(name, points, polygons, precision);
  else if (ext == "obj") ok = CGAL::IO::write_OBJ(name, points, polygons, precision);
  else if (ext == "ply") ok = CGAL::IO::write_PLY(name, points, polygons, precision);
  else if (ext == "stl") ok = CGAL::IO::write_STL(name, points, polygons, precision);
  else return makeError(ErrorCode::UnknownFormat, "unknown mesh format '" + ext + "'");
  if (!ok) return makeError(ErrorCode::PackIoError, "cannot write mesh " + path.string());
  return Ok{};
}

}  // namespace brittle

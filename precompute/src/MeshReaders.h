// MeshReaders.h — the surface formats brittle reads with its own parsers, OFF and PLY, because
// CGAL 5.5's readers are not safe on bad input (MeshReaders.cpp says how). Private to
// precompute: readSurfaceMesh (MeshIO.h) dispatches here and checks what they return.
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <vector>

#include "brittle/core/Result.h"

namespace brittle::detail {

/// Vertices (x, y, z as read) and polygons (0-based vertex indices). readSurfaceMesh checks the
/// rest: finite coordinates, indices below the vertex count, at least three corners.
struct PolygonSoup {
  std::vector<std::array<double, 3>> points;
  std::vector<std::vector<std::size_t>> polygons;
};

/// Text OFF and its [ST][C][N][4]OFF variants (only the coordinates are read; 4OFF's are
/// homogeneous), one vertex or face per line, "#" comments anywhere; binary OFF is refused.
/// Errors: FileNotFound, ParseError (naming the line), NonFiniteValue.
Result<PolygonSoup> readOff(const std::filesystem::path& path);

/// PLY in every format (ascii, binary little and big endian): "vertex" x, y, z and "face"
/// vertex_indices (or vertex_index); other elements and properties are skipped.
/// Errors: FileNotFound, ParseError.
Result<PolygonSoup> readPly(const std::filesystem::path& path);

}  // namespace brittle::detail

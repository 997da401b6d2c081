// MeshIO.h — reading surface meshes (OFF, OBJ, PLY, STL) into flat triangle arrays.
//
// Parsing is CGAL's (CGAL::IO::read_polygon_soup): the raw soup is kept as it is in the file —
// no silent repair or re-orientation — so that validation (MeshValidation.h) sees what the user
// gave. Polygons with more than three corners are fan-triangulated (exact for convex faces).
#pragma once

#include <filesystem>

#include "brittle/descriptors/MeshTypes.h"
#include "brittle/descriptors/Result.h"

namespace brittle {

/// Reads a surface mesh; the format is chosen by the (case-insensitive) extension.
/// Errors: FileNotFound; UnknownFormat (extension not off/obj/ply/stl); EmptyMesh (empty file or
/// no faces); NonFiniteValue (NaN or infinite coordinate, with the line or vertex); ParseError
/// (malformed file, face index out of range).
Result<TriangleMesh> readSurfaceMesh(const std::filesystem::path& path);

/// Writes a triangle mesh; the format is chosen by the extension (off, obj, ply, stl).
/// Errors: UnknownFormat, PackIoError (cannot write).
Status writeSurfaceMesh(const TriangleMesh& mesh, const std::filesystem::path& path);

}  // namespace brittle

// MeshIO.h — reading surface meshes (OFF, OBJ, PLY, STL) into flat triangle arrays.
//
// OBJ and STL are parsed by CGAL (CGAL::IO::read_polygon_soup); OFF and PLY are parsed here,
// because CGAL 5.5's readers for them are not memory-safe on malformed files. Either way the raw
// soup is kept as it is in the file — no silent repair or re-orientation — so that validation
// (MeshValidation.h) sees what the user gave. Polygons with more than three corners are
// fan-triangulated (exact for convex faces).
//
// OFF: the text format with one vertex or face per line and "#" comments, under the headers OFF,
// COFF, NOFF, STOFF and 4OFF (homogeneous) and their combinations; what follows a vertex's
// coordinates or a face's indices (normals, colours, texture coordinates) is ignored. Binary OFF,
// nOFF and SKEL are refused.
// PLY: ascii and binary of either byte order; x, y, z of the "vertex" element and the integer list
// "vertex_indices" (or "vertex_index") of the "face" element; other elements and properties are
// skipped.
#pragma once

#include <filesystem>

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"

namespace brittle {

/// Reads a surface mesh; the format is chosen by the (case-insensitive) extension.
/// Errors: FileNotFound; UnknownFormat (extension not off/obj/ply/stl); EmptyMesh (empty file or
/// no faces); NonFiniteValue (NaN or infinite coordinate, with the line or vertex); ParseError
/// (malformed file, face index out of range, counts in the header that the file cannot hold).
Result<TriangleMesh> readSurfaceMesh(const std::filesystem::path& path);

/// Writes a triangle mesh; the format is chosen by the extension (off, obj, ply, stl).
/// Errors: UnknownFormat, PackIoError (cannot write).
Status writeSurfaceMesh(const TriangleMesh& mesh, const std::filesystem::path& path);

}  // namespace brittle

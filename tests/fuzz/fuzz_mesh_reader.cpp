// Fuzz target: readSurfaceMesh (MeshIO.h) on OFF, OBJ, PLY and STL files.
//
// Input: one byte that picks the format (its value mod 4: off, obj, ply, stl; the seeds use the
// digits '0' to '3'), then the file's bytes. A mesh that reads must be what the header promises:
// at least one triangle, finite coordinates, every index in range.
#include <array>
#include <cstddef>
#include <cstdint>

#include "FuzzSupport.h"
#include "brittle/precompute/MeshIO.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace brittle;
  if (size < 1) return 0;
  static constexpr std::array<const char*, 4> kExtensions = {"off", "obj", "ply", "stl"};
  const char* ext = kExtensions[data[0] % kExtensions.size()];
  const auto path = fuzz::writeScratchFile(std::string("mesh.") + ext, data + 1, size - 1);

  const Result<TriangleMesh> mesh = readSurfaceMesh(path);
  fuzz::expectDocumentedError(mesh, {ErrorCode::FileNotFound, ErrorCode::UnknownFormat, ErrorCode::EmptyMesh,
                                     ErrorCode::NonFiniteValue, ErrorCode::ParseError});
  if (!mesh.ok()) return 0;
  const TriangleMesh& m = mesh.value();
  if (m.faces.rows() == 0 || m.vertices.rows() == 0) fuzz::finding("a mesh without faces or vertices was read");
  if (!m.vertices.allFinite()) fuzz::finding("a non-finite coordinate was read");
  if (m.faces.minCoeff() < 0 || m.faces.maxCoeff() >= m.vertices.rows()) fuzz::finding("a face index is out of range");
  return 0;
}

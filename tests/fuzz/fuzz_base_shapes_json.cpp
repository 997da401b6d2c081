// Fuzz target: loadBaseShapes (BaseShapes.h) on arbitrary bytes. The procedural definitions it
// returns must build with makeBaseShape, as its header promises; a mesh shape's file is read when
// it is built, so it may still fail then, with a documented error of reading or validating the
// file. The first few are built (a level-6 sphere is 80k faces, and an input can hold dozens).
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "FuzzSupport.h"
#include "brittle/precompute/BaseShapes.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace brittle;
  const auto path = fuzz::writeScratchFile("base-shapes.json", data, size);
  const Result<std::vector<BaseShapeDefinition>> shapes = loadBaseShapes(path);
  fuzz::expectDocumentedError(shapes, {ErrorCode::FileNotFound, ErrorCode::ParseError});
  if (!shapes.ok()) return 0;
  if (shapes.value().empty()) fuzz::finding("an empty list of base shapes was loaded");
  for (size_t i = 0; i < std::min<size_t>(shapes.value().size(), 4); ++i) {
    const BaseShapeDefinition& d = shapes.value()[i];
    const Result<TriangleMesh> built = makeBaseShape(d);
    if (d.kind == BaseShapeKind::Mesh) {
      fuzz::expectDocumentedError(built, {ErrorCode::FileNotFound, ErrorCode::UnknownFormat, ErrorCode::EmptyMesh,
                                          ErrorCode::NonFiniteValue, ErrorCode::ParseError, ErrorCode::DegenerateFace,
                                          ErrorCode::OpenMesh, ErrorCode::NonManifold, ErrorCode::InconsistentOrientation,
                                          ErrorCode::SelfIntersection, ErrorCode::InwardFacing});
      continue;
    }
    if (!built.ok()) fuzz::finding("base shape '" + d.name + "' loads but does not build");
  }
  return 0;
}

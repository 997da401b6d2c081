// SurfaceExpectations.h — what the base-shape and fragment-generator tests check on a surface.
#pragma once

#include <gtest/gtest.h>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/MeshValidation.h"

namespace brittle::testing {

inline double volumeOf(const TriangleMesh& m) { return computeSurfaceMassProperties(m, 1.0).volumeM3; }

/// The surface passes the bake's validator (closed, manifold, oriented, no self-intersection).
inline void expectValid(const TriangleMesh& m) {
  const Status valid = validateSurfaceMesh(m);
  EXPECT_TRUE(valid) << valid.error().message;
}

}  // namespace brittle::testing

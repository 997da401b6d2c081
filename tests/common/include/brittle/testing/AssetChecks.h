// AssetChecks.h — shared GoogleTest assertions on baked assets.
#pragma once

#include <gtest/gtest.h>

#include "brittle/database/ObjectAsset.h"

namespace brittle::testing {

/// Every baked dataset of two assets is bit-identical; only the wall-clock timings may differ.
inline void expectSameBakedData(const ObjectAsset& x, const ObjectAsset& y) {
  EXPECT_EQ(x.tetMesh.nodes, y.tetMesh.nodes);
  EXPECT_EQ(x.tetMesh.tets, y.tetMesh.tets);
  EXPECT_EQ(x.surfaceFaces, y.surfaceFaces);
  EXPECT_EQ(x.modal.modes, y.modal.modes);
  EXPECT_EQ(x.modal.eigenvaluesRad2PerS2, y.modal.eigenvaluesRad2PerS2);
  EXPECT_EQ(x.modal.residuals, y.modal.residuals);
  EXPECT_EQ(x.stressModes, y.stressModes);
  EXPECT_EQ(x.massProperties.inertiaKgM2, y.massProperties.inertiaKgM2);
  EXPECT_EQ(x.quality.minDihedralDeg, y.quality.minDihedralDeg);
  EXPECT_EQ(x.bake.cellSizeM, y.bake.cellSizeM);
  EXPECT_EQ(x.bake.shift, y.bake.shift);
}

}  // namespace brittle::testing

// AssetChecks.h — shared GoogleTest assertions on baked assets.
#pragma once

#include <gtest/gtest.h>

#include "brittle/database/FragmentDatabase.h"
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
  EXPECT_EQ(x.bake.thinStretch, y.bake.thinStretch);
  EXPECT_EQ(x.contactSpreadFraction, y.contactSpreadFraction);
  EXPECT_EQ(x.bake.shift, y.bake.shift);
}

/// Two fragment databases hold the same entries and descriptors bit for bit (timings aside).
inline void expectSameDatabase(const FragmentDatabase& a, const FragmentDatabase& b) {
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.referenceMaterial, b.referenceMaterial);
  ASSERT_EQ(a.entries.size(), b.entries.size());
  for (size_t i = 0; i < a.entries.size(); ++i) {
    SCOPED_TRACE("entry " + std::to_string(i));
    EXPECT_EQ(a.entries[i].asset.name, b.entries[i].asset.name);
    expectSameBakedData(a.entries[i].asset, b.entries[i].asset);
    EXPECT_EQ(a.entries[i].surface.vertices, b.entries[i].surface.vertices);
    EXPECT_EQ(a.entries[i].surface.faces, b.entries[i].surface.faces);
    EXPECT_EQ(a.entries[i].seed, b.entries[i].seed);
    EXPECT_EQ(a.entries[i].cut, b.entries[i].cut);
    EXPECT_EQ(a.entries[i].baseVolumeFraction, b.entries[i].baseVolumeFraction);
  }
  for (size_t k = 0; k < a.descriptors.size(); ++k) EXPECT_EQ(a.descriptors[k], b.descriptors[k]);
}

}  // namespace brittle::testing

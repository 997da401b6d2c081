// BakePipeline.h — surface mesh + material → checked modal asset, and a manifest of objects →
// pack. Stages: read → (repair) → validate → tetrahedralise → assemble K, M → modal basis →
// stress modes → mass properties. Every stage's failure is a typed error; nothing is written
// here (writing is writePack's job, which is atomic).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "brittle/database/Pack.h"
#include "brittle/runtime/FemAssembly.h"
#include "brittle/precompute/MeshRepair.h"
#include "brittle/precompute/ModalAnalysis.h"
#include "brittle/precompute/Progress.h"
#include "brittle/precompute/TetMesher.h"

namespace brittle {

struct ObjectBakeSettings {
  std::string name;                  ///< empty means the mesh file's stem
  std::filesystem::path meshPath;
  std::string sourceName;            ///< recorded as the source; empty means meshPath's file name
  Material material;
  bool repair = false;               ///< rebuild the surface through an OpenVDB level set first
  RepairSettings repairSettings;
  TetMeshSettings tetMesh;
  /// The finite element (ObjectAsset.h): P2 for thin parts, which lock in bending with P1.
  ElementOrder elementOrder = ElementOrder::P1;
  FemSettings fem;
  ModalSettings modal;               ///< shiftRad2PerS2 == 0 means defaultShift()
  /// ObjectAsset::contactSpreadFraction: the object's own floor on the contact load's spread, a
  /// fraction of its bounding-box diagonal that its mesh resolves (0: the World's setting alone).
  double contactSpreadFraction = 0.0;
  /// Bake an elimination order for the runtime's factorisation (FillOrdering.h). Database entries
  /// go without: the pack does not store theirs, and a database bakes thousands of them.
  bool fillOrdering = true;
};

/// What the bake measured beyond the asset itself.
struct ObjectBakeReport {
  RepairReport repair;
  double surfaceVolumeM3 = 0.0;       ///< exact volume of the validated input surface
  double tetVolumeRelativeError = 0.0;///< (V_tets − V_surface) / V_surface
  ModalSolveStats modalStats;
  int meshingRuns = 0;                            ///< final Mesh_3 runs (TetMeshResult)
  std::vector<MeshingAdjustment> meshingAdjustments;  ///< what the tet mesher changed, and why
};

/// Bakes one object. Errors: those of readSurfaceMesh, repairSurfaceMesh, validateSurfaceMesh,
/// tetrahedralize, assembleFem, computeModes (each says the object's name), InvalidMaterial.
Result<ObjectAsset> bakeObject(const ObjectBakeSettings& settings, ProgressSink* progress = nullptr,
                               ObjectBakeReport* report = nullptr);

/// Bakes an in-memory surface (settings.meshPath is ignored; settings.name must be set).
/// Errors: as bakeObject, without the reading ones; InvalidArgument for an empty name.
Result<ObjectAsset> bakeSurface(TriangleMesh surface, const ObjectBakeSettings& settings,
                                ProgressSink* progress = nullptr, ObjectBakeReport* report = nullptr);

/// Bakes every object in order into one pack; materials are stored once per name.
/// Errors: the first object's error; InvalidArgument on duplicate object names, or on two
/// different materials with the same name.
Result<Pack> bakePack(const std::vector<ObjectBakeSettings>& objects, ProgressSink* progress = nullptr,
                      std::vector<ObjectBakeReport>* reports = nullptr);

}  // namespace brittle

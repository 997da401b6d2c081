// MassProperties.h — exact mass properties of solids bounded by closed triangle meshes or made of
// linear tetrahedra.
//
// Both use the same exact formula: the solid is a sum of signed tetrahedra, and for a tetrahedron
// with vertices p0..p3 and volume V,  ∫ x xᵀ dV = V/20 · (Σ pₖpₖᵀ + s sᵀ), s = Σ pₖ.
// For a closed surface the tetrahedra are (r, a, b, c) for every face (a, b, c) and a reference
// point r (the divergence theorem in discrete form), so the result is exact for the polyhedron.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "brittle/core/MeshTypes.h"
#include "brittle/descriptors/VolumeMoments.h"

namespace brittle {

struct MassProperties {
  double volumeM3 = 0.0;
  double massKg = 0.0;
  Eigen::Vector3d centerOfMassM = Eigen::Vector3d::Zero();
  /// Inertia tensor about the centre of mass, in the mesh's axes (kg·m²).
  Eigen::Matrix3d inertiaKgM2 = Eigen::Matrix3d::Zero();
  /// Second moment of volume about the centre of mass, ∫(x−c)(x−c)ᵀ dV (m⁵). Density-free.
  Eigen::Matrix3d secondMomentM5 = Eigen::Matrix3d::Zero();
};

/// Mass properties of the solid enclosed by a closed, outward-oriented triangle mesh.
/// densityKgPerM3 scales mass and inertia only. An inward mesh gives a negative volume; an open
/// mesh gives a meaningless one (validate first).
MassProperties computeSurfaceMassProperties(const TriangleMesh& surface, double densityKgPerM3);

/// Mass properties of a tetrahedral mesh (sum over tets, each with its signed volume).
MassProperties computeTetMassProperties(const TetMesh& mesh, double densityKgPerM3);

/// Mass properties from volume moments (order ≥ 2) about originM (in the mesh's frame, m), e.g.
/// summed with addTetVolumeMoments: the same formulas as the two above, without a pass over a mesh.
MassProperties massPropertiesFromMoments(const VolumeMoments& moments, const Eigen::Vector3d& originM,
                                         double densityKgPerM3);
/// The same from the first monomialCount(2) = 10 values of VolumeMoments::values (graded order).
MassProperties massPropertiesFromMoments(const double* values, const Eigen::Vector3d& originM, double densityKgPerM3);

/// Signed volume of tetrahedron (a, b, c, d): positive when (b−a)·((c−a)×(d−a)) > 0.
inline double signedTetVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

}  // namespace brittle

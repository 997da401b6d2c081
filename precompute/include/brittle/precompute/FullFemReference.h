// FullFemReference.h — the ground truth for impact stresses: the same tet mesh with all its
// degrees of freedom, integrated in time by implicit Newmark (average acceleration, γ = ½, β = ¼:
// unconditionally stable, no numerical damping) with Rayleigh damping C = αM + βK, under the
// same Hertz pulse and load pattern as the runtime. Slow by design (one sparse factorisation, then
// one solve and one pass over the elements per step); it is the reference the modal model with
// and without its static correction is measured against.
#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "brittle/database/Material.h"
#include "brittle/core/MeshTypes.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/core/Result.h"
#include "brittle/runtime/HertzContact.h"

namespace brittle {

struct FullFemSettings {
  int stepsPerContact = 100;   ///< time step = t_c / stepsPerContact
  double durationS = 0.0;      ///< simulated time; ≤ 0: t_c plus as long again as `extraS`
  double extraS = 0.0;         ///< with durationS ≤ 0: time simulated after the contact
  ElementOrder elementOrder = ElementOrder::P1;  ///< the object's (ObjectAsset::elementOrder)
};

struct FullFemResult {
  double peakPrincipalPa = 0.0;  ///< largest principal stress over elements' stress points and steps
  int32_t peakElement = -1;
  double peakTimeS = 0.0;
  int64_t steps = 0;
};

/// Solves the free body under F(t)·f, f = Σ w_i d at node i (weights summing to 1, unit direction d).
/// Errors: those of assembleFem, FactorizationFailed, InvalidArgument (weights, settings).
Result<FullFemResult> solveFullFemImpact(const TetMesh& mesh, const Material& material,
                                         const std::vector<std::pair<int32_t, double>>& weights,
                                         const Eigen::Vector3d& direction, const HertzContact& contact,
                                         const FullFemSettings& settings);

}  // namespace brittle

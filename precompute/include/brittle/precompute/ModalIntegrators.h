// ModalIntegrators.h — the textbook one-step schemes the runtime's exact modal stepping
// (brittle/runtime/ModalResponse.h) is measured against (`brittle bench integrators`). Offline
// only: the runtime steps exactly and never uses these.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "brittle/core/Result.h"

namespace brittle {

/// How the modal response is stepped: each is the textbook one-step map for q̈ + 2ζωq̇ + ω²q = p.
///   ExplicitEuler:   q₁ = q₀ + h q̇₀,  q̇₁ = q̇₀ + h (p₀ − 2ζω q̇₀ − ω² q₀). Unstable for every
///                    h when ζ = 0 (|amplification| = √(1 + (ωh)²)).
///   SymplecticEuler: q̇₁ as above, then q₁ = q₀ + h q̇₁. Stable for ωh ≤ 2 (undamped), first order.
///   ImplicitEuler:   q₁ = q₀ + h q̇₁,  q̇₁ = q̇₀ + h (p₁ − 2ζω q̇₁ − ω² q₁). Stable for every h
///                    but damps: |amplification| = 1/√(1 + (ωh)²) when ζ = 0.
///   Exact:           exactStepMatrix, the runtime's (|amplification| = e^(−ζωh) ≤ 1 for every h).
enum class ModalIntegrator { Exact, ExplicitEuler, SymplecticEuler, ImplicitEuler };

/// "exact", "explicit-euler", "symplectic-euler", "implicit-euler".
const char* modalIntegratorName(ModalIntegrator integrator);

/// The one-step map [q₁; q̇₁] = P · [q₀; q̇₀; p₀; p₁] of `integrator` (inputs as exactStepMatrix).
Eigen::Matrix<double, 2, 4> stepMatrix(ModalIntegrator integrator, double omegaRadPerS, double dampingRatio,
                                       double stepS);

/// integrateModalResponse (brittle/runtime/ModalResponse.h) stepped by `integrator`: same inputs,
/// output and errors.
Status integrateModalResponse(const Eigen::VectorXd& omegaRadPerS, const Eigen::VectorXd& dampingRatio,
                              const Eigen::VectorXd& modalLoad, const std::vector<double>& timesS,
                              const std::vector<double>& forceN, Eigen::MatrixXd& q, ModalIntegrator integrator);

}  // namespace brittle

// ModalResponse.h — the response of a body's vibration modes to a contact force, integrated
// exactly.
//
// Mode j (mass-normalised, ω_j rad/s, damping ratio ζ_j) obeys q̈ + 2ζω q̇ + ω² q = g_j F(t), with
// g_j = φ_jᵀ f the mode's share of the spatial load pattern f (per newton of contact force).
// F(t) is sampled on a time grid and taken as linear between samples; over each step the
// response to such a force has a closed form, so the stepping is exact for that force and stable
// for any step (A. K. Chopra, Dynamics of Structures, §5.2, "interpolation of excitation"). The
// ring-down after the pulse is free vibration, where the stepping is exact outright.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "brittle/core/Result.h"

namespace brittle {

/// The exact one-step map for q̈ + 2ζω q̇ + ω² q = p(t), p linear over the step h:
///   [q₁; q̇₁] = P · [q₀; q̇₀; p₀; p₁].
/// ζ < 1 uses Chopra's closed form (Table 5.2.1); ζ ≥ 1 (and ωh < 1e-2, where the closed form
/// loses digits to cancellation) uses the exponential of the augmented 4 × 4 system.
/// Inputs: ω > 0 (rad/s), ζ ≥ 0, h > 0 (s).
Eigen::Matrix<double, 2, 4> exactStepMatrix(double omegaRadPerS, double dampingRatio, double stepS);

/// The same map from the matrix exponential alone (the reference the closed form is tested against).
Eigen::Matrix<double, 2, 4> exactStepMatrixByExponential(double omegaRadPerS, double dampingRatio, double stepS);

/// A one-step map [q₁; q̇₁] = P · [q₀; q̇₀; p₀; p₁] (inputs as exactStepMatrix). The runtime steps
/// with exactStepMatrix; the textbook schemes it is measured against live offline
/// (brittle/precompute/ModalIntegrators.h).
using StepMatrixFunction = Eigen::Matrix<double, 2, 4> (*)(double omegaRadPerS, double dampingRatio, double stepS);

/// The time grid of an impact: `pulseSteps` equal steps over the contact [0, t_c], then
/// `ringDownSteps` equal steps over ringDownS after it. Returns the instants (s), starting at 0.
std::vector<double> impactTimeGrid(double contactDurationS, int pulseSteps, double ringDownS, int ringDownSteps);
/// The same into `timesS` (resized; no allocation once its capacity suffices).
void impactTimeGrid(double contactDurationS, int pulseSteps, double ringDownS, int ringDownSteps,
                    std::vector<double>& timesS);

/// Modal coordinates at every instant of `timesS` (K instants, ascending, timesS[0] = 0, body at
/// rest there) under the force forceN[k] (N) at those instants, linear in between.
/// omega, zeta, modalLoad: r each (rad/s, 1, m/√kg·… per N). Output q: K by r.
/// q is resized only when its shape changes, so a reused q costs no allocation.
/// `stepMatrix` is the one-step map (the runtime's is exactStepMatrix).
/// Errors: InvalidArgument (sizes differ, non-finite values, ω ≤ 0, ζ < 0, times not increasing).
Status integrateModalResponse(const Eigen::VectorXd& omegaRadPerS, const Eigen::VectorXd& dampingRatio,
                              const Eigen::VectorXd& modalLoad, const std::vector<double>& timesS,
                              const std::vector<double>& forceN, Eigen::MatrixXd& q,
                              StepMatrixFunction stepMatrix = &exactStepMatrix);

}  // namespace brittle

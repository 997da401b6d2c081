// RuntimeSettingsFile.h — the runtime settings a scene was sized for (`brittle size` writes them
// beside the sized pack), read back by `brittle play --settings` and `brittle impact --settings`:
//
//   { "descriptor": "moment",            // the kind fragments are matched with
//     "debris_volume_fraction": 0.004,   // fragments below this share of their body stay rigid
//     "contact_spread_fraction": 0.05,   // the contact load's least radius, per bounding-box diagonal
//     "exact_modes_max_tets": 150,       // the exact path's size limit (0: never)
//     "exact_modes_max_dof": 2000,       // and its model's limit in degrees of freedom (0: none)
//     "exact_modes_budget_dof": 2000,    // and the exact-path pieces' total per impact (0: none)
//     "exact_mode_count": 20,
//     "exact_modes_delay_s": 0.25,       // a timed break's exact-path pieces are their match until
//                                        // this long after it (0: their analysis at birth)
//     "match_error_target": 0,           // a small fragment's match within this predicted error is
//                                        // taken instead of the exact path (0: size alone decides)
//     "polynomial_mode_degree": 5,       // matched bodies ring at their fragment's own frequencies
//                                        // (PolynomialModes.h; 0: the entry's own modes)
//     "mesh_ratio_max_dof": 3000,        // ... corrected by the fragment's own mesh up to this
//                                        // size in linear-tet DOF (FragmentModes.h; 0: never)
//     "mesh_ratio_delay_s": 0.25,        // ... from this long after a timed break (0: at birth)
//     "mesh_ratio_element": "p1",        // ... in linear or quadratic tets (p2: ~10x the cost)
//     "end_at_cracks": false,            // a crack ends where it meets another (a T-junction)
//                                        // instead of crossing it (CrackSettings::endAtCracks)
//     "modes": 0 }                       // modes per impact (0: all the pack stores)
//
// Every key is optional (a missing one keeps the value it replaces); unknown keys are refused, so
// a typo never passes silently. The search precision is not here: the sized pack's database
// stores its index settings.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "brittle/core/Result.h"
#include "brittle/runtime/World.h"

namespace brittle {

/// The settings of `json` over `base`. Errors: ParseError (bad JSON, a mistyped or unknown key,
/// naming it; an unknown descriptor), InvalidArgument (a value out of range: debris or contact
/// spread fraction outside [0, 1), negative counts, exact_mode_count < 1).
Result<FractureSettings> parseRuntimeSettings(std::string_view json, std::string_view sourceName,
                                              const FractureSettings& base = {});

/// Reads a settings file. Errors: FileNotFound, then those of parseRuntimeSettings.
Result<FractureSettings> loadRuntimeSettings(const std::filesystem::path& path, const FractureSettings& base = {});

/// The document above for `settings` (every key).
std::string runtimeSettingsJson(const FractureSettings& settings);

}  // namespace brittle

// MaterialLibrary.h — material presets (with cited sources) and custom materials from JSON.
//
// A custom material file is a JSON object with the keys of the preset table (SI units):
//   { "name": "my-glass", "youngs_modulus_pa": 7.2e10, "poisson_ratio": 0.22,
//     "density_kg_per_m3": 2500, "tensile_strength_pa": 5e7,
//     "fracture_energy_j_per_m2": 7.4            (or "fracture_toughness_pa_sqrt_m": 7.5e5),
//     "rayleigh_alpha_per_s": 0, "rayleigh_beta_s": 1.6e-7, "restitution": 0.5,
//     "source": "where the values come from" }
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "brittle/database/Material.h"
#include "brittle/core/Result.h"

namespace brittle {

/// Names of the built-in presets, sorted.
std::vector<std::string> materialPresetNames();

/// A built-in preset by name. Error: UnknownMaterial (the message lists the presets).
Result<Material> materialPreset(std::string_view name);

/// A custom material from a JSON file. Errors: FileNotFound, ParseError (bad JSON, missing or
/// mistyped key, both or neither of fracture energy and toughness), InvalidMaterial (nonsense
/// values: E ≤ 0, ν ≥ 0.5, NaN, ...).
Result<Material> loadMaterialFile(const std::filesystem::path& path);

/// Writes a material as a custom material file (the keys above, fracture energy rather than
/// toughness), atomically; loadMaterialFile reads it back equal. Errors: InvalidMaterial (the
/// material fails validateMaterial; nothing is written), PackIoError (cannot write the file).
Status saveMaterialFile(const Material& material, const std::filesystem::path& path);

/// A preset name or a path to a JSON file (anything ending in ".json" or naming an existing
/// file is read as a file).
Result<Material> resolveMaterial(const std::string& nameOrPath);

}  // namespace brittle

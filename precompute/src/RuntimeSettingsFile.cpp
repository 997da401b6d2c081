// RuntimeSettingsFile.cpp — the runtime settings file (RuntimeSettingsFile.h). Header-only use of
// the runtime (World.h's settings structs), so the fuzz targets build it without the runtime.
#include "brittle/precompute/RuntimeSettingsFile.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "brittle/core/JsonChecks.h"
#include "brittle/descriptors/ShapeDescriptors.h"
#include "brittle/runtime/PolynomialModes.h"

namespace brittle {
namespace {

Error settingsFileError(std::string_view source, const std::string& what) {
  return parseError("runtime settings " + std::string(source), what);
}

}  // namespace

Result<FractureSettings> parseRuntimeSettings(std::string_view json, std::string_view sourceName,
                                              const FractureSettings& base) {
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(json);
  } catch (const std::exception& e) {
    return settingsFileError(sourceName, e.what());
  }
  if (!doc.is_object()) return settingsFileError(sourceName, "not a JSON object");
  FractureSettings s = base;
  auto integer = [&](const std::string& key, int& out) -> Status {
    const auto& v = doc[key];
    if (!v.is_number_integer()) return settingsFileError(sourceName, "\"" + key + "\" must be an integer");
    const auto x = v.get<int64_t>();
    if (x < 0 || x > std::numeric_limits<int>::max()) return makeError(ErrorCode::InvalidArgument, "runtime settings " + std::string(sourceName) + ": \"" + key + "\" out of range");
    out = static_cast<int>(x);
    return Ok{};
  };
  // A number in [0, upper) (NaN refused), `range` naming it in the error.
  auto number = [&](const std::string& key, double& out, double upper, const char* range) -> Status {
    const auto& v = doc[key];
    if (!v.is_number()) return settingsFileError(sourceName, "\"" + key + "\" must be a number");
    const double x = v.get<double>();
    if (!(x >= 0.0 && x < upper)) {
      return makeError(ErrorCode::InvalidArgument, "runtime settings " + std::string(sourceName) + ": \"" + key + "\" must be " + range);
    }
    out = x;
    return Ok{};
  };
  auto fraction = [&](const std::string& key, double& out) { return number(key, out, 1.0, "in [0, 1)"); };
  auto finite = [&](const std::string& key, double& out) {
    return number(key, out, std::numeric_limits<double>::infinity(), "finite and ≥ 0");
  };
  for (const auto& [key, value] : doc.items()) {
    if (key == "descriptor") {
      if (!value.is_string()) return settingsFileError(sourceName, "\"descriptor\" must be a string");
      auto kind = parseDescriptorKind(value.get<std::string>());
      if (!kind) return settingsFileError(sourceName, kind.error().message);
      s.descriptor = kind.value();
    } else if (key == "debris_volume_fraction") {
      if (Status st = fraction(key, s.debrisVolumeFraction); !st) return st.error();
    } else if (key == "contact_spread_fraction") {
      if (Status st = fraction(key, s.contactSpreadFraction); !st) return st.error();
    } else if (key == "exact_modes_max_tets") {
      if (Status st = integer(key, s.exactModesMaxTets); !st) return st.error();
    } else if (key == "exact_modes_max_dof") {
      if (Status st = integer(key, s.exactModesMaxDof); !st) return st.error();
    } else if (key == "exact_modes_budget_dof") {
      if (Status st = integer(key, s.exactModesBudgetDof); !st) return st.error();
    } else if (key == "exact_mode_count") {
      if (Status st = integer(key, s.exactModeCount); !st) return st.error();
      if (s.exactModeCount < 1) return makeError(ErrorCode::InvalidArgument, "runtime settings " + std::string(sourceName) + ": \"exact_mode_count\" must be ≥ 1");
    } else if (key == "exact_modes_delay_s") {
      if (Status st = finite(key, s.exactModesDelayS); !st) return st.error();
    } else if (key == "match_error_target") {  // the World refuses an infinite one too
      if (Status st = finite(key, s.matchErrorTarget); !st) return st.error();
    } else if (key == "polynomial_mode_degree") {
      if (Status st = integer(key, s.polynomialModeDegree); !st) return st.error();
      if (s.polynomialModeDegree > kMaxPolynomialModeDegree) {
        return makeError(ErrorCode::InvalidArgument, "runtime settings " + std::string(sourceName) + ": \"polynomial_mode_degree\" must be in [0, " +
                                                         std::to_string(kMaxPolynomialModeDegree) + "]");
      }
    } else if (key == "mesh_ratio_max_dof") {
      if (Status st = integer(key, s.meshRatioMaxDof); !st) return st.error();
    } else if (key == "mesh_ratio_delay_s") {
      if (Status st = finite(key, s.meshRatioDelayS); !st) return st.error();
    } else if (key == "mesh_ratio_late_max_dof") {
      if (Status st = integer(key, s.meshRatioLateMaxDof); !st) return st.error();
    } else if (key == "mesh_ratio_late_delay_s") {
      if (Status st = finite(key, s.meshRatioLateDelayS); !st) return st.error();
    } else if (key == "frequency_error_target") {
      if (Status st = finite(key, s.frequencyErrorTarget); !st) return st.error();
    } else if (key == "mesh_ratio_escalation_delay_s") {
      if (Status st = finite(key, s.meshRatioEscalationDelayS); !st) return st.error();
    } else if (key == "mesh_ratio_element") {
      if (!value.is_string()) return settingsFileError(sourceName, "\"mesh_ratio_element\" must be a string");
      const auto order = parseElementOrder(value.get<std::string>());
      if (!order) return makeError(ErrorCode::InvalidArgument, "runtime settings " + std::string(sourceName) + ": \"mesh_ratio_element\" must be \"p1\" or \"p2\"");
      s.meshRatioElement = *order;
    } else if (key == "end_at_cracks") {
      if (!value.is_boolean()) return settingsFileError(sourceName, "\"end_at_cracks\" must be true or false");
      s.crack.endAtCracks = value.get<bool>();
    } else if (key == "modes") {
      if (Status st = integer(key, s.modeCount); !st) return st.error();
    } else {
      return settingsFileError(sourceName, unknownKeyMessage(key));
    }
  }
  return s;
}

Result<FractureSettings> loadRuntimeSettings(const std::filesystem::path& path, const FractureSettings& base) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(ErrorCode::FileNotFound, "runtime settings not found: " + path.string());
  std::ostringstream text;
  text << in.rdbuf();
  return parseRuntimeSettings(text.str(), path.filename().string(), base);
}

std::string runtimeSettingsJson(const FractureSettings& s) {
  const nlohmann::json doc = {{"descriptor", descriptorKindName(s.descriptor)},
                              {"debris_volume_fraction", s.debrisVolumeFraction},
                              {"contact_spread_fraction", s.contactSpreadFraction},
                              {"exact_modes_max_tets", s.exactModesMaxTets},
                              {"exact_modes_max_dof", s.exactModesMaxDof},
                              {"exact_modes_budget_dof", s.exactModesBudgetDof},
                              {"exact_mode_count", s.exactModeCount},
                              {"exact_modes_delay_s", s.exactModesDelayS},
                              {"match_error_target", s.matchErrorTarget},
                              {"polynomial_mode_degree", s.polynomialModeDegree},
                              {"mesh_ratio_max_dof", s.meshRatioMaxDof},
                              {"mesh_ratio_delay_s", s.meshRatioDelayS},
                              {"mesh_ratio_late_max_dof", s.meshRatioLateMaxDof},
                              {"mesh_ratio_late_delay_s", s.meshRatioLateDelayS},
                              {"frequency_error_target", s.frequencyErrorTarget},
                              {"mesh_ratio_escalation_delay_s", s.meshRatioEscalationDelayS},
                              {"mesh_ratio_element", elementOrderName(s.meshRatioElement)},
                              {"end_at_cracks", s.crack.endAtCracks},
                              {"modes", s.modeCount}};
  return doc.dump(2) + "\n";
}

}  // namespace brittle

// PackSchema.h — names the pack writer and reader must agree on (the rest is spelled out in
// PACK_SCHEMA.md and checked by the round-trip tests). Private to the database module.
#pragma once

namespace brittle::packschema {

struct UnitAttribute {
  const char* name;
  const char* value;
};

/// Root attributes that state the units of schema v1. The reader requires these exact values:
/// a pack in other units would be silently misread.
inline constexpr UnitAttribute kUnitAttributes[] = {
    {"length_unit", "m"},
    {"mass_unit", "kg"},
    {"time_unit", "s"},
    {"stress_unit", "Pa"},
    {"energy_per_area_unit", "J/m^2"},
    {"frequency_unit", "Hz"},
};

inline constexpr const char* kVoigtOrder = "xx,yy,zz,yz,xz,xy";

}  // namespace brittle::packschema

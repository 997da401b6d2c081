// Fingerprint.h — an impact's fingerprint (the Fingerprint class: brittle/core/Fingerprint.h).
#pragma once

#include <cstdint>
#include <string>

#include "brittle/core/Fingerprint.h"
#include "brittle/runtime/World.h"

namespace brittle {

/// Every value an impact computed: the contact, the peak, the load, the fracture state and each
/// fragment (path, reason, surface, mass properties, match). Left out: the stage times, and the
/// new objects' ids, which depend on the World's other objects. Equal fingerprints: the same
/// fracture, bit for bit.
uint64_t fingerprint(const ImpactResult& result);

/// 16 lower-case hex digits.
std::string fingerprintHex(uint64_t fingerprint);

}  // namespace brittle

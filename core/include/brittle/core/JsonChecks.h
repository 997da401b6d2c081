// JsonChecks.h — what brittle's strict JSON readers share: a ParseError whose message names the
// file and the key, and the refusal of keys outside a known set (so a typo never passes silently).
//
// Templated on the JSON type (nlohmann::json in the readers: anything whose items() yield key()),
// so core itself does not depend on a JSON library.
#pragma once

#include <algorithm>
#include <initializer_list>
#include <iterator>
#include <optional>
#include <string>
#include <string_view>

#include "brittle/core/Result.h"

namespace brittle {

/// ParseError "<context>: <what>", e.g. context "material file concrete.json".
inline Error parseError(std::string_view context, std::string_view what) {
  return makeError(ErrorCode::ParseError, std::string(context) + ": " + std::string(what));
}

/// "unknown key \"<key>\"", the wording every reader uses.
inline std::string unknownKeyMessage(std::string_view key) { return "unknown key \"" + std::string(key) + "\""; }

/// The first key of `object`, in its order, that is not in `known` (a range of strings); nullopt
/// when every key is known. `object` must be a JSON object.
template <typename Json, typename Keys>
std::optional<std::string> findUnknownKey(const Json& object, const Keys& known) {
  for (const auto& item : object.items()) {
    const std::string& key = item.key();
    if (std::find(std::begin(known), std::end(known), key) == std::end(known)) return key;
  }
  return std::nullopt;
}
template <typename Json>
std::optional<std::string> findUnknownKey(const Json& object, std::initializer_list<std::string_view> known) {
  return findUnknownKey<Json, std::initializer_list<std::string_view>>(object, known);
}

/// Ok when every key of `object` is in `known`; otherwise parseError(context, unknownKeyMessage(key)).
template <typename Json, typename Keys>
Status checkKnownKeys(const Json& object, const Keys& known, std::string_view context) {
  if (auto key = findUnknownKey(object, known)) return parseError(context, unknownKeyMessage(*key));
  return Ok{};
}
template <typename Json>
Status checkKnownKeys(const Json& object, std::initializer_list<std::string_view> known, std::string_view context) {
  return checkKnownKeys<Json, std::initializer_list<std::string_view>>(object, known, context);
}

}  // namespace brittle

#pragma once
// Fields of a JSON text (a --summary-json file, one monitor line) for the tests, read with
// nlohmann::json. A text that does not parse, a missing key or a value of another type reads as
// NaN (numbers) or "" (text), so the test's own assertion reports it.
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

namespace teleop::test {

/// `text` parsed (key order kept); a discarded value when it is not JSON.
inline nlohmann::ordered_json parse_json(const std::string& text) {
  return nlohmann::ordered_json::parse(text, nullptr, false);
}

/// The value of the first member named `key`, depth first in the text's order (the object itself,
/// then each member's value in turn); nullptr when there is none.
inline const nlohmann::ordered_json* find_member(const nlohmann::ordered_json& j,
                                                 const std::string& key) {
  if (!j.is_structured()) return nullptr;
  for (const auto& item : j.items()) {
    if (j.is_object() && item.key() == key) return &item.value();
    if (const auto* inner = find_member(item.value(), key)) return inner;
  }
  return nullptr;
}

/// The number of the first member named `key` (flat or nested: first in the text wins); NaN
/// when the text is not JSON, the key is missing or its value is not a number (null).
inline double json_value(const std::string& text, const std::string& key) {
  const auto j = parse_json(text);
  const auto* v = find_member(j, key);
  return v && v->is_number() ? v->get<double>() : std::nan("");
}

/// The number `inner` inside the first member named `outer` ("outer": {... "inner": value}).
inline double json_nested(const std::string& text, const std::string& outer,
                          const std::string& inner) {
  const auto j = parse_json(text);
  const auto* o = find_member(j, outer);
  const auto* v = o ? find_member(*o, inner) : nullptr;
  return v && v->is_number() ? v->get<double>() : std::nan("");
}

/// The text of the top-level member `key`; "" when missing or not a string.
inline std::string json_text(const std::string& text, const std::string& key) {
  const auto j = parse_json(text);
  if (!j.is_object() || !j.contains(key) || !j[key].is_string()) return "";
  return j[key].get<std::string>();
}

}  // namespace teleop::test

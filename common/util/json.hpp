#pragma once
// The project's JSON conventions over nlohmann::json (Debian's nlohmann-json3-dev): objects keep
// the order their keys were added in (ordered_json); a number is rounded to 6 significant digits
// (the precision of the figures it reports), a whole number printed as an integer, and NaN or
// infinity written as null (JSON has neither); text is escaped by nlohmann (control characters as
// \u00XX), bytes that are not UTF-8 replaced by U+FFFD. Two layouts besides nlohmann's own compact
// dump(): json_line ({"key": value, ...} on one line: monitor lines, events, drive and recording
// summaries) and json_document (one top-level key a line, indent 2, each value on its line: the
// --summary-json files). "n/a" in the text summaries where the JSON has null (nan_as_na).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>

namespace teleop {

using OrderedJson = nlohmann::ordered_json;

/// `v` as a JSON value: null when not finite, else rounded to 6 significant digits; a whole
/// number below 1e15 becomes an integer (printed without ".0").
inline OrderedJson json_number(double v) {
  if (!std::isfinite(v)) return nullptr;
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  const double r = std::strtod(buf, nullptr);
  if (r == std::floor(r) && std::fabs(r) < 1e15) return static_cast<std::int64_t>(r);
  return r;
}

/// `j` compact, as nlohmann writes it ({"a":1,"b":[1,2]}), invalid UTF-8 replaced.
inline std::string json_compact(const OrderedJson& j) {
  return j.dump(-1, ' ', false, OrderedJson::error_handler_t::replace);
}

namespace json_detail {
inline void append_line(std::string& out, const OrderedJson& j) {
  if (j.is_object() || j.is_array()) {
    const bool object = j.is_object();
    out += object ? '{' : '[';
    bool first = true;
    for (const auto& item : j.items()) {
      if (!first) out += ", ";
      first = false;
      if (object) out += json_compact(OrderedJson(item.key())) + ": ";
      append_line(out, item.value());
    }
    out += object ? '}' : ']';
    return;
  }
  out += json_compact(j);
}
}  // namespace json_detail

/// `j` on one line with a space after each ':' and ',' ({"a": 1, "b": [1, 2]}).
inline std::string json_line(const OrderedJson& j) {
  std::string out;
  json_detail::append_line(out, j);
  return out;
}

/// An object as a file: "{", each top-level key on its own line indented by 2 with its value as
/// json_line writes it, "}" and a newline. Anything but an object is written as json_line.
inline std::string json_document(const OrderedJson& j) {
  if (!j.is_object() || j.empty()) return json_line(j) + "\n";
  std::string out = "{\n";
  bool first = true;
  for (const auto& item : j.items()) {
    if (!first) out += ",\n";
    first = false;
    out += "  " + json_compact(OrderedJson(item.key())) + ": ";
    json_detail::append_line(out, item.value());
  }
  return out + "\n}\n";
}

/// `text` with every word "nan", "-nan", "inf" or "-inf" (a NaN or infinity printed by printf)
/// replaced by "n/a": the text summaries say "n/a" where the JSON summaries say null.
inline std::string nan_as_na(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  auto word_char = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '.';
  };
  std::size_t i = 0;
  while (i < text.size()) {
    const bool at_start = i == 0 || !word_char(text[i - 1]);
    std::size_t len = 0;
    if (at_start) {
      for (const char* w : {"-nan", "nan", "-inf", "inf"}) {
        const std::size_t n = std::char_traits<char>::length(w);
        if (text.compare(i, n, w) == 0 && (i + n == text.size() || !word_char(text[i + n]))) {
          len = n;
          break;
        }
      }
    }
    if (len > 0) {
      out += "n/a";
      i += len;
    } else {
      out += text[i++];
    }
  }
  return out;
}

}  // namespace teleop

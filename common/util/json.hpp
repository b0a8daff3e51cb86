#pragma once
// Numbers in the summaries' JSON: %.6g, and null for NaN or infinity (JSON has neither);
// text as the inside of a JSON string.
#include <cmath>
#include <cstdio>
#include <string>

namespace teleop {

inline std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

/// `text` as the inside of a JSON string (quotes and backslashes escaped, control characters
/// dropped).
inline std::string json_escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) out += c;
  }
  return out;
}

}  // namespace teleop

#pragma once
// Numbers in the summaries' JSON: %.6g, and null for NaN or infinity (JSON has neither);
// text as the inside of a JSON string; "n/a" in the text summaries where the JSON has null.
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

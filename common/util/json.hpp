#pragma once
// Numbers in the summaries' JSON: %.6g, and null for NaN or infinity (JSON has neither).
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

}  // namespace teleop

#pragma once
// The message of the teleop::config::ConfigError that `fn` throws, or "" if it throws none:
//   EXPECT_NE(config_error_of([&] { load(...); }).find("field.name"), std::string::npos);
#include <functional>
#include <string>

#include "common/config/config.hpp"

namespace teleop::test {

inline std::string config_error_of(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const teleop::config::ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace teleop::test

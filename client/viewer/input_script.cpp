#include "client/viewer/input_script.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/config/config.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::viewer {

namespace {

double number(const std::string& token, const std::string& where, const std::string& what) {
  std::size_t used = 0;
  double v = std::nan("");
  try {
    v = std::stod(token, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != token.size() || !std::isfinite(v)) {
    throw config::ConfigError(where + ": " + what + " '" + token + "' is not a number");
  }
  return v;
}

Eigen::Vector3d key_direction(const std::string& key, const std::string& where) {
  if (key == "up") return Eigen::Vector3d::UnitY();
  if (key == "down") return -Eigen::Vector3d::UnitY();
  if (key == "left") return -Eigen::Vector3d::UnitX();
  if (key == "right") return Eigen::Vector3d::UnitX();
  if (key == "pageup") return Eigen::Vector3d::UnitZ();
  if (key == "pagedown") return -Eigen::Vector3d::UnitZ();
  throw config::ConfigError(where + ": key '" + key +
                            "' is not one of up, down, left, right, pageup, pagedown");
}

void tune_field(ScriptAction& a, const std::string& field, double v, const std::string& where) {
  if (field == "master_stiffness_n_per_m") {
    a.fields |= TUNE_MASTER_STIFFNESS;
    a.master_stiffness_n_per_m = v;
  } else if (field == "master_damping_ns_per_m") {
    a.fields |= TUNE_MASTER_DAMPING;
    a.master_damping_ns_per_m = v;
  } else if (field == "force_gain") {
    a.fields |= TUNE_FORCE_GAIN;
    a.force_gain = v;
  } else if (field == "slave_stiffness_n_per_m") {
    a.fields |= TUNE_SLAVE_STIFFNESS;
    a.slave_stiffness_n_per_m = v;
  } else if (field == "forward_delay_ms") {
    a.fields |= TUNE_FORWARD_DELAY;
    a.forward_delay_ms = v;
  } else if (field == "backward_delay_ms") {
    a.fields |= TUNE_BACKWARD_DELAY;
    a.backward_delay_ms = v;
  } else if (field == "ramp_s") {
    a.ramp_s = v;
  } else {
    throw config::ConfigError(where + ": tuning field '" + field +
                              "' is not one of master_stiffness_n_per_m, "
                              "master_damping_ns_per_m, force_gain, slave_stiffness_n_per_m, "
                              "forward_delay_ms, backward_delay_ms, ramp_s");
  }
}

}  // namespace

std::vector<ScriptAction> parse_input_script_text(const std::string& text,
                                                  const std::string& where_file) {
  std::vector<ScriptAction> out;
  std::istringstream lines(text);
  std::string line;
  int n = 0;
  while (std::getline(lines, line)) {
    ++n;
    const std::string where = where_file + ":" + std::to_string(n);
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream in(line);
    std::vector<std::string> tok;
    for (std::string t; in >> t;) tok.push_back(t);
    if (tok.empty()) continue;
    if (tok.size() < 2) throw config::ConfigError(where + ": expected '<time_s> <action> ...'");
    ScriptAction a;
    a.text = line;
    a.at_s = number(tok[0], where, "time");
    if (a.at_s < 0.0) throw config::ConfigError(where + ": time " + tok[0] + " is negative");
    const std::string& act = tok[1];
    if (act == "drag") {
      if (tok.size() != 5) throw config::ConfigError(where + ": expected '<t> drag dx dy seconds'");
      a.kind = ScriptAction::Kind::kDrag;
      a.dx_px = number(tok[2], where, "dx");
      a.dy_px = number(tok[3], where, "dy");
      a.duration_s = number(tok[4], where, "seconds");
    } else if (act == "key") {
      if (tok.size() != 4) throw config::ConfigError(where + ": expected '<t> key NAME seconds'");
      a.kind = ScriptAction::Kind::kKey;
      a.key_direction = key_direction(tok[2], where);
      a.duration_s = number(tok[3], where, "seconds");
    } else if (act == "tune") {
      if (tok.size() < 4 || tok.size() % 2 != 0) {
        throw config::ConfigError(where + ": expected '<t> tune FIELD VALUE [FIELD VALUE ...]'");
      }
      a.kind = ScriptAction::Kind::kTune;
      for (std::size_t i = 2; i + 1 < tok.size(); i += 2) {
        tune_field(a, tok[i], number(tok[i + 1], where, tok[i]), where);
      }
    } else if (act == "snapshot") {
      if (tok.size() != 3) throw config::ConfigError(where + ": expected '<t> snapshot FILE.png'");
      a.kind = ScriptAction::Kind::kSnapshot;
      a.path = tok[2];
    } else if (act == "quit") {
      a.kind = ScriptAction::Kind::kQuit;
    } else {
      throw config::ConfigError(where + ": action '" + act +
                                "' is not one of drag, key, tune, snapshot, quit");
    }
    if ((a.kind == ScriptAction::Kind::kDrag || a.kind == ScriptAction::Kind::kKey) &&
        !(a.duration_s > 0.0 && a.duration_s <= 600.0)) {
      throw config::ConfigError(where + ": seconds " + std::to_string(a.duration_s) +
                                " is out of the allowed range (0, 600]");
    }
    out.push_back(a);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const ScriptAction& x, const ScriptAction& y) { return x.at_s < y.at_s; });
  return out;
}

std::vector<ScriptAction> parse_input_script(const std::string& path) {
  config::require_regular_file(path, "input script");  // a FIFO or device could block or never end
  if (std::filesystem::file_size(path) > config::Node::kMaxFileBytes) {
    throw config::ConfigError(path + ": larger than " +
                              std::to_string(config::Node::kMaxFileBytes >> 20) + " MB");
  }
  std::ifstream f(path);
  if (!f) throw config::ConfigError(path + ": cannot open the input script");
  std::stringstream buf;
  buf << f.rdbuf();
  return parse_input_script_text(buf.str(), path);
}

}  // namespace teleop::viewer

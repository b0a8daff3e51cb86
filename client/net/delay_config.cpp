#include "client/net/delay_config.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

namespace teleop::master {

using config::ConfigError;

double PortableRng::normal() {
  if (have_spare_) {
    have_spare_ = false;
    return spare_;
  }
  // Box-Muller on (0, 1] x [0, 1)
  const double u1 = 1.0 - uniform01();
  const double u2 = uniform01();
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double a = 2.0 * 3.14159265358979323846 * u2;
  spare_ = r * std::sin(a);
  have_spare_ = true;
  return r * std::cos(a);
}

void DelayConfig::validate() const {
  auto check = [](const char* field, double v, double lo, double hi) {
    config::check_range("delay channel", field, v, lo, hi);
  };
  check("delay_s", delay_s, 0.0, 10.0);
  check("jitter_s", jitter_s, 0.0, 10.0);
  check("loss_probability", loss_probability, 0.0, 1.0);
  check("burst_p_good_to_bad", burst_p_good_to_bad, 0.0, 1.0);
  if (burst_loss) {
    if (!(burst_p_bad_to_good > 0.0 && burst_p_bad_to_good <= 1.0)) {
      throw ConfigError("delay channel: burst p_bg = " + std::to_string(burst_p_bad_to_good) +
                        " is out of the allowed range (0, 1] (0 would lose everything forever)");
    }
  }
  check("spike_at_s", spike_at_s, 0.0, 1e6);
  check("spike_duration_s", spike_duration_s, 0.0, 3600.0);
  check("spike_extra_s", spike_extra_s, 0.0, 10.0);
  check("window_at_s", window_at_s, 0.0, 1e6);
  check("window_duration_s", window_duration_s, 0.0, 3600.0);
  check("window_loss", window_loss, 0.0, 1.0);
  if (capacity < 2 || capacity > (1u << 24)) {
    throw ConfigError("delay channel: capacity = " + std::to_string(capacity) +
                      " is out of the allowed range [2, 16777216]");
  }
}

std::string DelayConfig::describe() const {
  char buf[256];
  std::snprintf(buf, sizeof(buf), "delay %.3g ms, jitter %.3g ms %s%s, loss %.3g %%%s, seed %llu",
                delay_s * 1e3, jitter_s * 1e3,
                jitter_dist == JitterDist::kUniform ? "uniform" : "normal",
                reorder ? " (reordering)" : "", loss_probability * 100.0,
                burst_loss ? " + burst" : "", static_cast<unsigned long long>(seed));
  std::string s = buf;
  if (burst_loss) {
    std::snprintf(buf, sizeof(buf), " (p_gb %.3g, p_bg %.3g)", burst_p_good_to_bad,
                  burst_p_bad_to_good);
    s += buf;
  }
  if (spike_duration_s > 0.0 && spike_extra_s > 0.0) {
    std::snprintf(buf, sizeof(buf), ", +%.3g ms delay at %.3g s for %.3g s", spike_extra_s * 1e3,
                  spike_at_s, spike_duration_s);
    s += buf;
  }
  if (window_duration_s > 0.0 && window_loss > 0.0) {
    std::snprintf(buf, sizeof(buf), ", %.3g %% loss at %.3g s for %.3g s", window_loss * 100.0,
                  window_at_s, window_duration_s);
    s += buf;
  }
  return s;
}

double DelayConfig::expected_loss() const {
  // the bad state loses everything; the good state loses with the Bernoulli probability
  double bad = 0.0;
  if (burst_loss && burst_p_good_to_bad > 0.0) {
    bad = burst_p_good_to_bad / (burst_p_good_to_bad + burst_p_bad_to_good);
  }
  return bad + (1.0 - bad) * loss_probability;
}

double DelayConfig::expected_jitter_stddev_s() const {
  return jitter_dist == JitterDist::kUniform ? jitter_s / std::sqrt(3.0) : jitter_s;
}

bool delay_flag_takes_value(const std::string& flag) {
  return flag == "--delay" || flag == "--jitter" || flag == "--jitter-dist" || flag == "--loss" ||
         flag == "--burst-loss" || flag == "--seed" || flag == "--channel-capacity" ||
         flag == "--delay-spike" || flag == "--loss-window";
}

namespace {

/// A duration flag's value: its unit is required ("--delay 5": 5 s or 5 ms?); "0" alone is
/// allowed.
double duration_flag_s(const std::string& flag, const std::string& text) {
  const std::size_t digits = text.find_last_of("0123456789.");
  if (digits != std::string::npos && digits + 1 == text.size() && text != "0") {
    throw ConfigError("command line: " + flag + " '" + text +
                      "' has no unit; write it with one of s, ms, us, ns (e.g. " + text + "ms)");
  }
  return config::parse_duration_s(flag, text);
}

std::uint64_t parse_u64(const std::string& flag, const std::string& text, std::uint64_t lo,
                        std::uint64_t hi) {
  std::size_t pos = 0;
  unsigned long long v = 0;
  try {
    if (!text.empty() && text[0] == '-') throw std::invalid_argument("negative");
    v = std::stoull(text, &pos, 10);
  } catch (const std::exception&) {
    pos = 0;
  }
  if (pos == 0 || pos != text.size() || v < lo || v > hi) {
    throw ConfigError("command line: " + flag + " '" + text +
                      "' is not an integer in the allowed range [" + std::to_string(lo) + ", " +
                      std::to_string(hi) + "]");
  }
  return v;
}

JitterDist parse_jitter_dist(const std::string& where, const std::string& text) {
  if (text == "uniform") return JitterDist::kUniform;
  if (text == "normal") return JitterDist::kNormal;
  throw ConfigError(where + " '" + text +
                    "' is not a jitter distribution (allowed: uniform, normal)");
}

void parse_burst(DelayConfig& cfg, const std::string& flag, const std::string& text) {
  const auto comma = text.find(',');
  if (comma == std::string::npos) {
    throw ConfigError("command line: " + flag + " '" + text +
                      "' must be two probabilities p_gb,p_bg (example: 1%,30%)");
  }
  cfg.burst_loss = true;
  cfg.burst_p_good_to_bad = config::parse_probability(flag + " (p_gb)", text.substr(0, comma));
  cfg.burst_p_bad_to_good = config::parse_probability(flag + " (p_bg)", text.substr(comma + 1));
  if (cfg.burst_p_bad_to_good <= 0.0) {
    throw ConfigError("command line: " + flag + " '" + text +
                      "': p_bg must be > 0 (the bad state would never end)");
  }
}

/// "AT,DURATION,X": two durations and a third value parsed by `third`.
template <class F>
void parse_window(const std::string& flag, const std::string& text, double& at, double& duration,
                  double& third, const char* example, F third_parser) {
  const auto c1 = text.find(',');
  const auto c2 = c1 == std::string::npos ? c1 : text.find(',', c1 + 1);
  if (c2 == std::string::npos) {
    throw ConfigError("command line: " + flag + " '" + text +
                      "' must be AT,DURATION,VALUE (example: " + example + ")");
  }
  at = duration_flag_s(flag + " (at)", text.substr(0, c1));
  duration = duration_flag_s(flag + " (duration)", text.substr(c1 + 1, c2 - c1 - 1));
  third = third_parser(text.substr(c2 + 1));
}

}  // namespace

bool apply_delay_flag(DelayConfig& cfg, const std::string& flag, const std::string& value) {
  if (flag == "--delay") {
    cfg.delay_s = duration_flag_s(flag, value);
  } else if (flag == "--jitter") {
    cfg.jitter_s = duration_flag_s(flag, value);
  } else if (flag == "--jitter-dist") {
    cfg.jitter_dist = parse_jitter_dist("command line: " + flag, value);
  } else if (flag == "--reorder") {
    cfg.reorder = true;
  } else if (flag == "--loss") {
    cfg.loss_probability = config::parse_probability(flag, value);
  } else if (flag == "--burst-loss") {
    parse_burst(cfg, flag, value);
  } else if (flag == "--delay-spike") {
    parse_window(flag, value, cfg.spike_at_s, cfg.spike_duration_s, cfg.spike_extra_s, "3s,1s,1s",
                 [&](const std::string& t) { return duration_flag_s(flag + " (extra delay)", t); });
  } else if (flag == "--loss-window") {
    parse_window(
        flag, value, cfg.window_at_s, cfg.window_duration_s, cfg.window_loss, "3s,1s,50%",
        [&](const std::string& t) { return config::parse_probability(flag + " (loss)", t); });
  } else if (flag == "--seed") {
    cfg.seed = parse_u64(flag, value, 0, std::numeric_limits<std::uint64_t>::max());
  } else if (flag == "--channel-capacity") {
    cfg.capacity = static_cast<std::size_t>(parse_u64(flag, value, 2, 1u << 24));
  } else {
    return false;
  }
  return true;
}

std::vector<std::string> parse_delay_flags(DelayConfig& cfg, const std::vector<std::string>& args) {
  std::vector<std::string> rest;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    // accept --flag=value as well as --flag value
    const auto eq = a.find('=');
    const std::string flag = eq == std::string::npos ? a : a.substr(0, eq);
    if (flag == "--reorder") {
      apply_delay_flag(cfg, flag, "");
    } else if (delay_flag_takes_value(flag)) {
      std::string value;
      if (eq != std::string::npos) {
        value = a.substr(eq + 1);
      } else if (i + 1 < args.size()) {
        value = args[++i];
      } else {
        throw ConfigError("command line: " + flag + " needs a value");
      }
      apply_delay_flag(cfg, flag, value);
    } else {
      rest.push_back(a);
    }
  }
  cfg.validate();
  return rest;
}

DelayConfig delay_config_from_yaml(const config::Node& node) {
  DelayConfig cfg;
  if (!node.defined()) return cfg;
  node.reject_unknown_keys(
      {"delay", "jitter", "jitter_dist", "reorder", "loss", "burst_loss", "seed", "capacity"});
  // the text of a scalar field (numbers and strings alike)
  auto scalar = [&](const std::string& key) {
    const config::Node c = node.child(key);
    if (!c.raw().IsScalar()) node.fail(key, "must be a single value, not a list or mapping");
    return c.raw().as<std::string>();
  };
  // a duration: a number in seconds or a string with a unit
  auto duration = [&](const std::string& key, double fallback) {
    if (!node.has(key)) return fallback;
    const std::string text = scalar(key);
    try {
      return config::parse_duration_s(key, text);
    } catch (const ConfigError&) {
      node.fail(key, "'" + text + "' is not a duration >= 0 (examples: 50ms, 0.2s, 150us, 0.05)");
    }
  };
  auto probability = [&](const config::Node& n, const std::string& key, const std::string& text) {
    try {
      return config::parse_probability(key, text);
    } catch (const ConfigError&) {
      n.fail(key, "'" + text + "' is not a probability in [0, 1] (examples: 1%, 0.01)");
    }
  };
  cfg.delay_s = duration("delay", 0.0);
  cfg.jitter_s = duration("jitter", 0.0);
  const std::string dist = node.choice_or("jitter_dist", "uniform", {"uniform", "normal"});
  cfg.jitter_dist = dist == "normal" ? JitterDist::kNormal : JitterDist::kUniform;
  cfg.reorder = node.boolean_or("reorder", false);
  if (node.has("loss")) {
    cfg.loss_probability = probability(node, "loss", scalar("loss"));
  }
  if (node.has("burst_loss")) {
    const config::Node b = node.child("burst_loss");
    if (!b.is_sequence() || b.size() != 2) {
      node.fail("burst_loss", "must be a list of two probabilities [p_gb, p_bg]");
    }
    cfg.burst_loss = true;
    cfg.burst_p_good_to_bad =
        probability(node, "burst_loss", b.at(std::size_t{0}).raw().as<std::string>());
    cfg.burst_p_bad_to_good =
        probability(node, "burst_loss", b.at(std::size_t{1}).raw().as<std::string>());
    if (cfg.burst_p_bad_to_good <= 0.0) {
      node.fail("burst_loss", "p_bg must be > 0 (the bad state would never end), allowed (0, 1]");
    }
  }
  cfg.seed = static_cast<std::uint64_t>(node.integer_or("seed", 1, 0, (1LL << 62)));
  cfg.capacity = static_cast<std::size_t>(node.integer_or("capacity", 4096, 2, 1 << 24));
  try {
    cfg.validate();
  } catch (const ConfigError& e) {
    node.fail("delay", e.what());
  }
  return cfg;
}

}  // namespace teleop::master

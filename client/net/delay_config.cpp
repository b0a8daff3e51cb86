#include "client/net/delay_config.hpp"

#include <cmath>
#include <cstdio>
#include <set>

#include "client/net/delay_params.hpp"

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
  for (const DelayParam& d : delay_param_table()) d.check(*this);
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
  const DelayParam* d = delay_param_of_flag(flag);
  return d != nullptr && d->kind != DelayParamKind::kSwitch;
}

bool apply_delay_flag(DelayConfig& cfg, const std::string& flag, const std::string& value) {
  const DelayParam* d = delay_param_of_flag(flag);
  if (d == nullptr) return false;
  d->apply_flag(value, cfg);
  return true;
}

std::vector<std::string> parse_delay_flags(DelayConfig& cfg, const std::vector<std::string>& args) {
  std::vector<std::string> rest;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    // accept --flag=value as well as --flag value
    const auto eq = a.find('=');
    const std::string flag = eq == std::string::npos ? a : a.substr(0, eq);
    if (const DelayParam* d = delay_param_of_flag(flag);
        d != nullptr && d->kind == DelayParamKind::kSwitch) {
      d->apply_flag("", cfg);
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
  std::set<std::string> keys;
  for (const DelayParam& d : delay_param_table()) keys.insert(d.key);
  node.reject_unknown_keys(keys);
  for (const DelayParam& d : delay_param_table()) d.read(node, cfg);
  return cfg;
}

}  // namespace teleop::master

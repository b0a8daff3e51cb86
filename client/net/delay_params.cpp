#include "client/net/delay_params.hpp"

#include <cmath>
#include <stdexcept>

namespace teleop::master {

using config::ConfigError;
using config::param_number_text;

namespace {

/// The largest seed: every seed a double holds exactly (campaign files, JSON summaries).
constexpr double kMaxSeed = 9007199254740992.0;  // 2^53

const std::vector<std::string>& jitter_names() {
  static const std::vector<std::string> names = {"uniform", "normal"};
  return names;
}

std::string joined(const std::vector<std::string>& v, const char* sep) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

std::vector<std::string> split_commas(const std::string& text) {
  std::vector<std::string> out;
  std::size_t from = 0;
  for (;;) {
    const std::size_t comma = text.find(',', from);
    out.push_back(text.substr(from, comma - from));
    if (comma == std::string::npos) return out;
    from = comma + 1;
  }
}

const char* unit_of(const DelayPart& p) {
  return p.quantity == DelayQuantity::kDuration ? "s" : "-";
}

std::string range_of(const DelayPart& p) {
  return (p.lo_open ? "(" : "[") + param_number_text(p.lo) + ", " + param_number_text(p.hi) + "]";
}

bool in_range(const DelayPart& p, double v) {
  return (p.lo_open ? v > p.lo : v >= p.lo) && v <= p.hi;
}

/// `text` as the value of `part`: a problem (starting with the quoted text) or "" with `out` set.
/// A flag's duration needs its unit; a file's plain number is seconds.
std::string part_problem(const DelayPart& part, const std::string& text, bool flag, double& out) {
  const std::string quoted = "'" + text + "'";
  if (part.quantity == DelayQuantity::kDuration) {
    const std::size_t last = text.find_last_of("0123456789.");
    if (flag && last != std::string::npos && last + 1 == text.size() && text != "0") {
      return quoted + " has no unit; write it with one of s, ms, us, ns (e.g. " + text + "ms)";
    }
    try {
      out = config::parse_duration_s("", text);
    } catch (const ConfigError&) {
      return quoted + " is not a duration >= 0 (examples: 50ms, 0.2s, 150us" +
             (flag ? ")" : ", 0.05)");
    }
  } else {
    try {
      out = config::parse_probability("", text);
    } catch (const ConfigError&) {
      return quoted + " is not a probability in [0, 1] (examples: 1%, 0.01)";
    }
  }
  if (!in_range(part, out)) {
    return quoted + " is out of the allowed range " + range_of(part) + " " + unit_of(part) +
           (part.why_open.empty() ? "" : " (" + part.why_open + ")");
  }
  return "";
}

/// A count's text: a problem or "" with `out` set.
std::string count_problem(const DelayParam& d, const std::string& text, std::uint64_t& out) {
  if (!config::number_problem(text, d.lo, d.hi, true).empty()) {
    return "'" + text + "' is not a whole number in " + d.allowed_text();
  }
  out = static_cast<std::uint64_t>(std::stod(text));
  return "";
}

std::string choice_problem(const std::string& text, JitterDist& out) {
  const std::vector<std::string>& names = jitter_names();
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (text == names[i]) {
      out = static_cast<JitterDist>(i);
      return "";
    }
  }
  return "'" + text + "' is not a jitter distribution (allowed: " + joined(names, ", ") + ")";
}

/// The scalar texts of a file's value: one scalar, or a list of `count` scalars.
std::vector<std::string> yaml_texts(const config::Node& node, const std::string& key,
                                    std::size_t count) {
  const config::Node c = node.child(key);
  if (count == 1) {
    if (!c.raw().IsScalar()) node.fail(key, "must be a single value, not a list or mapping");
    return {c.raw().as<std::string>()};
  }
  if (!c.is_sequence() || c.size() != count) {
    node.fail(key, "must be a list of " + std::to_string(count) + " values");
  }
  std::vector<std::string> texts;
  for (std::size_t i = 0; i < count; ++i) {
    const config::Node item = c.at(i);
    const YAML::Node& e = item.raw();
    if (!e.IsScalar()) node.fail(key, "must be a list of " + std::to_string(count) + " values");
    texts.push_back(e.as<std::string>());
  }
  return texts;
}

}  // namespace

std::string DelayParam::unit_text() const {
  if (kind != DelayParamKind::kNumbers) return "";
  std::vector<std::string> units;
  for (const DelayPart& p : parts) units.emplace_back(unit_of(p));
  return joined(units, ", ");
}

std::string DelayParam::allowed_text() const {
  switch (kind) {
    case DelayParamKind::kNumbers: {
      if (parts.size() == 1) return range_of(parts[0]);
      std::vector<std::string> each;
      for (const DelayPart& p : parts) each.push_back(p.name + " " + range_of(p));
      return joined(each, ", ");
    }
    case DelayParamKind::kChoice:
      return joined(jitter_names(), ", ");
    case DelayParamKind::kSwitch:
      return "true, false";
    case DelayParamKind::kCount: {
      const auto whole = [](double v) { return std::to_string(static_cast<std::uint64_t>(v)); };
      return "[" + whole(lo) + ", " + (hi == kMaxSeed ? "2^53" : whole(hi)) + "]";
    }
  }
  return "";
}

std::string DelayParam::text(const DelayConfig& c) const {
  switch (kind) {
    case DelayParamKind::kNumbers: {
      if (enable != nullptr && !(c.*enable)) return "off";
      std::vector<std::string> each;
      for (const DelayPart& p : parts) each.push_back(param_number_text(c.*(p.field)));
      return parts.size() == 1 ? each[0] : "[" + joined(each, ", ") + "]";
    }
    case DelayParamKind::kChoice:
      return jitter_names()[static_cast<std::size_t>(c.*choice)];
    case DelayParamKind::kSwitch:
      return c.*enable ? "true" : "false";
    case DelayParamKind::kCount:
      return std::to_string(c.*count);
  }
  return "";
}

std::string DelayParam::flag_help() const {
  std::string units = unit_text();
  units = units.empty() ? "" : " [" + units + "]";
  if (kind == DelayParamKind::kSwitch) return help;
  if (kind == DelayParamKind::kChoice) return help + " (" + allowed_text() + ")";
  return help + units + ", " + allowed_text() + (example.empty() ? "" : " (e.g. " + example + ")");
}

void DelayParam::check(const DelayConfig& c) const {
  switch (kind) {
    case DelayParamKind::kNumbers:
      if (enable != nullptr && !(c.*enable)) return;
      for (const DelayPart& p : parts) {
        const double v = c.*(p.field);
        const std::string field = parts.size() == 1 ? key : key + " " + p.name;
        if (!in_range(p, v)) {
          throw ConfigError("delay channel: " + field + " = " + param_number_text(v) +
                            " is out of the allowed range " + range_of(p) + " " + unit_of(p) +
                            (p.why_open.empty() ? "" : " (" + p.why_open + ")"));
        }
      }
      return;
    case DelayParamKind::kChoice:
      if (static_cast<std::size_t>(c.*choice) >= jitter_names().size()) {
        throw ConfigError("delay channel: " + key + " is not one of " + allowed_text());
      }
      return;
    case DelayParamKind::kSwitch:
      return;
    case DelayParamKind::kCount: {
      const auto v = static_cast<double>(c.*count);
      if (!(v >= lo && v <= hi)) {
        throw ConfigError("delay channel: " + key + " = " + std::to_string(c.*count) +
                          " is out of the allowed range " + allowed_text());
      }
      return;
    }
  }
}

void DelayParam::apply_flag(const std::string& text, DelayConfig& c) const {
  const std::string where = "command line: " + flag + " ";
  std::string problem;
  switch (kind) {
    case DelayParamKind::kNumbers: {
      const std::vector<std::string> texts = split_commas(text);
      if (texts.size() != parts.size()) {
        std::vector<std::string> names;
        for (const DelayPart& p : parts) names.push_back(p.name.empty() ? "VALUE" : p.name);
        throw ConfigError(where + "'" + text + "' must be " + joined(names, ",") +
                          " (example: " + example + ")");
      }
      for (std::size_t i = 0; i < parts.size(); ++i) {
        const DelayPart& p = parts[i];
        const std::string label = p.name.empty() ? "" : "(" + p.name + ") ";
        double v = 0.0;
        problem = part_problem(p, texts[i], true, v);
        if (!problem.empty()) throw ConfigError(where + label + problem);
        c.*(p.field) = v;
      }
      if (enable != nullptr) c.*enable = true;
      return;
    }
    case DelayParamKind::kChoice:
      problem = choice_problem(text, c.*choice);
      break;
    case DelayParamKind::kSwitch:
      c.*enable = true;
      return;
    case DelayParamKind::kCount:
      problem = count_problem(*this, text, c.*count);
      break;
  }
  if (!problem.empty()) throw ConfigError(where + problem);
}

void DelayParam::read(const config::Node& node, DelayConfig& c) const {
  if (!node.has(key)) return;
  switch (kind) {
    case DelayParamKind::kNumbers: {
      const std::vector<std::string> texts = yaml_texts(node, key, parts.size());
      for (std::size_t i = 0; i < parts.size(); ++i) {
        const DelayPart& p = parts[i];
        double v = 0.0;
        const std::string problem = part_problem(p, texts[i], false, v);
        if (!problem.empty()) node.fail(key, (p.name.empty() ? "" : p.name + " ") + problem);
        c.*(p.field) = v;
      }
      if (enable != nullptr) c.*enable = true;
      return;
    }
    case DelayParamKind::kChoice: {
      const std::string problem = choice_problem(yaml_texts(node, key, 1)[0], c.*choice);
      if (!problem.empty()) node.fail(key, problem);
      return;
    }
    case DelayParamKind::kSwitch:
      c.*enable = node.boolean_or(key, false);
      return;
    case DelayParamKind::kCount: {
      const std::string problem = count_problem(*this, yaml_texts(node, key, 1)[0], c.*count);
      if (!problem.empty()) node.fail(key, problem);
      return;
    }
  }
}

const std::vector<DelayParam>& delay_param_table() {
  using C = DelayConfig;
  using Q = DelayQuantity;
  using K = DelayParamKind;
  static const std::vector<DelayParam> table = {
      {.key = "delay",
       .flag = "--delay",
       .help = "constant one-way delay D",
       .example = "50ms",
       .parts = {{.field = &C::delay_s, .hi = 10.0}}},
      {.key = "jitter",
       .flag = "--jitter",
       .help = "jitter scale J added to the delay (jitter_dist)",
       .example = "5ms",
       .parts = {{.field = &C::jitter_s, .hi = 10.0}}},
      {.key = "jitter_dist",
       .flag = "--jitter-dist",
       .help = "jitter shape: uniform in [D - J, D + J], or normal N(D, J^2) truncated to D +- 4 J",
       .kind = K::kChoice,
       .choice = &C::jitter_dist},
      {.key = "reorder",
       .flag = "--reorder",
       .help = "let jittered samples overtake each other",
       .kind = K::kSwitch,
       .enable = &C::reorder},
      {.key = "loss",
       .flag = "--loss",
       .help = "Bernoulli loss probability per sample",
       .example = "1%",
       .parts = {{.field = &C::loss_probability, .quantity = Q::kProbability, .hi = 1.0}}},
      {.key = "burst_loss",
       .flag = "--burst-loss",
       .help = "Gilbert-Elliott burst loss: p_gb, p_bg per sample (the bad state loses all)",
       .example = "1%,30%",
       .parts = {{.name = "p_gb",
                  .field = &C::burst_p_good_to_bad,
                  .quantity = Q::kProbability,
                  .hi = 1.0},
                 {.name = "p_bg",
                  .field = &C::burst_p_bad_to_good,
                  .quantity = Q::kProbability,
                  .hi = 1.0,
                  .lo_open = true,
                  .why_open = "p_bg = 0: the bad state would never end"}},
       .enable = &C::burst_loss},
      {.key = "delay_spike",
       .flag = "--delay-spike",
       .help = "samples sent in [at, at + duration) after the channel's first get extra more "
               "delay (the ones after queue behind them)",
       .example = "3s,1s,1s",
       .parts = {{.name = "at", .field = &C::spike_at_s, .hi = 1e6},
                 {.name = "duration", .field = &C::spike_duration_s, .hi = 3600.0},
                 {.name = "extra", .field = &C::spike_extra_s, .hi = 10.0}}},
      {.key = "loss_window",
       .flag = "--loss-window",
       .help = "samples sent in [at, at + duration) after the channel's first are lost with "
               "probability loss",
       .example = "3s,1s,50%",
       .parts =
           {{.name = "at", .field = &C::window_at_s, .hi = 1e6},
            {.name = "duration", .field = &C::window_duration_s, .hi = 3600.0},
            {.name = "loss", .field = &C::window_loss, .quantity = Q::kProbability, .hi = 1.0}}},
      {.key = "seed",
       .flag = "--seed",
       .help = "random seed (mt19937_64); teleop_master's backward channel uses seed + 1",
       .kind = K::kCount,
       .count = &C::seed,
       .hi = kMaxSeed},
      {.key = "capacity",
       .flag = "--channel-capacity",
       .help = "samples in flight at most (more are dropped and counted as lost)",
       .kind = K::kCount,
       .count = &C::capacity,
       .lo = 2.0,
       .hi = 16777216.0},
  };
  return table;
}

const DelayParam& delay_param(const std::string& key) {
  for (const DelayParam& d : delay_param_table()) {
    if (d.key == key) return d;
  }
  throw std::out_of_range("no delay parameter '" + key + "'");
}

const DelayParam* delay_param_of_flag(const std::string& flag) {
  for (const DelayParam& d : delay_param_table()) {
    if (d.flag == flag) return &d;
  }
  return nullptr;
}

std::string delay_params_markdown() {
  const DelayConfig defaults;
  std::string md =
      "| key | flag | unit | default | range | help |\n"
      "|---|---|---|---|---|---|\n";
  for (const DelayParam& d : delay_param_table()) {
    md += "| `" + d.key + "` | `" + d.flag + "` | " + d.unit_text() + " | " + d.text(defaults) +
          " | " + d.allowed_text() + " | " + d.help + " |\n";
  }
  return md;
}

}  // namespace teleop::master

#pragma once
// The injected channel's command-line flags, one for each entry of delay_param_table()
// (header-only: the apps link CLI11). The help gives the unit, the range and an example; the
// value goes to the table's one parser of that flag (DelayParam::apply_flag), which checks it.
// The values are applied over the DelayConfig already read (from --config), then validated.
#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "client/net/delay_params.hpp"

namespace teleop::master {

/// The channel flags of one CLI::App and what the command line gave them. CLI11 keeps pointers
/// into `text`, so it is neither copied nor moved.
struct DelayFlags {
  DelayFlags() = default;
  DelayFlags(const DelayFlags&) = delete;
  DelayFlags& operator=(const DelayFlags&) = delete;

  std::vector<CLI::Option*> options;  ///< the option of each table entry, in table order
  std::vector<std::string> text;      ///< the value given to each (a switch: none)

  /// True when the command line gave any of them.
  bool any() const {
    for (const CLI::Option* o : options) {
      if (o->count() > 0) return true;
    }
    return false;
  }
};

/// Adds to `app` one option per table entry; `what` ends each help ("both directions").
inline void add_delay_flags(CLI::App& app, DelayFlags& f, const std::string& what) {
  const DelayConfig defaults;
  const std::vector<DelayParam>& table = delay_param_table();
  f.text.assign(table.size(), std::string());  // never resized again: CLI11 binds to it
  for (std::size_t i = 0; i < table.size(); ++i) {
    const DelayParam& d = table[i];
    const std::string help = d.flag_help() + "; " + what;
    if (d.kind == DelayParamKind::kSwitch) {
      f.options.push_back(app.add_flag(d.flag)->description(help));
      continue;
    }
    CLI::Option* opt = app.add_option(d.flag, f.text[i], help);
    if (d.kind == DelayParamKind::kChoice) opt->default_str(d.text(defaults));
    f.options.push_back(opt);
  }
}

/// Applies the flags the command line gave to `c`, in table order, then validates `c`.
/// @throws config::ConfigError naming the flag, the value and the allowed values.
inline void apply_delay_flags(const DelayFlags& f, DelayConfig& c) {
  const std::vector<DelayParam>& table = delay_param_table();
  for (std::size_t i = 0; i < table.size(); ++i) {
    if (f.options[i]->count() > 0) table[i].apply_flag(f.text[i], c);
  }
  c.validate();
}

}  // namespace teleop::master

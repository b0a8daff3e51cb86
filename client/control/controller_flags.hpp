#pragma once
// The controller's command-line flags, one for each entry of controller_param_table() with a
// flag name (header-only: the apps link CLI11). A number flag is checked on its text with the
// table's range (config::number_in), a choice against the table's values, a switch sets the
// table's value; the help gives the unit and the range and the default is the struct's.
// The values are applied over ControllerParams already read (from --config), then validated.
#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "client/control/controller_params.hpp"
#include "common/config/flags.hpp"

namespace teleop::master {

/// The controller flags of one CLI::App and what the command line gave them. CLI11 keeps
/// pointers into `text`, so it is neither copied nor moved.
struct ControllerFlags {
  ControllerFlags() = default;
  ControllerFlags(const ControllerFlags&) = delete;
  ControllerFlags& operator=(const ControllerFlags&) = delete;

  std::vector<const ControllerParam*> params;  ///< table entries with a flag, in table order
  std::vector<CLI::Option*> options;           ///< the option of each
  std::vector<std::string> text;               ///< the value given to each (a switch: none)
};

/// Adds to `app` one option per table entry with a flag (see the file comment). Call once.
inline void add_controller_flags(CLI::App& app, ControllerFlags& f) {
  const ControllerParams defaults;
  for (const ControllerParam& d : controller_param_table()) {
    if (!d.flag.empty()) f.params.push_back(&d);
  }
  f.text.assign(f.params.size(), std::string());  // never resized again: CLI11 binds to it
  for (std::size_t i = 0; i < f.params.size(); ++i) {
    const ControllerParam& d = *f.params[i];
    if (d.kind() == ParamKind::kBool) {
      f.options.push_back(app.add_flag(d.flag)->description(d.flag_help()));
      continue;
    }
    CLI::Option* opt = app.add_option(d.flag, f.text[i], d.flag_help());
    if (d.kind() == ParamKind::kNumber)
      opt->type_name("FLOAT")->check(config::number_in(d.lo, d.hi));
    if (d.kind() == ParamKind::kChoice) opt->check(CLI::IsMember(d.choices));
    opt->default_str(d.text(defaults));
    f.options.push_back(opt);
  }
}

/// Applies the flags the command line gave over `p`, then validates `p`.
/// @throws config::ConfigError naming the flag (or field), the value and the range.
inline void apply_controller_flags(const ControllerFlags& f, ControllerParams& p) {
  for (std::size_t i = 0; i < f.params.size(); ++i) {
    if (f.options[i]->count() > 0) f.params[i]->apply_flag(f.text[i], p);
  }
  p.validate();
}

}  // namespace teleop::master

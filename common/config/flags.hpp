#pragma once
// The command-line rules every executable shares (header-only: the apps link CLI11).
//
//   - a number flag is declared with its range once, by add_number / add_integer: its text is
//     checked before conversion (number_in / integer_in: the whole text must be a finite number
//     within the range; "" (which CLI11 would turn into the default), "3x", "nan", "-0" or "-1"
//     where the range starts at 0 are refused), and its help ends in the unit and the range,
//     "session length after homing [s], [0, 1e6]";
//   - harden_flags(app), called once every option is declared: every option that takes a value
//     refuses an empty value (`--out ''`, `--domain=`), and every single-valued option refuses
//     to be given twice (`--out a --out b`); CLI11 itself refuses unknown arguments;
//   - parse_command_line(app, exe, argc, argv) adds --version, parses, prints a refusal as
//     "<exe>: <flag>: '<value>' ..." with the usage (an unknown flag with the closest known one:
//     "'--levle' is not an option of <exe> (did you mean '--level'?)"), and gives the exit
//     status: 2 for a mistake, 0 for --help or --version (nothing runs), -1 to go on.
// Checks that need another value (a range that depends on --rate or on the core count) stay
// after the parse, with config::check_flag / parse_number, which refuse the same texts.
#include <CLI/CLI.hpp>

#include <iostream>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "common/config/config.hpp"
#include "common/config/suggest.hpp"
#include "common/util/version.hpp"

namespace teleop::config {

/// A CLI11 check: the value is a finite number within [lo, hi] (see number_problem()).
inline CLI::Validator number_in(double lo, double hi) {
  return CLI::Validator([lo, hi](std::string& v) { return number_problem(v, lo, hi, false); },
                        "NUMBER in " + range_text(lo, hi));
}

/// A CLI11 check: the value is a whole number within [lo, hi].
inline CLI::Validator integer_in(double lo, double hi) {
  return CLI::Validator([lo, hi](std::string& v) { return number_problem(v, lo, hi, true); },
                        "INTEGER in " + range_text(lo, hi));
}

/// A range in a flag's help, as the parameter tables write it: "[0, 1e6]".
inline std::string help_range_text(double lo, double hi) {
  return "[" + param_number_text(lo) + ", " + param_number_text(hi) + "]";
}

/// The help of a number flag: `help`, then the unit in brackets where there is one, then the
/// range: "session length after homing [s], [0, 1e6]".
inline std::string number_help(const std::string& help, const std::string& unit, double lo,
                               double hi) {
  return help + (unit.empty() ? "" : " [" + unit + "]") + ", " + help_range_text(lo, hi);
}

namespace detail {
/// The value type a flag binds: T itself, or T of std::optional<T> (unset: not given).
template <typename T>
struct FlagValue {
  using type = T;
};
template <typename T>
struct FlagValue<std::optional<T>> {
  using type = T;
};
}  // namespace detail

/// Declares the number flag `flag` bound to `field` (a double, or std::optional<double> for a
/// flag whose absence means something): its text must be a finite number in [lo, hi]
/// (number_in) and its help is number_help(help, unit, lo, hi). Returns the option, for
/// ->capture_default_str() where the help shows the default.
template <typename T>
CLI::Option* add_number(CLI::App& app, const std::string& flag, T& field, double lo, double hi,
                        const std::string& help, const std::string& unit = "") {
  static_assert(std::is_floating_point_v<typename detail::FlagValue<T>::type>,
                "add_number binds a floating-point field; add_integer a whole number");
  return app.add_option(flag, field, number_help(help, unit, lo, hi))->check(number_in(lo, hi));
}

/// The same for a whole number (int, std::uint64_t, ..., or an optional one): integer_in.
template <typename T>
CLI::Option* add_integer(CLI::App& app, const std::string& flag, T& field, double lo, double hi,
                         const std::string& help, const std::string& unit = "") {
  static_assert(std::is_integral_v<typename detail::FlagValue<T>::type>,
                "add_integer binds an integer field; add_number a floating-point one");
  return app.add_option(flag, field, number_help(help, unit, lo, hi))->check(integer_in(lo, hi));
}

/// A CLI11 check: the value is not empty.
inline CLI::Validator non_empty() {
  return CLI::Validator(
      [](std::string& v) { return v.empty() ? std::string("'' is empty; a value is needed") : ""; },
      "");
}

/// Applies the shared rules to every option of `app` already declared (see the file comment).
/// Options bound to a list (`--exclude`, `--peer`) stay repeatable.
inline void harden_flags(CLI::App& app) {
  for (CLI::Option* opt : app.get_options()) {
    if (opt->get_items_expected_max() == 0) continue;  // a switch (--quiet) or --help
    opt->check(non_empty());
    if (opt->get_items_expected_max() == 1 &&
        opt->get_multi_option_policy() != CLI::MultiOptionPolicy::TakeAll) {
      opt->multi_option_policy(CLI::MultiOptionPolicy::Throw);
    }
  }
}

/// The long names of `app`'s options ("--out", "--help", ...).
inline std::vector<std::string> option_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::Option* opt : app.get_options()) {
    for (const std::string& n : opt->get_lnames()) names.push_back("--" + n);
  }
  return names;
}

/// The refusal of arguments CLI11 did not expect: each unknown flag with the closest known one
/// (the words after it, likely its value, are not listed), else each stray word.
inline std::string unexpected_arguments_text(const CLI::App& app, const std::string& exe) {
  std::string flags, words;
  const std::vector<std::string> names = option_names(app);
  for (const std::string& word : app.remaining(false)) {
    if (word.size() > 1 && word[0] == '-') {
      const std::string flag = word.substr(0, word.find('='));
      flags += (flags.empty() ? "" : "; ") + ("'" + flag + "' is not an option of " + exe) +
               did_you_mean(flag, names);
    } else {
      words +=
          (words.empty() ? "" : "; ") + ("'" + word + "' is not expected (no option takes it)");
    }
  }
  return flags.empty() ? words : flags;
}

/// Parses the command line with the shared rules. Returns -1 to go on, else the exit status:
/// 0 after --help or --version, 2 after a mistake (printed to stderr with the usage).
inline int parse_command_line(CLI::App& app, const std::string& exe, int argc, char** argv) {
  app.set_version_flag("--version", version_line(exe), "print the version and exit");
  harden_flags(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ExtrasError&) {
    std::cerr << exe << ": " << unexpected_arguments_text(app, exe) << "\n\n" << app.help();
    return 2;
  } catch (const CLI::ParseError& e) {
    // CLI11 says "--out: At Most 1 required but received 2" for a repeated flag
    std::string what = e.what();
    const std::string repeated = ": At Most 1 required but received ";
    if (const auto at = what.find(repeated); at != std::string::npos) {
      what = what.substr(0, at) + " is given " + what.substr(at + repeated.size()) +
             " times; it takes one value";
    }
    std::cerr << exe << ": " << what << "\n\n" << app.help();
    return 2;
  }
  return -1;
}

}  // namespace teleop::config

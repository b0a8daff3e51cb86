#pragma once
// The parameters of an injected channel (DelayConfig) and the one table that declares them.
//
// Each parameter is declared once, as a DelayParam (key in a YAML delay mapping, teleop_master
// flag, help, the numbers it holds with their units and ranges, and the fields of DelayConfig it
// sets); its default is the member initialiser of DelayConfig. DelayConfig::validate(), the YAML
// loader (delay_config_from_yaml), the flag parser (apply_delay_flag, parse_delay_flags),
// teleop_master's flags (client/net/delay_flags.hpp), the campaign axes' ranges and the table of
// docs/configuration.md (`teleop_master --print-delay-parameters`) all read it.
//
// The one difference between a file and a flag: a duration flag needs its unit ("--delay 5" is
// refused, "0" alone is allowed); in YAML a plain number is seconds. A parameter of several
// numbers is "A,B,C" on the command line and a list [A, B, C] in YAML.
// Everything here runs at configuration only, never in the loops.
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "client/net/delay_config.hpp"
#include "common/config/config.hpp"

namespace teleop::master {

static_assert(std::is_same_v<std::size_t, std::uint64_t>,
              "DelayConfig::capacity and ::seed share one member-pointer type");

/// What a number of a parameter is.
enum class DelayQuantity : std::uint8_t {
  kDuration,     ///< seconds (flags: with a unit, e.g. 50ms)
  kProbability,  ///< [0, 1] (also written as a percentage, e.g. 1%)
};

/// One number of a parameter: the field of DelayConfig it sets and its range.
struct DelayPart {
  std::string name{};  ///< its name in a parameter of several numbers ("p_gb"), else ""
  double DelayConfig::*field = nullptr;
  DelayQuantity quantity = DelayQuantity::kDuration;
  double lo = 0.0;
  double hi = 0.0;
  bool lo_open = false;    ///< the range is (lo, hi]
  std::string why_open{};  ///< why lo is excluded, for the refusal
};

/// What a parameter holds.
enum class DelayParamKind : std::uint8_t {
  kNumbers,  ///< one or more DelayParts
  kChoice,   ///< the jitter distribution
  kSwitch,   ///< a flag without a value that sets a bool (YAML: true or false)
  kCount,    ///< a whole number within [lo, hi]
};

/// One parameter of DelayConfig, declared once (see the file comment).
struct DelayParam {
  std::string key{};   ///< key in a delay mapping
  std::string flag{};  ///< teleop_master's flag
  std::string help{};
  std::string example{};  ///< a flag value, shown in refusals of a malformed value
  DelayParamKind kind = DelayParamKind::kNumbers;
  std::vector<DelayPart> parts{};               ///< kNumbers
  bool DelayConfig::*enable = nullptr;          ///< kNumbers: set when given (may be null); kSwitch
  JitterDist DelayConfig::*choice = nullptr;    ///< kChoice
  std::uint64_t DelayConfig::*count = nullptr;  ///< kCount
  double lo = 0.0, hi = 0.0;                    ///< kCount: the range

  /// The units of the numbers ("s", "-", "s, s, -"), "" for a choice, a switch or a count.
  std::string unit_text() const;
  /// The allowed values as the docs write them ("[0, 10]", "uniform, normal", "at [0, 1e6], ...").
  std::string allowed_text() const;
  /// The parameter's value in `c`, as YAML writes it ("0.05", "[0, 1]", "uniform", "false").
  std::string text(const DelayConfig& c) const;
  /// The flag's --help: the help, the unit and the allowed values.
  std::string flag_help() const;
  /// Checks the fields of `c` the parameter sets (where `enable` is false: nothing).
  /// @throws ConfigError "delay channel: KEY = VALUE is out of the allowed range [lo, hi]".
  void check(const DelayConfig& c) const;
  /// Sets the fields of `c` from the flag's text (a switch: `text` is not used), checked.
  /// @throws ConfigError "command line: FLAG 'TEXT' ..." naming the allowed values.
  void apply_flag(const std::string& text, DelayConfig& c) const;
  /// Sets the fields of `c` from the key of the delay mapping `node`, if given, checked.
  /// @throws ConfigError naming the file, the field path, the value and the allowed values.
  void read(const config::Node& node, DelayConfig& c) const;
};

/// Every parameter, in the order of the docs' table.
const std::vector<DelayParam>& delay_param_table();
/// The entry with key `key`. @throws std::out_of_range when there is none.
const DelayParam& delay_param(const std::string& key);
/// The entry whose flag is `flag`, or nullptr.
const DelayParam* delay_param_of_flag(const std::string& flag);

/// The table as markdown (key, flag, unit, default, range, help), one row a parameter, ending
/// with a newline: what `teleop_master --print-delay-parameters` prints and docs/configuration.md
/// holds between `<!-- delay-parameters -->` and `<!-- /delay-parameters -->`.
std::string delay_params_markdown();

}  // namespace teleop::master

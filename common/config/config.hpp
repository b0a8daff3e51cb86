#pragma once
// Typed configuration loading with validation at the edge.
//
// Every error names the file, the field path, the offending value and the allowed
// range, so a user can fix it without reading code. Loaders throw ConfigError; the
// executables catch it, print it and exit with status 2.

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace teleop::config {

/// A configuration or command-line mistake. what() is a complete user-facing message.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A YAML node together with the file it came from and its field path ("scene.sphere.radius_m").
/// Accessors validate type and range and throw ConfigError naming file, field, value, range.
class Node {
 public:
  Node(const YAML::Node& node, std::string file, std::string path);

  /// Largest file load_file() reads [bytes].
  static constexpr std::size_t kMaxFileBytes = std::size_t{16} << 20;

  /// Loads a YAML file. @throws ConfigError if it is a directory, cannot be read, is larger
  /// than kMaxFileBytes, or does not parse; and for what YAML itself lets pass: a key given
  /// twice in one mapping, a key that is not a plain scalar, an empty (null) mapping value,
  /// more than one document, nesting deeper than 64 levels. The message names the file, the
  /// field path and the line. An empty file (or one with only comments) loads as an empty
  /// document (empty_document() true): the loader decides whether that is acceptable.
  static Node load_file(const std::string& file);
  /// Parses YAML text with the same checks; `file` is used only in messages.
  static Node parse(const std::string& text, const std::string& file = "<string>");

  /// True when the document holds nothing (empty file, only comments, /dev/null).
  bool empty_document() const;

  bool has(const std::string& key) const;
  /// Child mapping entry; throws if missing.
  Node at(const std::string& key) const;
  /// Child entry or an undefined node (has() false) when missing.
  Node child(const std::string& key) const;
  /// Sequence element.
  Node at(std::size_t index) const;
  std::size_t size() const;
  bool is_map() const { return node_.IsMap(); }
  bool is_sequence() const { return node_.IsSequence(); }
  bool defined() const { return node_.IsDefined() && !node_.IsNull(); }

  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }
  const YAML::Node& raw() const { return node_; }

  /// Required number within [lo, hi].
  double number(const std::string& key, double lo, double hi) const;
  /// Required number within (0, hi]: above zero, as a step, a tolerance or a budget must be.
  double positive_number(const std::string& key, double hi) const;
  /// True if `key` holds the scalar `text` (e.g. "auto" where a number or a name may stand).
  bool is_text(const std::string& key, const std::string& text) const;
  /// Optional number within [lo, hi]; `fallback` when the key is missing.
  double number_or(const std::string& key, double fallback, double lo, double hi) const;
  /// Required integer within [lo, hi].
  long long integer(const std::string& key, long long lo, long long hi) const;
  long long integer_or(const std::string& key, long long fallback, long long lo,
                       long long hi) const;
  bool boolean_or(const std::string& key, bool fallback) const;
  std::string string(const std::string& key) const;
  std::string string_or(const std::string& key, const std::string& fallback) const;
  /// A string that must be one of `allowed`.
  std::string choice(const std::string& key, const std::vector<std::string>& allowed) const;
  std::string choice_or(const std::string& key, const std::string& fallback,
                        const std::vector<std::string>& allowed) const;
  /// A fixed-length list of numbers, each within [lo, hi].
  std::vector<double> numbers(const std::string& key, std::size_t count, double lo,
                              double hi) const;
  std::vector<double> numbers_or(const std::string& key, const std::vector<double>& fallback,
                                 double lo, double hi) const;

  /// Throws if the mapping has keys not in `known` (catches typos such as "radus_m"), or if the
  /// node is given but is not a mapping (`physics: 5`). Does nothing for a missing node.
  void reject_unknown_keys(const std::set<std::string>& known) const;

  /// Builds "<file>: field '<path>': <what>" for custom checks.
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;

 private:
  std::string field(const std::string& key) const;
  YAML::Node node_;
  std::string file_;
  std::string path_;
};

/// A number as the parameter tables write it: shortest of %g, exponent without "+" or leading
/// zeros ("1e6", "0.001", "1e-4" as "0.0001").
std::string param_number_text(double v);

/// Formats a range for messages and help texts: "[lo, hi]", each as param_number_text() writes
/// it ("[0, 1e6]").
std::string range_text(double lo, double hi);

/// Checks a field of a settings struct already read (from a file, flags or a live request):
/// throws ConfigError "OWNER: FIELD = VALUE is out of the allowed range [lo, hi]".
double check_range(const std::string& owner, const std::string& field, double value, double lo,
                   double hi);

/// Checks a command-line numeric flag; throws ConfigError naming the flag, value and range.
/// A negative zero is refused where the range starts at 0 or above (`--duration -0`).
double check_flag(const std::string& flag, double value, double lo, double hi);

/// Parses the whole of `text` as a finite number within [lo, hi] (no empty text, no trailing
/// characters such as "3x", no leading blanks, no "-0" where lo >= 0, no NaN or infinity).
/// @throws ConfigError "command line: <flag> '<text>' ..." naming the allowed range.
double parse_number(const std::string& flag, const std::string& text, double lo, double hi);
/// The same for a whole number within [lo, hi] ("1.5", "1e3" are refused).
long long parse_integer(const std::string& flag, const std::string& text, long long lo,
                        long long hi);
/// Exactly `count` numbers separated by commas ("x,y,z"), each parsed as parse_number() with the
/// per-component range [lo[i], hi[i]] (`lo`, `hi` of size `count`).
/// @throws ConfigError naming the flag, the text, the expected count and the range.
std::vector<double> parse_numbers(const std::string& flag, const std::string& text,
                                  std::size_t count, const std::vector<double>& lo,
                                  const std::vector<double>& hi);
/// Problem with `text` as a number in [lo, hi] (integer: whole numbers only), or "" when it is
/// fine. The message starts with the quoted text: "'-1' is out of the allowed range [0, 10]".
std::string number_problem(const std::string& text, double lo, double hi, bool integer);

/// Checks that `file` can be read as a file without blocking: a regular file, or /dev/null (an
/// empty input). A FIFO, socket, device or directory is refused (reading one may block forever
/// or never end). `what` names the role in the message ("scene", "recording").
/// @throws ConfigError "<file>: <what> is a FIFO, not a regular file".
void require_regular_file(const std::string& file, const std::string& what);

/// Parses durations such as "50ms", "0.2s", "150us", "3" (seconds); throws ConfigError.
double parse_duration_s(const std::string& flag, const std::string& text);
/// Parses "1%", "0.01"; returns a probability in [0, 1]; throws ConfigError.
double parse_probability(const std::string& flag, const std::string& text);

}  // namespace teleop::config

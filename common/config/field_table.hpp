#pragma once
// A table of the plain fields of one YAML mapping, each declared once: its key, unit, help and
// range, and how to reach the field of the struct the mapping fills; its default is the
// struct's. The loader reads the mapping with it (read_fields), its known keys come from it
// (field_keys), and the docs' table is printed from it (fields_markdown), so a program's
// `--print-...` output is what the docs hold. Fields with rules beyond a range (one field
// bounded by another, a list of mappings, a choice that changes other defaults) stay in the
// loader's code; the table holds their plain part.
//
//   static const std::vector<FieldParam<Plane>> planes = {
//       {.key = "friction", .unit = "-", .help = "Coulomb coefficient", .hi = 5.0,
//        .number = TELEOP_FIELD(Plane, friction)}};
//   read_fields(node, planes, plane);
#include <Eigen/Core>

#include <set>
#include <string>
#include <vector>

#include "common/config/config.hpp"

/// A captureless accessor of `S::member` (or a nested member, `tool.mass_kg`) for FieldParam.
// S names a type, which cannot stand in parentheses
#define TELEOP_FIELD(S, member) \
  ([](S & s) -> auto& { return s.member; })  // NOLINT(bugprone-macro-parentheses)

namespace teleop::config {

/// One field of a mapping that fills an S: set exactly one of number, integer, flag, point.
template <class S>
struct FieldParam {
  std::string key{};   ///< key in the mapping
  std::string unit{};  ///< "N/m", "-" for a ratio, "" for a boolean
  std::string help{};
  double lo = 0.0;  ///< number, point: smallest allowed value (each component)
  double hi = 0.0;  ///< number, point: largest allowed value (each component)
  /// number: the field holds the file's value times this (e.g. degrees in the file, radians in
  /// the field); lo, hi and the docs are in the file's unit.
  double scale = 1.0;
  double& (*number)(S&) = nullptr;
  int& (*integer)(S&) = nullptr;  ///< a whole number within [lo, hi]
  bool& (*flag)(S&) = nullptr;
  Eigen::Vector3d& (*point)(S&) = nullptr;

  /// Sets the field from `node`'s key when given (the field's value otherwise stays).
  /// @throws ConfigError naming the file, the field path, the value and the range.
  void read(const Node& node, S& s) const {
    if (number != nullptr) {
      number(s) = node.number_or(key, number(s) / scale, lo, hi) * scale;
    } else if (integer != nullptr) {
      integer(s) = static_cast<int>(
          node.integer_or(key, integer(s), static_cast<long long>(lo), static_cast<long long>(hi)));
    } else if (flag != nullptr) {
      flag(s) = node.boolean_or(key, flag(s));
    } else {
      Eigen::Vector3d& p = point(s);
      const std::vector<double> v = node.numbers_or(key, {p.x(), p.y(), p.z()}, lo, hi);
      p = Eigen::Vector3d(v[0], v[1], v[2]);
    }
  }
  /// The field's value in `s` as YAML writes it ("400", "true", "[0, 0, -9.81]").
  std::string text(S s) const {
    if (number != nullptr) return param_number_text(number(s) / scale);
    if (integer != nullptr) return std::to_string(integer(s));
    if (flag != nullptr) return flag(s) ? "true" : "false";
    const Eigen::Vector3d& p = point(s);
    return "[" + param_number_text(p.x()) + ", " + param_number_text(p.y()) + ", " +
           param_number_text(p.z()) + "]";
  }
  /// The allowed values as the docs write them ("[0, 1e6]", "each in [-100, 100]").
  std::string allowed_text() const {
    if (flag != nullptr) return "true, false";
    const std::string range = "[" + param_number_text(lo) + ", " + param_number_text(hi) + "]";
    if (integer != nullptr) return range + ", whole";
    return point != nullptr ? "each in " + range : range;
  }
};

/// Reads every field of `table` the mapping `node` gives into `s`.
template <class S>
void read_fields(const Node& node, const std::vector<FieldParam<S>>& table, S& s) {
  for (const FieldParam<S>& f : table) f.read(node, s);
}

/// The keys of `table` and `more` (the mapping's keys the loader reads itself).
template <class S>
std::set<std::string> field_keys(const std::vector<FieldParam<S>>& table,
                                 std::initializer_list<const char*> more = {}) {
  std::set<std::string> keys(more.begin(), more.end());
  for (const FieldParam<S>& f : table) keys.insert(f.key);
  return keys;
}

/// Rows of the docs' table (field, unit, default, range, help) for `table`, each field written
/// `prefix` + key ("tool.mass_kg"), defaults from `defaults`, ending with a newline.
template <class S>
std::string fields_markdown_rows(const std::string& prefix, const std::vector<FieldParam<S>>& table,
                                 const S& defaults) {
  std::string md;
  for (const FieldParam<S>& f : table) {
    md += "| `" + prefix + f.key + "` | " + f.unit + " | " + f.text(defaults) + " | " +
          f.allowed_text() + " | " + f.help + " |\n";
  }
  return md;
}

/// The header of the docs' table of fields_markdown_rows().
inline std::string fields_markdown_header() {
  return "| field | unit | default | range | help |\n|---|---|---|---|---|\n";
}

}  // namespace teleop::config

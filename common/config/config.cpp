#include "common/config/config.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

namespace teleop::config {

namespace {
std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

std::string where(const std::string& path) { return path.empty() ? "<root>" : path; }

// A short, bounded rendering of a node for messages. yaml-cpp's own emitter follows aliases
// without a limit (a self-referencing alias never ends), so this one stops at a depth and a
// length.
void short_text(const YAML::Node& n, int depth, std::string& out) {
  constexpr std::size_t kMaxChars = 80;
  if (out.size() > kMaxChars) return;
  if (!n.IsDefined() || n.IsNull()) {
    out += "~";
  } else if (n.IsScalar()) {
    out += n.Scalar();
  } else if (depth >= 3) {
    out += n.IsSequence() ? "[...]" : "{...}";
  } else if (n.IsSequence()) {
    out += "[";
    std::size_t i = 0;
    for (const auto& e : n) {
      if (i++ > 0) out += ", ";
      if (out.size() > kMaxChars) break;
      short_text(e, depth + 1, out);
    }
    out += "]";
  } else if (n.IsMap()) {
    out += "{";
    std::size_t i = 0;
    for (const auto& kv : n) {
      if (i++ > 0) out += ", ";
      if (out.size() > kMaxChars) break;
      short_text(kv.first, depth + 1, out);
      out += ": ";
      short_text(kv.second, depth + 1, out);
    }
    out += "}";
  }
  if (depth == 0 && out.size() > kMaxChars) out = out.substr(0, kMaxChars) + "...";
}

std::string scalar_text(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "<missing>";
  std::string s;
  short_text(n, 0, s);
  return "'" + s + "'";
}

std::string line_text(const YAML::Mark& m) {
  return m.is_null() ? std::string("?") : std::to_string(m.line + 1);
}

// The checks yaml-cpp does not make, over the whole parsed tree: every mapping key is a plain
// scalar given once (yaml-cpp keeps duplicates and node[key] silently returns the first), no
// mapping value is empty (`physics: ~` or `physics:` would otherwise mean "use the defaults"),
// and nesting stays shallow. Each collection is visited once (aliases share nodes; a
// self-referencing alias or a "billion laughs" document would otherwise never finish).
void check_tree(const YAML::Node& n, const std::string& file, const std::string& path, int depth,
                std::set<std::size_t>& visited) {
  constexpr int kMaxDepth = 64;
  if (!n.IsMap() && !n.IsSequence()) return;
  if (!visited.insert(static_cast<std::size_t>(n.Mark().pos)).second) return;
  if (depth > kMaxDepth) {
    throw ConfigError(file + ": field '" + where(path) + "' (line " + line_text(n.Mark()) +
                      "): nested deeper than " + std::to_string(kMaxDepth) + " levels");
  }
  if (n.IsSequence()) {
    std::size_t i = 0;
    for (const auto& e : n) {
      check_tree(e, file, path + "[" + std::to_string(i++) + "]", depth + 1, visited);
    }
    return;
  }
  std::map<std::string, YAML::Mark> seen;
  for (const auto& kv : n) {
    if (!kv.first.IsScalar()) {
      throw ConfigError(file + ": field '" + where(path) + "' (line " + line_text(kv.first.Mark()) +
                        "): key " + scalar_text(kv.first) +
                        " is not a plain name; keys are field names such as 'radius_m'");
    }
    const std::string key = kv.first.Scalar();
    const std::string field = join(path, key);
    const auto [it, fresh] = seen.emplace(key, kv.first.Mark());
    if (!fresh) {
      throw ConfigError(file + ": field '" + field + "' is given twice (lines " +
                        line_text(it->second) + " and " + line_text(kv.first.Mark()) + "; value " +
                        scalar_text(n[key]) + " and " + scalar_text(kv.second) +
                        "): YAML would silently keep one of them; remove the other");
    }
    if (!kv.second.IsDefined() || kv.second.IsNull()) {
      throw ConfigError(file + ": field '" + field + "' (line " + line_text(kv.first.Mark()) +
                        "): value is empty (null); give a value or remove the key to use the "
                        "default");
    }
    check_tree(kv.second, file, field, depth + 1, visited);
  }
}

// Byte offset of the first byte that is not part of valid UTF-8 (or a control character other
// than tab, newline and carriage return), or npos. YAML files are UTF-8 text; Debian's
// yaml-cpp 0.7 can spin on some invalid byte sequences (found by tests/fuzz: 9 bytes hung it
// for more than 13 s), so such files are refused before the parser sees them.
std::size_t first_invalid_byte(const std::string& text) {
  const auto* p = reinterpret_cast<const unsigned char*>(text.data());
  const std::size_t n = text.size();
  std::size_t i = 0;
  while (i < n) {
    const unsigned char c = p[i];
    if (c < 0x80) {
      if (c < 0x20 && c != '\t' && c != '\n' && c != '\r') return i;
      if (c == 0x7f) return i;
      ++i;
      continue;
    }
    int len = 0;
    std::uint32_t cp = 0;
    if ((c & 0xe0) == 0xc0) {
      len = 2;
      cp = c & 0x1f;
    } else if ((c & 0xf0) == 0xe0) {
      len = 3;
      cp = c & 0x0f;
    } else if ((c & 0xf8) == 0xf0) {
      len = 4;
      cp = c & 0x07;
    } else {
      return i;
    }
    if (i + len > n) return i;
    for (int k = 1; k < len; ++k) {
      if ((p[i + k] & 0xc0) != 0x80) return i;
      cp = (cp << 6) | (p[i + k] & 0x3f);
    }
    // overlong forms, surrogates and code points beyond U+10FFFF are not UTF-8
    if ((len == 2 && cp < 0x80) || (len == 3 && cp < 0x800) || (len == 4 && cp < 0x10000) ||
        (cp >= 0xd800 && cp <= 0xdfff) || cp > 0x10ffff) {
      return i;
    }
    i += len;
  }
  return std::string::npos;
}

// Where a text leaves the YAML subset configuration files use, and why (offset npos: it does
// not). Debian's yaml-cpp 0.7 spins or allocates without end on some malformed inputs that
// tests/fuzz keeps finding ("!visual_ra,e_hz", a file starting with ", a", '""&?ra"?"ar"kd,us_l'),
// so rather than chase them one by one, the parser only sees text within this subset:
//   block mappings and sequences, flow [ ] and { } (balanced), plain scalars, quoted scalars
//   closed on the line they open and followed only by ':', ',', ']', '}', a comment or the end
//   of the line, comments; no tags (!), anchors (&), aliases (*), complex keys (?), block
//   scalars (| >), directives (%), reserved indicators (@ `) and no ',' outside [ ] / { }.
struct SubsetError {
  std::size_t offset = std::string::npos;
  const char* why = "";
};

SubsetError first_outside_subset(const std::string& text) {
  constexpr std::size_t kMaxFlowDepth = 8;
  std::size_t flow = 0;     // depth of [ ] and { }
  char prev = '\n';         // the previous character outside quotes ('\n' at a line start)
  bool prev_starts = true;  // whether `prev` itself started a token (a "- " sequence entry)
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const bool token_start =
        std::strchr(" \t\n\r[{,:", prev) != nullptr || (prev == '-' && prev_starts);
    prev_starts = token_start;
    if (c == '\n') {
      prev = c;
      continue;
    }
    if (c == '#' && (prev == ' ' || prev == '\t' || prev == '\n')) {
      while (i + 1 < text.size() && text[i + 1] != '\n') ++i;  // a comment runs to the line end
      prev = ' ';
      prev_starts = true;
      continue;
    }
    if ((c == '\'' || c == '"') && token_start) {
      const std::size_t open = i;
      bool closed = false;
      for (++i; i < text.size() && text[i] != '\n'; ++i) {
        if (c == '"' && text[i] == '\\') {
          ++i;  // an escaped character
        } else if (text[i] == c) {
          if (c == '\'' && i + 1 < text.size() && text[i + 1] == '\'') {
            ++i;  // '' inside single quotes is one quote
          } else {
            closed = true;
            break;
          }
        }
      }
      if (!closed) return {open, "a quoted value is not closed on its line"};
      std::size_t j = i + 1;
      while (j < text.size() && (text[j] == ' ' || text[j] == '\t')) ++j;
      if (j < text.size() && !std::strchr(":,]}\r\n", text[j]) && !(text[j] == '#' && j > i + 1)) {
        return {j, "a quoted value is followed by more text; quote the whole value"};
      }
      prev = c;
      continue;
    }
    if (token_start && std::strchr("!&*?|>%@`", c) && c != '\0') {
      return {i,
              "a YAML tag, anchor, alias, complex key, block scalar or directive; quote the "
              "value if the character is meant literally"};
    }
    if (c == ',' && flow == 0 && (token_start || prev == '"' || prev == '\'')) {
      return {i, "a ',' outside [ ] or { }; quote the value if it is meant literally"};
    }
    if (c == '[' || c == '{') {
      if (++flow > kMaxFlowDepth) return {i, "[ ] / { } nested more than 8 deep"};
    } else if (c == ']' || c == '}') {
      if (flow == 0) return {i, "a closing ']' or '}' without its opening one"};
      --flow;
    }
    prev = c;
  }
  if (flow > 0) return {text.size(), "a [ ] or { } collection is not closed"};
  return {};
}

// Parses one YAML document from `text`; refuses several documents and the tree checks above.
YAML::Node parse_checked(const std::string& text, const std::string& file) {
  if (const std::size_t bad = first_invalid_byte(text); bad != std::string::npos) {
    const std::size_t line =
        1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + bad, '\n'));
    char byte[8];
    std::snprintf(byte, sizeof(byte), "0x%02x", static_cast<unsigned char>(text[bad]));
    throw ConfigError(file + ": byte " + std::to_string(bad) + " (line " + std::to_string(line) +
                      ") is " + byte +
                      ", not valid UTF-8 text or a control character; a "
                      "configuration file is UTF-8 YAML");
  }
  if (const SubsetError bad = first_outside_subset(text); bad.offset != std::string::npos) {
    const std::size_t line =
        1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + bad.offset, '\n'));
    throw ConfigError(file + ": line " + std::to_string(line) + " (byte " +
                      std::to_string(bad.offset) +
                      ") is outside the YAML subset configuration "
                      "files use: " +
                      bad.why);
  }
  std::vector<YAML::Node> docs;
  try {
    docs = YAML::LoadAll(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(file + ": YAML syntax error at line " + std::to_string(e.mark.line + 1) +
                      ", column " + std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  if (docs.size() > 1) {
    throw ConfigError(file + ": holds " + std::to_string(docs.size()) +
                      " YAML documents (separated by '---'); a configuration file is one");
  }
  if (docs.empty()) return YAML::Node(YAML::NodeType::Null);
  std::set<std::size_t> visited;
  check_tree(docs[0], file, "", 0, visited);
  return docs[0];
}
}  // namespace

std::string range_text(double lo, double hi) {
  return "[" + param_number_text(lo) + ", " + param_number_text(hi) + "]";
}

Node::Node(const YAML::Node& node, std::string file, std::string path)
    : node_(node), file_(std::move(file)), path_(std::move(path)) {}

Node Node::load_file(const std::string& file) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    throw ConfigError(file + ": is a directory, not a YAML file");
  }
  // a FIFO or device could block or never end (a missing file: "cannot open" below)
  if (std::filesystem::exists(file, ec)) require_regular_file(file, "YAML file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(file + ": cannot open the file for reading");
  std::string text;
  char buf[65536];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    text.append(buf, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxFileBytes) {
      throw ConfigError(file + ": larger than " + std::to_string(kMaxFileBytes >> 20) +
                        " MB; not a configuration file");
    }
  }
  if (in.bad()) throw ConfigError(file + ": read error");
  return Node(parse_checked(text, file), file, "");
}

Node Node::parse(const std::string& text, const std::string& file) {
  return Node(parse_checked(text, file), file, "");
}

bool Node::empty_document() const { return !node_.IsDefined() || node_.IsNull(); }

std::string Node::field(const std::string& key) const {
  return key.empty() ? where(path_) : join(path_, key);
}

void Node::fail(const std::string& key, const std::string& what) const {
  throw ConfigError(file_ + ": field '" + field(key) + "': " + what);
}

bool Node::has(const std::string& key) const {
  if (!node_.IsMap()) return false;
  const YAML::Node c = node_[key];
  return c.IsDefined() && !c.IsNull();
}

Node Node::at(const std::string& key) const {
  if (!node_.IsMap()) {
    throw ConfigError(file_ + ": field '" + (path_.empty() ? "<root>" : path_) +
                      "' must be a mapping (looking for '" + key + "')");
  }
  if (!has(key)) fail(key, "is required but missing");
  return Node(node_[key], file_, field(key));
}

Node Node::child(const std::string& key) const {
  if (!node_.IsMap()) return Node(YAML::Node(), file_, field(key));
  return Node(node_[key], file_, field(key));
}

Node Node::at(std::size_t index) const {
  if (!node_.IsSequence() || index >= node_.size()) {
    throw ConfigError(file_ + ": field '" + path_ + "': no element " + std::to_string(index));
  }
  return Node(node_[index], file_, path_ + "[" + std::to_string(index) + "]");
}

std::size_t Node::size() const { return node_.IsSequence() || node_.IsMap() ? node_.size() : 0; }

double Node::number(const std::string& key, double lo, double hi) const {
  const Node c = at(key);
  double v = 0.0;
  try {
    v = c.node_.as<double>();
  } catch (const YAML::Exception&) {
    fail(key,
         "value " + scalar_text(c.node_) + " is not a number; allowed range " + range_text(lo, hi));
  }
  if (!std::isfinite(v) || v < lo || v > hi) {
    fail(key,
         "value " + scalar_text(c.node_) + " is out of the allowed range " + range_text(lo, hi));
  }
  return v;
}

double Node::positive_number(const std::string& key, double hi) const {
  const Node c = at(key);
  std::ostringstream range;
  range << "(0, " << hi << "]";
  double v = 0.0;
  try {
    v = c.node_.as<double>();
  } catch (const YAML::Exception&) {
    fail(key, "value " + scalar_text(c.node_) + " is not a number; allowed range " + range.str());
  }
  if (!std::isfinite(v) || v <= 0.0 || v > hi) {
    fail(key, "value " + scalar_text(c.node_) + " is out of the allowed range " + range.str());
  }
  return v;
}

bool Node::is_text(const std::string& key, const std::string& text) const {
  if (!has(key)) return false;
  const YAML::Node c = node_[key];
  return c.IsScalar() && c.Scalar() == text;
}

double Node::number_or(const std::string& key, double fallback, double lo, double hi) const {
  return has(key) ? number(key, lo, hi) : fallback;
}

long long Node::integer(const std::string& key, long long lo, long long hi) const {
  const Node c = at(key);
  long long v = 0;
  try {
    v = c.node_.as<long long>();
  } catch (const YAML::Exception&) {
    fail(key, "value " + scalar_text(c.node_) + " is not an integer; allowed range " +
                  range_text(static_cast<double>(lo), static_cast<double>(hi)));
  }
  if (v < lo || v > hi) {
    fail(key, "value " + scalar_text(c.node_) + " is out of the allowed range " +
                  range_text(static_cast<double>(lo), static_cast<double>(hi)));
  }
  return v;
}

long long Node::integer_or(const std::string& key, long long fallback, long long lo,
                           long long hi) const {
  return has(key) ? integer(key, lo, hi) : fallback;
}

bool Node::boolean_or(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const Node c = at(key);
  try {
    return c.node_.as<bool>();
  } catch (const YAML::Exception&) {
    fail(key, "value " + scalar_text(c.node_) + " is not a boolean (true or false)");
  }
}

std::string Node::string(const std::string& key) const {
  const Node c = at(key);
  if (!c.node_.IsScalar()) fail(key, "value " + scalar_text(c.node_) + " is not a string");
  return c.node_.Scalar();
}

std::string Node::string_or(const std::string& key, const std::string& fallback) const {
  return has(key) ? string(key) : fallback;
}

std::string Node::choice(const std::string& key, const std::vector<std::string>& allowed) const {
  const std::string v = string(key);
  for (const auto& a : allowed) {
    if (a == v) return v;
  }
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
  fail(key, "value '" + v + "' is not one of {" + list + "}");
}

std::string Node::choice_or(const std::string& key, const std::string& fallback,
                            const std::vector<std::string>& allowed) const {
  return has(key) ? choice(key, allowed) : fallback;
}

std::vector<double> Node::numbers(const std::string& key, std::size_t count, double lo,
                                  double hi) const {
  const Node c = at(key);
  if (!c.node_.IsSequence() || c.node_.size() != count) {
    fail(key, "value " + scalar_text(c.node_) + " must be a list of " + std::to_string(count) +
                  " numbers, each in " + range_text(lo, hi));
  }
  std::vector<double> out(count);
  for (std::size_t i = 0; i < count; ++i) {
    double v = 0.0;
    try {
      v = c.node_[i].as<double>();
    } catch (const YAML::Exception&) {
      fail(key, "element " + std::to_string(i) + " " + scalar_text(c.node_[i]) +
                    " is not a number; allowed range " + range_text(lo, hi));
    }
    if (!std::isfinite(v) || v < lo || v > hi) {
      fail(key, "element " + std::to_string(i) + " " + scalar_text(c.node_[i]) +
                    " is out of the allowed range " + range_text(lo, hi));
    }
    out[i] = v;
  }
  return out;
}

std::vector<double> Node::numbers_or(const std::string& key, const std::vector<double>& fallback,
                                     double lo, double hi) const {
  return has(key) ? numbers(key, fallback.size(), lo, hi) : fallback;
}

void Node::reject_unknown_keys(const std::set<std::string>& known) const {
  if (!defined()) return;
  if (!node_.IsMap()) {
    std::string list;
    for (const auto& a : known) list += (list.empty() ? "" : ", ") + a;
    throw ConfigError(file_ + ": field '" + where(path_) + "': value " + scalar_text(node_) +
                      " must be a mapping of the fields {" + list + "}");
  }
  for (const auto& kv : node_) {
    if (!kv.first.IsScalar()) fail("", "key " + scalar_text(kv.first) + " is not a plain name");
    const std::string k = kv.first.Scalar();
    if (!known.count(k)) {
      std::string list;
      for (const auto& a : known) list += (list.empty() ? "" : ", ") + a;
      fail(k, "unknown field; known fields here are {" + list + "}");
    }
  }
}

double check_range(const std::string& owner, const std::string& field, double value, double lo,
                   double hi) {
  if (!(value >= lo && value <= hi)) {
    std::ostringstream os;
    os << owner << ": " << field << " = " << value << " is out of the allowed range "
       << range_text(lo, hi);
    throw ConfigError(os.str());
  }
  return value;
}

double check_flag(const std::string& flag, double value, double lo, double hi) {
  if (!std::isfinite(value) || value < lo || value > hi || (lo >= 0.0 && std::signbit(value))) {
    std::ostringstream os;
    os << "command line: " << flag << " " << value << " is out of the allowed range "
       << range_text(lo, hi);
    throw ConfigError(os.str());
  }
  return value;
}

std::string number_problem(const std::string& text, double lo, double hi, bool integer) {
  const std::string quoted = "'" + text + "'";
  const std::string range = " (allowed range " + range_text(lo, hi) + ")";
  if (text.empty()) return "'' is empty, not a number" + range;
  if (std::isspace(static_cast<unsigned char>(text.front())) ||
      std::isspace(static_cast<unsigned char>(text.back()))) {
    return quoted + " has blanks around the number" + range;
  }
  double v = 0.0;
  std::size_t pos = 0;
  try {
    v = std::stod(text, &pos);
  } catch (const std::out_of_range&) {
    return quoted + " is too large" + range;
  } catch (const std::exception&) {
    return quoted + " is not a number" + range;
  }
  if (pos != text.size())
    return quoted + " is not a number (it ends in '" + text.substr(pos) + "')" + range;
  if (!std::isfinite(v)) return quoted + " is not a finite number" + range;
  if (integer && (v != std::floor(v) || text.find_first_of(".eExX") != std::string::npos)) {
    return quoted + " is not a whole number" + range;
  }
  if (v < lo || v > hi) return quoted + " is out of the allowed range " + range_text(lo, hi);
  if (lo >= 0.0 && text.front() == '-') {
    return quoted + " is negative; the allowed range is " + range_text(lo, hi);
  }
  return "";
}

double parse_number(const std::string& flag, const std::string& text, double lo, double hi) {
  const std::string problem = number_problem(text, lo, hi, false);
  if (!problem.empty()) throw ConfigError("command line: " + flag + " " + problem);
  return std::stod(text);
}

long long parse_integer(const std::string& flag, const std::string& text, long long lo,
                        long long hi) {
  const std::string problem =
      number_problem(text, static_cast<double>(lo), static_cast<double>(hi), true);
  if (!problem.empty()) throw ConfigError("command line: " + flag + " " + problem);
  return std::stoll(text);
}

std::vector<double> parse_numbers(const std::string& flag, const std::string& text,
                                  std::size_t count, const std::vector<double>& lo,
                                  const std::vector<double>& hi) {
  std::vector<std::string> parts(1);
  for (char c : text) {
    if (c == ',') {
      parts.emplace_back();
    } else {
      parts.back() += c;
    }
  }
  std::string ranges;
  for (std::size_t i = 0; i < count; ++i) {
    ranges += (i ? ", " : "") + range_text(lo.at(i), hi.at(i));
  }
  if (parts.size() != count) {
    throw ConfigError("command line: " + flag + " '" + text + "' has " +
                      std::to_string(parts.size()) + " component(s); exactly " +
                      std::to_string(count) + " numbers separated by commas are needed, in " +
                      ranges);
  }
  std::vector<double> out(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::string problem = number_problem(parts[i], lo[i], hi[i], false);
    if (!problem.empty()) {
      throw ConfigError("command line: " + flag + " '" + text + "': component " +
                        std::to_string(i + 1) + " " + problem);
    }
    out[i] = std::stod(parts[i]);
  }
  return out;
}

void require_regular_file(const std::string& file, const std::string& what) {
  if (file.empty()) throw ConfigError("'': the " + what + " file name is empty");
  std::error_code ec;
  const auto st = std::filesystem::status(file, ec);
  if (ec || !std::filesystem::exists(st)) {
    throw ConfigError(file + ": " + what + " file does not exist");
  }
  if (std::filesystem::is_regular_file(st)) return;
  // /dev/null reads as an empty file (std::filesystem::equivalent refuses two devices)
  if (std::filesystem::canonical(file, ec) == "/dev/null" && !ec) return;
  const char* kind = std::filesystem::is_directory(st)        ? "a directory"
                     : std::filesystem::is_fifo(st)           ? "a FIFO"
                     : std::filesystem::is_socket(st)         ? "a socket"
                     : std::filesystem::is_character_file(st) ? "a character device"
                     : std::filesystem::is_block_file(st)     ? "a block device"
                                                              : "not a plain file";
  throw ConfigError(file + ": " + what + " is " + kind +
                    ", not a regular file (reading it may block or never end)");
}

double parse_duration_s(const std::string& flag, const std::string& text) {
  std::size_t pos = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &pos);
  } catch (const std::exception&) {
    throw ConfigError("command line: " + flag + " '" + text +
                      "' is not a duration (examples: 50ms, 0.2s, 150us)");
  }
  const std::string unit = text.substr(pos);
  double scale = 1.0;
  if (unit.empty() || unit == "s") {
    scale = 1.0;
  } else if (unit == "ms") {
    scale = 1e-3;
  } else if (unit == "us") {
    scale = 1e-6;
  } else if (unit == "ns") {
    scale = 1e-9;
  } else {
    throw ConfigError("command line: " + flag + " '" + text + "' has unknown unit '" + unit +
                      "' (allowed: s, ms, us, ns)");
  }
  const double s = v * scale;
  if (!std::isfinite(s) || s < 0.0 || (!text.empty() && text.front() == '-')) {
    throw ConfigError("command line: " + flag + " '" + text + "' must be a finite duration >= 0");
  }
  return s;
}

double parse_probability(const std::string& flag, const std::string& text) {
  std::size_t pos = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &pos);
  } catch (const std::exception&) {
    throw ConfigError("command line: " + flag + " '" + text +
                      "' is not a probability (examples: 1%, 0.01)");
  }
  const std::string unit = text.substr(pos);
  if (unit == "%") {
    v /= 100.0;
  } else if (!unit.empty()) {
    throw ConfigError("command line: " + flag + " '" + text + "' has unknown suffix '" + unit +
                      "' (allowed: %, or none)");
  }
  if (!std::isfinite(v) || v < 0.0 || v > 1.0) {
    throw ConfigError("command line: " + flag + " '" + text +
                      "' is out of the allowed range [0, 1] (or [0%, 100%])");
  }
  return v;
}

std::string param_number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", v);
  std::string s = buf;
  const auto e = s.find('e');
  if (e == std::string::npos) return s;
  std::string exponent = s.substr(e + 1);
  std::string sign;
  if (!exponent.empty() && (exponent[0] == '+' || exponent[0] == '-')) {
    if (exponent[0] == '-') sign = "-";
    exponent.erase(0, 1);
  }
  exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
  return s.substr(0, e) + "e" + sign + exponent;
}

}  // namespace teleop::config

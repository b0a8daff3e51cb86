#include "common/util/command_stream.hpp"

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/config/config.hpp"
#include "common/util/files.hpp"

namespace teleop {
namespace {

constexpr const char* kHeader = "receive_ns,source_ns,writer,payload";

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

[[noreturn]] void fail(const std::string& file, std::size_t line, const char* column,
                       const std::string& why) {
  throw config::ConfigError(file + ": line " + std::to_string(line) + ", column '" + column +
                            "': " + why);
}

std::int64_t parse_ns(const std::string& text, const std::string& file, std::size_t line,
                      const char* column) {
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || end != text.c_str() + text.size() || errno != 0 || v < 0) {
    fail(file, line, column, "'" + text + "' is not a time in ns (an integer >= 0)");
  }
  return static_cast<std::int64_t>(v);
}

}  // namespace

std::string to_hex(const std::uint8_t* bytes, std::size_t n) {
  static const char* digits = "0123456789abcdef";
  std::string s(2 * n, '0');
  for (std::size_t i = 0; i < n; ++i) {
    s[2 * i] = digits[bytes[i] >> 4];
    s[2 * i + 1] = digits[bytes[i] & 0xf];
  }
  return s;
}

void write_command_stream(const std::string& path, const std::vector<StreamedCommand>& rows) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw std::runtime_error(path + ": cannot open for writing");
  f << kHeader << "\n";
  for (const StreamedCommand& r : rows) {
    f << r.receive_ns << "," << r.source_ns << "," << r.writer << ","
      << to_hex(r.payload.data(), r.payload.size()) << "\n";
  }
  check_written(f, path);
}

namespace {
/// std::getline with a bound: false at the end of the input; throws past kMaxStreamLineBytes.
bool read_line(std::istream& in, std::string& line, const std::string& file, std::size_t line_no) {
  line.clear();
  std::streambuf* buf = in.rdbuf();
  for (;;) {
    const int c = buf->sbumpc();
    if (c == std::char_traits<char>::eof()) return !line.empty();
    if (c == '\n') return true;
    if (line.size() >= kMaxStreamLineBytes) {
      fail(file, line_no, "<line>",
           "longer than " + std::to_string(kMaxStreamLineBytes) +
               " bytes; not a command stream row");
    }
    line += static_cast<char>(c);
  }
}
}  // namespace

std::vector<StreamedCommand> read_command_stream(const std::string& path) {
  config::require_regular_file(path, "command stream");
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > kMaxStreamFileBytes) {
    throw config::ConfigError(path + ": command stream of " + std::to_string(size) +
                              " bytes; at most " + std::to_string(kMaxStreamFileBytes) +
                              " are read");
  }
  std::ifstream f(path, std::ios::binary);
  if (!f) throw config::ConfigError(path + ": cannot open the command stream for reading");
  std::string line;
  std::size_t line_no = 1;
  if (!read_line(f, line, path, 1) || line != kHeader) {
    fail(path, 1, "<header>", std::string("expected the header '") + kHeader + "'");
  }
  std::vector<StreamedCommand> out;
  while (read_line(f, line, path, line_no + 1)) {
    ++line_no;
    if (line.empty()) continue;
    std::stringstream ss(line);
    std::string fields[4];
    for (std::string& x : fields) std::getline(ss, x, ',');
    StreamedCommand c;
    c.receive_ns = parse_ns(fields[0], path, line_no, "receive_ns");
    c.source_ns = parse_ns(fields[1], path, line_no, "source_ns");
    if (fields[2].size() != 32) fail(path, line_no, "writer", "expected 32 hex digits");
    c.writer = fields[2];
    const std::string& hex = fields[3];
    if (hex.size() < 8 || hex.size() % 2 != 0) {
      fail(path, line_no, "payload", "expected an even number (>= 8) of hex digits");
    }
    c.payload.resize(hex.size() / 2);
    for (std::size_t i = 0; i < c.payload.size(); ++i) {
      const int hi = hex_digit(hex[2 * i]), lo = hex_digit(hex[2 * i + 1]);
      if (hi < 0 || lo < 0) fail(path, line_no, "payload", "not a hex digit");
      c.payload[i] = static_cast<std::uint8_t>(hi * 16 + lo);
    }
    if (!out.empty() && c.receive_ns < out.back().receive_ns) {
      fail(path, line_no, "receive_ns", "goes back in time (rows must be in receive order)");
    }
    out.push_back(std::move(c));
  }
  if (out.empty()) fail(path, line_no, "<rows>", "no commands");
  return out;
}

}  // namespace teleop

#include "common/util/files.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <system_error>

#include "common/config/config.hpp"

namespace teleop {

namespace {
std::mutex& failed_mutex() {
  static std::mutex m;
  return m;
}
std::vector<std::string>& failed_list() {
  static std::vector<std::string> list;
  return list;
}
std::string reason(int err) { return err ? std::strerror(err) : "unknown error"; }
}  // namespace

void write_text_file(const std::string& path, const std::string& text) {
  errno = 0;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error(path + ": cannot write: " + reason(errno));
  const std::size_t n = std::fwrite(text.data(), 1, text.size(), f);
  const int flushed = std::fflush(f);
  const int write_errno = errno;
  const int closed = std::fclose(f);
  if (n != text.size() || flushed != 0 || closed != 0) {
    throw std::runtime_error(path + ": cannot write: " + reason(write_errno ? write_errno : errno));
  }
}

namespace {
/// Makes `dir` and its parents; throws ConfigError starting with `what` on failure.
void make_folder(const std::string& what, const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) {
    throw config::ConfigError(what + ": '" + dir.string() + "' exists and is not a folder");
  }
  if (!fs::is_directory(dir, ec)) {
    fs::create_directories(dir, ec);
    if (ec) {
      throw config::ConfigError(what + ": cannot create the folder '" + dir.string() +
                                "': " + ec.message());
    }
  }
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    throw config::ConfigError(what + ": cannot write into the folder '" + dir.string() +
                              "': " + reason(errno));
  }
}
}  // namespace

void prepare_output_file(const std::string& flag, const std::string& path) {
  namespace fs = std::filesystem;
  const std::string what = "command line: " + flag + " '" + path + "'";
  if (path == "-") return;
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    throw config::ConfigError(what + " is a folder; a file name is needed");
  }
  if (fs::exists(path, ec)) {  // replaced in place (or a device such as /dev/full)
    if (::access(path.c_str(), W_OK) != 0) {
      throw config::ConfigError(what + ": cannot write it: " + reason(errno));
    }
    return;
  }
  const fs::path dir = fs::path(path).parent_path();
  if (!dir.empty()) make_folder(what, dir);
}

void prepare_output_dir(const std::string& flag, const std::string& dir) {
  make_folder("command line: " + flag + " '" + dir + "'", dir);
}

void check_written(std::ostream& out, const std::string& path) {
  errno = 0;
  out.flush();
  if (!out) throw std::runtime_error(path + ": write error: " + reason(errno));
}

std::vector<std::string> failed_writes() {
  std::lock_guard<std::mutex> lock(failed_mutex());
  return failed_list();
}

void note_failed_write(const std::string& message) {
  std::lock_guard<std::mutex> lock(failed_mutex());
  failed_list().push_back(message);
}

}  // namespace teleop

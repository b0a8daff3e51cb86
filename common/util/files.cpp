#include "common/util/files.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <stdexcept>

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

#pragma once
// Child processes for multi-process tests: start an executable with arguments, its output
// captured in files, wait with a timeout, signal it. Every child is killed when the Process
// object is destroyed, so a failing test never leaves processes behind.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/json_fields.hpp"

namespace teleop::test {

class Process {
 public:
  Process(const std::string& exe, const std::vector<std::string>& args, const std::string& tag)
      : out_path_("/tmp/teleop_test_" + tag + "_" + std::to_string(getpid()) + ".out"),
        err_path_("/tmp/teleop_test_" + tag + "_" + std::to_string(getpid()) + ".err") {
    std::fflush(stdout);
    std::fflush(stderr);
    pid_ = fork();
    if (pid_ == 0) {
      if (!freopen(out_path_.c_str(), "w", stdout)) _exit(126);
      if (!freopen(err_path_.c_str(), "w", stderr)) _exit(126);
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(exe.c_str()));
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      execv(exe.c_str(), argv.data());
      _exit(127);
    }
  }
  ~Process() {
    if (running()) {
      kill(pid_, SIGKILL);
      wait_for(5.0);
    }
  }
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  bool running() const { return pid_ > 0 && !done_; }
  pid_t pid() const { return pid_; }
  void signal(int sig) {
    if (running()) kill(pid_, sig);
  }
  /// Waits up to timeout_s; returns the exit status, or -1 on timeout, -2 if killed by a signal.
  int wait_for(double timeout_s) {
    if (done_) return status_;
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
      int st = 0;
      const pid_t r = waitpid(pid_, &st, WNOHANG);
      if (r == pid_) {
        done_ = true;
        status_ = WIFEXITED(st) ? WEXITSTATUS(st) : -2;
        return status_;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return -1;
  }
  std::string out() const { return slurp(out_path_); }
  std::string err() const { return slurp(err_path_); }

  static std::string slurp(const std::string& path) {
    std::ifstream f(path);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
  }

 private:
  pid_t pid_ = -1;
  bool done_ = false;
  int status_ = -1;
  std::string out_path_, err_path_;
};

}  // namespace teleop::test

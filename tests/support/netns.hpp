#pragma once
// A private network of N hosts for multi-host tests: network namespaces "host 1..N", each with
// its own loopback and one veth into a bridge that lives in a namespace of its own (the
// "switch"), so nothing is added to or sent through the machine's own namespace. Host i has
// address 10.77.0.i/24 and a multicast route on its veth. Everything is removed in the
// destructor (processes still running inside are killed first), also when a test fails.
// Needs root (CAP_SYS_ADMIN, CAP_NET_ADMIN) and `ip` (iproute2); otherwise create() returns
// false and why() says why, so the test can skip with that reason.
#include <signal.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace teleop::test {

class NetnsLab {
 public:
  explicit NetnsLab(int hosts) : hosts_(hosts), tag_(std::to_string(getpid())) {}
  ~NetnsLab() { destroy(); }
  NetnsLab(const NetnsLab&) = delete;
  NetnsLab& operator=(const NetnsLab&) = delete;

  /// The `ip` executable, or "" if there is none.
  static std::string ip_binary() {
    for (const char* p : {"/usr/sbin/ip", "/sbin/ip", "/usr/bin/ip", "/bin/ip"}) {
      if (std::filesystem::exists(p)) return p;
    }
    return "";
  }

  /// Builds the network; false (and why()) if this machine does not allow it.
  bool create() {
    ip_ = ip_binary();
    if (ip_.empty()) return fail("no `ip` command (iproute2) on this machine");
    if (geteuid() != 0) return fail("not root: creating network namespaces needs root");
    remove_stale();
    created_ = true;  // from here on, destroy() removes whatever was made
    const std::string sw = switch_ns();
    if (!run("netns add " + sw)) return fail("`ip netns add` is not allowed here");
    if (!run("-n " + sw + " link set lo up") ||
        !run("-n " + sw + " link add br0 type bridge mcast_snooping 0") ||
        !run("-n " + sw + " link set br0 up")) {
      return fail("cannot create a bridge in a network namespace");
    }
    for (int i = 1; i <= hosts_; ++i) {
      const std::string h = host(i), port = "p" + std::to_string(i);
      if (!run("netns add " + h) || !run("-n " + h + " link set lo up") ||
          !run("-n " + h + " link add eth0 type veth peer name " + port + " netns " + sw) ||
          !run("-n " + h + " addr add " + address(i) + "/24 dev eth0") ||
          !run("-n " + h + " link set eth0 up") ||
          !run("-n " + h + " route add 224.0.0.0/4 dev eth0") ||
          !run("-n " + sw + " link set " + port + " master br0") ||
          !run("-n " + sw + " link set " + port + " up")) {
        return fail("cannot create veth pairs between network namespaces");
      }
    }
    return true;
  }

  /// Removes the namespaces (idempotent); kills what still runs in them.
  void destroy() {
    if (!created_) return;
    created_ = false;
    for (int i = 1; i <= hosts_ + 1; ++i) {
      const std::string ns = i <= hosts_ ? host(i) : switch_ns();
      // kill by the pids the kernel lists for this namespace only
      if (FILE* f = popen((ip_ + " netns pids " + ns + " 2>/dev/null").c_str(), "r")) {
        int pid = 0;
        while (std::fscanf(f, "%d", &pid) == 1) {
          if (pid > 1 && pid != getpid()) kill(pid, SIGKILL);
        }
        pclose(f);
      }
      run("netns del " + ns);
    }
  }

  /// Adds a one-way delay to everything host i sends (tc netem on its veth); false where the
  /// kernel has no netem (as on the project's machines).
  bool add_netem_delay(int i, const std::string& delay) {
    return run("netns exec " + host(i) + " tc qdisc add dev eth0 root netem delay " + delay);
  }

  /// Removes namespaces left by an earlier test process that was killed before its cleanup
  /// (names tl<pid>h<i> / tl<pid>sw whose pid no longer exists).
  void remove_stale() {
    FILE* f = popen((ip_ + " netns list 2>/dev/null").c_str(), "r");
    if (!f) return;
    std::vector<std::string> stale;
    char line[256];
    while (std::fgets(line, sizeof line, f)) {
      const std::string name = std::string(line).substr(0, std::string(line).find_first_of(" \n"));
      if (name.rfind("tl", 0) != 0) continue;
      std::size_t end = 2;
      while (end < name.size() && std::isdigit(static_cast<unsigned char>(name[end]))) ++end;
      if (end == 2 || end == name.size()) continue;
      const std::string rest = name.substr(end);
      if (rest != "sw" && !(rest[0] == 'h' && rest.size() > 1)) continue;
      const int pid = std::atoi(name.substr(2, end - 2).c_str());
      if (pid != getpid() && kill(pid, 0) != 0 && errno == ESRCH) stale.push_back(name);
    }
    pclose(f);
    for (const auto& ns : stale) {
      if (FILE* p = popen((ip_ + " netns pids " + ns + " 2>/dev/null").c_str(), "r")) {
        int pid = 0;
        while (std::fscanf(p, "%d", &pid) == 1) {
          if (pid > 1 && pid != getpid()) kill(pid, SIGKILL);
        }
        pclose(p);
      }
      run("netns del " + ns);
    }
  }

  std::string host(int i) const { return "tl" + tag_ + "h" + std::to_string(i); }
  std::string switch_ns() const { return "tl" + tag_ + "sw"; }
  static std::string address(int i) { return "10.77.0." + std::to_string(i); }
  const std::string& why() const { return why_; }
  const std::string& ip() const { return ip_; }

  /// argv prefix that runs an executable inside host i: {ip, netns, exec, NAME}
  std::vector<std::string> exec_prefix(int i) const { return {"netns", "exec", host(i)}; }

 private:
  bool run(const std::string& args) {
    return std::system((ip_ + " " + args + " >/dev/null 2>&1").c_str()) == 0;
  }
  bool fail(const std::string& why) {
    why_ = why;
    return false;
  }

  int hosts_;
  std::string tag_, ip_, why_;
  bool created_ = false;
};

}  // namespace teleop::test

// Rule: tests and the default run send nothing beyond loopback. Checks that every UDP/TCP
// socket a running teleop_server opens is bound to 127.0.0.1 (no wildcard, no multicast
// listener), by matching the process's socket inodes against /proc/net/{udp,tcp}.
#include <gtest/gtest.h>

#include <dirent.h>
#include <unistd.h>

#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

std::set<std::string> socket_inodes(pid_t pid) {
  std::set<std::string> out;
  const std::string dir = "/proc/" + std::to_string(pid) + "/fd";
  DIR* d = opendir(dir.c_str());
  if (!d) return out;
  while (dirent* e = readdir(d)) {
    char buf[256];
    const std::string path = dir + "/" + e->d_name;
    const ssize_t n = readlink(path.c_str(), buf, sizeof(buf) - 1);
    if (n <= 0) continue;
    const std::string target(buf, static_cast<std::size_t>(n));
    if (target.rfind("socket:[", 0) == 0) out.insert(target.substr(8, target.size() - 9));
  }
  closedir(d);
  return out;
}

/// Local addresses (hex, as in /proc/net/*) of the sockets with the given inodes.
std::vector<std::string> local_addresses(const std::string& table,
                                         const std::set<std::string>& inodes) {
  std::vector<std::string> out;
  std::ifstream f(table);
  std::string line;
  std::getline(f, line);  // header
  while (std::getline(f, line)) {
    std::istringstream ss(line);
    std::string sl, local, remote, st, queues, tr, retr, uid, timeout, inode;
    ss >> sl >> local >> remote >> st >> queues >> tr >> retr >> uid >> timeout >> inode;
    if (inodes.count(inode)) out.push_back(local);
  }
  return out;
}

TEST(NetworkRules, DefaultProfileBindsOnlyToLoopback) {
  Process server(kServerBinary,
                 {"--domain", std::to_string(domains::kObservers), "--duration", "10", "--scene",
                  scene_file("tool_only.yaml")},
                 "netrules_server");
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  ASSERT_TRUE(server.running());
  // the server's pid is the child's: find it through the Process's /proc entry
  const std::set<std::string> inodes = socket_inodes(server.pid());
  const auto udp = local_addresses("/proc/net/udp", inodes);
  const auto tcp = local_addresses("/proc/net/tcp", inodes);
  const auto udp6 = local_addresses("/proc/net/udp6", inodes);
  EXPECT_FALSE(udp.empty()) << "the server should have UDP sockets";
  for (const auto& a : udp) EXPECT_EQ(a.substr(0, 8), "0100007F") << "UDP socket bound to " << a;
  for (const auto& a : tcp) EXPECT_EQ(a.substr(0, 8), "0100007F") << "TCP socket bound to " << a;
  EXPECT_TRUE(udp6.empty()) << "no IPv6 sockets expected";
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait_for(20.0), 0);
}

}  // namespace
}  // namespace teleop::test

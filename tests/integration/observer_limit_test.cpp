// The server counts its observers and warns past --max-observers: four observer participants
// on the 10 Hz state copy against a server started with --max-observers 2 make ServerStats
// report at least four observers and the limit, and the server publish one warning event.
#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

using Info = eprosima::fastdds::dds::SampleInfo;

struct Observer {
  explicit Observer(int domain)
      : participant(dds::ParticipantOptions{"loopback", domain, "limit-observer"}),
        reader(participant, dds::topics::kSlaveStateMonitor,
               [](const SlaveState&, const Info&) {}) {}
  dds::Participant participant;
  dds::Reader<SlaveStatePubSubType> reader;
};

TEST(ObserverLimit, TheServerCountsObserversAndWarnsPastItsLimit) {
  const int domain = domains::kObserverLimit;
  const std::string json = temp_path("obslimit", "server.json");
  Process server(
      kServerBinary,
      {"--domain", std::to_string(domain), "--duration", "60", "--max-observers", "2",
       "--stats-period", "0.2", "--scene", scene_file("tool_only.yaml"), "--summary-json", json},
      "obslimit_server");
  std::vector<std::unique_ptr<Observer>> observers;
  for (int i = 0; i < 4; ++i) observers.push_back(std::make_unique<Observer>(domain));
  dds::Participant p(dds::ParticipantOptions{"loopback", domain, "limit-watcher"});
  std::mutex m;
  long most_observers = -1, limit = -1;
  std::vector<std::string> warnings;
  dds::Reader<ServerStatsPubSubType> stats(
      p, dds::topics::kServerStats, [&](const ServerStats& s, const Info&) {
        std::lock_guard<std::mutex> lock(m);
        most_observers = std::max<long>(most_observers, s.observers());
        limit = s.max_observers();
      });
  dds::Reader<EventPubSubType> events(p, dds::topics::kEvents, [&](const Event& e, const Info&) {
    const std::string text = e.message().to_string();
    if (text.find("above --max-observers") == std::string::npos) return;
    std::lock_guard<std::mutex> lock(m);
    warnings.push_back(text);
  });
  const auto t0 = now_ns();
  auto done = [&] {
    std::lock_guard<std::mutex> lock(m);
    return most_observers >= 4 && !warnings.empty();
  };
  while (!done() && seconds_between(t0, now_ns()) < 30.0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  {
    std::lock_guard<std::mutex> lock(m);
    EXPECT_GE(most_observers, 4);  // the watcher reads no state: not counted
    EXPECT_EQ(limit, 2);
    ASSERT_EQ(warnings.size(), 1u);  // once while the count stays above the limit
    EXPECT_NE(warnings[0].find("above --max-observers 2"), std::string::npos) << warnings[0];
  }
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();
  const std::string s = Process::slurp(json);
  EXPECT_GE(json_value(s, "observers_max"), 4) << s;
  EXPECT_EQ(json_value(s, "max_observers"), 2) << s;
  EXPECT_NE(s.find("\"insecure\": false"), std::string::npos) << s;
}

}  // namespace
}  // namespace teleop::test

// Observers with any participant id find the server: 100 observer participants start before
// the "server" (a participant with the options teleop_server uses: announce_to_whole_domain),
// so the server takes participant id 100, far beyond the loopback profile's initial peer range
// of 32 ids. Every observer must receive the server's rate-limited state copy.
#include <gtest/gtest.h>

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <thread>
#include <vector>

#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"

namespace teleop::dds {
namespace {

using Info = eprosima::fastdds::dds::SampleInfo;

/// An observer as teleop_monitor is by default: its own participant, the 10 Hz state copy.
struct Observer {
  explicit Observer(int domain)
      : participant(ParticipantOptions{"loopback", domain, "many-observers"}),
        reader(participant, topics::kSlaveStateMonitor,
               [this](const SlaveState&, const Info&) { received.fetch_add(1); }) {}
  Participant participant;
  std::atomic<int> received{0};
  Reader<SlaveStatePubSubType> reader;
};

int observers_served(const std::vector<std::unique_ptr<Observer>>& obs) {
  int n = 0;
  for (const auto& o : obs) n += o->received.load() > 0 ? 1 : 0;
  return n;
}

constexpr int kObservers = 100;

/// How many of 100 observers started before the server received its state within 25 s.
int observers_served_by_a_late_server(int domain) {
  std::vector<std::unique_ptr<Observer>> obs;
  for (int i = 0; i < kObservers; ++i) obs.push_back(std::make_unique<Observer>(domain));
  ParticipantOptions server_options{"loopback", domain, "many-observers-server"};
  server_options.announce_to_whole_domain = true;  // as teleop_server and teleop_master
  Participant server(server_options);
  Writer<SlaveStatePubSubType> writer(server, topics::kSlaveStateMonitor);
  SlaveState s;
  const auto t0 = now_ns();
  // generous: discovery of 101 participants on a busy 2-core machine takes a few seconds
  while (observers_served(obs) < kObservers && seconds_between(t0, now_ns()) < 25.0) {
    s.seq(s.seq() + 1);
    writer.write(s);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return observers_served(obs);
}

// Fast DDS gives each participant of a process the next participant id and does not reuse ids,
// so after 101 participants this process's later ones would have ids beyond the loopback
// profile's 32: the check runs in a process of its own (a threadsafe death test runs this
// test again in a new process).
TEST(ManyObservers, HundredObserversStartedFirstAllFindTheServer) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        const int served = observers_served_by_a_late_server(test::domains::kManyObservers);
        std::fprintf(stderr, "%d of %d observers served\n", served, kObservers);
        std::_Exit(served == kObservers ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "100 of 100 observers served");
}

TEST(ManyObservers, OnlyTheWideningOptionReachesBeyondTheProfileRange) {
  // the profile's range stays 32 for observers (cheap discovery); the server's is the domain's
  using eprosima::fastdds::rtps::UDPv4TransportDescriptor;
  auto range = [](bool wide, int domain = 5) {
    ParticipantOptions o{"loopback", domain, "t"};
    o.announce_to_whole_domain = wide;
    std::uint32_t r = 0;
    const auto qos = participant_qos(o);
    for (const auto& t : qos.transport().user_transports) {
      if (auto u = std::dynamic_pointer_cast<UDPv4TransportDescriptor>(t))
        r = u->maxInitialPeersRange;
    }
    return r;
  };
  EXPECT_EQ(range(false), 32u);
  EXPECT_EQ(range(true), static_cast<std::uint32_t>(kWholeDomainPeers));
  EXPECT_EQ(range(false), 32u);  // the XML's descriptor was not changed in place
  // domain 232: ids up to 62 only (7411 + 250 * 232 + 2 * 62 = 65535; id 63 would pass it)
  EXPECT_EQ(range(true, 232), 63u);
}

}  // namespace
}  // namespace teleop::dds

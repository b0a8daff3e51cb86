#include "common/dds/participant.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>

#include "common/config/config.hpp"
#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"

namespace teleop::dds {
namespace {

// a reliable topic of commands of the test's own: no sample of the exchange may be lost
constexpr Topic<MasterCommandPubSubType> kReliableCommands{"test/commands",
                                                           TopicQos::kReliableStream};

TEST(DdsOptions, FlagsWinOverEnvironmentWhichWinsOverDefaults) {
  unsetenv("TELEOP_PROFILE");
  unsetenv("TELEOP_DOMAIN");
  auto o = resolve_participant_options(std::nullopt, std::nullopt, "x");
  EXPECT_EQ(o.profile, "loopback");
  EXPECT_EQ(o.domain, 0);
  setenv("TELEOP_DOMAIN", "17", 1);
  setenv("TELEOP_PROFILE", "lan", 1);
  setenv("TELEOP_INSECURE", "1", 1);  // lan has no DDS Security
  o = resolve_participant_options(std::nullopt, std::nullopt, "x");
  EXPECT_EQ(o.domain, 17);
  EXPECT_EQ(o.profile, "lan");
  o = resolve_participant_options(std::string("loopback"), 3, "x");
  EXPECT_EQ(o.domain, 3);
  EXPECT_EQ(o.profile, "loopback");
  setenv("TELEOP_DOMAIN", "seven", 1);
  EXPECT_THROW(resolve_participant_options(std::nullopt, std::nullopt, "x"), config::ConfigError);
  unsetenv("TELEOP_PROFILE");
  unsetenv("TELEOP_DOMAIN");
  unsetenv("TELEOP_INSECURE");
  EXPECT_THROW(resolve_participant_options(std::nullopt, 233, "x"), config::ConfigError);
  EXPECT_THROW(resolve_participant_options(std::nullopt, -1, "x"), config::ConfigError);
}

TEST(DdsOptions, UnknownProfileListsTheAvailableOnes) {
  try {
    profile_file("nope");
    FAIL() << "expected an error";
  } catch (const config::ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("loopback"), std::string::npos) << msg;
    EXPECT_NE(msg.find("lan"), std::string::npos) << msg;
  }
  EXPECT_NE(profile_file("loopback").find("deploy/profiles/loopback.xml"), std::string::npos);
}

TEST(DdsOptions, AParticipantFastDdsRefusesNamesProfileFileDomainAndFastDdsOwnLine) {
  // the loopback profile with a send buffer below the transport's largest message: Fast DDS
  // refuses to register the transport; the error says so without guessing a cause
  std::ifstream in(profile_file("loopback"));
  std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string type = "<type>UDPv4</type>";
  ASSERT_NE(xml.find(type), std::string::npos);
  xml.replace(xml.find(type), type.size(), type + "<sendBufferSize>16384</sendBufferSize>");
  const std::string file = testing::TempDir() + "small_buffers.xml";
  {
    std::ofstream out(file);
    out << xml;
  }
  ParticipantOptions o;
  o.profile = file;
  o.domain = test::domains::kParticipantRefused;
  std::string message;
  try {
    Participant p(o);
  } catch (const DdsError& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("cannot create a DDS participant with profile 'loopback' from " + file +
                         " on domain " + std::to_string(o.domain)),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("Fast DDS's own error is printed above"), std::string::npos) << message;
  EXPECT_EQ(message.find("Security"), std::string::npos) << message;
  std::remove(file.c_str());
}

TEST(DdsEndpoints, WriterAndWaitsetReaderExchangeSamples) {
  Participant pub(ParticipantOptions{"loopback", test::domains::kDdsHelpers, "pub"});
  Participant sub(ParticipantOptions{"loopback", test::domains::kDdsHelpers, "sub"});
  std::atomic<int> got{0};
  std::atomic<std::uint64_t> last{0};
  Reader<MasterCommandPubSubType> reader(
      sub, kReliableCommands,
      [&](const MasterCommand& c, const eprosima::fastdds::dds::SampleInfo&) {
        ++got;
        last = c.seq();
      });
  Writer<MasterCommandPubSubType> writer(pub, kReliableCommands);
  const auto t0 = now_ns();
  while ((writer.matched() < 1 || reader.matched() < 1) && seconds_between(t0, now_ns()) < 10) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(writer.matched(), 1);
  MasterCommand c;
  for (std::uint64_t i = 1; i <= 5; ++i) {
    c.seq(i);
    EXPECT_TRUE(writer.write(c));
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const auto t1 = now_ns();
  while (last.load() != 5 && seconds_between(t1, now_ns()) < 5) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(last.load(), 5u);
  EXPECT_EQ(got.load(), 5);
  EXPECT_EQ(writer.written(), 5u);
  EXPECT_EQ(writer.failures(), 0u);
  reader.stop();
  reader.stop();  // idempotent
}

TEST(Mailbox, HandsOverOnlyNewerValues) {
  Mailbox<int> box;
  int v = 0;
  std::uint64_t seen = 0;
  EXPECT_FALSE(box.take_if_newer(v, seen));
  box.put(3);
  EXPECT_TRUE(box.take_if_newer(v, seen));
  EXPECT_EQ(v, 3);
  EXPECT_FALSE(box.take_if_newer(v, seen));
  box.put(4);
  box.put(5);
  EXPECT_TRUE(box.take_if_newer(v, seen));
  EXPECT_EQ(v, 5);
}

}  // namespace
}  // namespace teleop::dds

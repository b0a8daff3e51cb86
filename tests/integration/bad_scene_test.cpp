// From outside: the real teleop_server refuses a scene that cannot run with exit status
// 2 and a message naming the scene file, the field and the value (before DDS starts); a scene
// whose deformable body sub-steps runs and says so; a malformed or oversized MasterCommand payload
// from a hostile participant is dropped and the server keeps running (it used to end in
// std::terminate: tests/fuzz/fuzz_command.cpp, common/dds/checked_type.hpp).
#include <gtest/gtest.h>

#include <signal.h>
#include <atomic>
#include <chrono>
#include <cstring>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <filesystem>
#include <fstream>
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

namespace fs = std::filesystem;

std::string tmp(const std::string& name) { return temp_path("badscene", name); }

struct Case {
  std::string name;
  std::string yaml;                   ///< written to <tmp>/<name>.yaml
  std::vector<std::string> expected;  ///< each in stderr, besides the scene file
  std::vector<std::string> extra_args = {};
};

TEST(BadScene, ServerExits2NamingFileFieldAndValue) {
  const std::string robot = scene_file("robot_puma560.yaml");
  const std::vector<Case> cases = {
      {"empty", "", {"the scene is empty"}},
      {"dup_keys",
       "physics:\n  rate_hz: 1000\n  rate_hz: 10\n",
       {"'physics.rate_hz' is given twice", "'1000'", "'10'"}},
      {"null_physics", "physics: ~\n", {"'physics'", "empty (null)"}},
      {"dup_ids",
       "deformables:\n  - {id: 12, body: {level: 1, radius_m: 0.1, centre_m: [0, 0, 0.2]}}\n"
       "  - {id: 12, body: {level: 1, radius_m: 0.1, centre_m: [0, 0.5, 0.2]}}\n",
       {"'deformables[1].id'", "'12'"}},
      {"far_sphere",
       "deformables:\n  - {body: {level: 1, radius_m: 0.25, centre_m: [9000, 0, 0.25]}}\n",
       {"'deformables[0].body.centre_m'", "'[9000, 0, 0.25]'", "outside the world box"}},
      {"radius_100",
       "deformables:\n  - {body: {level: 1, radius_m: 100}}\n",
       {"'deformables[0].body.radius_m'", "'100'"}},
      {"rate_10",
       "kind: robot\nphysics: {rate_hz: 10}\nrobot: {include: " + robot + "}\n",
       {"'physics.rate_hz'", "'10'", "robot.ik.gain_per_s"}},
      {"missing_mesh",
       "deformables:\n  - {body: {mesh_file: nothere.obj}}\n",
       {"'deformables[0].body.mesh_file'", "'nothere.obj'", "no such file"}},
      {"missing_include",
       "kind: robot\nrobot: {include: nothere.yaml}\n",
       {"'robot.include'", "'nothere.yaml'"}},
      {"cli_rate",
       "kind: robot\nrobot: {include: " + robot + "}\n",
       {"--rate 10", "robot.ik.gain_per_s"},
       {"--rate", "10"}},
  };
  const std::string d = std::to_string(domains::kBadScenes);
  int k = 0;
  for (const Case& c : cases) {
    const std::string file = tmp(c.name + ".yaml");
    std::ofstream(file) << c.yaml;
    std::vector<std::string> args = {"--scene", file, "--domain", d};
    args.insert(args.end(), c.extra_args.begin(), c.extra_args.end());
    Process s(kServerBinary, args, "badscene" + std::to_string(k++));
    EXPECT_EQ(s.wait_for(30.0), 2) << c.name << "\n" << s.err();
    const std::string err = s.err();
    if (c.extra_args.empty()) {
      EXPECT_NE(err.find(file), std::string::npos) << c.name << ": " << err;
    }
    for (const std::string& e : c.expected) {
      EXPECT_NE(err.find(e), std::string::npos) << c.name << ": '" << e << "' not in " << err;
    }
    fs::remove(file);
  }
  // special files
  for (const std::string& file : {std::string("/dev/null"), fs::temp_directory_path().string()}) {
    Process s(kServerBinary, {"--scene", file, "--domain", d}, "badscene_special");
    EXPECT_EQ(s.wait_for(30.0), 2) << file << "\n" << s.err();
    EXPECT_NE(s.err().find(file + ":"), std::string::npos) << s.err();
  }
}

TEST(BadScene, BodyThatSubStepsRunsAndSaysSo) {
  const std::string file = tmp("substeps.yaml");
  std::ofstream(file) << "planes:\n  - {name: floor, normal: [0, 0, 1]}\n"
                         "deformables:\n  - body: {level: 1, radius_m: 0.25, centre_m: [0.6, 0, "
                         "0.25], edge_stiffness_n_per_m: 50000}\n";
  Process s(
      kServerBinary,
      {"--scene", file, "--domain", std::to_string(domains::kSubstepScene), "--duration", "0.5"},
      "substep_scene");
  EXPECT_EQ(s.wait_for(60.0), 0) << s.err();
  const std::string out = s.out();
  EXPECT_NE(out.find("deformables[0] (id 10): dt 1 ms > largest stable step"), std::string::npos)
      << out;
  EXPECT_NE(out.find("sub-steps of"), std::string::npos) << out;
  fs::remove(file);
}

/// Bytes sent as a teleop::MasterCommand sample, whatever they hold (a hostile writer).
struct RawBytes {
  std::vector<std::uint8_t> bytes;
};

class RawCommandType : public eprosima::fastdds::dds::TopicDataType {
 public:
  RawCommandType() {
    MasterCommandPubSubType real;
    setName(real.getName());
    m_typeSize = 4096;
    m_isGetKeyDefined = false;
  }
  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* p) override {
    const auto& b = static_cast<RawBytes*>(data)->bytes;
    if (b.size() > p->max_size) return false;
    std::memcpy(p->data, b.data(), b.size());
    p->length = static_cast<std::uint32_t>(b.size());
    return true;
  }
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t*, void*) override { return false; }
  std::function<std::uint32_t()> getSerializedSizeProvider(void* data) override {
    return
        [data] { return static_cast<std::uint32_t>(static_cast<RawBytes*>(data)->bytes.size()); };
  }
  void* createData() override { return new RawBytes(); }
  void deleteData(void* data) override { delete static_cast<RawBytes*>(data); }
  bool getKey(void*, eprosima::fastrtps::rtps::InstanceHandle_t*, bool) override { return false; }
};

std::vector<std::uint8_t> serialized(MasterCommand c) {
  MasterCommandPubSubType t;
  eprosima::fastrtps::rtps::SerializedPayload_t p(t.m_typeSize);
  EXPECT_TRUE(t.serialize(&c, &p));
  return std::vector<std::uint8_t>(p.data, p.data + p.length);
}

TEST(BadScene, MalformedCommandPayloadIsDroppedAndTheServerRuns) {
  const int domain = domains::kMalformedCommands;
  const std::string json = tmp("malformed.json");
  Process server(kServerBinary,
                 {"--domain", std::to_string(domain), "--duration", "60", "--summary-json", json,
                  "--command-timeout", "5", "--scene", scene_file("tool_only.yaml")},
                 "malformed_server");
  dds::Participant participant(dds::ParticipantOptions{"loopback", domain, "hostile"});
  auto* topic = participant.topic(dds::topics::kMasterCommand.name,
                                  eprosima::fastdds::dds::TypeSupport(new RawCommandType()));
  auto* writer = participant.publisher()->create_datawriter(
      topic, dds::writer_qos(participant.publisher(), dds::topics::kMasterCommand.qos));
  ASSERT_NE(writer, nullptr);
  std::atomic<int> states{0};
  std::atomic<double> last_x{0.0};
  dds::Reader<SlaveStatePubSubType> reader(
      participant, dds::topics::kSlaveState,
      [&](const SlaveState& s, const eprosima::fastdds::dds::SampleInfo&) {
        ++states;
        last_x = s.tip_position_m()[0];
      });
  const auto t0 = now_ns();
  eprosima::fastdds::dds::PublicationMatchedStatus st;
  while (seconds_between(t0, now_ns()) < 20.0 &&
         (states.load() == 0 ||
          writer->get_publication_matched_status(st) != ReturnCode_t::RETCODE_OK ||
          st.current_count == 0)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_GT(states.load(), 0);
  MasterCommand c;
  c.position_m() = {0.5, 0.0, 0.4};
  c.orientation_wxyz() = {1, 0, 0, 0};
  c.enabled(true);
  std::uint64_t seq = 0;
  auto send = [&](std::vector<std::uint8_t> bytes) {
    RawBytes r{std::move(bytes)};
    writer->write(&r);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  };
  for (int i = 0; i < 20; ++i) {
    c.seq(++seq);
    std::vector<std::uint8_t> bad = serialized(c);
    // the boolean `enabled` (after 8 + 8 + 13 * 8 + 1 + 7 pad + 7 * 8 bytes) set to 2, or an
    // unknown encapsulation kind: both threw out of the generated deserialize()
    if (i % 2 == 0) {
      bad[4 + 8 + 8 + 13 * 8 + 8 + 7 * 8] = 2;
    } else {
      bad[1] = 9;
    }
    send(bad);
  }
  for (int i = 0; i < 5; ++i) {  // larger than a MasterCommand can be: dropped by Fast DDS
    std::vector<std::uint8_t> big(3000, 0);
    big[1] = 1;  // CDR little endian
    send(big);
  }
  for (int i = 0; i < 30; ++i) {
    c.seq(++seq);
    send(serialized(c));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  EXPECT_TRUE(server.running()) << server.err();
  EXPECT_NEAR(last_x.load(), 0.5, 0.03);  // the valid commands after them were applied
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();
  const std::string s = Process::slurp(json);
  EXPECT_EQ(json_value(s, "commands_accepted"), 30) << s;
  // each kind counted: the 20 that did not decode, the 5 too large (best effort: most arrive)
  EXPECT_GE(json_value(s, "commands_malformed"), 15) << s;
  EXPECT_LE(json_value(s, "commands_malformed"), 20) << s;
  EXPECT_GE(json_value(s, "samples_oversized"), 1) << s;
  EXPECT_LE(json_value(s, "samples_oversized"), 5) << s;
  participant.publisher()->delete_datawriter(writer);
}

}  // namespace
}  // namespace teleop::test

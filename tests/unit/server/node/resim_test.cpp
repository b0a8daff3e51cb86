// Off-line re-simulation from a command stream: bit-identical from run to run,
// sensitive to its input, and the node's edge validation applies (a rejected command never
// reaches the physics).
#include "server/node/resim.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "common/dds/teleop_idl.hpp"
#include "common/util/command_stream.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::server {
namespace {

const std::string kScene = std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/default.yaml";
constexpr std::int64_t kT0 = 1'700'000'000'000'000'000;  // an epoch time [ns]

StreamedCommand row_of(const MasterCommand& m, std::int64_t receive_ns) {
  MasterCommandPubSubType type;
  MasterCommand copy = m;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&copy)());
  EXPECT_TRUE(type.serialize(&copy, &payload));
  StreamedCommand r;
  r.receive_ns = receive_ns;
  r.source_ns = m.send_time_ns();
  r.writer = std::string(32, 'a');
  r.payload.assign(payload.data, payload.data + payload.length);
  return r;
}

/// The tip goes down from 0.65 m onto the default scene's sphere (top at 0.5 m) over 1.5 s,
/// holds 0.3 s 4 cm in; one command a millisecond, received 0.2 ms after sending.
std::vector<StreamedCommand> press_stream() {
  std::vector<StreamedCommand> rows;
  for (int k = 0; k < 1800; ++k) {
    const double t = 1e-3 * k;
    const double s = std::min(1.0, t / 1.5);
    SlaveCommand c;
    c.seq = static_cast<std::uint64_t>(k + 1);
    c.position_m = Eigen::Vector3d(0.6, 0.0, 0.65 - s * (0.65 - 0.47));
    c.velocity_mps = Eigen::Vector3d(0, 0, t < 1.5 ? -0.18 / 1.5 : 0.0);
    MasterCommand m;
    const std::int64_t send = kT0 + static_cast<std::int64_t>(k) * 1'000'000;
    to_idl(c, send, m);
    rows.push_back(row_of(m, send + 200'000));
  }
  return rows;
}

TEST(Resim, TwoRunsOfOneStreamAreBitIdenticalAndTouchTheSphere) {
  const sim::WorldModel model = sim::load_world_model(kScene);
  const auto stream = press_stream();
  double max_force = 0.0;
  bool touched = false;
  const ResimResult a = resimulate(model, stream, {}, [&](const ResimStep& s) {
    max_force = std::max(max_force, s.out->contact_force_n.norm());
    touched = touched || (s.out->in_contact && s.out->contact_object == 10);
  });
  const ResimResult b = resimulate(model, stream, {});
  EXPECT_EQ(a.hash, b.hash);
  EXPECT_EQ(a.steps, b.steps);
  EXPECT_EQ(a.events, b.events);
  EXPECT_EQ(a.accepted, 1800u);
  EXPECT_EQ(a.masters, 1u);
  EXPECT_TRUE(touched) << "the tip never touched the sphere (id 10)";
  EXPECT_GT(max_force, 0.5);
  EXPECT_GE(a.events, 1u);          // at least the contact begin
  EXPECT_GE(a.watchdog_trips, 1u);  // the stream ends 0.5 s before the run does
  // 1.8 s of stream + 0.5 s of tail at 1 kHz
  EXPECT_NEAR(static_cast<double>(a.steps), 2300.0, 2.0);
}

TEST(Resim, OneCommandMovedByAMicrometreChangesTheHash) {
  const sim::WorldModel model = sim::load_world_model(kScene);
  auto stream = press_stream();
  const ResimResult a = resimulate(model, stream, {});
  // command 1000 (in contact) 1 um lower
  MasterCommandPubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t p(
      static_cast<std::uint32_t>(stream[1000].payload.size()));
  std::copy(stream[1000].payload.begin(), stream[1000].payload.end(), p.data);
  p.length = static_cast<std::uint32_t>(stream[1000].payload.size());
  MasterCommand m;
  ASSERT_TRUE(type.deserialize(&p, &m));
  m.position_m()[2] -= 1e-6;
  stream[1000] = row_of(m, stream[1000].receive_ns);
  const ResimResult b = resimulate(model, stream, {});
  EXPECT_NE(a.hash, b.hash);
}

TEST(Resim, RejectedCommandsAreCountedAndNeverReachThePhysics) {
  const sim::WorldModel model = sim::load_world_model(kScene);
  const auto clean = press_stream();
  auto dirty = clean;
  // a NaN, a position outside the workspace and a replayed (stale) seq, each received between
  // two good commands: all rejected, so the states are the clean run's, bit for bit
  MasterCommand nan_cmd, far_cmd;
  SlaveCommand c;
  c.seq = 5000;
  c.position_m = Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 0.6);
  to_idl(c, kT0, nan_cmd);
  c.seq = 5001;
  c.position_m = Eigen::Vector3d(0.6, 0.0, 50.0);
  to_idl(c, kT0, far_cmd);
  const std::int64_t at = clean[700].receive_ns;
  dirty.insert(dirty.begin() + 701, row_of(nan_cmd, at));
  dirty.insert(dirty.begin() + 702, row_of(far_cmd, at));
  dirty.insert(dirty.begin() + 703, dirty[690]);  // seq 691 again
  dirty[703].receive_ns = at;
  const ResimResult a = resimulate(model, clean, {});
  const ResimResult b = resimulate(model, dirty, {});
  EXPECT_EQ(b.rejected_nan, 1u);
  EXPECT_EQ(b.rejected_workspace, 1u);
  EXPECT_EQ(b.rejected_stale, 1u);
  EXPECT_EQ(b.accepted, a.accepted);
  EXPECT_EQ(a.hash, b.hash);
}

TEST(Resim, CommandStreamFileRoundTripsAndBadFilesNameLineAndColumn) {
  const auto stream = press_stream();
  const std::string path = testing::TempDir() + "resim_stream.csv";
  write_command_stream(path, stream);
  const auto back = read_command_stream(path);
  ASSERT_EQ(back.size(), stream.size());
  EXPECT_EQ(back[17].payload, stream[17].payload);
  EXPECT_EQ(back[17].receive_ns, stream[17].receive_ns);
  {
    std::FILE* f = std::fopen(path.c_str(), "a");
    std::fputs("12,34,abc,00\n", f);
    std::fclose(f);
  }
  try {
    read_command_stream(path);
    ADD_FAILURE() << "a bad row was accepted";
  } catch (const std::exception& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path + ": line 1802, column 'writer'"), std::string::npos) << msg;
  }
  std::remove(path.c_str());
}

}  // namespace
}  // namespace teleop::server

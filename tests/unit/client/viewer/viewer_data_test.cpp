#include "client/viewer/viewer_data.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/support/alloc_counter.hpp"

namespace teleop::viewer {
namespace {

SceneDescription scene_with_mesh(std::int32_t id) {
  SceneDescription s;
  s.name("test");
  SceneObject o;
  o.id(id);
  o.kind(OBJECT_DEFORMABLE_MESH);
  s.objects().push_back(o);
  return s;
}

MeshTopology tetra_topology(std::int32_t id) {
  MeshTopology t;
  t.object_id(id);
  t.vertex_count(4);
  t.triangle_indices() = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2};
  return t;
}

MeshFrame tetra_frame(std::int32_t id, std::uint64_t no, float dz) {
  MeshFrame f;
  f.object_id(id);
  f.frame(no);
  f.positions_m() = {0, 0, dz, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  return f;
}

SlaveState slave(double fz, double penetration_m) {
  SlaveState s;
  s.joint_position_rad() = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
  s.joint_velocity_radps() = {0, 0, 0, 0, 0, 0};
  s.joint_torque_nm() = {0, 0, 0, 0, 0, 0};
  s.contact_force_n() = {0.0, 0.0, fz};
  s.penetration_m(penetration_m);
  return s;
}

TEST(ViewerData, CompleteOnceSceneSlaveTopologyAndFrameArrived) {
  ViewerData data(10.0, 0);
  ViewerView view;
  data.update(view);
  EXPECT_FALSE(view.complete());
  EXPECT_EQ(view.missing(), "teleop/scene, teleop/slave_state");
  data.on_scene(scene_with_mesh(10));
  data.update(view);
  EXPECT_EQ(view.missing(), "teleop/slave_state, teleop/mesh_topology, teleop/mesh_frame");
  // a frame may come before its topology (different QoS): kept, not drawable yet
  data.on_mesh_frame(tetra_frame(10, 1, 0.0f));
  data.on_slave_state(slave(0.0, 0.0), 1'000'000);
  data.update(view);
  EXPECT_EQ(view.missing(), "teleop/mesh_topology, teleop/mesh_frame");
  data.on_topology(tetra_topology(10));
  data.update(view);
  EXPECT_TRUE(view.complete()) << view.missing();
  const MeshSlot* m = view.mesh(10);
  ASSERT_NE(m, nullptr);
  EXPECT_TRUE(m->drawable());
  EXPECT_EQ(m->triangles.size(), 12u);
}

TEST(ViewerData, KeepsTheFirstFrameAsDisplacementReference) {
  ViewerData data(10.0, 0);
  ViewerView view;
  data.on_topology(tetra_topology(10));
  data.on_mesh_frame(tetra_frame(10, 1, 0.0f));
  data.on_mesh_frame(tetra_frame(10, 2, -0.01f));
  data.update(view);
  const MeshSlot* m = view.mesh(10);
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->frame, 2u);
  EXPECT_FLOAT_EQ(m->positions[2], -0.01f);
  EXPECT_FLOAT_EQ(m->reference[2], 0.0f);
  // a new scene (restarted server) takes the next frame as the reference
  data.on_scene(scene_with_mesh(10));
  data.on_mesh_frame(tetra_frame(10, 3, -0.02f));
  data.update(view);
  EXPECT_FLOAT_EQ(view.mesh(10)->reference[2], -0.02f);
}

TEST(ViewerData, RejectsMalformedTopologiesAndFrames) {
  ViewerData data(10.0, 0);
  ViewerView view;
  MeshTopology bad = tetra_topology(10);
  bad.triangle_indices()[4] = 9;  // >= vertex_count
  data.on_topology(bad);
  MeshTopology not_triangles = tetra_topology(11);
  not_triangles.triangle_indices().pop_back();
  data.on_topology(not_triangles);
  MeshFrame nan_frame = tetra_frame(10, 1, NAN);
  data.on_mesh_frame(nan_frame);
  data.update(view);
  EXPECT_EQ(view.counters.rejected, 3u);
  EXPECT_EQ(view.mesh_count, 0);
  // a frame whose size does not match the topology is kept but not drawable
  data.on_topology(tetra_topology(10));
  MeshFrame short_frame = tetra_frame(10, 2, 0.0f);
  short_frame.positions_m().resize(9);
  data.on_mesh_frame(short_frame);
  data.update(view);
  ASSERT_NE(view.mesh(10), nullptr);
  EXPECT_FALSE(view.mesh(10)->drawable());
}

TEST(ViewerData, PlotsForceAndPenetrationAgainstReceiveTime) {
  ViewerData data(10.0, 0);
  ViewerView view;
  // 1 kHz for 2 s: 3 N at 1 s, penetration 2 mm
  for (int k = 0; k < 2000; ++k) {
    const double fz = k == 1000 ? 3.0 : 0.5;
    data.on_slave_state(slave(fz, 0.002), static_cast<std::int64_t>(k) * 1'000'000);
  }
  data.update(view);
  const TimeSeries& f = view.series[kForceN];
  ASSERT_GT(f.size(), 100u);
  EXPECT_LE(f.size(), kSeriesPoints + 16);
  float peak = 0.0f;
  for (std::size_t i = 0; i < f.size(); ++i) peak = std::max(peak, f[i].max);
  EXPECT_FLOAT_EQ(peak, 3.0f);  // a one-sample spike survives the bucketing
  EXPECT_FLOAT_EQ(f.newest().last, 0.5f);
  EXPECT_NEAR(f.newest().t_s, 1.999, 0.01);
  EXPECT_FLOAT_EQ(view.series[kPenetrationMm].newest().last, 2.0f);
}

TEST(ViewerData, EventsAreListedNewestFirstAndKeepTheLastN) {
  ViewerData data(10.0, 0);
  ViewerView view;
  for (int i = 0; i < kMaxEvents + 5; ++i) {
    Event e;
    e.source("server");
    e.kind(EVENT_CONTACT_BEGIN);
    e.message("event " + std::to_string(i));
    data.on_event(e, i);
  }
  data.update(view);
  EXPECT_EQ(view.event_count, kMaxEvents);
  EXPECT_STREQ(view.events[0].message, ("event " + std::to_string(kMaxEvents + 4)).c_str());
  EXPECT_STREQ(view.events[kMaxEvents - 1].message, "event 5");
  EXPECT_STREQ(view.events[0].source, "server");
}

// The reader callbacks must not slow anybody: after the first sample of each kind nothing they
// do allocates, and neither does the render thread's update().
TEST(ViewerData, NoAllocationPerSampleAfterWarmUp) {
  ViewerData data(10.0, 0);
  ViewerView view;
  const SceneDescription scene = scene_with_mesh(10);
  const MeshTopology topo = tetra_topology(10);
  MeshFrame frame = tetra_frame(10, 1, 0.0f);
  const SlaveState s = slave(1.0, 0.001);
  MasterState m;
  ServerStats st;
  Event e;
  e.source("server");
  e.message("contact begins");
  // warm-up: every kind once, and one update to size the view
  data.on_scene(scene);
  data.on_topology(topo);
  data.on_mesh_frame(frame);
  data.on_slave_state(s, 1);
  data.on_master_state(m, 1);
  data.on_server_stats(st, 1);
  data.on_event(e, 1);
  data.update(view);

  teleop::test::NoAllocScope scope;
  for (int k = 0; k < 5000; ++k) {
    const std::int64_t t = 2 + static_cast<std::int64_t>(k) * 1'000'000;
    data.on_slave_state(s, t);
    if (k % 10 == 0) data.on_master_state(m, t);
    if (k % 16 == 0) {
      frame.frame(static_cast<std::uint64_t>(k));
      data.on_mesh_frame(frame);
    }
    if (k % 500 == 0) {
      data.on_server_stats(st, t);
      data.on_event(e, t);
    }
    if (k % 16 == 0) data.update(view);
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(TimeSeries, KeepsTheNewestBucketsInARing) {
  TimeSeries s(4, 1.0);
  for (int i = 0; i < 10; ++i) s.add(i, i);
  ASSERT_EQ(s.size(), 4u);
  EXPECT_DOUBLE_EQ(s[0].t_s, 6.0);
  EXPECT_DOUBLE_EQ(s.newest().t_s, 9.0);
  s.add(9.5, -3.0);  // same bucket: min, max and last merge
  EXPECT_FLOAT_EQ(s.newest().min, -3.0f);
  EXPECT_FLOAT_EQ(s.newest().max, 9.0f);
  EXPECT_FLOAT_EQ(s.newest().last, -3.0f);
  s.add(20.0, NAN);  // ignored
  EXPECT_DOUBLE_EQ(s.newest().t_s, 9.0);
}

TEST(ViewerData, TheExperimentReachesTheViewOnceAndOnEachChange) {
  ViewerData data(10.0, 0);
  ViewerView view;
  data.update(view);
  EXPECT_FALSE(view.have_experiment);
  ExperimentDescription e;
  e.scheme("wave-variables");
  e.forward_delay_ms(50.0);
  e.driver_live(true);
  data.on_experiment(e);
  data.update(view);
  ASSERT_TRUE(view.have_experiment);
  EXPECT_EQ(std::string(view.experiment.scheme().c_str()), "wave-variables");
  EXPECT_DOUBLE_EQ(view.experiment.forward_delay_ms(), 50.0);
  e.driver_live(false);  // the device fell silent: the next description says so
  data.on_experiment(e);
  {
    test::NoAllocScope no_alloc;  // the copy into the view allocates nothing
    data.update(view);
    EXPECT_EQ(no_alloc.allocations(), 0u);
  }
  EXPECT_FALSE(view.experiment.driver_live());
}

}  // namespace
}  // namespace teleop::viewer

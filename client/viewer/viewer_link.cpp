#include "client/viewer/viewer_link.hpp"

#include "common/dds/observer_topics.hpp"
#include "common/util/clock.hpp"

namespace teleop::viewer {

ViewerLink::ViewerLink(const dds::ParticipantOptions& dds_options, const ViewerOptions& options,
                       ViewerSession& session) {
  using eprosima::fastdds::dds::SampleInfo;
  participant_ = std::make_unique<dds::Participant>(dds_options);
  dds::Participant& p = *participant_;
  ViewerData& data = session.data();
  scene_ = std::make_unique<dds::Reader<SceneDescriptionPubSubType>>(
      p, dds::topics::kScene,
      [&data](const SceneDescription& s, const SampleInfo&) { data.on_scene(s); });
  topology_ = std::make_unique<dds::Reader<MeshTopologyPubSubType>>(
      p, dds::topics::kMeshTopology,
      [&data](const MeshTopology& t, const SampleInfo&) { data.on_topology(t); });
  const dds::ObserverTopics topics =
      dds::observer_topics(dds::ObserverKind::kView, options.full_rate);
  frames_ = std::make_unique<dds::Reader<MeshFramePubSubType>>(
      p, topics.mesh_frame,
      [&data](const MeshFrame& f, const SampleInfo&) { data.on_mesh_frame(f); });
  slave_ = std::make_unique<dds::Reader<SlaveStatePubSubType>>(
      p, topics.slave_state, [&session](const SlaveState& s, const SampleInfo& info) {
        session.on_slave_state(s, info.sample_identity.writer_guid().guidPrefix, now_ns());
      });
  master_ = std::make_unique<dds::Reader<MasterStatePubSubType>>(
      p, topics.master_state,
      [&data](const MasterState& s, const SampleInfo&) { data.on_master_state(s, now_ns()); });
  stats_ = std::make_unique<dds::Reader<ServerStatsPubSubType>>(
      p, dds::topics::kServerStats, [&session](const ServerStats& s, const SampleInfo& info) {
        session.on_server_stats(s, info.sample_identity.writer_guid().guidPrefix, now_ns());
      });
  events_ = std::make_unique<dds::Reader<EventPubSubType>>(
      p, dds::topics::kEvents,
      [&data](const Event& e, const SampleInfo&) { data.on_event(e, now_ns()); });
  experiment_ = std::make_unique<dds::Reader<ExperimentDescriptionPubSubType>>(
      p, dds::topics::kExperiment,
      [&data](const ExperimentDescription& e, const SampleInfo&) { data.on_experiment(e); });
  if (options.drive) {
    HandDriveParams hp;
    hp.position_scale = options.drive_scale;
    drive_ = std::make_unique<DriveSession>(p, hp, options.drive_peak_force_n);
  }
}

ViewerLink::~ViewerLink() {
  drive_.reset();
  // the readers before the participant, the newest first
  experiment_.reset();
  events_.reset();
  stats_.reset();
  master_.reset();
  slave_.reset();
  frames_.reset();
  topology_.reset();
  scene_.reset();
  participant_.reset();
}

}  // namespace teleop::viewer

#pragma once
// The viewer's DDS side: one participant, a reader per observer topic feeding a ViewerSession
// (each on its own reader thread), and with --drive the DriveSession that makes the viewer the
// master's device and tuning tool. Subscribes only otherwise: any number of viewers may join or
// leave; the latched topics (scene, mesh topology, events, experiment) bring a late one up to
// date.
#include <memory>

#include "client/viewer/drive_session.hpp"
#include "client/viewer/viewer_options.hpp"
#include "client/viewer/viewer_session.hpp"
#include "common/dds/endpoint.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::viewer {

class ViewerLink {
 public:
  /// Reads the 60 Hz *_view copies of the state, or the 1 kHz topics with options.full_rate;
  /// starts the drive with options.drive. `session` must outlive the link (the readers write
  /// into it until the link is destroyed). @throws dds::DdsError when an entity cannot be made.
  ViewerLink(const dds::ParticipantOptions& dds_options, const ViewerOptions& options,
             ViewerSession& session);
  /// Stops the drive, then the readers, then deletes the participant.
  ~ViewerLink();
  ViewerLink(const ViewerLink&) = delete;
  ViewerLink& operator=(const ViewerLink&) = delete;

  /// The drive (--drive), or nullptr.
  DriveSession* drive() { return drive_.get(); }

 private:
  std::unique_ptr<dds::Participant> participant_;
  std::unique_ptr<dds::Reader<SceneDescriptionPubSubType>> scene_;
  std::unique_ptr<dds::Reader<MeshTopologyPubSubType>> topology_;
  std::unique_ptr<dds::Reader<MeshFramePubSubType>> frames_;
  std::unique_ptr<dds::Reader<SlaveStatePubSubType>> slave_;
  std::unique_ptr<dds::Reader<MasterStatePubSubType>> master_;
  std::unique_ptr<dds::Reader<ServerStatsPubSubType>> stats_;
  std::unique_ptr<dds::Reader<EventPubSubType>> events_;
  std::unique_ptr<dds::Reader<ExperimentDescriptionPubSubType>> experiment_;
  std::unique_ptr<DriveSession> drive_;
};

}  // namespace teleop::viewer

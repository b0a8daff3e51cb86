#pragma once
// The topic table of the wire (docs/topics.md): every topic's name, IDL type and QoS class,
// declared once. Writers, readers, the recorder, the player, the bridge and the tools name a
// topic through it (dds::Writer, dds::Reader, dds::LatestWriter and dds::RateLimitedPublisher
// take a Topic), so a topic's type and QoS class are the same at every end.
//
//   dds::Writer w(participant, dds::topics::kMasterCommand);   // MasterCommand, stream
//   dds::topics::for_each([](const auto& t) { ... t.name, t.qos, PubSubOf<decltype(t)> ... });
//
// A test that needs a topic of its own (a private name) declares a Topic the same way.
#include "common/dds/participant.hpp"
#include "teleop/idl/DevicePubSubTypes.h"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::dds {

/// A topic: its name and QoS class, typed by the PubSubType of its IDL type.
template <class PubSub>
struct Topic {
  using PubSubType = PubSub;
  const char* name;
  TopicQos qos;
};

/// The PubSubType of a Topic (const or not).
template <class T>
using PubSubOf = typename std::remove_cv_t<std::remove_reference_t<T>>::PubSubType;

namespace topics {
// the session: commands, states, the scene and what the server says
inline constexpr Topic<MasterCommandPubSubType> kMasterCommand{"teleop/master_command",
                                                               TopicQos::kStream};
inline constexpr Topic<SlaveStatePubSubType> kSlaveState{"teleop/slave_state", TopicQos::kStream};
inline constexpr Topic<MasterStatePubSubType> kMasterState{"teleop/master_state",
                                                           TopicQos::kStream};
inline constexpr Topic<SceneDescriptionPubSubType> kScene{"teleop/scene", TopicQos::kLatched};
inline constexpr Topic<MeshTopologyPubSubType> kMeshTopology{"teleop/mesh_topology",
                                                             TopicQos::kLatched};
inline constexpr Topic<MeshFramePubSubType> kMeshFrame{"teleop/mesh_frame", TopicQos::kStream};
inline constexpr Topic<EventPubSubType> kEvents{"teleop/events", TopicQos::kEventLog};
inline constexpr Topic<ServerStatsPubSubType> kServerStats{"teleop/server_stats",
                                                           TopicQos::kReliableStream};
/// tools -> master: live tuning requests
inline constexpr Topic<TuningRequestPubSubType> kTuning{"teleop/tuning", TopicQos::kReliableStream};
/// master -> tools: what live tuning applied
inline constexpr Topic<TuningStatusPubSubType> kTuningStatus{"teleop/tuning_status",
                                                             TopicQos::kLatched};
/// master -> all: what the session is (scheme, gains, delays, device)
inline constexpr Topic<ExperimentDescriptionPubSubType> kExperiment{"teleop/experiment",
                                                                    TopicQos::kLatched};
// Rate-limited copies for observers: written off the loops' threads, so the number of observers
// does not load the 1 kHz path. `_view` at kViewRateHz for windows, `_monitor` at
// kMonitorRateHz for terminals and services.
inline constexpr Topic<SlaveStatePubSubType> kSlaveStateView{"teleop/slave_state_view",
                                                             TopicQos::kLatest};
inline constexpr Topic<SlaveStatePubSubType> kSlaveStateMonitor{"teleop/slave_state_monitor",
                                                                TopicQos::kLatest};
inline constexpr Topic<MasterStatePubSubType> kMasterStateView{"teleop/master_state_view",
                                                               TopicQos::kLatest};
inline constexpr Topic<MasterStatePubSubType> kMasterStateMonitor{"teleop/master_state_monitor",
                                                                  TopicQos::kLatest};
inline constexpr Topic<MeshFramePubSubType> kMeshFrameMonitor{"teleop/mesh_frame_monitor",
                                                              TopicQos::kLatest};
// an external device driver's pair (idl/Device.idl; docs/devices.md)
inline constexpr Topic<DeviceStatePubSubType> kDeviceState{"teleop/device_state",
                                                           TopicQos::kStream};
inline constexpr Topic<DeviceCommandPubSubType> kDeviceCommand{"teleop/device_command",
                                                               TopicQos::kStream};

inline constexpr double kViewRateHz = 60.0;     ///< rate of the `_view` topics [Hz]
inline constexpr double kMonitorRateHz = 10.0;  ///< rate of the `_monitor` topics [Hz]

/// Calls `f(topic)` for every topic of the table, in the order of docs/topics.md.
template <class F>
void for_each(F&& f) {
  f(kMasterCommand);
  f(kSlaveState);
  f(kMasterState);
  f(kScene);
  f(kMeshTopology);
  f(kMeshFrame);
  f(kEvents);
  f(kServerStats);
  f(kTuning);
  f(kTuningStatus);
  f(kExperiment);
  f(kSlaveStateView);
  f(kSlaveStateMonitor);
  f(kMasterStateView);
  f(kMasterStateMonitor);
  f(kMeshFrameMonitor);
  f(kDeviceState);
  f(kDeviceCommand);
}
}  // namespace topics

}  // namespace teleop::dds

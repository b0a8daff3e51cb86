#pragma once
// Which topics an observer reads (docs/topics.md, "Observer topics"). By default observers read
// the rate-limited copies (monitors 10 Hz, views 60 Hz), so their number does not load the
// 1 kHz loops; --full-rate makes them read the full-rate topics, as the master and the server do.
// teleop_monitor, teleop_viewer and the observers of `teleop_bench observers` use this one table.
#include "common/dds/participant.hpp"

namespace teleop::dds {

enum class ObserverKind {
  kMonitor,  ///< a terminal or service: rates, newest values (teleop_monitor)
  kView,     ///< a window: scene, mesh and plots (teleop_viewer)
};

struct ObservedTopic {
  const char* name;
  TopicQos qos;
};

struct ObserverTopics {
  ObservedTopic slave_state;
  ObservedTopic master_state;
  ObservedTopic mesh_frame;
  /// Subscribe to teleop/master_command (1 kHz, the master's own writer): only at full rate.
  /// Otherwise the command rate is the server's count (SlaveState.commands_received).
  bool master_command;
};

inline ObserverTopics observer_topics(ObserverKind kind, bool full_rate) {
  if (full_rate) {
    return {{topics::kSlaveState, TopicQos::kStream},
            {topics::kMasterState, TopicQos::kStream},
            {topics::kMeshFrame, TopicQos::kStream},
            kind == ObserverKind::kMonitor};
  }
  if (kind == ObserverKind::kView) {
    // mesh frames are written at the visual rate (60 Hz) already, from their own thread
    return {{topics::kSlaveStateView, TopicQos::kLatest},
            {topics::kMasterStateView, TopicQos::kLatest},
            {topics::kMeshFrame, TopicQos::kStream},
            false};
  }
  return {{topics::kSlaveStateMonitor, TopicQos::kLatest},
          {topics::kMasterStateMonitor, TopicQos::kLatest},
          {topics::kMeshFrameMonitor, TopicQos::kLatest},
          false};
}

}  // namespace teleop::dds

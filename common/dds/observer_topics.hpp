#pragma once
// Which topics an observer reads (docs/topics.md, "Observer topics"). By default observers read
// the rate-limited copies (monitors 10 Hz, views 60 Hz), so their number does not load the
// 1 kHz loops; --full-rate makes them read the full-rate topics, as the master and the server do.
// teleop_monitor, teleop_viewer and the observers of `teleop_bench observers` use this one table.
#include "common/dds/topics.hpp"

namespace teleop::dds {

enum class ObserverKind {
  kMonitor,  ///< a terminal or service: rates, newest values (teleop_monitor)
  kView,     ///< a window: scene, mesh and plots (teleop_viewer)
};

struct ObserverTopics {
  Topic<SlaveStatePubSubType> slave_state;
  Topic<MasterStatePubSubType> master_state;
  Topic<MeshFramePubSubType> mesh_frame;
  /// Subscribe to teleop/master_command (1 kHz, the master's own writer): only at full rate.
  /// Otherwise the command rate is the server's count (SlaveState.commands_received).
  bool master_command;
};

inline ObserverTopics observer_topics(ObserverKind kind, bool full_rate) {
  if (full_rate) {
    return {topics::kSlaveState, topics::kMasterState, topics::kMeshFrame,
            kind == ObserverKind::kMonitor};
  }
  if (kind == ObserverKind::kView) {
    // mesh frames are written at the visual rate (60 Hz) already, from their own thread
    return {topics::kSlaveStateView, topics::kMasterStateView, topics::kMeshFrame, false};
  }
  return {topics::kSlaveStateMonitor, topics::kMasterStateMonitor, topics::kMeshFrameMonitor,
          false};
}

}  // namespace teleop::dds

#pragma once
// TuningEndpoint: the master's end of live tuning over DDS (docs/topics.md, "Live tuning").
//
// It reads teleop/tuning (only when the master was started with --accept-tuning) into a small
// bounded queue from the reader's thread; the haptic loop polls it between cycles, hands each
// request for this master (or for any master) to MasterCycle::tune(), reports the outcome as an
// event and answers on teleop/tuning_status (reliable, latched: a late tool sees the values in
// force, the bounds, and what this master's scheme lets it set). A master that does not accept
// tuning still publishes its status (accepting = false), so a tool can say why nothing happens.
#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include "client/control/tuning.hpp"
#include "common/dds/async_writer.hpp"
#include "common/dds/endpoint.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::master {

class MasterCycle;

class TuningEndpoint {
 public:
  /// `master_session`: this master's ownership session (requests naming another are ignored).
  TuningEndpoint(dds::Participant& participant, std::uint32_t master_session, bool accepting);
  ~TuningEndpoint();

  /// Publishes the status: the values in force in `cycle`, its bounds, the newest answer.
  void publish_status(const MasterCycle& cycle, std::int64_t now_ns);
  /// Status writes the middleware refused.
  std::uint64_t write_failures() const { return status_writer_.failures(); }

  /// Applies the queued requests to `cycle` at `now_s`; calls `report(severity, message)` once
  /// per request handled (severity 0 applied, 1 rejected) and republishes the status. Returns
  /// the number handled. Does nothing (and allocates nothing) when the queue is empty.
  int poll(MasterCycle& cycle, double now_s, std::int64_t now_ns,
           const std::function<void(std::uint8_t, const std::string&)>& report);

  bool accepting() const { return accepting_; }
  /// Requests for this master received, ignored (for another master), dropped (queue full).
  std::uint64_t received() const { return received_.load(); }
  std::uint64_t ignored() const { return ignored_.load(); }
  std::uint64_t dropped() const { return dropped_.load(); }

 private:
  struct Pending {
    std::uint64_t seq = 0;
    char source[33] = {};
    TuningRequestData data;
  };
  void on_request(const TuningRequest& r);

  std::uint32_t master_session_;
  bool accepting_;
  // the status is answered from the haptic loop: written by the writer's network thread
  dds::LatestWriter<TuningStatusPubSubType> status_writer_;
  std::unique_ptr<dds::Reader<TuningRequestPubSubType>> reader_;
  std::mutex mutex_;
  static constexpr std::size_t kQueue = 16;
  std::array<Pending, kQueue> queue_{};
  std::size_t head_ = 0, count_ = 0;
  std::atomic<std::size_t> pending_{0};  // = count_, read by poll() without the lock
  std::atomic<std::uint64_t> received_{0}, ignored_{0}, dropped_{0};
  // the newest answer
  std::uint64_t answer_seq_ = 0;
  std::string answer_source_;
  bool answer_accepted_ = false;
  std::string answer_message_;
};

}  // namespace teleop::master

#pragma once
// Typed DDS writer and waitset-driven reader helpers.
//
//   dds::Participant p(options);
//   dds::Writer<teleop::MasterCommandPubSubType> w(p, dds::topics::kMasterCommand);
//   dds::Reader<teleop::SlaveStatePubSubType> r(p, dds::topics::kSlaveState,
//       [&](const teleop::SlaveState& s, const SampleInfo&) { mailbox.put(s); });
//
// Both take a Topic of the topic table (common/dds/topics.hpp): its name and QoS class.
//
// A Reader takes samples on its own thread, which waits on a WaitSet (data available or a
// stop guard) and calls the callback for each valid sample. Callbacks must be short.
#include <atomic>
#include <cstdint>
#include <fastdds/dds/core/condition/GuardCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/core/status/StatusMask.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include "common/dds/checked_type.hpp"
#include "common/dds/participant.hpp"
#include "common/dds/topics.hpp"

namespace teleop::dds {

template <class PubSub>
class Writer {
 public:
  using Sample = typename PubSub::type;

  Writer(Participant& participant, const Topic<PubSub>& t) : participant_(participant) {
    auto* topic =
        participant.topic(t.name, eprosima::fastdds::dds::TypeSupport(new CheckedType<PubSub>()));
    writer_ = participant.publisher()->create_datawriter(
        topic, writer_qos(participant.publisher(), t.qos));
    if (!writer_) throw DdsError(std::string("cannot create a DataWriter on ") + t.name);
  }
  ~Writer() {
    if (writer_) participant_.publisher()->delete_datawriter(writer_);
  }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Writes a sample; returns false (and counts it) if the middleware refused it.
  bool write(Sample& sample) {
    if (writer_->write(&sample)) {
      ++written_;
      return true;
    }
    ++failures_;
    return false;
  }

  /// Number of matched readers right now.
  int matched() const {
    eprosima::fastdds::dds::PublicationMatchedStatus st;
    if (writer_->get_publication_matched_status(st) != ReturnCode_t::RETCODE_OK) return -1;
    return st.current_count;
  }
  std::uint64_t written() const { return written_; }
  std::uint64_t failures() const { return failures_; }
  eprosima::fastdds::dds::DataWriter* raw() { return writer_; }

 private:
  Participant& participant_;
  eprosima::fastdds::dds::DataWriter* writer_ = nullptr;
  std::uint64_t written_ = 0;
  std::uint64_t failures_ = 0;
};

template <class PubSub>
class Reader {
 public:
  using Sample = typename PubSub::type;
  using Callback = std::function<void(const Sample&, const eprosima::fastdds::dds::SampleInfo&)>;

  Reader(Participant& participant, const Topic<PubSub>& t, Callback cb)
      : participant_(participant), callback_(std::move(cb)) {
    auto* topic =
        participant.topic(t.name, eprosima::fastdds::dds::TypeSupport(new CheckedType<PubSub>()));
    reader_ = participant.subscriber()->create_datareader(
        topic, reader_qos(participant.subscriber(), t.qos));
    if (!reader_) throw DdsError(std::string("cannot create a DataReader on ") + t.name);
    reader_->get_statuscondition().set_enabled_statuses(
        eprosima::fastdds::dds::StatusMask::data_available());
    thread_ = std::thread([this] { run(); });
  }

  ~Reader() { stop(); }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  /// Stops the thread and deletes the DataReader. Idempotent.
  void stop() {
    if (stopping_.exchange(true)) return;
    guard_.set_trigger_value(true);
    if (thread_.joinable()) thread_.join();
    if (reader_) {
      participant_.subscriber()->delete_datareader(reader_);
      reader_ = nullptr;
    }
  }

  /// Number of matched writers right now.
  int matched() const {
    eprosima::fastdds::dds::SubscriptionMatchedStatus st;
    if (reader_->get_subscription_matched_status(st) != ReturnCode_t::RETCODE_OK) return -1;
    return st.current_count;
  }
  std::uint64_t received() const { return received_.load(); }
  /// Samples dropped because they could not be deserialized (CheckedType).
  std::uint64_t malformed() const { return malformed_.load(); }

 private:
  void run() {
    eprosima::fastdds::dds::WaitSet waitset;
    waitset.attach_condition(reader_->get_statuscondition());
    waitset.attach_condition(guard_);
    eprosima::fastdds::dds::ConditionSeq active;
    Sample sample;
    eprosima::fastdds::dds::SampleInfo info;
    const eprosima::fastrtps::Duration_t timeout(0, 200'000'000);
    while (!stopping_.load()) {
      waitset.wait(active, timeout);  // timeout or trigger: both fine
      if (stopping_.load()) break;
      // bounded, in case a sample that fails to deserialize were not consumed by the take
      for (int i = 0; i < kMaxTakesPerWake; ++i) {
        // a malformed sample (CheckedType) is dropped and counted, never handed on; Fast DDS
        // may report it as a failed take, so it is counted before the return code is looked at
        const std::uint64_t malformed_before = malformed_samples();
        const ReturnCode_t rc = reader_->take_next_sample(&sample, &info);
        if (malformed_samples() != malformed_before) {
          malformed_.fetch_add(1);
          continue;
        }
        if (rc != ReturnCode_t::RETCODE_OK) break;
        if (!info.valid_data) continue;
        received_.fetch_add(1);
        callback_(sample, info);
      }
    }
    waitset.detach_condition(reader_->get_statuscondition());
    waitset.detach_condition(guard_);
  }

  static constexpr int kMaxTakesPerWake = 100000;
  Participant& participant_;
  Callback callback_;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;
  eprosima::fastdds::dds::GuardCondition guard_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> received_{0};
  std::atomic<std::uint64_t> malformed_{0};
  std::thread thread_;
};

/// Newest-value mailbox between a reader thread and a real-time loop. put() and take() copy
/// under a short mutex; the loop never waits for the middleware.
template <class T>
class Mailbox {
 public:
  void put(const T& value) {
    std::lock_guard<std::mutex> lock(mutex_);
    value_ = value;
    ++version_;
  }
  /// Copies the value into `out` if it changed since `seen_version`; updates seen_version.
  bool take_if_newer(T& out, std::uint64_t& seen_version) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (version_ == seen_version) return false;
    out = value_;
    seen_version = version_;
    return true;
  }
  std::uint64_t version() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return version_;
  }

 private:
  mutable std::mutex mutex_;
  T value_{};
  std::uint64_t version_ = 0;
};

}  // namespace teleop::dds

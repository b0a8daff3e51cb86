#pragma once
// The recorder behind teleop_record: one DataReader per known topic (topic_table.hpp), each
// with the QoS class of its live writers, reading serialized payloads as they are
// (raw_type.hpp). One thread waits on a WaitSet over all readers and moves samples into a
// bounded queue; another writes the queue to the recording file (common/record/recording.hpp:
// MCAP chunks, or SQLite transactions) at least every 50 ms. Memory is bounded: when the queue
// holds `queue_bytes`, new samples are dropped and counted (never silently). Lost samples are
// detected from each writer's DDS sequence numbers.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "common/dds/participant.hpp"
#include "common/record/recording.hpp"

namespace eprosima::fastdds::dds {
class DataReader;
}

namespace teleop::record {

struct RecorderOptions {
  std::string out;                        ///< recording file
  std::optional<RecordingFormat> format;  ///< default: format_for_path(out)
  McapOptions mcap;                       ///< chunking of an MCAP file
  std::size_t queue_bytes = 64u << 20;    ///< bound of the in-memory queue [bytes]
  std::vector<std::string> exclude;       ///< topic names not to record
  /// The reader thread sleeps this long between passes over the readers [ms] (0: wake per
  /// sample). Stream readers keep 64 samples, so up to ~50 ms is safe at 1 kHz.
  double batch_ms = 10.0;
};

/// What was recorded on one topic.
struct TopicCounts {
  std::string name;
  std::uint64_t samples = 0;       ///< recorded
  std::uint64_t bytes = 0;         ///< serialized payload bytes recorded
  std::uint64_t writers = 0;       ///< distinct writers heard
  std::uint64_t gaps = 0;          ///< samples missing between a writer's first and last seen
  std::uint64_t before_first = 0;  ///< a writer's samples written before the recorder heard it
  std::uint64_t dropped = 0;       ///< dropped because the queue was full
};

class Recorder {
 public:
  /// Creates the readers (not yet reading) and the file. @throws RecordingError, DdsError.
  Recorder(dds::Participant& participant, const RecorderOptions& options);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// Stops reading, writes what is queued, the counts and closes the file. Idempotent.
  void stop();
  /// Counts so far, one entry per recorded topic.
  std::vector<TopicCounts> counts() const;
  std::uint64_t samples() const { return samples_.load(); }
  /// Compressed / uncompressed payload bytes written so far.
  std::uint64_t stored_bytes() const;
  std::uint64_t raw_bytes() const;
  /// A JSON object with the counts (for --summary-json).
  std::string summary_json() const;
  /// True once writing the file failed (a full disk): the samples written before stay in the
  /// file (an MCAP file is closed as a valid one holding its complete chunks), the others are
  /// counted in lost_after_failure().
  bool failed() const { return failed_.load(); }
  /// What failed, naming the file; empty while nothing failed.
  std::string error() const;
  /// Samples in the file (MCAP: in complete chunks; SQLite: committed).
  std::uint64_t written() const { return written_.load(); }
  /// After a failure, the samples recorded but not in the file (0 otherwise).
  std::uint64_t lost_after_failure() const {
    return failed() && samples() > written() ? samples() - written() : 0;
  }

 private:
  struct Topic;
  void read_loop();
  void write_loop();
  void note_failure(const std::string& what);

  dds::Participant& participant_;
  RecorderOptions options_;
  std::unique_ptr<RecordingWriter> file_;
  std::vector<std::unique_ptr<Topic>> topics_;
  mutable std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<RecordedSample> queue_;
  std::size_t queued_bytes_ = 0;
  std::atomic<bool> stopping_{false};
  std::atomic<bool> reading_done_{false};
  std::atomic<std::uint64_t> samples_{0};
  std::atomic<std::uint64_t> raw_bytes_{0}, stored_bytes_{0};
  std::atomic<std::uint64_t> written_{0};
  std::atomic<bool> failed_{false};
  mutable std::mutex error_mutex_;
  std::string error_;
  std::int64_t started_ns_ = 0;
  std::thread reader_thread_, writer_thread_;
  bool stopped_ = false;
  void* guard_ = nullptr;  // eprosima::fastdds::dds::GuardCondition
};

}  // namespace teleop::record

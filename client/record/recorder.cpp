#include "client/record/recorder.hpp"

#include <fastdds/dds/core/condition/GuardCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/core/status/StatusMask.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>

#include "client/record/raw_reader.hpp"
#include "client/record/raw_type.hpp"
#include "client/record/topic_table.hpp"
#include "common/util/json.hpp"
#include "common/util/version.hpp"

namespace teleop::record {

namespace fdds = eprosima::fastdds::dds;

namespace {
std::int64_t wall_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

struct Recorder::Topic {
  const TopicEntry* entry = nullptr;
  int id = 0;
  fdds::DataReader* reader = nullptr;
  RawSample scratch;
  // counts: written by the reader thread, read by counts() under the mutex
  mutable std::mutex mutex;
  TopicCounts counts;
  struct WriterSeqs {
    std::int64_t first = 0, last = 0;
    std::uint64_t seen = 0;
  };
  std::map<std::array<std::uint8_t, 16>, WriterSeqs> writers;
};

Recorder::Recorder(dds::Participant& participant, const RecorderOptions& options)
    : participant_(participant), options_(options) {
  file_ = std::make_unique<RecordingWriter>(
      options.out, options.format.value_or(format_for_path(options.out)), options.mcap);
  started_ns_ = wall_ns();
  file_->set_meta("domain", std::to_string(participant.options().domain));
  file_->set_meta("profile", participant.options().profile);
  file_->set_meta("started_unix_ns", std::to_string(started_ns_));
  file_->set_meta("version", version_string());
  for (const auto& e : known_topics()) {
    if (std::find(options.exclude.begin(), options.exclude.end(), e.name) !=
        options.exclude.end()) {
      continue;
    }
    auto t = std::make_unique<Topic>();
    t->entry = &e;
    t->counts.name = e.name;
    t->id = file_->add_topic(e.name, e.type, qos_name(e.qos));
    // a recorder takes every sample: 64 deep absorbs 64 ms at 1 kHz
    t->reader = create_raw_reader(participant, e, 64);
    topics_.push_back(std::move(t));
  }
  guard_ = new fdds::GuardCondition();
  reader_thread_ = std::thread([this] { read_loop(); });
  writer_thread_ = std::thread([this] { write_loop(); });
}

Recorder::~Recorder() {
  try {
    stop();
  } catch (...) {
  }
  delete static_cast<fdds::GuardCondition*>(guard_);
}

void Recorder::read_loop() {
  auto* guard = static_cast<fdds::GuardCondition*>(guard_);
  fdds::WaitSet waitset;
  for (auto& t : topics_) waitset.attach_condition(t->reader->get_statuscondition());
  waitset.attach_condition(*guard);
  fdds::ConditionSeq active;
  fdds::SampleInfo info;
  const eprosima::fastrtps::Duration_t timeout(0, 100'000'000);
  while (true) {
    waitset.wait(active, timeout);
    const bool last_pass = stopping_.load();
    for (auto& t : topics_) {
      while (t->reader->take_next_sample(&t->scratch, &info) == ReturnCode_t::RETCODE_OK) {
        if (!info.valid_data) continue;
        RecordedSample s;
        s.topic_id = t->id;
        s.receive_ns = info.reception_timestamp.to_ns();
        s.source_ns = info.source_timestamp.to_ns();
        const auto& guid = info.sample_identity.writer_guid();
        std::array<std::uint8_t, 16> key{};
        std::memcpy(key.data(), guid.guidPrefix.value, 12);
        std::memcpy(key.data() + 12, guid.entityId.value, 4);
        std::memcpy(s.writer_guid, key.data(), 16);
        s.writer_seq = info.sample_identity.sequence_number().to64long();
        const std::size_t n = t->scratch.bytes.size();
        {
          std::lock_guard<std::mutex> l(t->mutex);
          auto [it, fresh] = t->writers.try_emplace(key);
          auto& w = it->second;
          if (fresh) {
            w.first = w.last = s.writer_seq;
            t->counts.writers = t->writers.size();
          }
          w.first = std::min(w.first, s.writer_seq);
          w.last = std::max(w.last, s.writer_seq);
          ++w.seen;
        }
        bool dropped = false;
        {
          std::lock_guard<std::mutex> l(queue_mutex_);
          if (queued_bytes_ + n > options_.queue_bytes) {
            dropped = true;
          } else {
            s.payload.swap(t->scratch.bytes);
            queued_bytes_ += n;
            queue_.push_back(std::move(s));
          }
        }
        std::lock_guard<std::mutex> l(t->mutex);
        if (dropped) {
          ++t->counts.dropped;
        } else {
          ++t->counts.samples;
          t->counts.bytes += n;
          samples_.fetch_add(1);
        }
      }
    }
    queue_cv_.notify_one();
    if (last_pass) break;
    // take in batches: at 1 kHz per stream topic a wake-up per sample costs the session's
    // processes CPU on a small machine; the reader histories (64 deep) hold a batch
    if (options_.batch_ms > 0.0) {
      std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(options_.batch_ms));
    }
  }
  for (auto& t : topics_) waitset.detach_condition(t->reader->get_statuscondition());
  waitset.detach_condition(*guard);
  reading_done_.store(true);
  queue_cv_.notify_one();
}

void Recorder::write_loop() {
  std::vector<RecordedSample> batch;
  while (true) {
    {
      std::unique_lock<std::mutex> l(queue_mutex_);
      queue_cv_.wait_for(l, std::chrono::milliseconds(50),
                         [this] { return queue_.size() >= 2000 || reading_done_.load(); });
      const bool done = reading_done_.load();
      batch.clear();
      batch.reserve(queue_.size());
      for (auto& s : queue_) batch.push_back(std::move(s));
      queue_.clear();
      queued_bytes_ = 0;
      l.unlock();
      if (!failed_.load()) {
        try {
          // an empty batch still lets an MCAP file write a chunk that has grown old
          file_->append(batch);
        } catch (const std::exception& e) {
          // a full disk or a failing file: keep what was written, stop writing, say so
          note_failure(e.what());
        }
      }
      written_.store(file_->samples_in_file());
      raw_bytes_.store(file_->raw_bytes());
      stored_bytes_.store(file_->stored_bytes());
      if (done) {
        std::lock_guard<std::mutex> l2(queue_mutex_);
        if (queue_.empty()) break;
      }
    }
  }
}

void Recorder::stop() {
  if (stopped_) return;
  stopped_ = true;
  stopping_.store(true);
  static_cast<fdds::GuardCondition*>(guard_)->set_trigger_value(true);
  if (reader_thread_.joinable()) reader_thread_.join();
  if (writer_thread_.joinable()) writer_thread_.join();
  for (auto& t : topics_) {
    if (t->reader) participant_.subscriber()->delete_datareader(t->reader);
    t->reader = nullptr;
  }
  try {
    file_->set_meta("stopped_unix_ns", std::to_string(wall_ns()));
    file_->set_meta("summary", summary_json());
    file_->close();
  } catch (const std::exception& e) {
    note_failure(e.what());
  }
  written_.store(file_->samples_in_file());
  raw_bytes_.store(file_->raw_bytes());
  stored_bytes_.store(file_->stored_bytes());
}

void Recorder::note_failure(const std::string& what) {
  std::lock_guard<std::mutex> el(error_mutex_);
  if (error_.empty()) {
    // the writers' messages name the file already
    error_ = what.find(options_.out) == std::string::npos ? options_.out + ": " + what : what;
  }
  failed_.store(true);
}

std::string Recorder::error() const {
  std::lock_guard<std::mutex> l(error_mutex_);
  return error_;
}

std::vector<TopicCounts> Recorder::counts() const {
  std::vector<TopicCounts> out;
  for (const auto& t : topics_) {
    std::lock_guard<std::mutex> l(t->mutex);
    TopicCounts c = t->counts;
    c.gaps = 0;
    c.before_first = 0;
    for (const auto& [guid, w] : t->writers) {
      const auto span = static_cast<std::uint64_t>(w.last - w.first + 1);
      c.gaps += span > w.seen ? span - w.seen : 0;
      c.before_first += static_cast<std::uint64_t>(std::max<std::int64_t>(0, w.first - 1));
    }
    out.push_back(c);
  }
  return out;
}

std::uint64_t Recorder::stored_bytes() const { return stored_bytes_.load(); }
std::uint64_t Recorder::raw_bytes() const { return raw_bytes_.load(); }

std::string Recorder::summary_json() const {
  std::uint64_t total = 0, dropped = 0, gaps = 0;
  OrderedJson topics = OrderedJson::object();
  for (const auto& c : counts()) {
    topics[c.name] = {{"samples", c.samples},           {"bytes", c.bytes},
                      {"writers", c.writers},           {"gaps", c.gaps},
                      {"before_first", c.before_first}, {"dropped", c.dropped}};
    total += c.samples;
    dropped += c.dropped;
    gaps += c.gaps;
  }
  OrderedJson o;
  o["topics"] = std::move(topics);
  o["format"] = format_name(file_->format());
  o["samples"] = total;
  o["gaps"] = gaps;
  o["dropped"] = dropped;
  o["payload_bytes"] = raw_bytes();
  o["stored_bytes"] = stored_bytes();
  o["version"] = version_string();
  return json_line(o);
}

}  // namespace teleop::record

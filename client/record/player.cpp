#include "client/record/player.hpp"

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <thread>

#include "client/record/raw_type.hpp"
#include "client/record/topic_table.hpp"
#include "common/config/config.hpp"
#include "common/record/recording.hpp"
#include "common/util/progress.hpp"
#include "common/util/signals.hpp"

namespace teleop::record {

namespace fdds = eprosima::fastdds::dds;

namespace {

/// Sleeps until `t` in short steps so a stop request is seen quickly.
void sleep_until(std::chrono::steady_clock::time_point t) {
  while (!stop_requested()) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= t) return;
    std::this_thread::sleep_for(
        std::min<std::chrono::steady_clock::duration>(t - now, std::chrono::milliseconds(50)));
  }
}

/// Sleeps `s` seconds in short steps (see sleep_until).
void sleep_for_s(double s) {
  sleep_until(
      std::chrono::steady_clock::now() +
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(s)));
}

/// The player's DataWriters: one per topic of the recording that is played (not excluded, its
/// type known here), deleted with this object.
class Writers {
 public:
  /// Skipped topics are counted in `result` and named on stderr.
  /// @throws dds::DdsError when a DataWriter cannot be made.
  Writers(dds::Participant& participant, const RecordingReader& rec, const PlayerOptions& o,
          PlayerResult& result)
      : participant_(participant) {
    for (const auto& t : rec.topics()) {
      if (std::find(o.exclude.begin(), o.exclude.end(), t.name) != o.exclude.end()) continue;
      const TopicEntry* e = find_topic(t.name);
      if (!e || e->type != t.type_name) {
        ++result.skipped_topics;
        std::fprintf(stderr, "teleop_play: skipping topic %s: type %s is not known here\n",
                     t.name.c_str(), t.type_name.c_str());
        continue;
      }
      const dds::TopicQos qos = qos_from_name(t.qos);
      auto* topic = participant.topic(t.name, fdds::TypeSupport(new RawPubSubType(e->make_type())));
      fdds::DataWriterQos q = dds::writer_qos(participant.publisher(), qos);
      Out out;
      out.writer = participant.publisher()->create_datawriter(topic, q);
      if (!out.writer) throw dds::DdsError("cannot create a DataWriter on " + t.name);
      out.latched = is_latched(qos);
      outs_[t.id] = out;
      all_ids_.push_back(t.id);
      if (out.latched) latched_ids_.push_back(t.id);
    }
  }
  ~Writers() {
    for (auto& [id, out] : outs_) participant_.publisher()->delete_datawriter(out.writer);
  }
  Writers(const Writers&) = delete;
  Writers& operator=(const Writers&) = delete;

  /// Writes the sample on its topic (a topic not played: nothing), counted in `result`.
  void write(const RecordedSample& sample, PlayerResult& result) {
    auto it = outs_.find(sample.topic_id);
    if (it == outs_.end()) return;
    raw_.bytes = sample.payload;
    if (it->second.writer->write(&raw_)) {
      ++it->second.written;
      ++result.written;
    } else {
      ++result.failures;
    }
  }
  std::size_t size() const { return outs_.size(); }
  const std::vector<int>& all_ids() const { return all_ids_; }
  const std::vector<int>& latched_ids() const { return latched_ids_; }

 private:
  struct Out {
    fdds::DataWriter* writer = nullptr;
    bool latched = false;
    std::uint64_t written = 0;
  };
  dds::Participant& participant_;
  std::map<int, Out> outs_;
  std::vector<int> latched_ids_, all_ids_;
  RawSample raw_;
};

/// Every sample from `seek_ns` on, paced by the recorded receive times at --speed; a pause in the
/// recording longer than --max-gap (a clock jump, a stopped session) is cut to it.
void play_paced(RecordingReader& rec, Writers& writers, std::int64_t seek_ns,
                const PlayerOptions& o, PlayerResult& result) {
  if (!writers.all_ids().empty()) rec.scan(seek_ns, 0, writers.all_ids());
  Progress progress(o.progress, "teleop_play", result.recording_s - o.seek_s, "s", 1);
  const auto t0 = std::chrono::steady_clock::now();
  const auto max_gap_ns = static_cast<std::int64_t>(o.max_gap_s * 1e9);
  std::int64_t prev_ns = seek_ns, skipped_ns = 0;
  RecordedSample s;
  while (!writers.all_ids().empty() && !stop_requested() && rec.next(s)) {
    if (s.receive_ns - prev_ns > max_gap_ns) {
      const std::int64_t cut = s.receive_ns - prev_ns - max_gap_ns;
      skipped_ns += cut;
      ++result.gaps_skipped;
      std::fprintf(stderr,
                   "teleop_play: %s: skipped %.3f s of a %.3f s pause at %.3f s (--max-gap %g)\n",
                   o.file.c_str(), static_cast<double>(cut) * 1e-9,
                   static_cast<double>(s.receive_ns - prev_ns) * 1e-9,
                   static_cast<double>(prev_ns - rec.first_ns()) * 1e-9, o.max_gap_s);
    }
    prev_ns = s.receive_ns;
    const double offset_s =
        static_cast<double>(s.receive_ns - seek_ns - skipped_ns) * 1e-9 / o.speed;
    sleep_until(t0 + std::chrono::duration_cast<std::chrono::nanoseconds>(
                         std::chrono::duration<double>(offset_s)));
    if (stop_requested()) break;
    writers.write(s, result);
    progress.set(static_cast<double>(s.receive_ns - seek_ns) * 1e-9);
  }
  progress.finish();
}

}  // namespace

PlayerResult play(dds::Participant& participant, const PlayerOptions& o) {
  RecordingReader rec(o.file);
  PlayerResult result;
  result.recording_s = static_cast<double>(rec.last_ns() - rec.first_ns()) * 1e-9;
  if (o.seek_s > result.recording_s) {
    char buf[160];
    std::snprintf(buf, sizeof(buf),
                  "command line: --seek %g is beyond the end of the recording "
                  "(allowed: 0 to %.3f s)",
                  o.seek_s, result.recording_s);
    throw config::ConfigError(buf);
  }
  Writers writers(participant, rec, o, result);
  const std::int64_t seek_ns = rec.first_ns() + static_cast<std::int64_t>(o.seek_s * 1e9);
  if (!o.quiet) {
    std::printf(
        "teleop_play: %s: %.3f s, %zu topics; playing from %.3f s at %gx on domain %d "
        "(profile %s)\n",
        o.file.c_str(), result.recording_s, writers.size(), o.seek_s, o.speed,
        participant.options().domain, participant.options().profile.c_str());
    std::fflush(stdout);
  }
  sleep_for_s(o.wait_s);
  // 1. the latched state before the seek point (scene, topology, events so far)
  if (o.seek_s > 0.0 && !writers.latched_ids().empty()) {
    RecordedSample s;
    rec.scan(rec.first_ns(), seek_ns, writers.latched_ids());
    while (!stop_requested() && rec.next(s)) writers.write(s, result);
  }
  // 2. everything from the seek point, paced by the recorded receive times
  play_paced(rec, writers, seek_ns, o, result);
  // 3. let reliable readers acknowledge and late observers pick up the latched topics
  sleep_for_s(o.linger_s);
  if (!o.quiet) {
    std::printf("teleop_play: wrote %llu samples (%llu refused)\n",
                static_cast<unsigned long long>(result.written),
                static_cast<unsigned long long>(result.failures));
    std::fflush(stdout);
  }
  return result;
}

}  // namespace teleop::record

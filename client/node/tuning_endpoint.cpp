#include "client/node/tuning_endpoint.hpp"

#include <algorithm>
#include <cstdio>

#include "client/cycle/master_cycle.hpp"

namespace teleop::master {

namespace {
constexpr std::uint8_t kApplied = 0;
constexpr std::uint8_t kRejected = 1;
}  // namespace

TuningEndpoint::TuningEndpoint(dds::Participant& participant, std::uint32_t master_session,
                               bool accepting)
    : master_session_(master_session),
      accepting_(accepting),
      status_writer_(participant, dds::topics::kTuningStatus) {
  TuningStatus prototype;  // the strings' capacity, so that the loop's copies do not allocate
  prototype.scheme(std::string(32, ' '));
  prototype.request_source(std::string(32, ' '));
  prototype.message(std::string(256, ' '));
  status_writer_.prime(prototype);
  if (!accepting_) return;
  reader_ = std::make_unique<dds::Reader<TuningRequestPubSubType>>(
      participant, dds::topics::kTuning,
      [this](const TuningRequest& r, const eprosima::fastdds::dds::SampleInfo&) { on_request(r); });
}

TuningEndpoint::~TuningEndpoint() {
  if (reader_) reader_->stop();
}

void TuningEndpoint::on_request(const TuningRequest& r) {
  if (r.master_session() != 0 && r.master_session() != master_session_) {
    ignored_.fetch_add(1);
    return;
  }
  received_.fetch_add(1);
  Pending p;
  p.seq = r.seq();
  std::snprintf(p.source, sizeof(p.source), "%s", r.source().c_str());
  p.data.fields = r.fields();
  TuningValues& v = p.data.values;
  v.master_stiffness_n_per_m = r.master_stiffness_n_per_m();
  v.master_damping_ns_per_m = r.master_damping_ns_per_m();
  v.force_gain = r.force_gain();
  v.slave_stiffness_n_per_m = r.slave_stiffness_n_per_m();
  v.forward_delay_s = r.forward_delay_ms() * 1e-3;
  v.backward_delay_s = r.backward_delay_ms() * 1e-3;
  p.data.ramp_s = r.ramp_s();
  std::lock_guard<std::mutex> lock(mutex_);
  if (count_ == kQueue) {
    dropped_.fetch_add(1);
    return;
  }
  queue_[(head_ + count_) % kQueue] = p;
  ++count_;
  pending_.store(count_);
}

int TuningEndpoint::poll(MasterCycle& cycle, double now_s, std::int64_t now_ns,
                         const std::function<void(std::uint8_t, const std::string&)>& report) {
  if (pending_.load() == 0) return 0;  // the common case: no lock, nothing to do
  int handled = 0;
  for (;;) {
    Pending p;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (count_ == 0) break;
      p = queue_[head_];
      head_ = (head_ + 1) % kQueue;
      --count_;
      pending_.store(count_);
    }
    ++handled;
    const TuningValues before = cycle.tuning().current();
    const std::string problem = cycle.tune(p.data, now_s);
    answer_seq_ = p.seq;
    answer_source_ = p.source;
    answer_accepted_ = problem.empty();
    const std::string from = answer_source_.empty() ? std::string("a tool") : answer_source_;
    answer_message_ =
        answer_accepted_
            ? "tuning from " + from + ": " +
                  describe_tuning(p.data, before,
                                  std::max(p.data.ramp_s, cycle.tuning_limits().min_ramp_s))
            : "tuning from " + from + " rejected: " + problem;
    report(answer_accepted_ ? kApplied : kRejected, answer_message_);
  }
  if (handled > 0) publish_status(cycle, now_ns);
  return handled;
}

void TuningEndpoint::publish_status(const MasterCycle& cycle, std::int64_t now_ns) {
  const TuningLimits& l = cycle.tuning_limits();
  const TuningValues& v = cycle.tuning().target();
  TuningStatus s;
  s.time_ns(now_ns);
  s.master_session(master_session_);
  s.scheme(cycle.config().controller.scheme);
  s.accepting(accepting_);
  s.tunable(l.tunable);
  s.request_seq(answer_seq_);
  s.request_source(answer_source_);
  s.accepted(answer_accepted_);
  s.message(answer_message_.substr(0, 255));
  s.accepted_count(cycle.tunings_accepted());
  s.rejected_count(cycle.tunings_rejected());
  s.master_stiffness_n_per_m(v.master_stiffness_n_per_m);
  s.master_damping_ns_per_m(v.master_damping_ns_per_m);
  s.force_gain(v.force_gain);
  s.slave_stiffness_n_per_m(v.slave_stiffness_n_per_m);
  s.forward_delay_ms(v.forward_delay_s * 1e3);
  s.backward_delay_ms(v.backward_delay_s * 1e3);
  s.max_master_stiffness_n_per_m(l.max_master_stiffness_n_per_m);
  s.max_master_damping_ns_per_m(l.max_master_damping_ns_per_m);
  s.max_force_gain(l.max_force_gain);
  s.max_slave_stiffness_n_per_m(l.max_slave_stiffness_n_per_m);
  s.max_delay_ms(l.max_delay_s * 1e3);
  status_writer_.write(s);
}

}  // namespace teleop::master

#include "client/viewer/drive_session.hpp"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cstdio>
#include <iostream>

#include "common/util/clock.hpp"
#include "common/util/json.hpp"
#include "common/util/rate_loop.hpp"
#include "common/util/version.hpp"

namespace teleop::viewer {

DriveSession::DriveSession(dds::Participant& participant, const HandDriveParams& params,
                           double peak_force_n)
    : peak_force_n_(peak_force_n),
      state_writer_(participant, dds::topics::kDeviceState),
      tuning_writer_(participant, dds::topics::kTuning),
      drive_(params) {
  command_reader_ = std::make_unique<dds::Reader<DeviceCommandPubSubType>>(
      participant, dds::topics::kDeviceCommand,
      [this](const DeviceCommand& c, const eprosima::fastdds::dds::SampleInfo&) {
        const Eigen::Vector3d f(c.force_n()[0], c.force_n()[1], c.force_n()[2]);
        std::lock_guard<std::mutex> lock(mutex_);
        ++view_.commands_received;
        last_command_ns_ = now_ns();
        view_.force_enabled = c.enable();
        view_.force_n = f.allFinite() ? f : Eigen::Vector3d::Zero();
        if (c.enable() && f.allFinite()) view_.max_force_n = std::max(view_.max_force_n, f.norm());
      });
  status_reader_ = std::make_unique<dds::Reader<TuningStatusPubSubType>>(
      participant, dds::topics::kTuningStatus,
      [this](const TuningStatus& s, const eprosima::fastdds::dds::SampleInfo&) {
        std::lock_guard<std::mutex> lock(mutex_);
        view_.status = s;
        view_.have_status = true;
      });
  thread_ = std::thread([this] { run(); });
}

DriveSession::~DriveSession() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (command_reader_) command_reader_->stop();
  if (status_reader_) status_reader_->stop();
}

void DriveSession::run() {
  // the viewer runs niced (it yields to the loops); the device thread must not be late by the
  // master's staleness timeout (10 ms), so it asks for the normal priority back
  const pid_t tid = static_cast<pid_t>(syscall(SYS_gettid));
  if (setpriority(PRIO_PROCESS, static_cast<id_t>(tid), 0) != 0) {
    std::cerr << "teleop_viewer: warning: the drive thread keeps the viewer's low priority "
                 "(no CAP_SYS_NICE); under load the master may see the device as stale\n";
  }
  RateLoop loop(1000.0);
  const double dt = loop.period_s();
  DeviceState s;
  s.orientation_wxyz()[0] = 1.0;
  s.engaged(true);
  s.max_force_n(peak_force_n_);
  std::uint64_t seq = 0;
  while (!stop_.load()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      drive_.advance(dt);
      for (int i = 0; i < 3; ++i) {
        s.position_m()[static_cast<std::size_t>(i)] = drive_.position_m()[i];
        s.linear_velocity_mps()[static_cast<std::size_t>(i)] = drive_.velocity_mps()[i];
      }
      ++view_.states_written;
    }
    s.seq(++seq);
    s.time_ns(now_ns());
    state_writer_.write(s);
    loop.wait();
  }
}

void DriveSession::grab(const Eigen::Vector3d& anchor, const Eigen::Vector3d& view_dir,
                        const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  std::lock_guard<std::mutex> lock(mutex_);
  drive_.grab(anchor, view_dir, o, d);
}
void DriveSession::drag(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  std::lock_guard<std::mutex> lock(mutex_);
  drive_.drag(o, d);
}
void DriveSession::release() {
  std::lock_guard<std::mutex> lock(mutex_);
  drive_.release();
}
bool DriveSession::dragging() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return drive_.dragging();
}
void DriveSession::nudge(const Eigen::Vector3d& direction, double dt_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  drive_.nudge(direction, dt_s);
}

void DriveSession::send_tuning(const TuningRequest& request) {
  TuningRequest r = request;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    r.seq(++tuning_seq_);
    ++view_.tunings_sent;
  }
  r.time_ns(now_ns());
  if (r.source().size() == 0) r.source("viewer");
  tuning_writer_.write(r);
}

DriveView DriveSession::view() const {
  std::lock_guard<std::mutex> lock(mutex_);
  DriveView v = view_;
  v.target_m = drive_.target_m();
  v.position_m = drive_.position_m();
  v.force_age_s = last_command_ns_ ? seconds_between(last_command_ns_, now_ns()) : 1e9;
  return v;
}

std::string DriveSession::summary_json() const {
  const DriveView v = view();
  OrderedJson out;
  out["states_written"] = v.states_written;
  out["commands_received"] = v.commands_received;
  out["max_force_n"] = json_number(v.max_force_n);
  out["final_position_m"] =
      OrderedJson::array({json_number(v.position_m.x()), json_number(v.position_m.y()),
                          json_number(v.position_m.z())});
  out["tunings_sent"] = v.tunings_sent;
  if (v.have_status) {
    const TuningStatus& s = v.status;
    out["status"] = {{"accepting", s.accepting()},
                     {"accepted_count", s.accepted_count()},
                     {"rejected_count", s.rejected_count()},
                     {"last_accepted", s.accepted()},
                     {"message", s.message().to_string()},
                     {"force_gain", json_number(s.force_gain())},
                     {"master_damping_ns_per_m", json_number(s.master_damping_ns_per_m())},
                     {"forward_delay_ms", json_number(s.forward_delay_ms())}};
  }
  out["version"] = version_string();
  return json_line(out);
}

}  // namespace teleop::viewer

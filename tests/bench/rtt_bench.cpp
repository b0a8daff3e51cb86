// teleop_bench rtt --out DIR: DDS round trip between two processes on loopback, for a
// 200-byte sample (a command) and a 60 KB sample (a level-4 mesh frame in doubles), paced at
// 1 kHz and as fast as possible, over UDP on 127.0.0.1 (profile loopback, the default) and
// shared memory + UDP (profile loopback_shm). Writes DIR/rtt.csv and DIR/rtt.png.
//
// --profiles A,B   other profiles (default loopback,loopback_shm); a secure profile also needs
//                  --security-dir DIR (deploy/make_security.sh, which makes the identity "bench"
//                  allowed to publish and subscribe bench/*), e.g.
//   teleop_bench rtt --profiles loopback,secure --security-dir /tmp/sec --out /tmp/r --no-chart
//
// The echo side is this same executable, started as `teleop_bench rtt-echo`.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <iostream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "common/util/csv.hpp"
#include "common/util/rate_loop.hpp"
#include "common/util/registry.hpp"
#include "common/util/stats.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/process.hpp"

namespace teleop::bench {
namespace {

// the benchmark's own pair of topics: mesh frames (a size like the real ones), stream QoS
constexpr dds::Topic<MeshFramePubSubType> kPing{"bench/ping", dds::TopicQos::kStream};
constexpr dds::Topic<MeshFramePubSubType> kPong{"bench/pong", dds::TopicQos::kStream};
constexpr std::uint64_t kStopFrame = ~0ULL;

/// Options of a bench participant: a secure profile uses the identity "bench" of --security-dir.
dds::ParticipantOptions bench_options(const std::string& profile, int domain,
                                      const std::string& name, const std::string& security_dir) {
  dds::ParticipantOptions o{profile, domain, name};
  if (profile.starts_with("secure")) {
    o.network.security = {security_dir, "--security-dir", "bench", "--identity"};
  }
  return o;
}

std::vector<std::string> split_commas(const std::string& text) {
  std::vector<std::string> out;
  std::size_t p = 0;
  while (p <= text.size()) {
    const auto c = text.find(',', p);
    const std::string item = text.substr(p, c == std::string::npos ? std::string::npos : c - p);
    if (!item.empty()) out.push_back(item);
    if (c == std::string::npos) break;
    p = c + 1;
  }
  return out;
}

int rtt_echo(const CommandArgs& args) {
  const int domain = std::stoi(args.option("--domain", "100"));
  const std::string profile = args.option("--profile", "loopback");
  dds::Participant p(bench_options(profile, domain, "rtt-echo", args.option("--security-dir", "")));
  dds::Writer<MeshFramePubSubType> pong(p, kPong);
  std::atomic<bool> stop{false};
  dds::Reader<MeshFramePubSubType> ping(
      p, kPing, [&](const MeshFrame& f, const eprosima::fastdds::dds::SampleInfo&) {
        if (f.frame() == kStopFrame) {
          stop = true;
          return;
        }
        MeshFrame copy = f;
        pong.write(copy);
      });
  const auto t0 = now_ns();
  while (!stop && seconds_between(t0, now_ns()) < 600) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return 0;
}

struct Result {
  Summary rtt_us;
  std::uint64_t lost = 0;
};

Result measure(dds::Writer<MeshFramePubSubType>& ping, std::mutex& m, std::condition_variable& cv,
               std::uint64_t& last_pong, std::size_t floats, int samples, bool paced) {
  MeshFrame f;
  f.object_id(0);
  f.positions_m().assign(floats, 0.5f);
  std::vector<double> rtts;
  rtts.reserve(static_cast<std::size_t>(samples));
  Result r;
  static std::uint64_t frame = 1;
  RateLoop loop(1000.0);
  for (int i = 0; i < samples; ++i) {
    const std::uint64_t id = ++frame;
    f.frame(id);
    const auto t_send = now_ns();
    ping.write(f);
    std::unique_lock<std::mutex> lock(m);
    const bool ok =
        cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return last_pong >= id; });
    const auto t_recv = now_ns();
    lock.unlock();
    if (ok) {
      rtts.push_back(static_cast<double>(t_recv - t_send) * 1e-3);
    } else {
      ++r.lost;
    }
    if (paced) loop.wait();
  }
  r.rtt_us = summarize(rtts);
  return r;
}

int rtt(const CommandArgs& args) {
  const int samples = std::stoi(args.option("--samples", args.quick ? "300" : "5000"));
  const int domain = std::stoi(args.option("--domain", "100"));
  const std::string csv_path = (args.out_dir / "rtt.csv").string();
  CsvWriter csv(csv_path, {"profile", "payload_bytes", "mode", "samples", "lost", "rtt_us_p50",
                           "rtt_us_p90", "rtt_us_p99", "rtt_us_p999", "rtt_us_max"});
  const std::string security_dir = args.option("--security-dir", "");
  const std::vector<std::string> profiles =
      split_commas(args.option("--profiles", "loopback,loopback_shm"));
  Progress progress("rtt", 4.0 * static_cast<double>(profiles.size()), "cases");
  for (const std::string& profile : profiles) {
    // the echo side: this executable in another process
    char self[4096];
    const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
    if (n <= 0) throw std::runtime_error("cannot find /proc/self/exe");
    self[n] = '\0';
    std::vector<std::string> echo_args = {
        "rtt-echo",  "--out", args.out_dir.string(), "--domain", std::to_string(domain),
        "--profile", profile};
    if (!security_dir.empty()) {
      echo_args.push_back("--security-dir");
      echo_args.push_back(security_dir);
    }
    teleop::test::Process echo(self, echo_args, "rtt_echo");
    dds::Participant p(bench_options(profile, domain, "rtt-ping", security_dir));
    dds::Writer<MeshFramePubSubType> ping(p, kPing);
    std::mutex m;
    std::condition_variable cv;
    std::uint64_t last_pong = 0;
    dds::Reader<MeshFramePubSubType> pong(
        p, kPong, [&](const MeshFrame& f, const eprosima::fastdds::dds::SampleInfo&) {
          {
            std::lock_guard<std::mutex> lock(m);
            last_pong = std::max(last_pong, f.frame());
          }
          cv.notify_one();
        });
    const auto t0 = now_ns();
    while (ping.matched() < 1 || pong.matched() < 1) {
      if (seconds_between(t0, now_ns()) > 20) throw std::runtime_error("echo never matched");
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    measure(ping, m, cv, last_pong, 44, 200, false);  // warm-up
    // 200 B: a command-sized sample; 61,488 B: 2562 x 3 doubles, a level-4 mesh frame
    for (const std::size_t floats : {std::size_t{44}, std::size_t{15372}}) {
      for (const bool paced : {true, false}) {
        const Result r = measure(ping, m, cv, last_pong, floats, samples, paced);
        const std::size_t bytes = 24 + 4 * floats;
        csv.row_text({profile, std::to_string(bytes), paced ? "paced_1kHz" : "max_rate",
                      std::to_string(samples), std::to_string(r.lost), format_number(r.rtt_us.p50),
                      format_number(r.rtt_us.p90), format_number(r.rtt_us.p99),
                      format_number(r.rtt_us.p999), format_number(r.rtt_us.max)});
        std::printf("%-13s %6zu B %-10s p50 %7.1f us  p99 %7.1f us  p99.9 %7.1f us  lost %llu\n",
                    profile.c_str(), bytes, paced ? "1 kHz" : "max", r.rtt_us.p50, r.rtt_us.p99,
                    r.rtt_us.p999, static_cast<unsigned long long>(r.lost));
        progress.add();
      }
    }
    MeshFrame stop;
    stop.frame(kStopFrame);
    ping.write(stop);
    echo.wait_for(5.0);
  }
  progress.finish();
  csv.flush();
  if (!args.no_chart) run_chart_script("rtt.py", {csv_path, (args.out_dir / "rtt.png").string()});
  return 0;
}

TELEOP_REGISTER_COMMAND(bench, "rtt", "DDS round trip, 200 B and 60 KB, paced and max rate", rtt,
                        integer_option("--samples", 1, 1e7, "samples per case"),
                        integer_option("--domain", 0, 232, "DDS domain id"),
                        text_option("--profiles", "profiles P,P,..."),
                        text_option("--security-dir", "DDS Security files"));
TELEOP_REGISTER_COMMAND(bench, "rtt-echo", "(internal) echo side of the rtt benchmark", rtt_echo,
                        integer_option("--domain", 0, 232, "DDS domain id"),
                        text_option("--profile", "participant profile"),
                        text_option("--security-dir", "DDS Security files"));

}  // namespace
}  // namespace teleop::bench

// Delay channel: measured delay, jitter and loss match the configuration; reproducible;
// FIFO without reordering; allocation-free; bad flags and YAML rejected with clear errors.
#include <gtest/gtest.h>

#include "tests/support/config_error.hpp"

#include <cmath>
#include <functional>
#include <vector>

#include "client/net/delay_channel.hpp"
#include "common/config/config.hpp"
#include "tests/support/alloc_counter.hpp"

using namespace teleop::master;
using namespace teleop;

namespace {

std::string error_of(const std::function<void()>& fn) { return teleop::test::config_error_of(fn); }

struct Delivery {
  int value;
  double at_s;
  bool operator==(const Delivery& o) const { return value == o.value && at_s == o.at_s; }
};

/// Pushes n samples at 1 kHz and polls every 0.1 ms; returns what was delivered, in order.
std::vector<Delivery> run(DelayChannel<int>& ch, int n) {
  std::vector<Delivery> out;
  out.reserve(static_cast<std::size_t>(n));
  const double end = n * 1e-3 + 1.0;
  int next = 0;
  for (long k = 0; k * 1e-4 < end; ++k) {
    const double t = k * 1e-4;
    if (k % 10 == 0 && next < n) ch.push(next++, t);
    int v = 0;
    while (ch.pop(t, v)) out.push_back({v, t});
  }
  return out;
}

TEST(DelayChannel, ConstantDelayIsApplied) {
  DelayConfig c;
  c.delay_s = 0.05;
  DelayChannel<int> ch(c);
  const auto d = run(ch, 10000);
  ASSERT_EQ(d.size(), 10000u);
  const ChannelReport r = ch.report();
  EXPECT_NEAR(r.delay_mean_ms, 50.0, 0.11);  // polling quantum 0.1 ms
  EXPECT_NEAR(r.delay_p50_ms, 50.0, 0.11);
  EXPECT_NEAR(r.delay_p99_ms, 50.0, 0.11);
  EXPECT_LT(r.delay_std_ms, 0.1);
  EXPECT_EQ(r.loss_fraction, 0.0);
}

TEST(DelayChannel, UniformAndNormalJitterMatchTheirStatistics) {
  for (JitterDist dist : {JitterDist::kUniform, JitterDist::kNormal}) {
    DelayConfig c;
    c.delay_s = 0.05;
    c.jitter_s = 0.005;
    c.jitter_dist = dist;
    c.reorder = true;  // delays independent, so the sample statistics are the configured ones
    c.seed = 42;
    DelayChannel<int> ch(c);
    run(ch, 10000);
    const ChannelReport r = ch.report();
    const double sd_ms = c.expected_jitter_stddev_s() * 1e3;
    EXPECT_NEAR(r.delay_mean_ms, 50.0 + 0.05, 0.25) << static_cast<int>(dist);
    EXPECT_NEAR(r.delay_std_ms, sd_ms, 0.08 * sd_ms) << static_cast<int>(dist);
    EXPECT_NEAR(r.delay_p50_ms, 50.0, 0.3);
    if (dist == JitterDist::kUniform) {
      EXPECT_LE(r.delay_max_ms, 55.1);
      EXPECT_NEAR(r.delay_p99_ms, 54.9, 0.2);  // 99 % of the way across [45, 55]
    } else {
      EXPECT_NEAR(r.delay_p99_ms, 50.0 + 2.326 * 5.0, 0.8);
    }
    EXPECT_GT(r.counters.reordered, 0u);  // jitter 5 ms at 1 kHz does reorder
  }
}

TEST(DelayChannel, WithoutReorderingNoSampleOvertakesAnother) {
  DelayConfig c;
  c.delay_s = 0.02;
  c.jitter_s = 0.02;  // ten times the sample period: reordering would be frequent
  c.jitter_dist = JitterDist::kNormal;
  c.seed = 3;
  DelayChannel<int> ch(c);
  const auto d = run(ch, 10000);
  ASSERT_EQ(d.size(), 10000u);
  for (std::size_t i = 1; i < d.size(); ++i) ASSERT_GT(d[i].value, d[i - 1].value) << i;
  EXPECT_EQ(ch.counters().reordered, 0u);
  // holding back behind a late sample can only add delay
  EXPECT_GE(ch.report().delay_mean_ms, 20.0);
}

TEST(DelayChannel, SameSeedSameRunDifferentSeedDifferentRun) {
  DelayConfig c;
  c.delay_s = 0.03;
  c.jitter_s = 0.004;
  c.jitter_dist = JitterDist::kNormal;
  c.reorder = true;
  c.loss_probability = 0.05;
  c.burst_loss = true;
  c.burst_p_good_to_bad = 0.01;
  c.burst_p_bad_to_good = 0.3;
  c.seed = 1234;
  DelayChannel<int> a(c), b(c);
  const auto da = run(a, 10000), db = run(b, 10000);
  EXPECT_EQ(da, db);
  a.reset();  // reset reseeds: the same future again
  EXPECT_EQ(run(a, 10000), da);
  c.seed = 1235;
  DelayChannel<int> other(c);
  EXPECT_NE(run(other, 10000), da);
}

TEST(DelayChannel, BernoulliLossMatchesItsProbability) {
  DelayConfig c;
  c.loss_probability = 0.01;
  c.seed = 9;
  DelayChannel<int> ch(c);
  const auto d = run(ch, 10000);
  const auto& k = ch.counters();
  EXPECT_EQ(k.pushed, 10000u);
  EXPECT_EQ(k.lost_random + d.size(), 10000u);
  // 100 expected, standard deviation ~10
  EXPECT_GT(k.lost_random, 60u);
  EXPECT_LT(k.lost_random, 140u);
  EXPECT_NEAR(ch.report().loss_fraction, c.expected_loss(), 0.004);
}

TEST(DelayChannel, GilbertElliottBurstLossMatchesStationaryRateAndIsBursty) {
  DelayConfig c;
  c.burst_loss = true;
  c.burst_p_good_to_bad = 0.01;
  c.burst_p_bad_to_good = 0.2;  // mean burst length 5
  c.seed = 5;
  DelayChannel<int> ch(c);
  const int n = 100000;
  const auto d = run(ch, n);
  const double loss = ch.report().loss_fraction;
  EXPECT_NEAR(loss, c.expected_loss(), 0.25 * c.expected_loss());  // 4.76 %
  // mean burst length from the gaps between delivered values
  long bursts = 0, lost = 0;
  for (std::size_t i = 1; i < d.size(); ++i) {
    const int gap = d[i].value - d[i - 1].value - 1;
    if (gap > 0) {
      ++bursts;
      lost += gap;
    }
  }
  ASSERT_GT(bursts, 0);
  EXPECT_NEAR(static_cast<double>(lost) / static_cast<double>(bursts), 5.0, 1.0);
}

TEST(DelayChannel, PopNewestKeepsNewestAndDropsStale) {
  DelayConfig c;
  c.delay_s = 0.01;
  c.jitter_s = 0.01;
  c.reorder = true;
  c.seed = 77;
  DelayChannel<int> ch(c);
  int last = -1;
  for (int k = 0; k < 5000; ++k) {
    const double t = k * 1e-3;
    ch.push(k, t);
    int v = 0;
    if (ch.pop_newest(t, v)) {
      ASSERT_GT(v, last);  // never goes back in time
      last = v;
    }
  }
  EXPECT_GT(ch.counters().stale + ch.counters().superseded, 0u);
}

TEST(DelayChannel, OverflowIsCountedAsLoss) {
  DelayConfig c;
  c.delay_s = 1.0;
  c.capacity = 16;
  DelayChannel<int> ch(c);
  for (int k = 0; k < 20; ++k) ch.push(k, k * 1e-3);
  EXPECT_EQ(ch.counters().lost_overflow, 4u);
  EXPECT_EQ(ch.in_flight(), 16u);
}

TEST(DelayChannel, PushAndPopAllocateNothing) {
  DelayConfig c;
  c.delay_s = 0.02;
  c.jitter_s = 0.003;
  c.jitter_dist = JitterDist::kNormal;
  c.loss_probability = 0.01;
  c.burst_loss = true;
  c.burst_p_good_to_bad = 0.01;
  c.burst_p_bad_to_good = 0.5;
  DelayChannel<int> ch(c);
  teleop::test::NoAllocScope scope;
  int v = 0;
  for (int k = 0; k < 20000; ++k) {
    ch.push(k, k * 1e-3);
    ch.pop_newest(k * 1e-3, v);
    ch.pop(k * 1e-3, v);
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(DelayConfig, ParsesFlags) {
  DelayConfig c;
  const auto rest = parse_delay_flags(
      c, {"--delay", "50ms", "--jitter=5ms", "--jitter-dist", "normal", "--reorder", "--loss", "1%",
          "--burst-loss", "1%,30%", "--seed", "7", "--scheme", "force-position"});
  EXPECT_DOUBLE_EQ(c.delay_s, 0.05);
  EXPECT_DOUBLE_EQ(c.jitter_s, 0.005);
  EXPECT_EQ(c.jitter_dist, JitterDist::kNormal);
  EXPECT_TRUE(c.reorder);
  EXPECT_DOUBLE_EQ(c.loss_probability, 0.01);
  EXPECT_TRUE(c.burst_loss);
  EXPECT_DOUBLE_EQ(c.burst_p_good_to_bad, 0.01);
  EXPECT_DOUBLE_EQ(c.burst_p_bad_to_good, 0.30);
  EXPECT_EQ(c.seed, 7u);
  EXPECT_EQ(rest, (std::vector<std::string>{"--scheme", "force-position"}));
  EXPECT_NE(c.describe().find("50 ms"), std::string::npos) << c.describe();
}

TEST(DelayConfig, BadFlagsGiveClearErrors) {
  auto err = [](std::vector<std::string> args) {
    return error_of([&] {
      DelayConfig c;
      parse_delay_flags(c, args);
    });
  };
  std::string m = err({"--delay", "50parsecs"});
  EXPECT_NE(m.find("--delay"), std::string::npos) << m;
  EXPECT_NE(m.find("parsecs"), std::string::npos) << m;
  m = err({"--loss", "150%"});
  EXPECT_NE(m.find("--loss"), std::string::npos) << m;
  EXPECT_NE(m.find("[0, 1]"), std::string::npos) << m;
  m = err({"--jitter-dist", "cauchy"});
  EXPECT_NE(m.find("cauchy"), std::string::npos) << m;
  EXPECT_NE(m.find("uniform, normal"), std::string::npos) << m;
  m = err({"--burst-loss", "0.1"});
  EXPECT_NE(m.find("p_gb,p_bg"), std::string::npos) << m;
  m = err({"--burst-loss", "0.1,0"});
  EXPECT_NE(m.find("p_bg"), std::string::npos) << m;
  m = err({"--seed", "-3"});
  EXPECT_NE(m.find("--seed"), std::string::npos) << m;
  m = err({"--delay"});
  EXPECT_NE(m.find("needs a value"), std::string::npos) << m;
  m = err({"--delay", "20s"});
  EXPECT_NE(m.find("--delay '20s'"), std::string::npos) << m;
  EXPECT_NE(m.find("[0, 10] s"), std::string::npos) << m;
}

TEST(DelayConfig, ADurationFlagNeedsItsUnit) {
  auto err = [](std::vector<std::string> args) {
    return error_of([&] {
      DelayConfig c;
      parse_delay_flags(c, args);
    });
  };
  for (const char* bad : {"5", "0.05", "1e3", "-0", "5."}) {
    const std::string m = err({"--delay", bad});
    EXPECT_NE(m.find(std::string("--delay '") + bad + "' has no unit"), std::string::npos) << m;
  }
  EXPECT_NE(err({"--jitter", "2"}).find("--jitter '2' has no unit"), std::string::npos);
  EXPECT_NE(err({"--delay-spike", "3,1s,1s"}).find("has no unit"), std::string::npos);
  DelayConfig c;
  parse_delay_flags(c, {"--delay", "0", "--jitter", "2ms"});  // a bare zero is zero in any unit
  EXPECT_EQ(c.delay_s, 0.0);
  EXPECT_DOUBLE_EQ(c.jitter_s, 0.002);
  // YAML keeps plain numbers as seconds (docs/configuration.md)
  const DelayConfig y = delay_config_from_yaml(teleop::config::Node::parse("{delay: 0.05}", "t"));
  EXPECT_DOUBLE_EQ(y.delay_s, 0.05);
}

TEST(DelayConfig, ParsesYamlAndRejectsBadFields) {
  const auto n = teleop::config::Node::parse(
      "forward: {delay: 80ms, jitter: 0.002, jitter_dist: normal, reorder: true, loss: 2%,\n"
      "          burst_loss: [0.01, 0.25], seed: 11}\n",
      "net.yaml");
  const DelayConfig c = delay_config_from_yaml(n.at("forward"));
  EXPECT_DOUBLE_EQ(c.delay_s, 0.08);
  EXPECT_DOUBLE_EQ(c.jitter_s, 0.002);
  EXPECT_EQ(c.jitter_dist, JitterDist::kNormal);
  EXPECT_TRUE(c.reorder);
  EXPECT_DOUBLE_EQ(c.loss_probability, 0.02);
  EXPECT_DOUBLE_EQ(c.burst_p_bad_to_good, 0.25);
  EXPECT_EQ(c.seed, 11u);

  auto err = [](const std::string& yaml) {
    return error_of([&] {
      delay_config_from_yaml(teleop::config::Node::parse(yaml, "net.yaml").at("forward"));
    });
  };
  std::string m = err("forward: {delay: fast}");
  EXPECT_NE(m.find("net.yaml"), std::string::npos) << m;
  EXPECT_NE(m.find("forward.delay"), std::string::npos) << m;
  EXPECT_NE(m.find("fast"), std::string::npos) << m;
  m = err("forward: {dealy: 5ms}");
  EXPECT_NE(m.find("dealy"), std::string::npos) << m;
  m = err("forward: {loss: 2}");
  EXPECT_NE(m.find("forward.loss"), std::string::npos) << m;
  m = err("forward: {burst_loss: [0.1]}");
  EXPECT_NE(m.find("forward.burst_loss"), std::string::npos) << m;
  m = err("forward: {delay: [1, 2]}");
  EXPECT_NE(m.find("forward.delay"), std::string::npos) << m;
  EXPECT_NE(m.find("single value"), std::string::npos) << m;
  m = err("forward: {jitter_dist: cauchy}");
  EXPECT_NE(m.find("cauchy"), std::string::npos) << m;
}

}  // namespace

// Scheduled faults for the fault suite: a delay spike and a loss window, timed from
// the channel's first sample.
TEST(DelayChannelFaults, DelaySpikeDelaysOnlyTheWindowAndKeepsOrder) {
  DelayConfig cfg;
  cfg.delay_s = 0.010;
  apply_delay_flag(cfg, "--delay-spike", "2s,1s,1s");
  cfg.validate();
  DelayChannel<int> ch(cfg);
  const double t0 = 100.0;  // any origin: the window counts from the first sample
  int last = -1;
  double max_delay_in = 0.0, max_delay_out = 0.0;
  std::vector<double> sent(6000);
  for (int k = 0; k < 6000; ++k) {
    const double now = t0 + 1e-3 * k;
    sent[static_cast<std::size_t>(k)] = now;
    ch.push(k, now);
    int v = 0;
    while (ch.pop(now, v)) {
      EXPECT_GT(v, last);  // FIFO: the samples after the spike queue behind it
      last = v;
      const double d = now - sent[static_cast<std::size_t>(v)];
      (v >= 2000 && v < 3000 ? max_delay_in : max_delay_out) =
          std::max(v >= 2000 && v < 3000 ? max_delay_in : max_delay_out, d);
    }
  }
  EXPECT_NEAR(max_delay_in, 1.010, 1.5e-3);
  EXPECT_LT(ch.counters().delivered, 6000u);  // the last second is still in flight
  EXPECT_EQ(ch.counters().lost_window, 0u);
  EXPECT_NE(cfg.describe().find("+1e+03 ms delay at 2 s for 1 s"), std::string::npos)
      << cfg.describe();
}

TEST(DelayChannelFaults, LossWindowLosesAboutPInsideAndNothingOutside) {
  DelayConfig cfg;
  apply_delay_flag(cfg, "--loss-window", "1s,2s,50%");
  DelayChannel<int> ch(cfg);
  int lost_in = 0, lost_out = 0;
  for (int k = 0; k < 4000; ++k) {
    if (!ch.push(k, 5.0 + 1e-3 * k)) (k >= 1000 && k < 3000 ? lost_in : lost_out)++;
    int v = 0;
    while (ch.pop(5.0 + 1e-3 * k, v)) {
    }
  }
  EXPECT_EQ(lost_out, 0);
  EXPECT_NEAR(lost_in, 1000, 120);  // 2000 samples at p = 0.5: sd 22
  EXPECT_EQ(ch.counters().lost_window, static_cast<std::uint64_t>(lost_in));
  EXPECT_NEAR(ch.counters().loss_fraction(), lost_in / 4000.0, 1e-12);
  // bad values name the flag and the part
  const std::string msg = error_of([] {
    DelayConfig c;
    apply_delay_flag(c, "--loss-window", "1s,2s");
  });
  EXPECT_NE(msg.find("--loss-window '1s,2s' must be at,duration,loss"), std::string::npos) << msg;
}

TEST(DelayChannelFaults, WithoutAWindowTheRandomStreamIsUnchanged) {
  // a channel with a spike (no random draw) and one without give the same losses and delays
  DelayConfig a;
  a.delay_s = 0.02;
  a.jitter_s = 0.005;
  a.loss_probability = 0.05;
  DelayConfig b = a;
  b.spike_at_s = 100.0;  // after the run: never active
  b.spike_duration_s = 1.0;
  b.spike_extra_s = 1.0;
  DelayChannel<int> ca(a), cb(b);
  for (int k = 0; k < 3000; ++k) {
    const double now = 1e-3 * k;
    EXPECT_EQ(ca.push(k, now), cb.push(k, now));
    int va = 0, vb = 0;
    bool ga = false, gb = false;
    while ((ga = ca.pop(now, va)) | (gb = cb.pop(now, vb))) {
      ASSERT_EQ(ga, gb);
      EXPECT_EQ(va, vb);
    }
  }
}

#include "common/util/stats.hpp"

#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <cstdio>

#include "common/util/rate_loop.hpp"
#include "common/util/realtime.hpp"
#include "tests/support/alloc_counter.hpp"

namespace {

TEST(Stats, PercentilesInterpolate) {
  std::vector<double> v;
  for (int i = 1; i <= 101; ++i) v.push_back(i);
  EXPECT_DOUBLE_EQ(teleop::percentile(v, 50), 51);
  EXPECT_DOUBLE_EQ(teleop::percentile(v, 99), 100);
  const auto s = teleop::summarize(v);
  EXPECT_EQ(s.count, 101u);
  EXPECT_DOUBLE_EQ(s.min, 1);
  EXPECT_DOUBLE_EQ(s.max, 101);
  EXPECT_DOUBLE_EQ(s.mean, 51);
}

// What the server's 1 Hz statistics use on the physics thread: a window copied into reserved
// scratch and summarised in place, without allocating.
TEST(Stats, SnapshotAndSummaryInPlaceDoNotAllocate) {
  teleop::SampleWindow w(1000);
  for (int i = 0; i < 1500; ++i) w.record(static_cast<double>((i * 7919) % 1000));
  std::vector<double> scratch;
  scratch.reserve(w.capacity());
  teleop::Summary s;
  {
    teleop::test::NoAllocScope scope;
    w.snapshot_into(scratch);
    s = teleop::summarize_in_place(scratch);
    EXPECT_EQ(scope.allocations(), 0u);
  }
  EXPECT_EQ(s.count, 1000u);
  EXPECT_DOUBLE_EQ(s.min, 0.0);
  EXPECT_DOUBLE_EQ(s.max, 999.0);
  EXPECT_EQ(s.p50, teleop::summarize(w.snapshot()).p50);
}

TEST(Stats, EmptyPercentileIsNan) { EXPECT_TRUE(std::isnan(teleop::percentile({}, 50))); }

TEST(Stats, SampleWindowKeepsNewestAndDoesNotAllocate) {
  teleop::SampleWindow w(4);
  {
    teleop::test::NoAllocScope scope;
    for (int i = 0; i < 10; ++i) w.record(i);
    EXPECT_EQ(scope.allocations(), 0u);
  }
  EXPECT_EQ(w.size(), 4u);
  EXPECT_EQ(w.total_recorded(), 10u);
  EXPECT_EQ(w.snapshot(), (std::vector<double>{6, 7, 8, 9}));
}

TEST(AllocCounter, SeesVectorGrowth) {
  teleop::test::NoAllocScope scope;
  std::vector<int> v;
  v.push_back(1);
  EXPECT_GE(scope.allocations(), 1u);
}

TEST(RateLoop, HoldsRateAndCountsOverruns) {
  teleop::RateLoop loop(1000.0);
  for (int i = 0; i < 50; ++i) loop.wait();
  EXPECT_EQ(loop.iterations(), 50u);
  // a deliberate 20 ms stall must be counted as missed periods
  const auto before = loop.overruns();
  struct timespec ts {
    0, 20'000'000
  };
  nanosleep(&ts, nullptr);
  loop.wait();
  EXPECT_GE(loop.overruns() - before, 10u);
}

TEST(RateLoop, RejectsNonPositiveRate) {
  EXPECT_THROW(teleop::RateLoop(0.0), std::invalid_argument);
  EXPECT_THROW(teleop::RateLoop(-5.0), std::invalid_argument);
}

TEST(RateLoop, SpinningNeverWakesBeforeTheDeadline) {
  EXPECT_THROW(teleop::RateLoop(1000.0, 16, -1), std::invalid_argument);
  EXPECT_THROW(teleop::RateLoop(1000.0, 16, 1'000'000), std::invalid_argument);
  teleop::RateLoop loop(1000.0, 64, 200'000);
  EXPECT_EQ(loop.spin_ns(), 200'000);
  for (int i = 0; i < 50; ++i) loop.wait();
  EXPECT_EQ(loop.iterations(), 50u);
  // the busy-wait ends at the deadline, never before it: no negative lateness
  const teleop::Summary s = teleop::summarize(loop.lateness_us().snapshot());
  EXPECT_GE(s.min, 0.0);
}

TEST(DmaLatencyHold, NegativeHoldsNothingAndAFailureIsExplained) {
  const teleop::DmaLatencyHold none(-1);
  EXPECT_FALSE(none.held());
  EXPECT_TRUE(none.problem().empty());
  teleop::DmaLatencyHold h(0);
  // root on a machine with the device holds it; anywhere else the reason names the device
  if (!h.held()) {
    EXPECT_NE(h.problem().find("/dev/cpu_dma_latency"), std::string::npos);
  }
  teleop::DmaLatencyHold moved(std::move(h));
  EXPECT_FALSE(h.held());  // NOLINT(bugprone-use-after-move): the moved-from holder is empty
}

}  // namespace

#include <fstream>
#include <sstream>

#include "common/util/csv.hpp"

namespace {

TEST(CsvWriter, RealTimeRowsDoNotAllocateAndRoundTrip) {
  const std::string path = "/tmp/teleop_csv_test_" + std::to_string(getpid()) + ".csv";
  {
    teleop::CsvWriter csv(path, {"a", "b", "c"});
    const double row[3] = {0.1234567890123456789, -2.5e-300, 42.0};
    csv.row(row, 3);  // first write may size the stream buffer
    teleop::test::NoAllocScope scope;
    for (int i = 0; i < 100; ++i) csv.row(row, 3);
    EXPECT_EQ(scope.allocations(), 0u);
    EXPECT_THROW(csv.row(row, 2), std::logic_error);
  }
  std::ifstream in(path);
  std::string header, line;
  std::getline(in, header);
  std::getline(in, line);
  EXPECT_EQ(header, "a,b,c");
  std::istringstream ss(line);
  double a, b, c;
  char k1, k2;
  ss >> a >> k1 >> b >> k2 >> c;
  EXPECT_EQ(a, 0.1234567890123456789);  // shortest round-trip form
  EXPECT_EQ(b, -2.5e-300);
  EXPECT_EQ(c, 42.0);
  std::remove(path.c_str());
}

}  // namespace

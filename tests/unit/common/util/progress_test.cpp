// The tools' progress line (common/util/progress.hpp): its text, when it draws, the final line.
// A fake clock drives the reporter: nothing here depends on real time.
#include "common/util/progress.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/alloc_counter.hpp"

namespace {

using teleop::Progress;
using teleop::ProgressMode;
using teleop::ProgressView;

std::string duration(double s) {
  char buf[32];
  teleop::format_duration(buf, sizeof(buf), s);
  return buf;
}

std::string line(const ProgressView& v) {
  char buf[256];
  const std::size_t n = teleop::format_progress(buf, sizeof(buf), v);
  EXPECT_EQ(n, std::string(buf).size());
  return buf;
}

/// A stream in memory and what was written to it.
struct Capture {
  char* data = nullptr;
  std::size_t size = 0;
  std::FILE* f = open_memstream(&data, &size);
  ~Capture() {
    if (f) std::fclose(f);
    std::free(data);
  }
  std::string text() {
    std::fflush(f);
    return std::string(data, size);
  }
};

TEST(Progress, DurationText) {
  EXPECT_EQ(duration(0.0), "0s");
  EXPECT_EQ(duration(7.4), "7s");
  EXPECT_EQ(duration(59.6), "1m00s");
  EXPECT_EQ(duration(185.0), "3m05s");
  EXPECT_EQ(duration(3599.4), "59m59s");
  EXPECT_EQ(duration(2 * 3600 + 4 * 60 + 20), "2h04m");
  EXPECT_EQ(duration(-1.0), "?");
  EXPECT_EQ(duration(1.0 / 0.0), "?");
}

TEST(Progress, LineShowsCountRateElapsedAndEta) {
  ProgressView v;
  v.label = "delay";
  v.unit = "runs";
  v.done = 120;
  v.total = 500;
  v.elapsed_s = 20;
  // 6 runs/s, 380 left: 63.3 s
  EXPECT_EQ(line(v), "delay: 120/500 runs (24.0 %), 6.00 runs/s, 20s elapsed, ETA 1m03s");
  v.final = true;
  v.done = 500;
  v.elapsed_s = 80;
  EXPECT_EQ(line(v), "delay: 500/500 runs (100.0 %), 6.25 runs/s, done in 1m20s");
}

TEST(Progress, LineForATimedRunAndUnknowns) {
  ProgressView v;
  v.label = "record";
  v.unit = "s";
  v.decimals = 1;
  v.done = 4.54;
  v.total = 9.0;
  v.elapsed_s = 4.5;
  EXPECT_EQ(line(v), "record: 4.5/9.0 s (50.4 %), 1.01 s/s, 5s elapsed, ETA 4s");
  // nothing done yet: no rate, the ETA is unknown
  v.done = 0.0;
  EXPECT_EQ(line(v), "record: 0.0/9.0 s (0.0 %), 0.00 s/s, 5s elapsed, ETA ?");
  // no total: neither a percentage nor an ETA; a rate of 10 or more has one decimal
  ProgressView u;
  u.unit = "frames";
  u.done = 250;
  u.elapsed_s = 2.0;
  EXPECT_EQ(line(u), "250 frames, 125.0 frames/s, 2s elapsed");
}

TEST(Progress, LineIsTruncatedToItsBuffer) {
  ProgressView v;
  v.label = "a-long-label-that-does-not-fit";
  v.unit = "runs";
  v.total = 10;
  char buf[12];
  EXPECT_EQ(teleop::format_progress(buf, sizeof(buf), v), 11u);
  EXPECT_EQ(std::string(buf), "a-long-labe");
}

TEST(Progress, ModeDecidesWhetherItDraws) {
  EXPECT_TRUE(teleop::progress_wanted(ProgressMode::kAuto, true));
  EXPECT_FALSE(teleop::progress_wanted(ProgressMode::kAuto, false));
  EXPECT_TRUE(teleop::progress_wanted(ProgressMode::kOn, false));
  EXPECT_FALSE(teleop::progress_wanted(ProgressMode::kOff, true));
  EXPECT_EQ(teleop::progress_mode_from(false, false, false), ProgressMode::kAuto);
  EXPECT_EQ(teleop::progress_mode_from(true, false, false), ProgressMode::kOn);
  EXPECT_EQ(teleop::progress_mode_from(true, true, false), ProgressMode::kOff);
  EXPECT_EQ(teleop::progress_mode_from(true, false, true), ProgressMode::kOff);
}

TEST(Progress, RedrawsAtMostFourTimesASecondThenAFinalLine) {
  Capture out;
  double now = 100.0;
  {
    Progress p(out.f, "sweep", 10, "runs", 0, [&] { return now; });
    p.poll();  // the first call draws at once
    EXPECT_EQ(out.text(), "\rsweep: 0/10 runs (0.0 %), 0.00 runs/s, 0s elapsed, ETA ?");
    now += 0.1;
    p.add();  // 0.1 s after the last draw: not drawn
    EXPECT_EQ(out.text().find("1/10"), std::string::npos);
    now += 0.2;
    p.add();  // due: drawn
    now += 0.1;
    p.add();  // 0.1 s after the last draw: not drawn
    std::string s = out.text();
    EXPECT_EQ(s.substr(s.rfind('\r')),
              "\rsweep: 2/10 runs (20.0 %), 6.67 runs/s, 0s elapsed, ETA 1s");
    now += 0.2;
    p.poll();  // due again, nothing counted
    s = out.text();
    EXPECT_NE(s.find("\rsweep: 3/10 runs (30.0 %)"), std::string::npos);
    now += 1.0;
    for (int i = 0; i < 7; ++i) p.add();
  }  // the destructor writes the final line
  const std::string s = out.text();
  EXPECT_NE(s.find("\rsweep: 10/10 runs (100.0 %), 6.25 runs/s, done in 2s"), std::string::npos);
  EXPECT_EQ(s.back(), '\n');
  EXPECT_EQ(s.find('\n'), s.size() - 1);  // one line, redrawn in place
}

TEST(Progress, ShorterLinePadsOverTheLongerOne) {
  Capture out;
  double now = 0.0;
  Progress p(out.f, "", 1000, "runs", 0, [&] { return now; });
  p.poll();
  now = 1.0;
  p.add(999);  // "999/1000 runs (99.9 %), 999.0 runs/s, 1s elapsed, ETA 0s"
  now = 100.0;
  p.finish();  // shorter: "1000/1000 ... done in 1m40s" needs padding only if shorter
  p.finish();  // a second call writes nothing
  std::string s = out.text();
  s = s.substr(s.find('\r', 1));  // from the second line: 999/1000, then the final one
  const std::size_t second = s.find('\r', 1);
  ASSERT_NE(second, std::string::npos);
  EXPECT_GE(s.size() - second - 2, second - 1);  // the final line covers the one before
  EXPECT_EQ(s.find('\n'), s.size() - 1);
}

TEST(Progress, CountingAndDrawingDoNotAllocate) {
  std::FILE* sink = std::fopen("/dev/null", "w");
  ASSERT_NE(sink, nullptr);
  std::fputs("x", sink);  // the stream's buffer is made at its first write
  double now = 0.0;
  {
    Progress p(sink, "loop", 1e6, "steps", 0, [&] { return now; });
    teleop::test::NoAllocScope scope;
    for (int i = 0; i < 1000; ++i) {
      now += 0.01;  // a draw every 25 counts
      p.add();
    }
    p.set(2000);
    p.finish();
    EXPECT_EQ(scope.allocations(), 0u);
  }
  std::fclose(sink);
}

TEST(Progress, SilentReporterWritesNothingButCounts) {
  Progress p(nullptr, "x", 5, "runs", 0);
  EXPECT_FALSE(p.active());
  p.add(2);
  p.set(4);
  p.finish();
  EXPECT_EQ(p.done(), 4.0);
}

TEST(Progress, CountsFromManyThreads) {
  Capture out;
  double now = 0.0;
  {
    Progress p(out.f, "pool", 4000, "runs", 0, [&] { return now; });
    std::vector<std::thread> pool;
    for (int t = 0; t < 4; ++t) {
      pool.emplace_back([&] {
        for (int i = 0; i < 1000; ++i) p.add();
      });
    }
    for (std::thread& t : pool) t.join();
    EXPECT_EQ(p.done(), 4000.0);
  }
  EXPECT_NE(out.text().find("4000/4000 runs (100.0 %)"), std::string::npos);
}

}  // namespace

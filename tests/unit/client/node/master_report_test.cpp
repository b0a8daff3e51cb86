// The master's report of a made-up session: the printout's lines and figures, the JSON summary's
// keys and values, the verdict of a refused master, and the CSV log's header and row.
#include "client/node/master_report.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "client/device/simulated_device.hpp"
#include "common/util/exit_codes.hpp"

namespace teleop::master {
namespace {

/// A link whose slave never answers.
struct SilentLink final : SlaveLink {
  void send(const SlaveCommand&) override {}
  bool receive(double, SlaveSample&, double&) override { return false; }
};

/// A session's objects for the report: a cycle that never ran, options, a binding, a scene.
struct Fixture {
  SimulatedDevice device{SimulatedDeviceParams{}};
  SilentLink link;
  MasterCycle cycle{MasterCycleConfig{}, device, link};
  MasterOptions options;
  ServerBinding binding{0x1234, 1'000'000'000};
  SceneDescription scene;
  SessionReport rep;
  Fixture() {
    rep.elapsed_s = 3.5;
    rep.session_s = 2.0;
    rep.issued = 1000;
    rep.in_flight = 10;
    rep.sent = 1000;
    rep.received = 980;
    rep.stalls = 1;
    rep.longest_stall_s = 0.25;
    rep.rtt_ms = Summary{};
    rep.rtt_ms.p50 = 1.5;
    rep.rtt_ms.p99 = 2.5;
    rep.rtt_ms.max = 3.0;
    rep.rtt_ms.count = 900;
  }
  ReportContext context() const {
    return ReportContext{options, binding, scene, 0x1234, 0, TuningCounts{}};
  }
};

TEST(MasterReport, ThePrintoutHasItsLinesInOrderWithTheSessionsFigures) {
  Fixture f;
  const std::string text = session_summary_text(f.cycle, f.rep, f.context());
  const std::string scheme = f.cycle.config().controller.scheme;
  EXPECT_EQ(text.rfind("session summary (" + scheme + ", simulated, script press-slip)\n", 0), 0u)
      << text;
  // 990 commands left the injected channel, 980 arrived: 10 lost
  EXPECT_NE(text.find("  commands        1000 issued, 980 received by the server, 10 lost "
                      "(1.01%; 0 dropped by the injected channel, 1000 sent), 10 in flight at "
                      "the end\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("  round trip      p50 1.500 ms  p99 2.500 ms  max 3.000 ms  (900 echoes, "
                      "network)\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("loop stalls 1 (longest 0.250 s)"), std::string::npos) << text;
  EXPECT_NE(text.find("  ownership       session 0x00001234: owned the slave\n"), std::string::npos)
      << text;
  EXPECT_NE(text.find("never bound, followed"), std::string::npos) << text;
  EXPECT_EQ(text.find("  tuning "), std::string::npos) << "no tuning line unless accepting";
  // no contact: the relative force error is a dash, never "nan"
  EXPECT_NE(text.find("(no contact: - of the mean contact force)"), std::string::npos) << text;
  EXPECT_EQ(text.find(" nan"), std::string::npos) << text;
  EXPECT_EQ(text.find(" -nan"), std::string::npos) << text;
  const char* order[] = {
      "  duration ",    "  commands ",  "  injected delay ", "  round trip ",     "  loop delay ",
      "  loop jitter ", "  tracking ",  "  force ",          "  transparency ",   "  passivity ",
      "  safety ",      "  ownership ", "  server binding ", "  network thread ", "  device ",
      "  server ",      "  verdict "};
  std::size_t at = 0;
  for (const char* line : order) {
    const std::size_t next = text.find(std::string("\n") + line, at);
    ASSERT_NE(next, std::string::npos) << line << " missing or out of order in\n" << text;
    at = next + 1;
  }
  EXPECT_EQ(text.back(), '\n');
}

TEST(MasterReport, TheJsonSummaryCarriesTheFiguresAndTheSession) {
  Fixture f;
  const OrderedJson j = session_summary_json(f.cycle, f.rep, f.context());
  EXPECT_EQ(j.begin().key(), "version");
  EXPECT_EQ(j["issued"], 1000u);
  EXPECT_EQ(j["received"], 980u);
  EXPECT_EQ(j["lost"], 10u);
  EXPECT_EQ(j["rtt_ms"]["count"], 900u);
  EXPECT_DOUBLE_EQ(j["rtt_ms"]["p99"].get<double>(), 2.5);
  EXPECT_TRUE(j["force_error_relative"].is_null()) << "no contact: NaN, null in the JSON";
  EXPECT_EQ(j["stalls"]["count"], 1u);
  EXPECT_EQ(j["ownership"]["session"], 0x1234u);
  EXPECT_EQ(j["ownership"]["refused"], false);
  EXPECT_EQ(j["device"], "simulated");
  EXPECT_EQ(j["hertz"]["valid"], false) << "the scene has no deformable body";
  EXPECT_EQ(j["tuning"]["accepting"], false);
  EXPECT_TRUE(j.contains("server_binding"));
  EXPECT_TRUE(j.contains("verdict"));
}

TEST(MasterReport, ARefusedMasterThatIssuedNothingIsRefused) {
  Fixture f;
  f.rep = SessionReport{};
  f.rep.refused = true;
  f.rep.issued_before_owning = 5;
  const SessionVerdict v =
      session_verdict(f.cycle.metrics(), f.rep, f.cycle.config().controller.scheme);
  EXPECT_EQ(v.name, "refused");
  EXPECT_EQ(v.exit_status, exit_code::kRefused);
  const std::string text = session_summary_text(f.cycle, f.rep, f.context());
  EXPECT_NE(text.find("  ownership       session 0x00001234: REFUSED, another master owns the "
                      "slave (5 commands sent while refused, "),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("  verdict         refused - another master owns the slave\n"),
            std::string::npos)
      << text;
  EXPECT_EQ(session_summary_json(f.cycle, f.rep, f.context())["verdict"], "refused");
}

TEST(MasterReport, TheCycleLogWritesItsHeaderAndOneRowOfEveryColumn) {
  Fixture f;
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("master_report_test_" + std::to_string(::getpid()) + ".csv"))
                               .string();
  {
    CycleLog log(path, 30.0);
    log.row(f.cycle, 0.5, 1.25, std::nan(""));
    log.close();
  }
  std::ifstream in(path);
  std::string header, row, extra;
  ASSERT_TRUE(std::getline(in, header));
  ASSERT_TRUE(std::getline(in, row));
  EXPECT_FALSE(std::getline(in, extra));
  std::filesystem::remove(path);
  auto fields = [](const std::string& line) {
    std::vector<std::string> out;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) out.push_back(x);
    return out;
  };
  const std::vector<std::string> names = fields(header);
  const std::vector<std::string> values = fields(row);
  ASSERT_EQ(names.size(), CycleLog::kColumns);
  ASSERT_EQ(values.size(), CycleLog::kColumns);
  EXPECT_EQ(names.front(), "t_s");
  EXPECT_EQ(names.back(), "loading");
  auto value = [&](const std::string& name) {
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (names[i] == name) return values[i];
    }
    return std::string("(no column)");
  };
  EXPECT_DOUBLE_EQ(std::stod(value("t_s")), 0.5);
  EXPECT_DOUBLE_EQ(std::stod(value("rtt_ms")), 1.25);
  EXPECT_DOUBLE_EQ(std::stod(value("delay_injected_ms")), 30.0);
}

}  // namespace
}  // namespace teleop::master

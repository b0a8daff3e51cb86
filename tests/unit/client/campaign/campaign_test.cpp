// Campaigns: the file expands into runs in a fixed order and is refused with a message naming
// the file, the field, the value and the range; a point run is the delay sweep's run; the
// table is the same bytes whatever the threads, shards and interruptions; a world run steps
// the default scene with the robot homed first.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "client/campaign/campaign.hpp"
#include "client/campaign/results.hpp"
#include "client/campaign/runner.hpp"
#include "client/campaign/store.hpp"
#include "client/control/scheme_traits.hpp"
#include "common/util/csv.hpp"
#include "tests/support/config_error.hpp"
#include "tests/support/press_world.hpp"

namespace teleop::campaign {
namespace {

namespace fs = std::filesystem;
using test::config_error_of;

const char* kSmall = R"(name: small
model: point
duration_s: 4
defaults:
  environment: sphere
  stiffness_n_per_m: 2000
sweeps:
  - name: a
    scheme: [position-position, force-position]
    delay_ms: {from: 0, to: 60, step: 30}
  - name: b
    scheme: wave-variables
    environment: wall
    stiffness_n_per_m: 20000
    loss: [0, 0.05]
    seed: [1, 2]
)";

/// A folder of its own, removed at the end.
class CampaignDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("teleop_campaign_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& leaf) const { return (dir_ / leaf).string(); }
  static std::string read(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
  fs::path dir_;
};

TEST(CampaignFile, ExpandsSweepsInFileOrderLastAxisFastest) {
  const Campaign c = parse_campaign(kSmall, "small.yaml");
  ASSERT_EQ(c.runs.size(), 2u * 3u + 2u * 2u);
  EXPECT_EQ(c.runs[0].scheme, "position-position");
  EXPECT_EQ(c.runs[0].delay_ms, 0.0);
  EXPECT_EQ(c.runs[1].delay_ms, 30.0);
  EXPECT_EQ(c.runs[2].delay_ms, 60.0);
  EXPECT_EQ(c.runs[3].scheme, "force-position");
  EXPECT_EQ(c.runs[6].sweep, "b");
  EXPECT_EQ(c.runs[6].environment, "wall");
  EXPECT_EQ(c.runs[6].stiffness_n_per_m, 20000.0);
  EXPECT_EQ(c.runs[7].seed, 2u);
  EXPECT_EQ(c.runs[8].loss, 0.05);
  for (std::size_t i = 0; i < c.runs.size(); ++i) EXPECT_EQ(c.runs[i].id, i);
  // the defaults apply where a sweep says nothing
  EXPECT_EQ(c.runs[0].stiffness_n_per_m, 2000.0);
  EXPECT_EQ(c.duration_s, 4.0);
}

TEST(CampaignFile, RefusesBadInputNamingFileFieldValueAndRange) {
  const auto err = [](const std::string& text) {
    return config_error_of([&] { parse_campaign(text, "bad.yaml"); });
  };
  const std::string head = "name: x\nmodel: point\nduration_s: 2\nsweeps:\n  - name: s\n";
  struct Case {
    std::string text;
    std::vector<std::string> says;
  };
  const std::vector<Case> cases = {
      {head + "    delay_ms: [0, -5]\n", {"bad.yaml", "delay_ms[1]", "'-5'", "[0, 10000]"}},
      {head + "    scheme: [pp]\n", {"bad.yaml", "scheme[0]", "'pp'", "force-position"}},
      {head + "    loss: 1.5\n", {"bad.yaml", "loss", "'1.5'", "[0, 1]"}},
      {head + "    scene: a.yaml\n", {"bad.yaml", "scene", "does not apply to model 'point'"}},
      {head + "    delya_ms: 5\n", {"bad.yaml", "delya_ms"}},
      {head + "    delay_ms: []\n", {"bad.yaml", "delay_ms", "empty list"}},
      {head + "    delay_ms: {from: 10, to: 0, step: 1}\n", {"bad.yaml", "to", "'0'"}},
      {"name: x\nsweeps:\n  - name: s\n    script: hold\n", {"bad.yaml", "duration_s", "hold"}},
      {"name: x\nmodel: world\nsweeps:\n  - name: s\n    environment: wall\n",
       {"bad.yaml", "environment", "model 'world'"}},
      {"name: x\nmodel: world\nsweeps:\n  - name: s\n    delay_ms: 1\n",
       {"bad.yaml", "names no scene"}},
      {"name: a b\nsweeps:\n  - name: s\n", {"bad.yaml", "name", "'a b'"}},
      {"name: x\nmeasure: [speed]\nsweeps:\n  - name: s\n", {"bad.yaml", "measure[0]", "'speed'"}},
      {"name: x\nsweeps: []\n", {"bad.yaml", "sweeps"}},
      {head + "  - name: s\n", {"bad.yaml", "'s' names two sweeps"}},
  };
  for (const Case& c : cases) {
    const std::string msg = err(c.text);
    ASSERT_FALSE(msg.empty()) << c.text;
    for (const std::string& s : c.says) EXPECT_NE(msg.find(s), std::string::npos) << msg;
  }
  EXPECT_NE(config_error_of([] { load_campaign("/nonexistent/c.yaml"); }).find("/nonexistent"),
            std::string::npos);
}

TEST(CampaignFile, SchemeLabelsAndLawsAreTheSchemesVariantsAndTraits) {
  struct Law {
    const char* label;
    const char* scheme;
    const char* tdpa_base;
    bool force_gain;
  };
  const std::vector<Law> laws = {
      {"position-position", "position-position", "position-position", false},
      {"force-position", "force-position", "position-position", true},
      {"wave-variables", "wave-variables", "position-position", false},
      {"tdpa", "tdpa", "position-position", false},
      {"tdpa-fp", "tdpa", "force-position", true},
      {"model-mediated", "model-mediated", "position-position", true},
  };
  std::vector<std::string> labels;
  for (const Law& w : laws) labels.emplace_back(w.label);
  EXPECT_EQ(scheme_labels(), labels);
  for (const Law& w : laws) {
    const SchemeLaw law = scheme_law(w.label);
    EXPECT_EQ(law.scheme, w.scheme) << w.label;
    EXPECT_EQ(law.tdpa_base, w.tdpa_base) << w.label;
    EXPECT_EQ(law.force_gain, w.force_gain) << w.label;
    // the gain axis is the scheme's own answer
    master::ControllerParams p;
    p.scheme = law.scheme;
    p.tdpa_base = law.tdpa_base;
    EXPECT_EQ(law.force_gain, !master::scheme_traits(p).position_based) << w.label;
  }
  EXPECT_NE(config_error_of([] { scheme_law("pp"); }).find("tdpa, tdpa-fp, model-mediated"),
            std::string::npos);
}

TEST(CampaignRun, TracesRecordEveryCycleAndLeaveTheRowAsItIs) {
  const Campaign c = parse_campaign(kSmall, "small.yaml");
  const RunParams& p = c.runs.back();
  RunTraces t;
  const std::string row = run_one(c, p, &t);
  EXPECT_EQ(row, run_one(c, p));
  // duration_s 4 at 1 kHz, nothing past the room made for it
  EXPECT_EQ(t.dropped, 0u);
  EXPECT_NEAR(static_cast<double>(t.size), 4000.0, 2.0);
  EXPECT_GE(t.capacity, t.size);
  for (std::size_t k = 0; k < RunTraces::kChannelCount; ++k) {
    EXPECT_EQ(t.data[k].size(), t.capacity * RunTraces::width(k)) << RunTraces::name(k);
  }
  const std::vector<double>& time = t.data[RunTraces::kTime];
  for (std::size_t i = 1; i < t.size; ++i) ASSERT_GT(time[i], time[i - 1]) << i;
  // the press reaches the object: the tip feels an upward force while in contact
  double touching = 0.0, up_n = 0.0;
  for (std::size_t i = 0; i < t.size; ++i) {
    if (t.data[RunTraces::kInContact][i] == 0.0) continue;
    touching += 1.0;
    up_n += t.data[RunTraces::kContactForce][3 * i + 2];
  }
  EXPECT_GT(touching, 100.0);
  EXPECT_GT(up_n / touching, 0.1);
  // a second run into the same traces starts them afresh
  run_one(c, p, &t);
  EXPECT_EQ(t.dropped, 0u);
  EXPECT_NEAR(static_cast<double>(t.size), 4000.0, 2.0);
}

TEST(CampaignRun, APointRunIsTheDelaySweepsRun) {
  // the same press scenario teleop_bench delay runs (tests/support/press_world.hpp)
  const Campaign c = parse_campaign(R"(name: same
model: point
sweeps:
  - name: s
    scheme: [position-position, force-position, tdpa-fp]
    environment: [sphere, wall]
    stiffness_n_per_m: 2000
    gain: 0
    delay_ms: [0, 60]
)",
                                    "same.yaml");
  std::size_t unstable = 0;
  for (const RunParams& p : c.runs) {
    master::PressScenario s;
    const SchemeLaw law = scheme_law(p.scheme);
    s.scheme = law.scheme;
    s.tdpa_base = law.tdpa_base;
    s.environment =
        p.environment == "wall" ? master::Environment::kWall : master::Environment::kSphere;
    s.env_stiffness_n_per_m = 2000.0;
    s.env_damping_ns_per_m = p.environment == "wall" ? 50.0 : 5.0;
    s.one_way_delay_s = p.delay_ms * 1e-3;
    const master::PressResult want = test::run_press_world(s);
    const std::string row = run_one(c, p);
    const std::string verdict = std::string(",") + master::verdict_name(want.verdict) + ",";
    EXPECT_NE(row.find(verdict), std::string::npos) << row;
    EXPECT_NE(row.find("," + format_number(want.position_error_rms_m * 1e3) + ","),
              std::string::npos)
        << row;
    EXPECT_NE(row.find("," + format_number(want.max_device_force_n) + ","), std::string::npos);
    unstable += want.verdict != master::Verdict::kStable;
  }
  // the grid holds both verdicts: the comparison above is not of a trivial case
  EXPECT_GT(unstable, 0u);
  EXPECT_LT(unstable, c.runs.size());
}

TEST_F(CampaignDir, TheTableIsTheSameBytesForAnyThreadsShardsAndInterruptions) {
  const Campaign c = parse_campaign(kSmall, "small.yaml");
  RunOptions one;
  one.out_dir = path("one");
  one.jobs = 1;
  const RunReport r1 = run_campaign(c, one);
  EXPECT_EQ(r1.ran, c.runs.size());
  ASSERT_EQ(merge_runs(one.out_dir).missing, 0u);
  const std::string table = read(path("one/results.csv"));
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 1 + static_cast<long>(c.runs.size()));

  // three shards, two threads each, the first interrupted after two runs and resumed
  RunOptions sh;
  sh.out_dir = path("sharded");
  sh.jobs = 2;
  for (std::size_t i = 0; i < 3; ++i) {
    sh.shard = Shard{i, 3};
    sh.max_runs = i == 0 ? 2 : 0;
    run_campaign(c, sh);
  }
  const MergeReport partial = merge_runs(sh.out_dir);
  EXPECT_EQ(partial.missing, 2u);  // shard 0 has 4 runs, 2 ran
  EXPECT_FALSE(fs::exists(path("sharded/results.csv")));
  // a run file planted in place of a finished run is kept: finished runs are not repeated
  const std::string planted = path("sharded/runs/" + run_name(3) + ".csv");
  const std::string original = read(planted);
  { std::ofstream(planted) << "planted\n"; }
  // and a temporary file left by a killed run is cleared
  std::ofstream(path("sharded/runs/" + run_name(0) + ".csv.tmp.1.1")) << "half";
  sh.shard = Shard{0, 3};
  sh.max_runs = 0;
  const RunReport resumed = run_campaign(c, sh);
  EXPECT_EQ(resumed.shard_runs, 4u);
  EXPECT_EQ(resumed.skipped, 2u);
  EXPECT_EQ(resumed.ran, 2u);
  EXPECT_EQ(read(planted), "planted\n");
  EXPECT_FALSE(fs::exists(path("sharded/runs/" + run_name(0) + ".csv.tmp.1.1")));
  { std::ofstream(planted) << original; }
  ASSERT_EQ(merge_runs(sh.out_dir).missing, 0u);
  EXPECT_EQ(read(path("sharded/results.csv")), table);
}

TEST_F(CampaignDir, RefusesAFolderOfAnotherCampaign) {
  const Campaign c = parse_campaign(kSmall, "small.yaml");
  prepare_output(c, path("out"));
  std::string other = kSmall;
  other.replace(other.find("to: 60"), 6, "to: 90");
  const Campaign d = parse_campaign(other, "other.yaml");
  const std::string msg = config_error_of([&] { prepare_output(d, path("out")); });
  EXPECT_NE(msg.find("another campaign"), std::string::npos) << msg;
  EXPECT_NE(config_error_of([&] { merge_runs(path("nothing")); }).find("no campaign"),
            std::string::npos);
  EXPECT_NE(config_error_of([] { parse_shard("3/3"); }).find("--shard"), std::string::npos);
  EXPECT_NE(config_error_of([] { parse_shard("1"); }).find("I/N"), std::string::npos);
  EXPECT_EQ(parse_shard("2/5").index, 2u);
}

TEST(CampaignSlurm, EachArrayTaskRunsItsShard) {
  SlurmOptions o;
  o.exe = "/opt/teleop/bin/teleop_campaign";
  o.campaign_file = "/data/c.yaml";
  o.out_dir = "/data/out";
  o.shards = 8;
  o.cpus_per_task = 4;
  o.partition = "short";
  const std::string s = slurm_array_script("c", o);
  EXPECT_NE(s.find("#SBATCH --array=0-7\n"), std::string::npos) << s;
  EXPECT_NE(s.find("#SBATCH --cpus-per-task=4\n"), std::string::npos);
  EXPECT_NE(s.find("#SBATCH --partition=short\n"), std::string::npos);
  EXPECT_NE(s.find("'/opt/teleop/bin/teleop_campaign' run '/data/c.yaml' --out '/data/out' "
                   "--shard \"${SLURM_ARRAY_TASK_ID}/8\" --jobs 4"),
            std::string::npos)
      << s;
  EXPECT_NE(slurm_merge_script("c", o).find("merge '/data/out'"), std::string::npos);
}

TEST(CampaignRun, AWorldRunHomesTheRobotAndPressesTheSphere) {
  const std::string scene = std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/default.yaml";
  const Campaign c = parse_campaign(
      "name: w\nmodel: world\nduration_s: 4\nhoming_s: 1\n"
      "sweeps:\n  - name: s\n    scene: " +
          scene + "\n    scheme: force-position\n",
      "w.yaml");
  ASSERT_EQ(c.runs.size(), 1u);
  std::vector<std::string> cells;
  std::stringstream row(run_one(c, c.runs[0]));
  for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
  std::vector<std::string> names;
  std::stringstream header(results_header(c));
  for (std::string cell; std::getline(header, cell, ',');) names.push_back(cell);
  ASSERT_EQ(cells.size(), names.size());
  const auto at = [&](const std::string& n) {
    const auto it = std::find(names.begin(), names.end(), n);
    return it == names.end() ? std::string("?") : cells[it - names.begin()];
  };
  EXPECT_EQ(at("verdict"), "stable");
  // after homing the operator reaches the sphere's top and presses it (press-slip: the press
  // starts after about 2 s)
  EXPECT_GT(std::stod(at("contact_time_s")), 0.5);
  EXPECT_GT(std::stod(at("mean_contact_force_n")), 0.05);
  EXPECT_LT(std::stod(at("position_error_rms_mm")), 20.0);
  EXPECT_EQ(at("world_faults"), "0");
  EXPECT_EQ(at("watchdog_trips"), "0");
}

TEST_F(CampaignDir, WorldRunsOnTwoThreadsGiveTheRowsOfOne) {
  const std::string scene = std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/default.yaml";
  const Campaign c = parse_campaign(
      "name: w2\nmodel: world\nduration_s: 0.5\nhoming_s: 0.3\n"
      "sweeps:\n  - name: s\n    scene: " +
          scene +
          "\n    scheme: [force-position, position-position]\n"
          "    delay_ms: [0, 20]\n",
      "w2.yaml");
  RunOptions o;
  o.out_dir = path("two");
  o.jobs = 2;
  run_campaign(c, o);
  o.out_dir = path("one");
  o.jobs = 1;
  run_campaign(c, o);
  ASSERT_EQ(merge_runs(path("one")).missing, 0u);
  ASSERT_EQ(merge_runs(path("two")).missing, 0u);
  EXPECT_EQ(read(path("two/results.csv")), read(path("one/results.csv")));
  EXPECT_EQ(read(path("one/results.csv")).find(",error,"), std::string::npos);
}

TEST_F(CampaignDir, ARecordedTrajectoryDrivesTheDeviceInsteadOfTheScript) {
  // down from 5 cm above the sphere's top to 1 cm into it, held, and back up
  std::ofstream(path("press.csv")) << "time_s,x,y,z\n0,0,0,0.05\n1,0,0,-0.01\n2,0,0,-0.01\n"
                                      "3,0,0,0.05\n";
  const std::string text =
      "name: t\nsweeps:\n  - name: s\n    trajectory: press.csv\n"
      "    scheme: force-position\n    stiffness_n_per_m: 2000\n";
  const Campaign c = parse_campaign(text, path("t.yaml"));
  ASSERT_EQ(c.runs.size(), 1u);
  ASSERT_EQ(c.trajectories.size(), 1u);
  std::vector<std::string> cells, names;
  std::stringstream row(run_one(c, c.runs[0])), header(results_header(c));
  for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
  for (std::string cell; std::getline(header, cell, ',');) names.push_back(cell);
  const auto at = [&](const std::string& n) {
    const auto it = std::find(names.begin(), names.end(), n);
    return it == names.end() ? std::string("?") : cells[it - names.begin()];
  };
  EXPECT_EQ(at("trajectory"), "press.csv");
  EXPECT_EQ(at("verdict"), "stable");
  // in contact from about 0.8 s to 2.2 s of the 3 s record (+3 s after it)
  EXPECT_GT(std::stod(at("contact_time_s")), 0.8);
  EXPECT_LT(std::stod(at("contact_time_s")), 2.5);
  EXPECT_GT(std::stod(at("mean_contact_force_n")), 2.0);
  // a trajectory that cannot be read is refused naming its file
  std::ofstream(path("bad.csv")) << "time_s,x,y,z\n0,0,0\n";
  std::string bad = text;
  bad.replace(bad.find("press.csv"), 9, "bad.csv");
  EXPECT_NE(config_error_of([&] { parse_campaign(bad, path("t.yaml")); }).find("bad.csv"),
            std::string::npos);
}

TEST_F(CampaignDir, TheProgressLineCountsRunsAndGivesAnEta) {
  const Campaign c = parse_campaign(kSmall, "small.yaml");
  RunOptions o;
  o.out_dir = path("p");
  o.jobs = 2;
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  o.progress = f;
  run_campaign(c, o);
  std::rewind(f);
  std::string text;
  for (int ch; (ch = std::fgetc(f)) != EOF;) text += static_cast<char>(ch);
  std::fclose(f);
  EXPECT_NE(text.find("10/10 runs (100.0 %)"), std::string::npos) << text;
  EXPECT_NE(text.find("ETA"), std::string::npos) << text;
}

}  // namespace
}  // namespace teleop::campaign

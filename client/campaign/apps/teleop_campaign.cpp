// teleop_campaign: robustness campaigns of in-process sessions (docs/campaigns.md).
//
//   teleop_campaign run FILE --out DIR [--jobs N] [--shard I/N] [--max-runs N] [--no-chart]
//   teleop_campaign slurm FILE --out DIR [--shards N] [--cpus-per-task C] [--partition P]
//                   [--time T] [--submit | --dry-run]
//   teleop_campaign merge DIR [--no-chart]
//
// Exit status: 0 done, 2 bad command line or campaign file, 1 runtime failure (a file that
// cannot be written, runs missing at merge, sbatch failing).
#include <sys/wait.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "client/campaign/campaign.hpp"
#include "client/campaign/runner.hpp"
#include "common/config/flags.hpp"
#include "common/util/files.hpp"
#include "common/util/progress.hpp"
#include "common/util/registry.hpp"

namespace {

namespace fs = std::filesystem;
using teleop::campaign::Campaign;

struct Options {
  std::string file, out, shard, partition, time_limit;
  std::size_t jobs = 0, shards = 0, cpus_per_task = 1, max_runs = 0;
  bool no_chart = false, submit = false, dry_run = false;
  bool progress = false, no_progress = false;
};

/// Merges DIR into its table and draws the charts; returns the exit status.
int merge(const std::string& dir, bool no_chart) {
  const teleop::campaign::MergeReport r = teleop::campaign::merge_runs(dir);
  if (r.missing > 0) {
    std::fprintf(stderr,
                 "teleop_campaign: %s: %zu of %zu runs have no result yet (first: run %s); run "
                 "the campaign (or the missing shards) again, then merge\n",
                 dir.c_str(), r.missing, r.runs, r.first_missing.c_str());
    return 1;
  }
  std::printf("teleop_campaign: %zu runs -> %s\n", r.runs, r.table.c_str());
  if (!no_chart) teleop::run_chart_script("campaign.py", {r.table, dir});
  return 0;
}

int run(const Options& o) {
  const Campaign c = teleop::campaign::load_campaign(o.file);
  teleop::campaign::RunOptions ro;
  ro.out_dir = o.out;
  if (!o.shard.empty()) ro.shard = teleop::campaign::parse_shard(o.shard);
  ro.jobs = o.jobs;
  ro.max_runs = o.max_runs;
  const teleop::ProgressMode mode = o.progress      ? teleop::ProgressMode::kOn
                                    : o.no_progress ? teleop::ProgressMode::kOff
                                                    : teleop::ProgressMode::kAuto;
  ro.progress = teleop::progress_wanted(mode, isatty(STDERR_FILENO) == 1) ? stderr : nullptr;
  const teleop::campaign::RunReport rep = teleop::campaign::run_campaign(c, ro);
  std::printf("teleop_campaign: %s, shard %zu/%zu: %zu runs, %zu done before, %zu ran in %.2f s\n",
              c.name.c_str(), ro.shard.index, ro.shard.count, rep.shard_runs, rep.skipped, rep.ran,
              rep.wall_s);
  if (ro.shard.count > 1 || rep.skipped + rep.ran < rep.shard_runs) return 0;
  return merge(o.out, o.no_chart);
}

/// Runs a command; returns its standard output (trailing newline removed) and status.
int capture(const std::string& cmd, std::string& out) {
  out.clear();
  std::FILE* p = popen(cmd.c_str(), "r");
  if (!p) return -1;
  char buf[256];
  while (std::fgets(buf, sizeof(buf), p)) out += buf;
  const int rc = pclose(p);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return rc == -1 ? -1 : WEXITSTATUS(rc);
}

/// A value that goes into an #SBATCH line: letters, digits and _ . , : - only.
void check_sbatch_word(const std::string& flag, const std::string& v) {
  for (char ch : v) {
    if (!std::isalnum(static_cast<unsigned char>(ch)) &&
        std::string("_.,:-").find(ch) == std::string::npos) {
      throw teleop::config::ConfigError("command line: " + flag + " '" + v +
                                        "' may hold only letters, digits and _ . , : -");
    }
  }
}

int slurm(const Options& o) {
  check_sbatch_word("--partition", o.partition);
  check_sbatch_word("--time", o.time_limit);
  const Campaign c = teleop::campaign::load_campaign(o.file);
  teleop::campaign::SlurmOptions so;
  so.exe = fs::canonical("/proc/self/exe").string();
  so.campaign_file = fs::absolute(o.file).lexically_normal().string();
  fs::create_directories(fs::path(o.out) / "slurm");
  so.out_dir = fs::canonical(o.out).string();
  so.shards =
      o.shards > 0 ? std::min(o.shards, c.runs.size()) : std::min<std::size_t>(c.runs.size(), 100);
  so.cpus_per_task = o.cpus_per_task;
  so.partition = o.partition;
  so.time_limit = o.time_limit;
  const std::string array = so.out_dir + "/slurm/array.sbatch";
  const std::string merge_job = so.out_dir + "/slurm/merge.sbatch";
  teleop::write_text_file(array, teleop::campaign::slurm_array_script(c.name, so));
  teleop::write_text_file(merge_job, teleop::campaign::slurm_merge_script(c.name, so));
  std::printf("teleop_campaign: %zu runs in %zu array tasks: %s, then %s\n", c.runs.size(),
              so.shards, array.c_str(), merge_job.c_str());
  if (!o.submit) {
    std::printf(
        "submit with:\n  jid=$(sbatch --parsable %s)\n"
        "  sbatch --dependency=afterok:${jid%%%%;*} %s\n",
        array.c_str(), merge_job.c_str());
    return 0;
  }
  std::string jid;
  if (capture("sbatch --parsable '" + array + "'", jid) != 0 || jid.empty()) {
    std::fprintf(stderr, "teleop_campaign: sbatch %s failed\n", array.c_str());
    return 1;
  }
  jid = jid.substr(0, jid.find(';'));
  std::string mid;
  if (capture("sbatch --parsable --dependency=afterok:" + jid + " '" + merge_job + "'", mid) != 0) {
    std::fprintf(stderr, "teleop_campaign: sbatch %s failed\n", merge_job.c_str());
    return 1;
  }
  std::printf("submitted array job %s and merge job %s\n", jid.c_str(), mid.c_str());
  return 0;
}

void add_flags(CLI::App& app, Options& o, CLI::App*& run_cmd, CLI::App*& slurm_cmd,
               CLI::App*& merge_cmd) {
  using teleop::config::add_integer;
  app.require_subcommand(1);
  run_cmd = app.add_subcommand("run", "run a campaign (or one shard of it) on this machine");
  run_cmd->add_option("FILE", o.file, "campaign file (YAML)")->required();
  run_cmd->add_option("--out", o.out, "output folder (created; resumed when it holds the runs)")
      ->required();
  add_integer(*run_cmd, "--jobs", o.jobs, 1, 4096, "threads (default: every core)");
  run_cmd->add_option("--shard", o.shard, "run only shard I of N (runs with id % N == I)");
  add_integer(*run_cmd, "--max-runs", o.max_runs, 1, 1e9,
              "stop after this many runs (a later call resumes)");
  run_cmd->add_flag("--no-chart", o.no_chart, "write the table only");
  run_cmd->add_flag("--progress", o.progress,
                    "draw the progress line even when stderr is not a terminal");
  run_cmd->add_flag("--no-progress", o.no_progress, "no progress line")->excludes("--progress");

  slurm_cmd = app.add_subcommand("slurm", "write (and submit) a Slurm array job of the campaign");
  slurm_cmd->add_option("FILE", o.file, "campaign file (YAML)")->required();
  slurm_cmd->add_option("--out", o.out, "output folder, on storage every node sees")->required();
  add_integer(*slurm_cmd, "--shards", o.shards, 1, 1e6,
              "array tasks (at most one per run; default: min(runs, 100))");
  add_integer(*slurm_cmd, "--cpus-per-task", o.cpus_per_task, 1, 4096, "threads per task");
  slurm_cmd->add_option("--partition", o.partition, "sbatch --partition");
  slurm_cmd->add_option("--time", o.time_limit, "sbatch --time (e.g. 01:00:00)");
  auto* submit = slurm_cmd->add_flag("--submit", o.submit, "submit with sbatch");
  slurm_cmd->add_flag("--dry-run", o.dry_run, "write the scripts only (the default)")
      ->excludes(submit);

  merge_cmd = app.add_subcommand("merge", "join a campaign's runs into its table and charts");
  merge_cmd->add_option("DIR", o.out, "output folder of the campaign")->required();
  merge_cmd->add_flag("--no-chart", o.no_chart, "write the table only");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"teleop_campaign: robustness campaigns of in-process teleoperation sessions"};
  Options o;
  CLI::App *run_cmd = nullptr, *slurm_cmd = nullptr, *merge_cmd = nullptr;
  add_flags(app, o, run_cmd, slurm_cmd, merge_cmd);
  for (CLI::App* sub : {run_cmd, slurm_cmd, merge_cmd}) teleop::config::harden_flags(*sub);
  if (const int status = teleop::config::parse_command_line(app, "teleop_campaign", argc, argv);
      status >= 0) {
    return status;
  }
  try {
    if (run_cmd->parsed()) return run(o);
    if (slurm_cmd->parsed()) return slurm(o);
    return merge(o.out, o.no_chart);
  } catch (const teleop::config::ConfigError& e) {
    std::cerr << "teleop_campaign: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "teleop_campaign: error: " << e.what() << "\n";
    return 1;
  }
}

#include "client/campaign/runner.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "client/campaign/results.hpp"
#include "common/util/progress.hpp"

namespace teleop::campaign {

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

RunReport run_campaign(const Campaign& c, const RunOptions& o) {
  const auto t0 = Clock::now();
  prepare_output(c, o.out_dir);
  const std::vector<std::size_t> todo = pending_runs(c, o.out_dir, o.shard);
  RunReport rep;
  for (const RunParams& p : c.runs) rep.shard_runs += o.shard.takes(p.id);
  rep.skipped = rep.shard_runs - todo.size();
  const std::size_t limit = o.max_runs > 0 ? std::min(o.max_runs, todo.size()) : todo.size();
  std::size_t jobs = o.jobs > 0 ? o.jobs : std::max(1u, std::thread::hardware_concurrency());
  jobs = std::max<std::size_t>(1, std::min(jobs, limit));

  std::atomic<std::size_t> next{0}, done{0};
  Progress progress(o.progress, "", static_cast<double>(limit), "runs", 0);
  std::exception_ptr failure;
  std::mutex failure_mutex;
  std::atomic<bool> failed{false};
  auto worker = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < limit;) {
      try {
        const RunParams& p = c.runs[todo[i]];
        write_run(o.out_dir, p.id, run_one(c, p));
        done.fetch_add(1);
        progress.add();
      } catch (...) {
        const std::lock_guard<std::mutex> lock(failure_mutex);
        if (!failure) failure = std::current_exception();
        failed.store(true);
        next.store(limit);  // the others stop after their current run
      }
    }
  };
  std::vector<std::thread> pool;
  for (std::size_t k = 0; k < jobs; ++k) pool.emplace_back(worker);
  if (progress.active()) {  // the elapsed time and ETA move between runs too
    while (done.load() < limit && !failed.load()) {
      progress.poll();
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
  }
  for (std::thread& t : pool) t.join();
  rep.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  progress.finish();
  if (failure) std::rethrow_exception(failure);
  rep.ran = done.load();
  return rep;
}

namespace {

/// Single-quotes `s` for sh.
std::string sh(const std::string& s) {
  std::string out = "'";
  for (char ch : s) out += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return out + "'";
}

std::string common_header(const std::string& job, const SlurmOptions& o) {
  std::string s = "#!/bin/bash\n";
  s += "#SBATCH --job-name=" + job + "\n";
  if (!o.partition.empty()) s += "#SBATCH --partition=" + o.partition + "\n";
  if (!o.time_limit.empty()) s += "#SBATCH --time=" + o.time_limit + "\n";
  return s;
}

}  // namespace

std::string slurm_array_script(const std::string& name, const SlurmOptions& o) {
  std::string s = common_header("teleop-" + name, o);
  s += "#SBATCH --array=0-" + std::to_string(o.shards - 1) + "\n";
  s += "#SBATCH --ntasks=1\n";
  s += "#SBATCH --cpus-per-task=" + std::to_string(o.cpus_per_task) + "\n";
  s += "#SBATCH --output=" + o.out_dir + "/slurm/%A_%a.out\n";
  s += "# one shard of the campaign per array task; a task that is run again skips the runs\n";
  s += "# whose files are there\n";
  s += "set -eu\n";
  s += "exec " + sh(o.exe) + " run " + sh(o.campaign_file) + " --out " + sh(o.out_dir) +
       " --shard \"${SLURM_ARRAY_TASK_ID}/" + std::to_string(o.shards) + "\" --jobs " +
       std::to_string(o.cpus_per_task) + " --no-chart\n";
  return s;
}

std::string slurm_merge_script(const std::string& name, const SlurmOptions& o) {
  std::string s = common_header("teleop-" + name + "-merge", o);
  s += "#SBATCH --ntasks=1\n";
  s += "#SBATCH --cpus-per-task=1\n";
  s += "#SBATCH --output=" + o.out_dir + "/slurm/merge_%j.out\n";
  s += "set -eu\n";
  s += "exec " + sh(o.exe) + " merge " + sh(o.out_dir) + "\n";
  return s;
}

}  // namespace teleop::campaign

#pragma once
// Runs a campaign's pending runs on a pool of threads, each run written to its own file as it
// finishes (campaign/store.hpp), and writes the Slurm array job that spreads the same runs over
// a cluster.
#include <cstddef>
#include <cstdio>
#include <string>

#include "client/campaign/campaign.hpp"
#include "client/campaign/store.hpp"

namespace teleop::campaign {

struct RunOptions {
  std::string out_dir;
  Shard shard;
  std::size_t jobs = 0;           ///< threads; 0: every core
  std::FILE* progress = nullptr;  ///< a terminal for the progress line (nullptr: quiet)
  /// Stop after this many runs have finished in this call (0: no limit): what a test uses to
  /// leave a campaign half done.
  std::size_t max_runs = 0;
};

struct RunReport {
  std::size_t shard_runs = 0;  ///< runs of this shard
  std::size_t skipped = 0;     ///< already done before this call
  std::size_t ran = 0;         ///< finished in this call
  double wall_s = 0.0;         ///< time this call took [s]
};

/// Prepares the folder and runs every pending run of the shard. Rows are the same whatever
/// the thread count and order. @throws config::ConfigError (folder of another campaign),
/// std::runtime_error (a file that cannot be written).
RunReport run_campaign(const Campaign& c, const RunOptions& o);

/// Settings of the Slurm array job.
struct SlurmOptions {
  std::string exe;            ///< absolute path of teleop_campaign
  std::string campaign_file;  ///< absolute path of the campaign
  std::string out_dir;        ///< absolute path of the output folder (shared by the nodes)
  std::size_t shards = 1;     ///< array tasks
  std::size_t cpus_per_task = 1;
  std::string partition;   ///< "" : the cluster's default
  std::string time_limit;  ///< sbatch --time ("" : the partition's default)
};
/// The sbatch script of the array job: task i runs `teleop_campaign run FILE --out DIR
/// --shard i/N --jobs C --no-chart`.
std::string slurm_array_script(const std::string& name, const SlurmOptions& o);
/// The sbatch script of the merge job that runs after the array (`teleop_campaign merge DIR`).
std::string slurm_merge_script(const std::string& name, const SlurmOptions& o);

}  // namespace teleop::campaign

#pragma once
// A campaign's output folder:
//
//   DIR/manifest.txt     the campaign's name, digest, run count and table header (written
//                        once, the same bytes by every shard; a folder holding another
//                        campaign is refused)
//   DIR/runs/NNNNNNN.csv one row per finished run, written to a temporary file and renamed, so a
//                        run file is whole or absent: an interrupted campaign (even kill -9)
//                        resumes by running only the runs without a file
//   DIR/results.csv      the table: the header and every run's row by run id (merge)
//
// Shard i of N runs the runs whose id is i modulo N; any split of the same campaign gives the
// same run files, so the merged table is the same bytes however the runs were spread.
#include <cstddef>
#include <string>
#include <vector>

#include "client/campaign/campaign.hpp"

namespace teleop::campaign {

/// Which share of the runs a process takes: those with id % count == index.
struct Shard {
  std::size_t index = 0, count = 1;
  bool takes(std::size_t id) const { return id % count == index; }
};
/// Parses "i/N" (0 <= i < N <= 10^6). @throws config::ConfigError naming --shard.
Shard parse_shard(const std::string& text);

/// Creates DIR and DIR/runs, and writes DIR/manifest.txt or checks that the one there is this
/// campaign's. Removes temporary files an interrupted run left. @throws config::ConfigError
/// when DIR holds another campaign or cannot be created; std::runtime_error when a file cannot
/// be written.
void prepare_output(const Campaign& c, const std::string& dir);

/// Ids of the shard's runs that have no run file yet, ascending.
std::vector<std::size_t> pending_runs(const Campaign& c, const std::string& dir, const Shard& s);

/// Writes run `id`'s row atomically (temporary file, then rename). Thread-safe.
/// @throws std::runtime_error naming the file.
void write_run(const std::string& dir, std::size_t id, const std::string& row);

/// What a merge found.
struct MergeReport {
  std::size_t runs = 0;     ///< runs the manifest lists
  std::size_t missing = 0;  ///< runs without a file (the table is not written then)
  std::string first_missing;
  std::string table;  ///< path of the table written
};
/// Joins DIR/runs into DIR/results.csv (written atomically), by run id. With runs missing it
/// writes nothing and says which. @throws config::ConfigError when DIR holds no campaign.
MergeReport merge_runs(const std::string& dir);

}  // namespace teleop::campaign

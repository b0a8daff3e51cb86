#include "client/campaign/store.hpp"

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "client/campaign/results.hpp"
#include "common/util/files.hpp"

namespace teleop::campaign {

namespace fs = std::filesystem;

namespace {

constexpr const char* kManifestMagic = "teleop campaign v1";

std::string manifest_text(const Campaign& c) {
  std::ostringstream s;
  s << kManifestMagic << '\n'
    << "name " << c.name << '\n'
    << "digest " << campaign_digest(c) << '\n'
    << "runs " << c.runs.size() << '\n'
    << "header " << results_header(c) << '\n';
  return s.str();
}

std::string read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Writes `text` to `path` through a temporary file of this process and thread, renamed into
/// place (a reader sees the old file or the whole new one).
void write_atomically(const fs::path& path, const std::string& text) {
  static std::atomic<unsigned long> counter{0};
  const fs::path tmp = path.string() + ".tmp." + std::to_string(getpid()) + "." +
                       std::to_string(counter.fetch_add(1));
  write_text_file(tmp.string(), text);
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw std::runtime_error(path.string() + ": cannot write: " + ec.message());
  }
}

fs::path run_file(const std::string& dir, std::size_t id) {
  return fs::path(dir) / "runs" / (run_name(id) + ".csv");
}

}  // namespace

Shard parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  if (slash == std::string::npos) {
    throw config::ConfigError("command line: --shard '" + text +
                              "' is not I/N (shard I of N, 0 <= I < N <= 1000000)");
  }
  Shard s;
  s.count = static_cast<std::size_t>(
      config::parse_integer("--shard", text.substr(slash + 1), 1, 1'000'000));
  s.index = static_cast<std::size_t>(config::parse_integer("--shard", text.substr(0, slash), 0,
                                                           static_cast<long long>(s.count) - 1));
  return s;
}

void prepare_output(const Campaign& c, const std::string& dir) {
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "runs", ec);
  if (ec) {
    throw config::ConfigError("command line: --out '" + dir +
                              "': cannot create the output folder: " + ec.message());
  }
  const fs::path manifest = fs::path(dir) / "manifest.txt";
  const std::string mine = manifest_text(c);
  if (fs::exists(manifest)) {
    const std::string there = read_all(manifest);
    if (there != mine) {
      throw config::ConfigError(dir +
                                ": --out holds another campaign (its manifest.txt differs "
                                "from " +
                                c.file + "'s); use an empty folder");
    }
  } else {
    write_atomically(manifest, mine);
  }
  // temporary files of a run that was killed before it could rename them
  for (const auto& e : fs::directory_iterator(fs::path(dir) / "runs")) {
    if (e.path().filename().string().find(".tmp.") != std::string::npos) fs::remove(e.path(), ec);
  }
}

std::vector<std::size_t> pending_runs(const Campaign& c, const std::string& dir, const Shard& s) {
  std::vector<std::size_t> out;
  for (const RunParams& p : c.runs) {
    if (s.takes(p.id) && !fs::exists(run_file(dir, p.id))) out.push_back(p.id);
  }
  return out;
}

void write_run(const std::string& dir, std::size_t id, const std::string& row) {
  write_atomically(run_file(dir, id), row + "\n");
}

MergeReport merge_runs(const std::string& dir) {
  const fs::path manifest = fs::path(dir) / "manifest.txt";
  std::ifstream in(manifest);
  std::string magic, key, header;
  std::size_t runs = 0;
  std::getline(in, magic);
  if (!in || magic != kManifestMagic) {
    throw config::ConfigError(dir + ": no campaign here (" + manifest.string() +
                              " is missing or not a campaign manifest)");
  }
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("runs ", 0) == 0) runs = std::stoull(line.substr(5));
    if (line.rfind("header ", 0) == 0) header = line.substr(7);
  }
  MergeReport r;
  r.runs = runs;
  std::string table = header + "\n";
  for (std::size_t id = 0; id < runs; ++id) {
    const fs::path f = run_file(dir, id);
    std::string row = fs::exists(f) ? read_all(f) : std::string();
    if (row.empty() || row.back() != '\n') {
      if (r.missing++ == 0) r.first_missing = run_name(id);
      continue;
    }
    table += row;
  }
  if (r.missing > 0) return r;
  r.table = (fs::path(dir) / "results.csv").string();
  write_atomically(r.table, table);
  return r;
}

}  // namespace teleop::campaign

#include "client/device/replay_device.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "common/config/config.hpp"

namespace teleop::master {

namespace {

const char* const kColumnNames[8] = {"time_s", "x", "y", "z", "qw", "qx", "qy", "qz"};

[[noreturn]] void fail_at(const std::string& file, std::size_t line, std::size_t col,
                          const std::string& what) {
  throw config::ConfigError(file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": " +
                            what);
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

bool parse_double(const std::string& text, double& out) {
  const std::string t = trim(text);
  if (t.empty()) return false;
  char* end = nullptr;
  out = std::strtod(t.c_str(), &end);
  return end == t.c_str() + t.size() && std::isfinite(out);
}

/// The allowed magnitude of column k (time, x, y, z, qw, qx, qy, qz) and its unit.
double column_bound(int k) {
  return k == 0 ? kReplayMaxTimeS : k < 4 ? kReplayMaxPositionM : kReplayMaxQuaternion;
}
const char* column_unit(int k) { return k == 0 ? " s" : k < 4 ? " m" : ""; }

/// Parses field `text` of column k into v; a bad number or one out of range fails naming the
/// file, row, column, value and range.
void parse_column(const std::string& file, std::size_t line_no, std::size_t col, int k,
                  const std::string& text, double& v) {
  if (!parse_double(text, v)) {
    fail_at(file, line_no, col,
            std::string("column '") + kColumnNames[k] + "': '" + trim(text) +
                "' is not a finite number");
  }
  const double bound = column_bound(k);
  if (std::fabs(v) > bound) {
    fail_at(file, line_no, col,
            "row " + std::to_string(line_no) + ", column '" + kColumnNames[k] + "': " + trim(text) +
                " is outside the allowed range " + config::range_text(-bound, bound) +
                column_unit(k));
  }
}

}  // namespace

namespace {

/// Split `line` at commas, with each field's 1-based column.
void split_fields(const std::string& line, std::vector<std::string>& fields,
                  std::vector<std::size_t>& cols) {
  fields.clear();
  cols.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(
        line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    cols.push_back(start + 1);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
}

/// Where the 8 replay values sit in a row: from a header naming them (time_s or t_s; x, y, z
/// or the master log's dev_x, dev_y, dev_z; optional qw.. or dev_qw..), else positional.
struct ColumnMap {
  bool named = false;
  std::size_t width = 0;  ///< fields a row must have when named
  int index[8] = {};      ///< field of time, x, y, z, qw, qx, qy, qz (-1: absent)
};

ColumnMap map_header(const std::vector<std::string>& header) {
  ColumnMap m;
  auto find = [&](std::initializer_list<const char*> names) {
    for (std::size_t i = 0; i < header.size(); ++i) {
      for (const char* n : names) {
        if (trim(header[i]) == n) return static_cast<int>(i);
      }
    }
    return -1;
  };
  m.index[0] = find({"time_s", "t_s"});
  const char* pos[3][2] = {{"x", "dev_x"}, {"y", "dev_y"}, {"z", "dev_z"}};
  for (int k = 0; k < 3; ++k) m.index[1 + k] = find({pos[k][0], pos[k][1]});
  const char* rot[4][2] = {{"qw", "dev_qw"}, {"qx", "dev_qx"}, {"qy", "dev_qy"}, {"qz", "dev_qz"}};
  for (int k = 0; k < 4; ++k) m.index[4 + k] = find({rot[k][0], rot[k][1]});
  m.named = m.index[0] >= 0 && m.index[1] >= 0 && m.index[2] >= 0 && m.index[3] >= 0;
  if (m.named && (m.index[4] < 0 || m.index[5] < 0 || m.index[6] < 0 || m.index[7] < 0)) {
    for (int k = 4; k < 8; ++k) m.index[k] = -1;
  }
  m.width = header.size();
  return m;
}

}  // namespace

std::vector<ReplaySample> parse_replay_csv(const std::string& text, const std::string& file) {
  std::vector<ReplaySample> out;
  std::istringstream in(text);
  std::string line;
  std::size_t line_no = 0;
  bool first_content = true;
  ColumnMap map;
  std::vector<std::string> fields;
  std::vector<std::size_t> cols;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    split_fields(line, fields, cols);
    double first = 0.0;
    if (first_content && !parse_double(fields[0], first)) {
      first_content = false;  // a header line: named columns are taken by name
      map = map_header(fields);
      continue;
    }
    first_content = false;
    double v[8] = {0, 0, 0, 0, 1, 0, 0, 0};
    if (map.named) {
      if (fields.size() != map.width) {
        fail_at(file, line_no, 1,
                "expected " + std::to_string(map.width) + " fields as in the header, found " +
                    std::to_string(fields.size()));
      }
      for (int k = 0; k < 8; ++k) {
        if (map.index[k] < 0) continue;
        const auto i = static_cast<std::size_t>(map.index[k]);
        parse_column(file, line_no, cols[i], k, fields[i], v[k]);
      }
    } else {
      if (fields.size() != 4 && fields.size() != 8) {
        fail_at(file, line_no, 1,
                "expected 4 fields (time_s,x,y,z) or 8 (time_s,x,y,z,qw,qx,qy,qz), or a header "
                "naming them (a teleop_master --log file has one), found " +
                    std::to_string(fields.size()));
      }
      for (std::size_t i = 0; i < fields.size(); ++i) {
        parse_column(file, line_no, cols[i], static_cast<int>(i), fields[i], v[i]);
      }
    }
    ReplaySample s;
    s.time_s = v[0];
    s.position_m = Eigen::Vector3d(v[1], v[2], v[3]);
    const Eigen::Quaterniond q(v[4], v[5], v[6], v[7]);
    if (q.norm() < 1e-9) {
      fail_at(file, line_no, cols.size() > 4 ? cols[4] : 1,
              "column 'qw': the quaternion has zero norm");
    }
    s.orientation = q.normalized();
    if (!out.empty() && !(s.time_s > out.back().time_s)) {
      fail_at(file, line_no, cols[map.named ? static_cast<std::size_t>(map.index[0]) : 0],
              "column 'time_s': " + config::range_text(out.back().time_s, 1e300) +
                  " required (time must increase strictly), found " +
                  trim(fields[map.named ? static_cast<std::size_t>(map.index[0]) : 0]));
    }
    out.push_back(s);
  }
  if (out.empty()) fail_at(file, line_no, 1, "no samples (expected rows time_s,x,y,z[,q...])");
  return out;
}

std::vector<ReplaySample> load_replay_csv(const std::string& path) {
  config::require_regular_file(path, "replay file");  // a FIFO or device could block or never end
  if (std::filesystem::file_size(path) > config::Node::kMaxFileBytes) {
    throw config::ConfigError(path + ": larger than " +
                              std::to_string(config::Node::kMaxFileBytes >> 20) + " MB");
  }
  std::ifstream f(path);
  if (!f) throw config::ConfigError(path + ": cannot open replay file");
  std::stringstream ss;
  ss << f.rdbuf();
  return parse_replay_csv(ss.str(), path);
}

ReplayDevice::ReplayDevice(std::string path, DeviceSpec spec, bool loop)
    : path_(std::move(path)), spec_(std::move(spec)), loop_(loop) {}

ReplayDevice::ReplayDevice(std::vector<ReplaySample> samples, DeviceSpec spec, bool loop)
    : spec_(std::move(spec)), loop_(loop), samples_(std::move(samples)) {}

void ReplayDevice::configure() {
  if (!path_.empty()) samples_ = load_replay_csv(path_);
  if (samples_.empty()) throw config::ConfigError("replay device: no samples");
  for (std::size_t i = 1; i < samples_.size(); ++i) {
    if (!(samples_[i].time_s > samples_[i - 1].time_s)) {
      throw config::ConfigError("replay device: sample " + std::to_string(i) +
                                ": time must increase strictly");
    }
  }
  time_s_ = 0.0;
  cursor_ = 0;
  state_ = DeviceLifecycle::kInactive;
}

void ReplayDevice::activate() {
  if (state_ == DeviceLifecycle::kUnconfigured) configure();
  state_ = DeviceLifecycle::kActive;
}

void ReplayDevice::deactivate() {
  force_n_.setZero();
  if (state_ == DeviceLifecycle::kActive) state_ = DeviceLifecycle::kInactive;
}

double ReplayDevice::duration_s() const {
  return samples_.empty() ? 0.0 : samples_.back().time_s - samples_.front().time_s;
}

DeviceReading ReplayDevice::read() {
  DeviceReading r;
  r.time_s = time_s_;
  r.valid = state_ == DeviceLifecycle::kActive && !samples_.empty();
  if (samples_.empty()) return r;
  const double t0 = samples_.front().time_s;
  double t = t0 + time_s_;
  const double dur = duration_s();
  if (loop_ && dur > 0.0) t = t0 + std::fmod(time_s_, dur);
  if (samples_.size() == 1 || t <= t0) {
    r.position_m = samples_.front().position_m;
    r.orientation = samples_.front().orientation;
    cursor_ = 0;
    return r;
  }
  if (t >= samples_.back().time_s) {
    r.position_m = samples_.back().position_m;
    r.orientation = samples_.back().orientation;
    return r;
  }
  // find segment [i, i+1] containing t; usually the cursor or the next one
  if (samples_[cursor_].time_s > t) cursor_ = 0;
  while (cursor_ + 1 < samples_.size() && samples_[cursor_ + 1].time_s < t) ++cursor_;
  const ReplaySample& a = samples_[cursor_];
  const ReplaySample& b = samples_[cursor_ + 1];
  const double h = b.time_s - a.time_s;
  const double u = (t - a.time_s) / h;
  r.position_m = a.position_m + u * (b.position_m - a.position_m);
  r.linear_velocity_mps = (b.position_m - a.position_m) / h;
  r.orientation = a.orientation.slerp(u, b.orientation);
  Eigen::Quaterniond dq = b.orientation * a.orientation.conjugate();
  if (dq.w() < 0.0) dq.coeffs() *= -1.0;
  const Eigen::AngleAxisd aa(dq);
  r.angular_velocity_radps = (aa.angle() / h) * aa.axis();
  return r;
}

void ReplayDevice::write(const Eigen::Vector3d& force_n, const Eigen::Vector3d& /*torque_nm*/) {
  force_n_ = saturate_norm(force_n, spec_.max_force_n);
}

}  // namespace teleop::master

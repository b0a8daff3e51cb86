// Recordings for Python: read a recording (MCAP or SQLite, common/record/recording.hpp) into
// numpy arrays by topic, each sample's payload decoded with the generated types of idl/; and
// write an in-process session's traces as a recording (teleop/slave_state and
// teleop/master_state) that the players, Foxglove and read_recording open.
#include <fastdds/rtps/common/SerializedPayload.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "client/python/bindings.hpp"
#include "client/record/topic_table.hpp"
#include "common/dds/checked_type.hpp"
#include "common/dds/participant.hpp"
#include "common/record/recording.hpp"
#include "teleop/idl/Teleop.h"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace py = pybind11;

namespace teleop::python {

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
/// Width of a joint column (the IDL's bound on the joint sequences).
constexpr std::size_t kJointWidth = 16;

/// The columns of one topic: each field a float64 array (rows x width), in first-seen order.
struct Columns {
  struct Column {
    std::size_t width = 1;
    std::vector<double> values;
  };
  std::vector<std::string> order;
  std::map<std::string, Column> columns;
  std::size_t rows = 0;  ///< rows decoded so far (the row being added is rows)

  Column& column(const char* name, std::size_t width) {
    auto it = columns.find(name);
    if (it == columns.end()) {
      order.emplace_back(name);
      it = columns.emplace(name, Column{width, std::vector<double>(rows * width, kNan)}).first;
    }
    return it->second;
  }
  template <class T>
  void add(const char* name, const T& v) {
    if constexpr (std::is_arithmetic_v<T>) {
      column(name, 1).values.push_back(static_cast<double>(v));
    } else if constexpr (std::is_same_v<T, std::vector<double>>) {
      Column& c = column(name, kJointWidth);
      for (std::size_t k = 0; k < kJointWidth; ++k) c.values.push_back(k < v.size() ? v[k] : kNan);
    } else {
      Column& c = column(name, v.size());
      for (double x : v) c.values.push_back(x);
    }
  }
  /// Ends a row: columns this row did not fill get NaN (a sample that did not decode).
  void end_row() {
    ++rows;
    for (auto& [name, c] : columns) c.values.resize(rows * c.width, kNan);
  }
};

#define TELEOP_COL(f) cols.add(#f, s.f())

void decode(const MasterCommand& s, Columns& cols) {
  TELEOP_COL(seq), TELEOP_COL(send_time_ns), TELEOP_COL(position_m);
  TELEOP_COL(orientation_wxyz), TELEOP_COL(linear_velocity_mps);
  TELEOP_COL(angular_velocity_radps), TELEOP_COL(scheme), TELEOP_COL(master_force_n);
  TELEOP_COL(wave_u), TELEOP_COL(position_gain_n_per_m), TELEOP_COL(enabled);
  TELEOP_COL(passivity_session), TELEOP_COL(wave_impedance_ns_per_m), TELEOP_COL(wave_matched);
  TELEOP_COL(tdpa_energy_in_j), TELEOP_COL(master_session), TELEOP_COL(release);
}

void decode(const SlaveState& s, Columns& cols) {
  TELEOP_COL(seq), TELEOP_COL(command_seq), TELEOP_COL(command_send_time_ns);
  TELEOP_COL(server_time_ns), TELEOP_COL(sim_time_s), TELEOP_COL(joint_position_rad);
  TELEOP_COL(joint_velocity_radps), TELEOP_COL(joint_torque_nm), TELEOP_COL(tip_position_m);
  TELEOP_COL(tip_orientation_wxyz), TELEOP_COL(tip_linear_velocity_mps);
  TELEOP_COL(tip_angular_velocity_radps), TELEOP_COL(contact_force_n);
  TELEOP_COL(contact_torque_nm), TELEOP_COL(penetration_m), TELEOP_COL(in_contact);
  TELEOP_COL(contact_object), TELEOP_COL(wave_v), TELEOP_COL(holding), TELEOP_COL(step_time_us);
  TELEOP_COL(commands_received), TELEOP_COL(deformation_m), TELEOP_COL(tdpa_energy_in_j);
  TELEOP_COL(tdpa_energy_out_j), TELEOP_COL(passivity_dissipated_j), TELEOP_COL(owner_session);
  TELEOP_COL(owner_active), TELEOP_COL(model_valid), TELEOP_COL(model_normal);
  TELEOP_COL(model_offset_m), TELEOP_COL(model_stiffness_n_per_m);
}

void decode(const MasterState& s, Columns& cols) {
  TELEOP_COL(seq), TELEOP_COL(time_ns), TELEOP_COL(device_position_m);
  TELEOP_COL(device_orientation_wxyz), TELEOP_COL(device_velocity_mps);
  TELEOP_COL(rendered_force_n), TELEOP_COL(environment_force_n), TELEOP_COL(position_error_m);
  TELEOP_COL(passivity_energy_j), TELEOP_COL(rtt_ms), TELEOP_COL(mode), TELEOP_COL(link_ok);
  TELEOP_COL(passivity_observer_j), TELEOP_COL(passivity_dissipated_j);
  TELEOP_COL(command_position_m);
}

void decode(const Event& s, Columns& cols) {
  TELEOP_COL(seq), TELEOP_COL(time_ns), TELEOP_COL(kind), TELEOP_COL(severity);
  TELEOP_COL(value);
}

void decode(const ServerStats& s, Columns& cols) {
  TELEOP_COL(time_ns), TELEOP_COL(sim_time_s), TELEOP_COL(steps), TELEOP_COL(loop_rate_hz);
  TELEOP_COL(step_us_p50), TELEOP_COL(step_us_p99), TELEOP_COL(step_us_max), TELEOP_COL(overruns);
  TELEOP_COL(commands_received), TELEOP_COL(watchdog_trips), TELEOP_COL(faults);
}

#undef TELEOP_COL

/// Deserializes `payload` as PubSub's type into `value`; false when it does not decode.
template <class PubSub>
bool deserialize_into(std::vector<std::uint8_t>& payload, typename PubSub::type& value) {
  eprosima::fastrtps::rtps::SerializedPayload_t p;
  p.data = payload.data();
  p.length = static_cast<std::uint32_t>(payload.size());
  p.max_size = p.length;
  const bool ok = dds::deserialize_checked<PubSub>(p, value);
  p.data = nullptr;  // not owned
  return ok;
}

/// Deserializes `payload` as PubSub's type and adds its fields; false when it does not decode.
template <class PubSub>
bool decode_as(std::vector<std::uint8_t>& payload, Columns& cols) {
  typename PubSub::type value;
  const bool ok = deserialize_into<PubSub>(payload, value);
  if (ok) decode(value, cols);
  return ok;
}

/// What one topic of a recording holds: per sample its times, sizes and decoded fields; the
/// types whose samples are not rows of numbers keep them whole (events' texts, mesh frames and
/// topologies, scene descriptions).
struct TopicArrays {
  std::string type;
  std::vector<double> receive_ns, source_ns, writer_seq, payload_bytes;
  std::size_t malformed = 0;
  Columns fields;
  std::vector<std::string> source, message;           // teleop::Event
  std::vector<std::vector<float>> positions_m;        // teleop::MeshFrame, 3 per vertex
  std::vector<std::vector<std::uint32_t>> triangles;  // teleop::MeshTopology, 3 per triangle
  std::vector<SceneDescription> scenes;               // teleop::SceneDescription
};

/// Events, mesh frames and topologies: their numbers as columns, the rest kept whole.
bool decode_whole(std::vector<std::uint8_t>& payload, TopicArrays& t) {
  if (t.type == "teleop::Event") {
    Event e;
    const bool ok = deserialize_into<EventPubSubType>(payload, e);
    if (ok) decode(e, t.fields);
    t.source.push_back(ok ? e.source().to_string() : "");
    t.message.push_back(ok ? e.message().to_string() : "");
    return ok;
  }
  if (t.type == "teleop::MeshFrame") {
    MeshFrame f;
    const bool ok = deserialize_into<MeshFramePubSubType>(payload, f);
    if (ok) t.fields.add("object_id", f.object_id()), t.fields.add("frame", f.frame());
    if (ok) t.fields.add("sim_time_s", f.sim_time_s());
    t.positions_m.push_back(ok ? f.positions_m() : std::vector<float>{});
    return ok;
  }
  MeshTopology m;
  const bool ok = deserialize_into<MeshTopologyPubSubType>(payload, m);
  if (ok) t.fields.add("object_id", m.object_id()), t.fields.add("vertex_count", m.vertex_count());
  t.triangles.push_back(ok ? m.triangle_indices() : std::vector<std::uint32_t>{});
  return ok;
}

/// Decodes one sample into its topic's arrays.
void add_sample(record::RecordedSample& s, TopicArrays& t) {
  t.receive_ns.push_back(static_cast<double>(s.receive_ns));
  t.source_ns.push_back(static_cast<double>(s.source_ns));
  t.writer_seq.push_back(static_cast<double>(s.writer_seq));
  t.payload_bytes.push_back(static_cast<double>(s.payload.size()));
  bool ok = true;
  const std::string& type = t.type;
  if (type == "teleop::MasterCommand") ok = decode_as<MasterCommandPubSubType>(s.payload, t.fields);
  if (type == "teleop::SlaveState") ok = decode_as<SlaveStatePubSubType>(s.payload, t.fields);
  if (type == "teleop::MasterState") ok = decode_as<MasterStatePubSubType>(s.payload, t.fields);
  if (type == "teleop::ServerStats") ok = decode_as<ServerStatsPubSubType>(s.payload, t.fields);
  if (type == "teleop::Event" || type == "teleop::MeshFrame" || type == "teleop::MeshTopology") {
    ok = decode_whole(s.payload, t);
  }
  if (type == "teleop::SceneDescription") {
    t.scenes.emplace_back();
    ok = deserialize_into<SceneDescriptionPubSubType>(s.payload, t.scenes.back());
    if (!ok) t.scenes.pop_back();
  }
  if (!ok) ++t.malformed;
  t.fields.end_row();
}

/// The samples kept whole, as Python lists.
void add_whole(const TopicArrays& t, py::dict& d) {
  if (t.type == "teleop::Event") d["source"] = t.source, d["message"] = t.message;
  if (t.type == "teleop::MeshFrame") {
    py::list frames;
    for (const std::vector<float>& p : t.positions_m) {
      py::array_t<float> a({static_cast<py::ssize_t>(p.size() / 3), py::ssize_t{3}});
      std::copy(p.begin(), p.begin() + static_cast<std::ptrdiff_t>(p.size() / 3 * 3),
                a.mutable_data());
      frames.append(a);
    }
    d["positions_m"] = frames;
  }
  if (t.type == "teleop::MeshTopology") {
    py::list tris;
    for (const std::vector<std::uint32_t>& v : t.triangles) {
      py::array_t<std::int64_t> a({static_cast<py::ssize_t>(v.size() / 3), py::ssize_t{3}});
      std::copy(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 3 * 3),
                a.mutable_data());
      tris.append(a);
    }
    d["triangles"] = tris;
  }
  if (t.type == "teleop::SceneDescription") {
    py::list scenes;
    for (const SceneDescription& s : t.scenes) scenes.append(scene_description_dict(s));
    d["description"] = scenes;
  }
}

py::dict read_recording(const std::string& path) {
  std::map<int, TopicArrays> topics;
  std::map<int, std::string> names;
  {
    py::gil_scoped_release release;
    record::RecordingReader reader(path);
    for (const record::TopicRecord& t : reader.topics()) {
      topics[t.id].type = t.type_name;
      names[t.id] = t.name;
    }
    reader.scan(0);
    record::RecordedSample s;
    while (reader.next(s)) {
      auto it = topics.find(s.topic_id);
      if (it != topics.end()) add_sample(s, it->second);
    }
  }
  py::dict out;
  for (auto& [id, t] : topics) {
    const std::size_t n = t.receive_ns.size();
    py::dict d;
    d["receive_ns"] = array_of(t.receive_ns.data(), n, 1);
    d["source_ns"] = array_of(t.source_ns.data(), n, 1);
    d["writer_seq"] = array_of(t.writer_seq.data(), n, 1);
    d["payload_bytes"] = array_of(t.payload_bytes.data(), n, 1);
    for (const std::string& name : t.fields.order) {
      const Columns::Column& c = t.fields.columns.at(name);
      d[py::str(name)] = array_of(c.values.data(), t.fields.rows, c.width);
    }
    add_whole(t, d);
    d["type"] = t.type;
    d["malformed"] = t.malformed;
    out[py::str(names[id])] = d;
  }
  return out;
}

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// The trace `name` of `traces`, checked to hold `rows` rows of `width` values.
Array trace(const py::dict& traces, const char* name, std::size_t rows, std::size_t width) {
  if (!traces.contains(name)) throw py::value_error(std::string("traces: no '") + name + "'");
  Array a = traces[name].cast<Array>();
  const std::size_t cols = a.ndim() == 1 ? 1 : static_cast<std::size_t>(a.shape(1));
  if (a.ndim() > 2 || static_cast<std::size_t>(a.shape(0)) != rows || cols != width) {
    throw py::value_error(std::string("traces['") + name + "'] must be " + std::to_string(rows) +
                          " x " + std::to_string(width));
  }
  return a;
}

/// Serializes `value` with PubSub into a recorded sample.
template <class PubSub>
record::RecordedSample sample_of(typename PubSub::type& value, int topic, std::int64_t t_ns,
                                 std::int64_t seq) {
  PubSub type;
  eprosima::fastrtps::rtps::SerializedPayload_t p(type.getSerializedSizeProvider(&value)() + 8);
  if (!type.serialize(&value, &p)) throw std::runtime_error("a sample could not be serialized");
  record::RecordedSample s;
  s.topic_id = topic;
  s.receive_ns = t_ns;
  s.source_ns = t_ns;
  s.writer_seq = seq;
  s.payload.assign(p.data, p.data + p.length);
  return s;
}

template <std::size_t N>
std::array<double, N> row(const Array& a, std::size_t i) {
  std::array<double, N> r{};
  for (std::size_t k = 0; k < N; ++k) r[k] = a.at(i, k);
  return r;
}

/// Writes a session's traces as teleop/slave_state and teleop/master_state samples, one pair
/// per cycle, stamped with the session's clock. Returns the samples written.
std::size_t write_recording(const std::string& path, const py::dict& traces,
                            const std::string& format) {
  if (!traces.contains("time_s")) throw py::value_error("traces: no 'time_s'");
  const auto n = static_cast<std::size_t>(traces["time_s"].cast<Array>().shape(0));
  const Array t = trace(traces, "time_s", n, 1), xs = trace(traces, "slave_position_m", n, 3),
              fe = trace(traces, "contact_force_n", n, 3),
              pen = trace(traces, "penetration_m", n, 1), con = trace(traces, "in_contact", n, 1),
              xm = trace(traces, "master_position_m", n, 3),
              fd = trace(traces, "device_force_n", n, 3),
              fm = trace(traces, "contact_force_at_master_n", n, 3);
  record::RecordingWriter w(path, format.empty() ? record::format_for_path(path)
                                                 : record::parse_format("format", format));
  const auto topic = [&](const char* name) {
    const record::TopicEntry* e = record::find_topic(name);
    return w.add_topic(name, e->type, record::qos_name(e->qos));
  };
  const int slave_topic = topic(dds::topics::kSlaveState.name),
            master_topic = topic(dds::topics::kMasterState.name);
  w.set_meta("source", "teleop.write_recording (an in-process session)");
  std::vector<record::RecordedSample> batch;
  for (std::size_t i = 0; i < n; ++i) {
    const auto t_ns = static_cast<std::int64_t>(std::llround(t.at(i) * 1e9));
    SlaveState s;
    s.seq(i);
    s.sim_time_s(t.at(i));
    s.tip_position_m(row<3>(xs, i));
    s.contact_force_n(row<3>(fe, i));
    s.penetration_m(pen.at(i));
    s.in_contact(con.at(i) != 0.0);
    s.contact_object(-1);
    batch.push_back(sample_of<SlaveStatePubSubType>(s, slave_topic, t_ns, 2 * i + 1));
    MasterState ms;
    ms.seq(i);
    ms.time_ns(t_ns);
    ms.command_position_m(row<3>(xm, i));
    ms.rendered_force_n(row<3>(fd, i));
    ms.environment_force_n(row<3>(fm, i));
    ms.link_ok(true);
    batch.push_back(sample_of<MasterStatePubSubType>(ms, master_topic, t_ns, 2 * i + 2));
    if (batch.size() >= 2000 || i + 1 == n) {
      w.append(batch);
      batch.clear();
    }
  }
  w.close();
  return 2 * n;
}

}  // namespace

void bind_recording(py::module_& m) {
  m.def("read_recording", &read_recording, py::arg("path"),
        "Reads a recording (MCAP or SQLite): {topic: {field: numpy array}}.");
  m.def("write_recording", &write_recording, py::arg("path"), py::arg("traces"),
        py::arg("format") = "",
        "Writes a session's traces as teleop/slave_state and teleop/master_state samples.");
}

}  // namespace teleop::python

#include "client/bridge/scene_json.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cmath>

#include "common/util/json.hpp"

namespace teleop::bridge {

namespace {

// The JSON schemas: the fields of Foxglove's published message definitions this bridge writes.
#define TELEOP_T \
  R"({"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}})"
#define TELEOP_V3 \
  R"({"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"}}})"
#define TELEOP_Q                                                                                         \
  R"({"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"},)" \
  R"("w":{"type":"number"}}})"
#define TELEOP_C                                                                                         \
  R"({"type":"object","properties":{"r":{"type":"number"},"g":{"type":"number"},"b":{"type":"number"},)" \
  R"("a":{"type":"number"}}})"
#define TELEOP_POSE \
  R"({"type":"object","properties":{"position":)" TELEOP_V3 R"(,"orientation":)" TELEOP_Q "}}"
#define TELEOP_ARR(item) R"({"type":"array","items":)" item "}"
#define TELEOP_PRIM(extra) \
  R"({"type":"object","properties":{"pose":)" TELEOP_POSE R"(,"color":)" TELEOP_C extra "}}"

}  // namespace

const char* const kSceneUpdateSchema =
    R"({"title":"foxglove.SceneUpdate","type":"object","properties":{"deletions":)" TELEOP_ARR(
        R"({"type":"object","properties":{"timestamp":)" TELEOP_T R"(,"type":{"type":"integer"},)"
        R"("id":{"type":"string"}}})") R"(,"entities":)" TELEOP_ARR(
        R"({"type":"object","properties":{"timestamp":)" TELEOP_T R"(,"frame_id":{"type":"string"},)"
        R"("id":{"type":"string"},"lifetime":)" TELEOP_T R"(,"frame_locked":{"type":"boolean"},)"
        R"("metadata":)" TELEOP_ARR(
            R"({"type":"object","properties":{"key":{"type":"string"},"value":{"type":"string"}}})")
        R"(,"arrows":)" TELEOP_ARR(TELEOP_PRIM(
            R"(,"shaft_length":{"type":"number"},"shaft_diameter":{"type":"number"},)"
            R"("head_length":{"type":"number"},"head_diameter":{"type":"number"})"))
        R"(,"cubes":)" TELEOP_ARR(TELEOP_PRIM(R"(,"size":)" TELEOP_V3))
        R"(,"spheres":)" TELEOP_ARR(TELEOP_PRIM(R"(,"size":)" TELEOP_V3))
        R"(,"cylinders":)" TELEOP_ARR(TELEOP_PRIM(
            R"(,"size":)" TELEOP_V3 R"(,"bottom_scale":{"type":"number"},"top_scale":{"type":"number"})"))
        R"(,"lines":)" TELEOP_ARR(TELEOP_PRIM(
            R"(,"type":{"type":"integer"},"thickness":{"type":"number"},)"
            R"("scale_invariant":{"type":"boolean"},"points":)" TELEOP_ARR(TELEOP_V3)
            R"(,"colors":)" TELEOP_ARR(TELEOP_C) R"(,"indices":{"type":"array","items":{"type":"integer"}})"))
        R"(,"triangles":)" TELEOP_ARR(TELEOP_PRIM(
            R"(,"points":)" TELEOP_ARR(TELEOP_V3) R"(,"colors":)" TELEOP_ARR(TELEOP_C)
            R"(,"indices":{"type":"array","items":{"type":"integer"}})"))
        R"(,"texts":{"type":"array"},"models":{"type":"array"}}})") "}}";

const char* const kFrameTransformsSchema =
    R"({"title":"foxglove.FrameTransforms","type":"object","properties":{"transforms":)" TELEOP_ARR(
        R"({"type":"object","properties":{"timestamp":)" TELEOP_T
        R"(,"parent_frame_id":{"type":"string"},)"
        R"("child_frame_id":{"type":"string"},"translation":)" TELEOP_V3 R"(,"rotation":)" TELEOP_Q
        "}}") "}}";

const char* const kPlotSchema =
    R"({"title":"teleop.bridge.Plot","type":"object","properties":{"timestamp":)" TELEOP_T
    R"(,"sim_time_s":{"type":"number"},"contact_force_n":)" TELEOP_V3
    R"(,"tip_position_m":)" TELEOP_V3
    R"(,"force_norm_n":{"type":"number"},"rtt_ms":{"type":"number"},"in_contact":{"type":"boolean"}}})";

const char* const kEventSchema =
    R"({"title":"teleop.bridge.Event","type":"object","properties":{"seq":{"type":"integer"},)"
    R"("time_ns":{"type":"integer"},"source":{"type":"string"},"kind":{"type":"integer"},)"
    R"("severity":{"type":"integer"},"message":{"type":"string"},"value":{"type":"number"}}})";

#undef TELEOP_T
#undef TELEOP_V3
#undef TELEOP_Q
#undef TELEOP_C
#undef TELEOP_POSE
#undef TELEOP_ARR
#undef TELEOP_PRIM

namespace {

struct Rgba {
  float r, g, b, a;
};
constexpr Rgba kPlaneColour{0.55f, 0.57f, 0.6f, 1.0f};
constexpr Rgba kBodyColour{0.85f, 0.45f, 0.3f, 1.0f};
constexpr Rgba kSolidColour{0.4f, 0.55f, 0.75f, 1.0f};
constexpr Rgba kRobotColour{0.3f, 0.3f, 0.35f, 1.0f};
constexpr Rgba kTipColour{0.2f, 0.7f, 0.3f, 1.0f};
constexpr Rgba kForceColour{0.9f, 0.15f, 0.15f, 1.0f};
/// Length of the force arrow per newton [m/N], and its longest length [m].
constexpr double kArrowMPerN = 0.01, kArrowMaxM = 0.3;
constexpr double kPlaneHalfExtentM = 1.0, kPlaneThicknessM = 0.002;

void num(std::string& o, double v) {
  if (!std::isfinite(v)) v = 0.0;
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 7);
  o.append(buf, r.ptr);
}
void integer(std::string& o, std::uint64_t v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  o.append(buf, r.ptr);
}
void vec3(std::string& o, double x, double y, double z) {
  o += "{\"x\":";
  num(o, x);
  o += ",\"y\":";
  num(o, y);
  o += ",\"z\":";
  num(o, z);
  o += '}';
}
void quat(std::string& o, const Eigen::Quaterniond& q) {
  o += "{\"x\":";
  num(o, q.x());
  o += ",\"y\":";
  num(o, q.y());
  o += ",\"z\":";
  num(o, q.z());
  o += ",\"w\":";
  num(o, q.w());
  o += '}';
}
void pose(std::string& o, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  o += "\"pose\":{\"position\":";
  vec3(o, p.x(), p.y(), p.z());
  o += ",\"orientation\":";
  quat(o, q);
  o += '}';
}
void colour(std::string& o, const Rgba& c) {
  o += "\"color\":{\"r\":";
  num(o, c.r);
  o += ",\"g\":";
  num(o, c.g);
  o += ",\"b\":";
  num(o, c.b);
  o += ",\"a\":";
  num(o, c.a);
  o += '}';
}
void stamp(std::string& o, std::uint64_t ns) {
  o += "{\"sec\":";
  integer(o, ns / 1'000'000'000u);
  o += ",\"nsec\":";
  integer(o, ns % 1'000'000'000u);
  o += '}';
}
/// Opens an entity; the caller writes its primitive arrays and closes it with close_entity.
void open_entity(std::string& o, const std::string& id, std::uint64_t ns) {
  o += "{\"timestamp\":";
  stamp(o, ns);
  o += ",\"frame_id\":\"world\",\"id\":\"";
  o += id;
  o += "\",\"lifetime\":{\"sec\":0,\"nsec\":0},\"frame_locked\":false,\"metadata\":[]";
}
void close_entity(std::string& o) { o += '}'; }
/// Empty arrays for the primitive kinds an entity does not use (after the ones it wrote).
void empty_arrays(std::string& o, std::initializer_list<const char*> names) {
  for (const char* n : names) {
    o += ",\"";
    o += n;
    o += "\":[]";
  }
}

bool finite3(const double* v) {
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

}  // namespace

void SceneJson::set_scene(const SceneDescription& scene) {
  scene_ = scene;
  have_scene_ = true;
  viewer::skeleton_from_scene(scene_, skeleton_);
}

bool SceneJson::set_topology(const MeshTopology& t) {
  const auto& idx = t.triangle_indices();
  bool ok = idx.size() % 3 == 0 && t.vertex_count() > 0;
  for (const auto i : idx) ok = ok && i < t.vertex_count();
  if (!ok) {
    ++rejected_;
    return false;
  }
  Body& b = bodies_[t.object_id()];
  b.indices.assign(idx.begin(), idx.end());
  b.vertices = t.vertex_count();
  if (b.positions.size() != 3u * b.vertices) b.positions.clear();
  return true;
}

bool SceneJson::set_frame(const MeshFrame& f) {
  auto it = bodies_.find(f.object_id());
  const auto& p = f.positions_m();
  bool ok = it != bodies_.end() && p.size() == 3u * it->second.vertices;
  for (std::size_t i = 0; ok && i < p.size(); ++i) ok = std::isfinite(p[i]);
  if (!ok) {
    // a frame before its topology is normal for a moment; counted all the same
    ++rejected_;
    return false;
  }
  it->second.positions.assign(p.begin(), p.end());
  return true;
}

bool SceneJson::set_slave(const SlaveState& s) {
  if (!finite3(s.tip_position_m().data()) || !finite3(s.contact_force_n().data()) ||
      !std::isfinite(s.sim_time_s())) {
    ++rejected_;
    return false;
  }
  std::copy_n(s.tip_position_m().data(), 3, tip_.begin());
  std::copy_n(s.contact_force_n().data(), 3, force_.begin());
  const auto& q = s.tip_orientation_wxyz();
  if (std::isfinite(q[0]) && std::isfinite(q[1]) && std::isfinite(q[2]) && std::isfinite(q[3])) {
    std::copy_n(q.data(), 4, tip_q_.begin());
  }
  joints_.assign(s.joint_position_rad().begin(), s.joint_position_rad().end());
  for (auto& j : joints_) j = std::isfinite(j) ? j : 0.0;
  in_contact_ = s.in_contact();
  sim_time_s_ = s.sim_time_s();
  have_slave_ = true;
  return true;
}

bool SceneJson::set_master(const MasterState& m) {
  if (!std::isfinite(m.rtt_ms())) {
    ++rejected_;
    return false;
  }
  rtt_ms_ = m.rtt_ms();
  have_master_ = true;
  return true;
}

double SceneJson::period_s() const {
  const double hz = have_scene_ ? scene_.visual_rate_hz() : 30.0;
  return 1.0 / std::clamp(std::isfinite(hz) ? hz : 30.0, 1.0, 30.0);
}

std::size_t SceneJson::triangle_count() const {
  std::size_t n = 0;
  for (const auto& [id, b] : bodies_) n += b.positions.empty() ? 0 : b.indices.size() / 3;
  return n;
}

void SceneJson::write_bodies(std::string& o) const {
  for (const auto& [id, b] : bodies_) {
    if (b.positions.empty()) continue;
    o += ",{\"pose\":{\"position\":{\"x\":0,\"y\":0,\"z\":0},\"orientation\":{\"x\":0,\"y\":0,"
         "\"z\":0,\"w\":1}},\"points\":[";
    for (std::uint32_t v = 0; v < b.vertices; ++v) {
      if (v) o += ',';
      vec3(o, b.positions[3 * v], b.positions[3 * v + 1], b.positions[3 * v + 2]);
    }
    o += "],";
    colour(o, kBodyColour);
    o += ",\"colors\":[],\"indices\":[";
    for (std::size_t i = 0; i < b.indices.size(); ++i) {
      if (i) o += ',';
      integer(o, b.indices[i]);
    }
    o += "]}";
  }
}

void SceneJson::write_static(std::string& o) const {
  // planes as thin squares, their top face on the plane; spheres and boxes where they are
  std::string cubes, spheres;
  for (const auto& s : scene_.objects()) {
    const Eigen::Vector3d p(s.position_m()[0], s.position_m()[1], s.position_m()[2]);
    const auto& r = s.orientation_wxyz();
    Eigen::Quaterniond q(r[0], r[1], r[2], r[3]);
    q = q.norm() > 0.5 ? q.normalized() : Eigen::Quaterniond::Identity();
    std::string& out = s.kind() == OBJECT_SPHERE ? spheres : cubes;
    if (s.kind() == OBJECT_PLANE) {
      Eigen::Vector3d n(s.normal()[0], s.normal()[1], s.normal()[2]);
      if (!(n.norm() > 0.5)) continue;
      n.normalize();
      const Eigen::Vector3d c = n * (s.offset_m() - kPlaneThicknessM / 2);
      out += out.empty() ? "{" : ",{";
      pose(out, c, Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), n));
      out += ",\"size\":";
      vec3(out, 2 * kPlaneHalfExtentM, 2 * kPlaneHalfExtentM, kPlaneThicknessM);
      out += ',';
      colour(out, kPlaneColour);
      out += '}';
    } else if (s.kind() == OBJECT_SPHERE || s.kind() == OBJECT_BOX) {
      const bool sphere = s.kind() == OBJECT_SPHERE;
      const auto& z = s.size_m();
      out += out.empty() ? "{" : ",{";
      pose(out, p, q);
      out += ",\"size\":";
      if (sphere) vec3(out, 2 * z[0], 2 * z[0], 2 * z[0]);
      if (!sphere) vec3(out, z[0], z[1], z[2]);
      out += ',';
      colour(out, kSolidColour);
      out += '}';
    }
  }
  o += ",\"cubes\":[" + cubes + "],\"spheres\":[" + spheres + "]";
}

void SceneJson::write_robot_and_tip(std::string& o) const {
  const Eigen::Vector3d tip(tip_[0], tip_[1], tip_[2]);
  const Eigen::Quaterniond tq =
      Eigen::Quaterniond(tip_q_[0], tip_q_[1], tip_q_[2], tip_q_[3]).normalized();
  o += ",\"spheres\":[{";
  pose(o, tip, tq);
  o += ",\"size\":";
  const double d = 2 * scene_.tip_radius_m();
  vec3(o, d, d, d);
  o += ',';
  colour(o, kTipColour);
  o += "}],\"lines\":[";
  if (skeleton_.joints > 0) {
    std::array<Eigen::Isometry3d, viewer::kMaxSkeletonJoints + 1> frames;
    viewer::skeleton_frames(skeleton_, joints_.data(), static_cast<int>(joints_.size()), frames);
    o += "{\"type\":0,";
    pose(o, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
    o += ",\"thickness\":0.02,\"scale_invariant\":false,\"points\":[";
    for (int i = 0; i <= skeleton_.joints; ++i) {
      const auto t = frames[static_cast<std::size_t>(i)].translation();
      if (i) o += ',';
      vec3(o, t.x(), t.y(), t.z());
    }
    // the tool: from the last frame to the tip's centre
    o += ',';
    vec3(o, tip.x(), tip.y(), tip.z());
    o += "],";
    colour(o, kRobotColour);
    o += ",\"colors\":[],\"indices\":[]}";
  }
  o += "],\"arrows\":[";
  const Eigen::Vector3d f(force_[0], force_[1], force_[2]);
  const double len = std::min(kArrowMaxM, f.norm() * kArrowMPerN);
  if (len > 1e-4) {
    o += '{';
    pose(o, tip, Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), f));
    o += ",\"shaft_length\":";
    num(o, 0.8 * len);
    o += ",\"shaft_diameter\":0.006,\"head_length\":";
    num(o, 0.2 * len);
    o += ",\"head_diameter\":0.015,";
    colour(o, kForceColour);
    o += '}';
  }
  o += ']';
}

void SceneJson::scene_update(std::string& o, std::uint64_t ns) const {
  o.clear();
  o += "{\"deletions\":[],\"entities\":[";
  open_entity(o, "environment", ns);
  write_static(o);
  empty_arrays(o, {"arrows", "cylinders", "lines", "triangles", "texts", "models"});
  close_entity(o);
  o += ',';
  open_entity(o, "deformable", ns);
  o += ",\"triangles\":[";
  const std::size_t at = o.size();
  write_bodies(o);
  if (o.size() > at) o.erase(at, 1);  // the leading comma
  o += ']';
  empty_arrays(o, {"arrows", "cubes", "spheres", "cylinders", "lines", "texts", "models"});
  close_entity(o);
  o += ',';
  open_entity(o, "robot", ns);
  write_robot_and_tip(o);
  empty_arrays(o, {"cubes", "cylinders", "triangles", "texts", "models"});
  close_entity(o);
  o += "]}";
}

void SceneJson::frame_transforms(std::string& o, std::uint64_t ns) const {
  o.clear();
  o += "{\"transforms\":[";
  auto one = [&](const std::string& child, const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
    if (o.back() != '[') o += ',';
    o += "{\"timestamp\":";
    stamp(o, ns);
    o += ",\"parent_frame_id\":\"world\",\"child_frame_id\":\"" + child + "\",\"translation\":";
    vec3(o, t.x(), t.y(), t.z());
    o += ",\"rotation\":";
    quat(o, q);
    o += '}';
  };
  one("tip", Eigen::Vector3d(tip_[0], tip_[1], tip_[2]),
      Eigen::Quaterniond(tip_q_[0], tip_q_[1], tip_q_[2], tip_q_[3]).normalized());
  if (skeleton_.joints > 0) {
    std::array<Eigen::Isometry3d, viewer::kMaxSkeletonJoints + 1> frames;
    viewer::skeleton_frames(skeleton_, joints_.data(), static_cast<int>(joints_.size()), frames);
    for (int i = 0; i <= skeleton_.joints; ++i) {
      const auto& f = frames[static_cast<std::size_t>(i)];
      one("robot_" + std::to_string(i), f.translation(), Eigen::Quaterniond(f.rotation()));
    }
  }
  o += "]}";
}

bool SceneJson::plot(std::string& o, std::uint64_t ns) const {
  if (!have_slave_) return false;
  o.clear();
  o += "{\"timestamp\":";
  stamp(o, ns);
  o += ",\"sim_time_s\":";
  num(o, sim_time_s_);
  o += ",\"contact_force_n\":";
  vec3(o, force_[0], force_[1], force_[2]);
  o += ",\"tip_position_m\":";
  vec3(o, tip_[0], tip_[1], tip_[2]);
  o += ",\"force_norm_n\":";
  num(o, std::sqrt(force_[0] * force_[0] + force_[1] * force_[1] + force_[2] * force_[2]));
  o += ",\"rtt_ms\":";
  num(o, have_master_ ? rtt_ms_ : 0.0);
  o += ",\"in_contact\":";
  o += in_contact_ ? "true" : "false";
  o += '}';
  return true;
}

std::string event_json(const Event& e) {
  OrderedJson o;
  o["seq"] = e.seq();
  o["time_ns"] = e.time_ns();
  o["source"] = e.source().to_string();
  o["kind"] = static_cast<unsigned>(e.kind());
  o["severity"] = static_cast<unsigned>(e.severity());
  o["message"] = e.message().to_string();
  o["value"] = std::isfinite(e.value()) ? e.value() : 0.0;
  return json_compact(o);
}

}  // namespace teleop::bridge

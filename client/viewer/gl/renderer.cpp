#include "client/viewer/gl/renderer.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "common/dds/scene_objects.hpp"

namespace teleop::viewer {
namespace {

const char* const kLitVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_color;
uniform mat4 u_model;
uniform mat3 u_normal_matrix;
uniform mat4 u_view_projection;
uniform int u_vertex_color;
uniform vec4 u_color;
out vec3 v_position;
out vec3 v_normal;
out vec4 v_color;
void main() {
  vec4 world = u_model * vec4(a_position, 1.0);
  v_position = world.xyz;
  v_normal = u_normal_matrix * a_normal;
  v_color = u_vertex_color != 0 ? vec4(a_color, u_color.a) : u_color;
  gl_Position = u_view_projection * world;
}
)";

// key light near the camera, a sky/ground fill and a small highlight; two-sided so the inside
// of a pressed mesh is lit too
const char* const kLitFragment = R"(#version 330 core
in vec3 v_position;
in vec3 v_normal;
in vec4 v_color;
uniform vec3 u_eye;
uniform vec3 u_light_dir;
out vec4 frag_color;
void main() {
  vec3 n = normalize(v_normal);
  if (!gl_FrontFacing) n = -n;
  vec3 to_eye = normalize(u_eye - v_position);
  float diffuse = max(dot(n, u_light_dir), 0.0);
  float fill = 0.5 + 0.5 * n.z;
  float spec = pow(max(dot(n, normalize(u_light_dir + to_eye)), 0.0), 48.0);
  vec3 c = v_color.rgb * (0.22 + 0.62 * diffuse + 0.22 * fill) + vec3(0.22 * spec);
  frag_color = vec4(c, v_color.a);
}
)";

const char* const kLineVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec4 a_color;
uniform mat4 u_view_projection;
out vec4 v_color;
void main() {
  v_color = a_color;
  gl_Position = u_view_projection * vec4(a_position, 1.0);
}
)";

const char* const kLineFragment = R"(#version 330 core
in vec4 v_color;
out vec4 frag_color;
void main() { frag_color = v_color; }
)";

// planes: one colour per plane, lit on the CPU (a directional light shades a plane evenly), so
// the largest surfaces on screen cost a software rasteriser no per-pixel lighting
const char* const kFlatVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
uniform mat4 u_view_projection;
void main() { gl_Position = u_view_projection * vec4(a_position, 1.0); }
)";

const char* const kFlatFragment = R"(#version 330 core
uniform vec4 u_color;
out vec4 frag_color;
void main() { frag_color = u_color; }
)";

GLuint compile(GLenum type, const char* source, std::string& error) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetShaderInfoLog(s, sizeof(log), nullptr, log);
    error = std::string("shader compilation failed: ") + log;
    glDeleteShader(s);
    return 0;
  }
  return s;
}

GLuint link(const char* vertex, const char* fragment, std::string& error) {
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex, error);
  if (!vs) return 0;
  const GLuint fs = compile(GL_FRAGMENT_SHADER, fragment, error);
  if (!fs) {
    glDeleteShader(vs);
    return 0;
  }
  const GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetProgramInfoLog(p, sizeof(log), nullptr, log);
    error = std::string("shader link failed: ") + log;
    glDeleteProgram(p);
    return 0;
  }
  return p;
}

const void* byte_offset(std::size_t bytes) { return reinterpret_cast<const void*>(bytes); }

Eigen::Vector3f vec3(const std::array<double, 3>& a) {
  return Eigen::Vector3f(static_cast<float>(a[0]), static_cast<float>(a[1]),
                         static_cast<float>(a[2]));
}

/// The tip touches something: a finite contact force above 0.02 N.
bool tip_touching(const ViewerView& view) {
  if (!view.have_slave) return false;
  const float f = vec3(view.slave.contact_force_n()).norm();
  return std::isfinite(f) && f > 0.02f;
}

/// Model matrix of a unit primitive along z stretched from a to b with radius r.
Eigen::Matrix4f along(const Eigen::Vector3f& a, const Eigen::Vector3f& b, float r) {
  const Eigen::Vector3f d = b - a;
  const float len = d.norm();
  Eigen::Affine3f m = Eigen::Affine3f::Identity();
  m.translate(a);
  if (len > 1e-9f) m.rotate(Eigen::Quaternionf::FromTwoVectors(Eigen::Vector3f::UnitZ(), d / len));
  m.scale(Eigen::Vector3f(r, r, len));
  return m.matrix();
}

/// The scene's planes (into `planes`) and what their patches must cover: the workspace, the
/// bodies and the robot's base, with a margin.
Bounds plane_bounds(const SceneDescription& scene, std::vector<Plane>& planes) {
  Bounds b;
  b.min = vec3(scene.workspace_min_m());
  b.max = vec3(scene.workspace_max_m());
  if (!(b.min.array() < b.max.array()).all() || !b.min.allFinite() || !b.max.allFinite()) {
    b.min = Eigen::Vector3f::Constant(-1.0f);
    b.max = Eigen::Vector3f::Constant(1.0f);
  }
  for (const auto& o : scene.objects()) {
    if (o.kind() == OBJECT_PLANE) {
      const Eigen::Vector3f n = vec3(o.normal());
      if (n.norm() > 0.5f && n.allFinite()) {
        planes.push_back(Plane{n.normalized(), static_cast<float>(o.offset_m())});
      }
    } else if (o.kind() == OBJECT_DEFORMABLE_MESH ||
               (o.kind() == OBJECT_ROBOT_LINK && o.id() == scene_objects::kRobotFrameIdBase)) {
      const Eigen::Vector3f p = vec3(o.position_m());
      const float r = static_cast<float>(o.size_m()[0]);
      if (p.allFinite() && std::isfinite(r)) {
        b.min = b.min.cwiseMin(p - Eigen::Vector3f::Constant(r));
        b.max = b.max.cwiseMax(p + Eigen::Vector3f::Constant(r));
      }
    }
  }
  b.min -= Eigen::Vector3f::Constant(0.35f);
  b.max += Eigen::Vector3f::Constant(0.35f);
  return b;
}

}  // namespace

bool SceneRenderer::init(std::string& error) {
  lit_program_ = link(kLitVertex, kLitFragment, error);
  if (!lit_program_) return false;
  line_program_ = link(kLineVertex, kLineFragment, error);
  if (!line_program_) return false;
  flat_program_ = link(kFlatVertex, kFlatFragment, error);
  if (!flat_program_) return false;
  u_model_ = glGetUniformLocation(lit_program_, "u_model");
  u_normal_matrix_ = glGetUniformLocation(lit_program_, "u_normal_matrix");
  u_view_projection_ = glGetUniformLocation(lit_program_, "u_view_projection");
  u_color_ = glGetUniformLocation(lit_program_, "u_color");
  u_vertex_color_ = glGetUniformLocation(lit_program_, "u_vertex_color");
  u_eye_ = glGetUniformLocation(lit_program_, "u_eye");
  u_light_dir_ = glGetUniformLocation(lit_program_, "u_light_dir");
  u_line_view_projection_ = glGetUniformLocation(line_program_, "u_view_projection");
  u_flat_view_projection_ = glGetUniformLocation(flat_program_, "u_view_projection");
  u_flat_color_ = glGetUniformLocation(flat_program_, "u_color");

  sphere_ = upload(make_sphere(3));
  cylinder_ = upload(make_cylinder(24));
  cone_ = upload(make_cone(24));

  glGenVertexArrays(1, &plane_vao_);
  glGenBuffers(1, &plane_vbo_);
  glGenVertexArrays(1, &line_vao_);
  glGenBuffers(1, &line_vbo_);
  glBindVertexArray(line_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, line_vbo_);
  line_capacity_ = 4096;
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(line_capacity_ * 7 * sizeof(float)),
               nullptr, GL_STREAM_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 7 * sizeof(float), byte_offset(0));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, 7 * sizeof(float),
                        byte_offset(3 * sizeof(float)));
  glBindVertexArray(0);
  line_scratch_.reserve(line_capacity_ * 7);
  frame_lines_.reserve(64);
  if (const GLenum e = glGetError(); e != GL_NO_ERROR) {
    error = "OpenGL error " + std::to_string(e) + " while setting up the renderer";
    return false;
  }
  return true;
}

SceneRenderer::GpuMesh SceneRenderer::upload(const PrimitiveMesh& mesh) {
  GpuMesh g;
  std::vector<float> interleaved;
  interleaved.reserve(mesh.positions.size() * 6);
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    interleaved.insert(interleaved.end(), mesh.positions[i].data(), mesh.positions[i].data() + 3);
    interleaved.insert(interleaved.end(), mesh.normals[i].data(), mesh.normals[i].data() + 3);
  }
  glGenVertexArrays(1, &g.vao);
  glBindVertexArray(g.vao);
  glGenBuffers(1, &g.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(interleaved.size() * sizeof(float)),
               interleaved.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), byte_offset(0));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        byte_offset(3 * sizeof(float)));
  glGenBuffers(1, &g.ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(mesh.indices.size() * sizeof(std::uint32_t)),
               mesh.indices.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);
  g.count = static_cast<GLsizei>(mesh.indices.size());
  return g;
}

void SceneRenderer::sync_scene(const ViewerView& view) {
  if (view.scene_version == scene_version_) return;
  scene_version_ = view.scene_version;
  const SceneDescription& scene = view.scene;
  tip_radius_m_ = scene.tip_radius_m() > 0.0 ? static_cast<float>(scene.tip_radius_m()) : 0.05f;
  skeleton_from_scene(scene, skeleton_);

  std::vector<Plane> planes;
  const Bounds b = plane_bounds(scene, planes);

  patches_.clear();
  patch_first_.clear();
  patch_count_.clear();
  grid_lines_.clear();
  patch_of_line_.clear();
  have_floor_ = false;
  mesh_ids_.clear();
  for (const auto& o : scene.objects()) {
    if (o.kind() == OBJECT_DEFORMABLE_MESH) mesh_ids_.push_back(o.id());
  }
  std::vector<float> vertices;
  for (std::size_t i = 0; i < planes.size(); ++i) {
    PlanePatch patch = make_plane_patch(planes, i, b, 0.1f);
    const bool floor = patch.plane.normal.z() > 0.7f;
    if (floor && patch.plane.normal.z() > 0.99f && !have_floor_) {
      have_floor_ = true;
      floor_z_ = patch.plane.offset_m / patch.plane.normal.z();
    }
    patch_first_.push_back(static_cast<GLint>(vertices.size() / 6));
    patch_count_.push_back(static_cast<GLsizei>(patch.polygon.size()));
    for (const auto& p : patch.polygon) {
      vertices.insert(vertices.end(), p.data(), p.data() + 3);
      vertices.insert(vertices.end(), patch.plane.normal.data(), patch.plane.normal.data() + 3);
    }
    const Eigen::Vector4f grid_color = floor ? Eigen::Vector4f(0.46f, 0.45f, 0.42f, 1.0f)
                                             : Eigen::Vector4f(0.8f, 0.85f, 0.9f, 0.25f);
    for (const auto& seg : patch.grid) {
      grid_lines_.push_back(Line{seg[0] + 0.001f * patch.plane.normal,
                                 seg[1] + 0.001f * patch.plane.normal, grid_color});
      patch_of_line_.push_back(i);
    }
    patches_.push_back(std::move(patch));
  }
  upload_planes(vertices);
}

/// The planes' vertices (position, normal) into their buffer; the line buffer grown to hold the
/// grid and a frame's lines.
void SceneRenderer::upload_planes(const std::vector<float>& vertices) {
  glBindVertexArray(plane_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, plane_vbo_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)),
               vertices.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), byte_offset(0));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        byte_offset(3 * sizeof(float)));
  glBindVertexArray(0);
  if (grid_lines_.size() * 2 + 256 > line_capacity_) {
    line_capacity_ = grid_lines_.size() * 2 + 256;
    glBindBuffer(GL_ARRAY_BUFFER, line_vbo_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(line_capacity_ * 7 * sizeof(float)),
                 nullptr, GL_STREAM_DRAW);
    line_scratch_.reserve(line_capacity_ * 7);
  }
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

/// A body's buffers made (once) and sized for its vertices, its triangles uploaded; the frame
/// and the colours' reference start over.
void SceneRenderer::set_topology(DeformableGpu& g, const MeshSlot& m) {
  const std::size_t floats = 3u * m.vertex_count;
  if (!g.vao) {
    glGenVertexArrays(1, &g.vao);
    glGenBuffers(1, &g.positions);
    glGenBuffers(1, &g.normals);
    glGenBuffers(1, &g.colors);
    glGenBuffers(1, &g.ebo);
  }
  glBindVertexArray(g.vao);
  const auto bytes = static_cast<GLsizeiptr>(floats * sizeof(float));
  int location = 0;
  for (const GLuint buffer : {g.positions, g.normals, g.colors}) {
    glBindBuffer(GL_ARRAY_BUFFER, buffer);
    glBufferData(GL_ARRAY_BUFFER, bytes, nullptr, GL_DYNAMIC_DRAW);
    glEnableVertexAttribArray(static_cast<GLuint>(location));
    glVertexAttribPointer(static_cast<GLuint>(location), 3, GL_FLOAT, GL_FALSE, 0, byte_offset(0));
    ++location;
  }
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(m.triangles.size() * sizeof(std::uint32_t)),
               m.triangles.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);
  g.object_id = m.object_id;
  g.vertex_count = m.vertex_count;
  g.count = static_cast<GLsizei>(m.triangles.size());
  g.topology_version = m.topology_version;
  g.frame_version = 0;
  g.normal_scratch.resize(floats);
  g.color_scratch.resize(floats);
  g.reference.resize(floats);
  g.have_reference = false;
}

void SceneRenderer::upload_deformables(const ViewerView& view, const RenderOptions& options) {
  for (int i = 0; i < view.mesh_count; ++i) {
    const MeshSlot& m = view.meshes[static_cast<std::size_t>(i)];
    DeformableGpu& g = deformables_[static_cast<std::size_t>(i)];
    // only the bodies of the current scene (a restarted server may have dropped one)
    const bool in_scene =
        std::find(mesh_ids_.begin(), mesh_ids_.end(), m.object_id) != mesh_ids_.end();
    if (!m.drawable() || !in_scene) {
      g.count = 0;
      continue;
    }
    const std::size_t floats = 3u * m.vertex_count;
    if (g.topology_version != m.topology_version || g.object_id != m.object_id ||
        g.vertex_count != m.vertex_count) {
      set_topology(g, m);
    }
    const bool recolor =
        options.displacement_colors != g.colored || options.displacement_scale_m != g.color_scale_m;
    if (g.frame_version == m.frame_version && !recolor) continue;
    vertex_normals(m.positions.data(), m.vertex_count, m.triangles.data(), m.triangles.size() / 3,
                   g.normal_scratch.data());
    const auto bytes = static_cast<GLsizeiptr>(floats * sizeof(float));
    glBindBuffer(GL_ARRAY_BUFFER, g.positions);
    glBufferSubData(GL_ARRAY_BUFFER, 0, bytes, m.positions.data());
    glBindBuffer(GL_ARRAY_BUFFER, g.normals);
    glBufferSubData(GL_ARRAY_BUFFER, 0, bytes, g.normal_scratch.data());
    if (options.displacement_colors) {
      if (i == 0) max_displacement_m_ = 0.0f;
      // the reference follows the body while the tip touches nothing, so what is coloured is
      // the deformation since the contact began (a settling body stays blue)
      if (!g.have_reference || !tip_touching(view)) {
        std::copy(m.positions.data(), m.positions.data() + floats, g.reference.data());
        g.have_reference = true;
      }
      const RigidFit fit = best_rigid_fit(g.reference.data(), m.positions.data(), m.vertex_count);
      for (std::size_t v = 0; v < m.vertex_count; ++v) {
        const Eigen::Map<const Eigen::Vector3f> p(m.positions.data() + 3 * v),
            p0(g.reference.data() + 3 * v);
        const float d = (p - fit.apply(p0)).norm();
        max_displacement_m_ = std::max(max_displacement_m_, d);
        Eigen::Map<Eigen::Vector3f>(g.color_scratch.data() + 3 * v) =
            displacement_color(d, options.displacement_scale_m);
      }
      glBindBuffer(GL_ARRAY_BUFFER, g.colors);
      glBufferSubData(GL_ARRAY_BUFFER, 0, bytes, g.color_scratch.data());
    }
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    g.frame_version = m.frame_version;
    g.colored = options.displacement_colors;
    g.color_scale_m = options.displacement_scale_m;
  }
}

void SceneRenderer::draw_primitive(const GpuMesh& mesh, const Eigen::Matrix4f& model,
                                   const Eigen::Vector3f& color, float alpha) {
  const Eigen::Matrix3f normal_matrix = model.topLeftCorner<3, 3>().inverse().transpose();
  glUniformMatrix4fv(u_model_, 1, GL_FALSE, model.data());
  glUniformMatrix3fv(u_normal_matrix_, 1, GL_FALSE, normal_matrix.data());
  glUniform4f(u_color_, color.x(), color.y(), color.z(), alpha);
  glUniform1i(u_vertex_color_, 0);
  glBindVertexArray(mesh.vao);
  glDrawElements(GL_TRIANGLES, mesh.count, GL_UNSIGNED_INT, nullptr);
}

void SceneRenderer::draw_sphere(const Eigen::Vector3f& centre, float radius,
                                const Eigen::Vector3f& color, float alpha) {
  Eigen::Affine3f m = Eigen::Affine3f::Identity();
  m.translate(centre);
  m.scale(radius);
  draw_primitive(sphere_, m.matrix(), color, alpha);
}

void SceneRenderer::draw_cylinder(const Eigen::Vector3f& a, const Eigen::Vector3f& b, float radius,
                                  const Eigen::Vector3f& color) {
  draw_primitive(cylinder_, along(a, b, radius), color);
}

void SceneRenderer::draw_cone(const Eigen::Vector3f& base, const Eigen::Vector3f& apex,
                              float radius, const Eigen::Vector3f& color) {
  draw_primitive(cone_, along(base, apex, radius), color);
}

void SceneRenderer::draw_lines(const std::vector<Line>& lines) {
  if (lines.empty()) return;
  const std::size_t n = std::min(lines.size() * 2, line_capacity_) / 2;
  line_scratch_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    for (const Eigen::Vector3f* p : {&lines[i].a, &lines[i].b}) {
      line_scratch_.insert(line_scratch_.end(), p->data(), p->data() + 3);
      line_scratch_.insert(line_scratch_.end(), lines[i].color.data(), lines[i].color.data() + 4);
    }
  }
  glUseProgram(line_program_);
  glUniformMatrix4fv(u_line_view_projection_, 1, GL_FALSE, view_projection_.data());
  glBindVertexArray(line_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, line_vbo_);
  glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(line_scratch_.size() * sizeof(float)),
                  line_scratch_.data());
  glDrawArrays(GL_LINES, 0, static_cast<GLsizei>(2 * n));
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glUseProgram(lit_program_);
}

void SceneRenderer::draw_planes(const Eigen::Vector3f& eye, bool walls) {
  frame_lines_.clear();
  glUseProgram(flat_program_);
  glUniformMatrix4fv(u_flat_view_projection_, 1, GL_FALSE, view_projection_.data());
  glBindVertexArray(plane_vao_);
  for (std::size_t i = 0; i < patches_.size(); ++i) {
    const Plane& pl = patches_[i].plane;
    const bool is_floor = pl.normal.z() > 0.7f;
    if (is_floor == walls || patch_count_[i] < 3) continue;
    // seen from behind (outside the box): leave it out so the camera looks through it
    if (pl.normal.dot(eye) < pl.offset_m) continue;
    // the lit shader's ambient, key and sky terms, without the highlight
    const float shade = 0.22f + 0.62f * std::max(pl.normal.dot(light_), 0.0f) +
                        0.22f * (0.5f + 0.5f * pl.normal.z());
    const Eigen::Vector3f c = (is_floor ? colors::kFloor : colors::kWall) * shade;
    glUniform4f(u_flat_color_, c.x(), c.y(), c.z(), is_floor ? 1.0f : 0.18f);
    glDrawArrays(GL_TRIANGLE_FAN, patch_first_[i], patch_count_[i]);
    for (std::size_t k = 0; k < grid_lines_.size(); ++k) {
      if (patch_of_line_[k] == i) frame_lines_.push_back(grid_lines_[k]);
    }
  }
  draw_lines(frame_lines_);  // leaves the lit program bound
}

void SceneRenderer::draw_robot(const ViewerView& view, const Eigen::Vector3f& tip) {
  const int n = skeleton_.joints;
  const auto& q = view.slave.joint_position_rad();
  if (n <= 0 || static_cast<int>(q.size()) < n) return;
  skeleton_frames(skeleton_, q.data(), static_cast<int>(q.size()), frames_);
  std::array<Eigen::Vector3f, kMaxSkeletonJoints + 1> o;
  for (int i = 0; i <= n; ++i) {
    o[static_cast<std::size_t>(i)] =
        frames_[static_cast<std::size_t>(i)].translation().cast<float>();
  }
  // pedestal: the base stands on the floor (drawn only; it is not simulated)
  if (have_floor_ && o[0].z() > floor_z_ + 0.01f) {
    draw_cylinder(Eigen::Vector3f(o[0].x(), o[0].y(), floor_z_),
                  o[0] - Eigen::Vector3f(0, 0, 0.05f), 0.07f, colors::kJoint);
  }
  for (int i = 1; i <= n; ++i) {
    const auto& a = o[static_cast<std::size_t>(i - 1)];
    const auto& b = o[static_cast<std::size_t>(i)];
    if ((b - a).norm() > 1e-3f) draw_cylinder(a, b, 0.035f, colors::kRobot);
  }
  for (int i = 0; i <= n; ++i) draw_sphere(o[static_cast<std::size_t>(i)], 0.045f, colors::kJoint);
  // the tool: flange to tip centre
  const auto& flange = o[static_cast<std::size_t>(n)];
  if ((tip - flange).norm() > tip_radius_m_) draw_cylinder(flange, tip, 0.012f, colors::kRobot);
}

/// The deformable bodies, lit, coloured by their deformation or as wireframe.
void SceneRenderer::draw_deformables(const ViewerView& view, const RenderOptions& options) {
  for (int i = 0; i < view.mesh_count; ++i) {
    const DeformableGpu& g = deformables_[static_cast<std::size_t>(i)];
    if (g.count == 0) continue;
    const Eigen::Matrix4f identity = Eigen::Matrix4f::Identity();
    const Eigen::Matrix3f identity3 = Eigen::Matrix3f::Identity();
    glUniformMatrix4fv(u_model_, 1, GL_FALSE, identity.data());
    glUniformMatrix3fv(u_normal_matrix_, 1, GL_FALSE, identity3.data());
    const Eigen::Vector3f c =
        options.wireframe ? Eigen::Vector3f(0.55f, 0.78f, 1.0f) : colors::kDeformable;
    glUniform4f(u_color_, c.x(), c.y(), c.z(), 1.0f);
    glUniform1i(u_vertex_color_, options.displacement_colors ? 1 : 0);
    if (options.wireframe) glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    glBindVertexArray(g.vao);
    glDrawElements(GL_TRIANGLES, g.count, GL_UNSIGNED_INT, nullptr);
    if (options.wireframe) glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  }
}

/// The robot, the tip (see-through in contact) and its shadow and drop line on the floor.
void SceneRenderer::draw_tip(const ViewerView& view) {
  const Eigen::Vector3f tip = vec3(view.slave.tip_position_m());
  if (tip.allFinite()) {
    draw_robot(view, tip);
    // in contact the tip is see-through, so the dent under it shows
    const bool touching = tip_touching(view);
    if (touching) {
      glEnable(GL_BLEND);
      glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
      glDepthMask(GL_FALSE);
    }
    draw_sphere(tip, tip_radius_m_, colors::kTip, touching ? 0.45f : 1.0f);
    if (touching) {
      glDepthMask(GL_TRUE);
      glDisable(GL_BLEND);
    }
    // shadow and drop line on the floor: where the tip is over the floor
    if (have_floor_ && tip.z() > floor_z_) {
      glEnable(GL_BLEND);
      glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
      glDepthMask(GL_FALSE);
      Eigen::Affine3f m = Eigen::Affine3f::Identity();
      m.translate(Eigen::Vector3f(tip.x(), tip.y(), floor_z_ + 0.002f));
      m.scale(Eigen::Vector3f(tip_radius_m_, tip_radius_m_, 0.0005f));
      draw_primitive(sphere_, m.matrix(), Eigen::Vector3f::Zero(), 0.35f);
      frame_lines_.clear();
      frame_lines_.push_back(Line{tip, Eigen::Vector3f(tip.x(), tip.y(), floor_z_),
                                  Eigen::Vector4f(1.0f, 1.0f, 1.0f, 0.35f)});
      draw_lines(frame_lines_);
      glDepthMask(GL_TRUE);
      glDisable(GL_BLEND);
    }
  }
}

/// The contact force last, over everything: it starts inside the tool and points into the
/// tool's shaft when the tip presses down.
void SceneRenderer::draw_force(const ViewerView& view, const RenderOptions& options) {
  if (view.have_slave && options.show_force) {
    const Eigen::Vector3f tip = vec3(view.slave.tip_position_m());
    const Eigen::Vector3f f = vec3(view.slave.contact_force_n());
    const float fn = f.norm();
    if (tip.allFinite() && std::isfinite(fn) && fn > 0.02f) {
      glClear(GL_DEPTH_BUFFER_BIT);  // within the scissor-free viewport: the arrow wins
      const Eigen::Vector3f d = f / fn;
      const float len = std::min(fn * options.force_scale_m_per_n, 0.6f);
      const Eigen::Vector3f start = tip + d * tip_radius_m_;
      const float head = std::min(0.05f, 0.4f * len);
      draw_cylinder(start, start + d * (len - head), 0.012f, colors::kForce);
      draw_cone(start + d * (len - head), start + d * len, 0.03f, colors::kForce);
    }
  }
}

void SceneRenderer::draw(const ViewerView& view, const OrbitCamera& camera,
                         const RenderOptions& options, int x, int y, int w, int h) {
  glViewport(x, y, w, h);
  glEnable(GL_SCISSOR_TEST);
  glScissor(x, y, w, h);
  glClearColor(colors::kBackground.x(), colors::kBackground.y(), colors::kBackground.z(), 1.0f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
  if (!view.have_scene()) return;
  upload_deformables(view, options);

  const float aspect = static_cast<float>(w) / static_cast<float>(std::max(h, 1));
  view_projection_ = camera.projection(aspect) * camera.view();
  const Eigen::Vector3f eye = camera.eye();
  const Eigen::Vector3f to_eye = (eye - camera.target).normalized();
  const Eigen::Vector3f left = Eigen::Vector3f::UnitZ().cross(to_eye).normalized();
  const Eigen::Vector3f light =
      (to_eye + 1.2f * Eigen::Vector3f::UnitZ() + 0.4f * left).normalized();
  light_ = light;

  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glUseProgram(lit_program_);
  glUniformMatrix4fv(u_view_projection_, 1, GL_FALSE, view_projection_.data());
  glUniform3f(u_eye_, eye.x(), eye.y(), eye.z());
  glUniform3f(u_light_dir_, light.x(), light.y(), light.z());

  // opaque floors (pushed back a little so their grid and shadows win the depth test)
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.0f, 1.0f);
  draw_planes(eye, false);
  glDisable(GL_POLYGON_OFFSET_FILL);

  draw_deformables(view, options);
  if (view.have_slave) draw_tip(view);

  // see-through walls
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glDepthMask(GL_FALSE);
  draw_planes(eye, true);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);

  draw_force(view, options);
  glDisable(GL_DEPTH_TEST);
  glBindVertexArray(0);
  glUseProgram(0);
}

void SceneRenderer::release() {
  for (GpuMesh* m : {&sphere_, &cylinder_, &cone_}) {
    if (m->vao) glDeleteVertexArrays(1, &m->vao);
    if (m->vbo) glDeleteBuffers(1, &m->vbo);
    if (m->ebo) glDeleteBuffers(1, &m->ebo);
    *m = GpuMesh{};
  }
  for (DeformableGpu& g : deformables_) {
    if (g.vao) glDeleteVertexArrays(1, &g.vao);
    for (GLuint* b : {&g.positions, &g.normals, &g.colors, &g.ebo}) {
      if (*b) glDeleteBuffers(1, b);
      *b = 0;
    }
    g.vao = 0;
  }
  for (GLuint* vao : {&plane_vao_, &line_vao_}) {
    if (*vao) glDeleteVertexArrays(1, vao);
    *vao = 0;
  }
  for (GLuint* b : {&plane_vbo_, &line_vbo_}) {
    if (*b) glDeleteBuffers(1, b);
    *b = 0;
  }
  if (lit_program_) glDeleteProgram(lit_program_);
  if (line_program_) glDeleteProgram(line_program_);
  if (flat_program_) glDeleteProgram(flat_program_);
  lit_program_ = line_program_ = flat_program_ = 0;
}

}  // namespace teleop::viewer

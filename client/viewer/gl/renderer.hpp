#pragma once
// Draws the 3-D scene with OpenGL 3.3 core: the scene's planes (a patch each, with a grid;
// walls are see-through and hidden from behind, so the camera looks into a closed box), the
// deformable meshes with per-vertex normals (optionally coloured by displacement from the first
// frame received), the robot skeleton posed from the joint positions, the tip sphere, its shadow
// on the floor and the contact force as an arrow.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "client/viewer/camera.hpp"
#include "client/viewer/gl/gl_api.hpp"
#include "client/viewer/robot_skeleton.hpp"
#include "client/viewer/scene_geometry.hpp"
#include "client/viewer/viewer_data.hpp"

namespace teleop::viewer {

struct RenderOptions {
  bool wireframe = false;  ///< deformable meshes as wireframe
  /// colour meshes by deformation: each vertex's displacement since the tip's contact began,
  /// less the body's best rigid motion (a settling, sliding or rolling body stays blue; a dent
  /// shows)
  bool displacement_colors = true;
  float displacement_scale_m = 0.003f;  ///< deformation shown fully red [m]
  float force_scale_m_per_n = 0.25f;    ///< force arrow length per newton [m/N]
  bool show_force = true;
};

/// Colours of the scene (linear RGB). Tests look for the tip colour in snapshots.
namespace colors {
inline const Eigen::Vector3f kBackground(0.15f, 0.16f, 0.19f);
inline const Eigen::Vector3f kFloor(0.62f, 0.60f, 0.56f);
inline const Eigen::Vector3f kWall(0.75f, 0.80f, 0.88f);
inline const Eigen::Vector3f kDeformable(0.30f, 0.58f, 0.92f);
inline const Eigen::Vector3f kRobot(0.55f, 0.60f, 0.68f);
inline const Eigen::Vector3f kJoint(0.36f, 0.39f, 0.45f);
inline const Eigen::Vector3f kTip(0.98f, 0.42f, 0.08f);
inline const Eigen::Vector3f kForce(1.00f, 0.86f, 0.16f);
}  // namespace colors

class SceneRenderer {
 public:
  SceneRenderer() = default;
  ~SceneRenderer() = default;  // call release() while the context is current
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;

  /// Compiles the shaders and uploads the unit primitives. False (with `error`) on failure.
  bool init(std::string& error);
  /// Rebuilds what depends on the scene description when view.scene_version changed.
  void sync_scene(const ViewerView& view);
  /// Draws into the current framebuffer's rectangle (x, y from the bottom-left, w x h pixels).
  void draw(const ViewerView& view, const OrbitCamera& camera, const RenderOptions& options, int x,
            int y, int w, int h);
  /// Uploads the meshes' newest frames (and colours); draw() does it too, but a caller that
  /// shows max_displacement_m() in the same frame calls it first.
  void upload_deformables(const ViewerView& view, const RenderOptions& options);
  /// Deletes the GL objects.
  void release();

  const RobotSkeleton& skeleton() const { return skeleton_; }
  /// Largest vertex deformation (displacement since the contact began less the body's best
  /// rigid motion) over all meshes at the last upload [m] (computed while the colours are on).
  float max_displacement_m() const { return max_displacement_m_; }

 private:
  struct GpuMesh {  // a static indexed mesh: position + normal, interleaved
    GLuint vao = 0, vbo = 0, ebo = 0;
    GLsizei count = 0;
  };
  struct DeformableGpu {
    std::int32_t object_id = -1;
    GLuint vao = 0, positions = 0, normals = 0, colors = 0, ebo = 0;
    GLsizei count = 0;
    std::uint32_t vertex_count = 0;
    std::uint64_t topology_version = 0, frame_version = 0;
    bool colored = false;
    float color_scale_m = 0.0f;
    std::vector<float> normal_scratch, color_scratch;
    std::vector<float> reference;  ///< the body before the current contact (colours)
    bool have_reference = false;
  };
  struct Line {
    Eigen::Vector3f a, b;
    Eigen::Vector4f color;
  };

  GpuMesh upload(const PrimitiveMesh& mesh);
  void draw_primitive(const GpuMesh& mesh, const Eigen::Matrix4f& model,
                      const Eigen::Vector3f& color, float alpha = 1.0f);
  void draw_sphere(const Eigen::Vector3f& centre, float radius, const Eigen::Vector3f& color,
                   float alpha = 1.0f);
  void draw_cylinder(const Eigen::Vector3f& a, const Eigen::Vector3f& b, float radius,
                     const Eigen::Vector3f& color);
  void draw_cone(const Eigen::Vector3f& base, const Eigen::Vector3f& apex, float radius,
                 const Eigen::Vector3f& color);
  void draw_lines(const std::vector<Line>& lines);
  void draw_planes(const Eigen::Vector3f& eye, bool walls);
  void draw_robot(const ViewerView& view, const Eigen::Vector3f& tip);
  void draw_deformables(const ViewerView& view, const RenderOptions& options);
  void draw_tip(const ViewerView& view);
  void draw_force(const ViewerView& view, const RenderOptions& options);
  void upload_planes(const std::vector<float>& vertices);
  void set_topology(DeformableGpu& g, const MeshSlot& m);

  GLuint lit_program_ = 0, line_program_ = 0, flat_program_ = 0;
  // lit program uniforms
  GLint u_model_ = -1, u_normal_matrix_ = -1, u_view_projection_ = -1, u_color_ = -1,
        u_vertex_color_ = -1, u_eye_ = -1, u_light_dir_ = -1;
  GLint u_line_view_projection_ = -1;
  GLint u_flat_view_projection_ = -1, u_flat_color_ = -1;

  GpuMesh sphere_, cylinder_, cone_;
  GLuint plane_vao_ = 0, plane_vbo_ = 0;
  GLuint line_vao_ = 0, line_vbo_ = 0;
  std::size_t line_capacity_ = 0;  // vertices
  std::vector<float> line_scratch_;

  std::uint64_t scene_version_ = 0;
  std::vector<PlanePatch> patches_;
  std::vector<GLint> patch_first_;
  std::vector<GLsizei> patch_count_;
  std::vector<Line> grid_lines_;  // all planes, with their plane index in patch_of_line_
  std::vector<std::size_t> patch_of_line_;
  std::vector<Line> frame_lines_;       // rebuilt every frame (capacity kept)
  std::vector<std::int32_t> mesh_ids_;  // deformable objects of the current scene
  float floor_z_ = 0.0f;
  bool have_floor_ = false;
  float tip_radius_m_ = 0.05f;
  float max_displacement_m_ = 0.0f;
  RobotSkeleton skeleton_;
  std::array<Eigen::Isometry3d, kMaxSkeletonJoints + 1> frames_{};
  std::array<DeformableGpu, kMaxMeshes> deformables_{};
  Eigen::Matrix4f view_projection_ = Eigen::Matrix4f::Identity();
  Eigen::Vector3f light_ = Eigen::Vector3f::UnitZ();  ///< towards the key light, this frame
};

}  // namespace teleop::viewer

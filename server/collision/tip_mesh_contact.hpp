#pragma once
// Contact between the slave's spherical tip and one deformable closed triangle mesh (the
// paper's "Interaction between virtual objects").
//
// Detection: an AabbTree over the mesh, refitted every step (rebuilt when degraded).
// Onset is continuous along the tip centre's path within the step: conservative advancement
// with the exact point-mesh distance finds the first instant the tip sphere touches the
// surface (so no speed tunnels through), with the paper's segment-triangle test, eq. (8),
// as a backstop, and for a closed mesh a pseudo-normal inside test catches a tip that is
// already inside.
//
// Response (god-object / surface proxy): the surface point where the tip entered is kept as
// a material point of the mesh (triangle + barycentric weights), so it moves with the
// deforming surface. The proxy centre is that anchor plus r along the surface normal; the
// penetration is x = r - (c - anchor).n and the normal force F = k x (+ a damping term that
// is ramped in with x so the force is continuous at onset). Tangentially the anchor sticks
// (static Coulomb friction) until the tangential force exceeds mu_s * F_n, then slides
// along the surface keeping |F_t| = mu_k * F_n ("tip slippery").
//
// Area contact: a tip much larger than the triangles presses many nodes at once. Every
// surface node inside the tip sphere (on the body side of its centre) is pushed radially out
// of it by a penalty k_node (r - |x_i - c|), the tip taking the sum; a conservative, smooth
// law that stays stable with an explicit body. The proxy spring acts alone while the node
// response is below a quarter of it (a coarse mesh between nodes, a thin sheet, the centre
// through the surface), the node penalty alone once it is 1.75 times the proxy's, and in
// between a smooth blend of the two, forces and reactions alike, scaled so that the normal
// force is the larger of the two responses (as a hard switch between them gave): the switch
// made the surface spring back as the first nodes entered the tip, and the force on a tip
// loading the sphere at 1 cm/s dropped by 0.24 N in one step. Friction always acts through the
// proxy.
//
// The anchor is the surface point (anchor triangle + barycentric weights), so it moves with
// the deforming surface. The proxy's reaction is spread over a patch of nodes with weights
// w_i (sum 1): a blend of the anchor's barycentric weights and a smooth kernel over the
// anchor triangle's one-ring, so the node forces sum to exactly minus the tip force
// (momentum is conserved). Spreading the load over the patch rather than three vertices
// keeps an explicit deformable step stable with a stiff contact (the effective mass is the
// patch's) and avoids a crease under a point load; with patch_blend = 0 the weights are the
// barycentric ones (the paper's three-vertex push, exactly energy-consistent).
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "common/sim/events.hpp"
#include "server/collision/aabb_tree.hpp"
#include "server/collision/surface_topology.hpp"

namespace teleop::sim::collision {

/// Contact law parameters (from the scene).
struct TipContactParams {
  double stiffness_n_per_m = 300.0;  ///< k of F = k x for the proxy spring [N/m]
  double damping_ns_per_m = 1.0;     ///< normal contact damping b [N s/m]; >= k dt / 2
                                     ///< keeps the sampled contact passive
  double damping_ramp_m = 2.0e-4;    ///< damping grows linearly to b over this depth [m]
  double friction_static = 0.0;      ///< Coulomb static coefficient mu_s [-]
  double friction_kinetic = 0.0;     ///< Coulomb kinetic coefficient mu_k <= mu_s [-]
  double max_force_n = 0.0;          ///< saturation of |F| [N]; 0 = none
  /// Radius of the node patch that shares the reaction [m] (weights fall off smoothly with
  /// distance from the anchor, over the anchor triangle and its one-ring). About the tip
  /// radius: a narrower patch than the tip digs a crease the proxy then wanders in.
  double patch_radius_m = 0.06;
  /// Share of the reaction spread over the patch, the rest going to the anchor triangle's
  /// corners with barycentric weights [0..1]; 0 is the paper's three-vertex push.
  double patch_blend = 0.8;
  /// Penalty stiffness of each surface node inside the tip sphere [N/m]; 0 = the paper's
  /// single-point proxy only. Keep k_node dt^2 / m_node well below 1 for an explicit body.
  double node_stiffness_n_per_m = 200.0;
  /// Damping of each node penalty (compression only, ramped in) [N s/m]; >= k_node dt / 2.
  double node_damping_ns_per_m = 0.2;
  /// Node area the two values above are for [m^2]: node i's penalty is scaled by
  /// A_i / this (A_i its area at rest, set_node_areas), so the penalty is a pressure per depth
  /// and the force on the tip does not grow as the mesh is refined. The default is the mean
  /// node area of the paper's level-4 sphere (radius 0.25 m). 0: the same penalty on every
  /// node whatever its area.
  double node_reference_area_m2 = 3.06e-4;
};

/// Outcome of one contact update.
struct TipContactResult {
  bool in_contact = false;  ///< the tip presses on the mesh after this step
  bool began = false;       ///< contact started in this step
  bool ended = false;       ///< contact ended in this step
  bool inside = false;      ///< onset came from the inside test (tip found inside the mesh)
  bool sliding = false;     ///< the proxy slid (kinetic friction) in this step
  bool fault = false;       ///< non-finite input or output: contact dropped, force zero
  Eigen::Vector3d force_on_tip_n = Eigen::Vector3d::Zero();   ///< force on the tip [N]
  Eigen::Vector3d contact_point_m = Eigen::Vector3d::Zero();  ///< anchor on the surface [m]
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();           ///< unit outward normal
  Eigen::Vector3d entry_point_m = Eigen::Vector3d::Zero();    ///< where contact began [m]
  double penetration_m = 0.0;                                 ///< x = r - (c - anchor).n [m]
  double normal_force_n = 0.0;                                ///< F_n [N]
  double tangential_force_n = 0.0;                            ///< |F_t| [N]
  int triangle = -1;                                          ///< anchor triangle
  int ccd_iterations = 0;         ///< conservative-advancement iterations used
  int node_contacts = 0;          ///< nodes carrying node-penalty forces (0: proxy spring acts)
  double max_node_depth_m = 0.0;  ///< deepest node inside the tip sphere [m]
};

/// Tip-mesh contact of one deformable object. Not thread-safe; one per object.
class TipMeshContact {
 public:
  explicit TipMeshContact(TipContactParams params = {}, AabbTree::Options tree_options = {});

  /// Sizes everything for the mesh (x: 3 x N positions [m], tris: 3 x T, CCW from outside),
  /// builds the tree and forgets any contact. Allocates.
  void reset(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xi& tris);

  /// One step: refits the tree to x, detects contact along tip_prev_m -> tip_now_m (centre of
  /// the tip sphere of radius tip_radius_m), computes the force on the tip and adds the
  /// reaction to node_forces_n (3 x N, +=). tip_velocity_mps feeds the contact damping,
  /// dt_s (> 0) the surface velocity estimate. Allocates nothing.
  TipContactResult update(const Eigen::Matrix3Xd& x, const Eigen::Vector3d& tip_prev_m,
                          const Eigen::Vector3d& tip_now_m, double tip_radius_m,
                          const Eigen::Vector3d& tip_velocity_mps, double dt_s,
                          Eigen::Matrix3Xd& node_forces_n);

  /// As above, with the nodes' velocities v (3 x N [m/s]) for the contact damping: the
  /// anchor's velocity is then sum_i w_i v_i instead of a backward difference, which has no
  /// lag. With it, damping b >= k dt / 2 makes the sampled contact passive for the body
  /// (Colgate & Schenkel 1997). Pass nullptr to fall back to the difference.
  TipContactResult update(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd* v,
                          const Eigen::Vector3d& tip_prev_m, const Eigen::Vector3d& tip_now_m,
                          double tip_radius_m, const Eigen::Vector3d& tip_velocity_mps, double dt_s,
                          Eigen::Matrix3Xd& node_forces_n);

  /// The nodes' areas at rest [m^2] (size: the mesh's nodes), for node_reference_area_m2;
  /// kept across reset(). Allocates.
  void set_node_areas(const Eigen::VectorXd& area_m2);

  /// Forgets the current contact (the next update detects afresh).
  void release() { in_contact_ = false; }

  /// True when p is inside the closed mesh at positions x (tree must be refitted to x).
  /// Always false for an open mesh.
  bool inside(const Eigen::Vector3d& p, const Eigen::Matrix3Xd& x) const;

  /// Signed distance of p from the surface [m] (negative inside; unsigned for open meshes).
  double signed_distance(const Eigen::Vector3d& p, const Eigen::Matrix3Xd& x) const;

  void set_params(const TipContactParams& p) { params_ = p; }
  const TipContactParams& params() const { return params_; }
  const AabbTree& tree() const { return tree_; }
  /// Reads the tree and the scratch an update uses into the caches; changes nothing.
  std::uint64_t touch() const;
  AabbTree& tree() { return tree_; }
  const SurfaceTopology& topology() const { return topo_; }
  bool in_contact() const { return in_contact_; }
  /// Faults (non-finite data) seen since reset().
  std::uint64_t fault_count() const { return faults_; }

  /// Conservative-advancement iteration cap before the eq. (8) backstop.
  static constexpr int kMaxCcdIterations = 48;
  /// Most nodes in a reaction patch.
  static constexpr int kMaxPatch = 48;
  /// Nodes sharing the current reaction (valid while in_contact()).
  int patch_size() const { return patch_size_; }

 private:
  Eigen::Vector3d anchor_position(const Eigen::Matrix3Xd& x) const;
  bool detect(const Eigen::Matrix3Xd& x, const Eigen::Vector3d& c0, const Eigen::Vector3d& c1,
              double r, TipContactResult& res);
  void set_anchor(const Eigen::Matrix3Xd& x, int tri, const Eigen::Vector3d& bary);

  /// The proxy contact of one update: anchor, normal, tip offset, penetration, forces.
  struct Proxy;
  /// Velocity of the anchor: the patch nodes' velocities `v` with the anchor's weights [m/s].
  Eigen::Vector3d patch_velocity(const Eigen::Matrix3Xd& v) const;
  /// Keeps the contact while the tip is still below the anchor's surface, else looks for a new
  /// one; false (res.ended set) when there is none. anchor_vel: the anchor's velocity [m/s].
  bool keep_or_find_contact(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd* v,
                            const Eigen::Vector3d& tip_prev_m, const Eigen::Vector3d& tip_now_m,
                            double r, double dt_s, bool was_in_contact, TipContactResult& res,
                            Eigen::Vector3d& anchor_vel);
  /// Proxy normal force [N] at penetration pen_m [m] and penetration rate pen_rate [m/s].
  double normal_force(double pen_m, double pen_rate) const;
  /// Node penalty: nodes inside the tip sphere (centre c, radius r) on the body side of normal
  /// n into node_list_ / node_force_; returns their total force on the tip [N].
  Eigen::Vector3d node_penalty(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd* v,
                               const Eigen::Vector3d& c, double r, const Eigen::Vector3d& n,
                               double pen, const Eigen::Vector3d& tip_velocity_mps,
                               double& max_node_depth);
  /// Kinetic friction: slides the proxy along the surface until |F_t| = mu_k F_n; false when the
  /// tip has left the surface on the way.
  bool slide_proxy(const Eigen::Matrix3Xd& x, const Eigen::Vector3d& c, double r, double pen_rate,
                   double fn_nodes, double mu_k, Proxy& pr);
  /// Applies the reaction of force f on the tip to the nodes (node penalty forces scaled by
  /// `node_scale`, the proxy's share f_patch to the patch nodes).
  void apply_reaction(const Eigen::Vector3d& f_patch, double node_scale,
                      Eigen::Matrix3Xd& node_forces_n) const;
  /// The in-contact fields of res for force f [N] on the tip at proxy pr.
  void set_contact_result(const Eigen::Vector3d& f, const Proxy& pr, TipContactResult& res) const;
  /// Non-finite data: the contact dropped, a fault counted; the result says so (no force).
  TipContactResult drop_on_fault(bool was_in_contact);
  /// The tangential (friction) force on the tip into ft: the proxy spring's while it sticks
  /// (|F_t| <= mu_s F_n), else kinetic friction (res.sliding, the proxy slid); false when the tip
  /// left the surface while sliding.
  bool friction_force(const Eigen::Matrix3Xd& x, const Eigen::Vector3d& c, double r,
                      double pen_rate, double fn_nodes, Proxy& pr, Eigen::Vector3d& ft,
                      TipContactResult& res);
  /// The node penalty's share a of the response and the scale s (with nodes in contact): a is a
  /// smoothstep of fn_nodes / fn_proxy over [0.25, 1.75]; s keeps the normal force the larger of
  /// the two.
  static void blend_weights(double fn_nodes, double fn_proxy, double& a, double& s);

  TipContactParams params_;
  AabbTree tree_;
  SurfaceTopology topo_;
  bool in_contact_ = false;
  int tri_ = -1;
  Eigen::Vector3d bary_ = Eigen::Vector3d::Zero();
  std::vector<int> hit_tris_;         ///< scratch: triangles near the tip
  std::vector<std::uint32_t> stamp_;  ///< scratch: node visited marks
  std::uint32_t stamp_counter_ = 0;
  Eigen::VectorXd node_area_m2_;  ///< nodes' rest areas (empty: every node the reference)
  std::vector<int> node_list_;    ///< scratch: nodes inside the tip sphere
  Eigen::Matrix3Xd node_force_;   ///< scratch: their penalty forces [N]
  int node_contacts_ = 0;
  int patch_size_ = 0;
  std::array<int, kMaxPatch> patch_node_{};
  std::array<double, kMaxPatch> patch_w_{};
  Eigen::Vector3d anchor_prev_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d entry_point_m_ = Eigen::Vector3d::Zero();
  double side_ = 1.0;  ///< +1: outward normal is free space (always, for a closed mesh)
  bool anchor_velocity_valid_ = false;
  std::uint64_t faults_ = 0;
};

/// Pushes kContactBegin / kContactEnd (value: normal force [N] / 0) and, for a fault, a
/// kFault warning for `object_id` onto `events`. Allocates nothing.
void push_contact_events(const TipContactResult& result, int object_id, double sim_time_s,
                         EventQueue& events);

}  // namespace teleop::sim::collision

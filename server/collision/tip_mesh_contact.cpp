#include "server/collision/tip_mesh_contact.hpp"

#include "common/util/prewarm.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace teleop::sim::collision {

// The parts of update() below are always inlined into it: one function for the compiler, as
// before the split (the tip contact runs every physics step).
#if defined(__GNUC__)
#define TELEOP_TIP_INLINE inline __attribute__((always_inline))
#else
#define TELEOP_TIP_INLINE inline
#endif

TipMeshContact::TipMeshContact(TipContactParams params, AabbTree::Options tree_options)
    : params_(params), tree_(tree_options) {}

void TipMeshContact::reset(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xi& tris) {
  topo_.build(tris, static_cast<int>(x.cols()));
  tree_.build(x, tris);
  in_contact_ = false;
  tri_ = -1;
  faults_ = 0;
  const auto nv = static_cast<std::size_t>(x.cols());
  hit_tris_.clear();
  hit_tris_.reserve(static_cast<std::size_t>(tris.cols()));
  stamp_.assign(nv, 0u);
  stamp_counter_ = 0;
  node_list_.assign(nv, -1);
  node_force_.setZero(3, static_cast<Eigen::Index>(nv));
  node_contacts_ = 0;
}

void TipMeshContact::set_node_areas(const Eigen::VectorXd& area_m2) { node_area_m2_ = area_m2; }

Eigen::Vector3d TipMeshContact::anchor_position(const Eigen::Matrix3Xd& x) const {
  // the exact surface point: barycentric on the anchor triangle
  const Eigen::Matrix3Xi& t = topo_.triangles();
  return bary_[0] * x.col(t(0, tri_)) + bary_[1] * x.col(t(1, tri_)) + bary_[2] * x.col(t(2, tri_));
}

void TipMeshContact::set_anchor(const Eigen::Matrix3Xd& x, int tri, const Eigen::Vector3d& bary) {
  tri_ = tri;
  bary_ = bary;
  const Eigen::Matrix3Xi& tris = topo_.triangles();
  const Eigen::Vector3d s =
      bary[0] * x.col(tris(0, tri)) + bary[1] * x.col(tris(1, tri)) + bary[2] * x.col(tris(2, tri));
  // the patch: the anchor triangle's corners first, then their one-ring
  patch_size_ = 0;
  auto add = [&](int v) {
    for (int i = 0; i < patch_size_; ++i) {
      if (patch_node_[static_cast<std::size_t>(i)] == v) return;
    }
    if (patch_size_ < kMaxPatch) {
      patch_node_[static_cast<std::size_t>(patch_size_)] = v;
      patch_w_[static_cast<std::size_t>(patch_size_)] = 0.0;
      ++patch_size_;
    }
  };
  for (int k = 0; k < 3; ++k) add(tris(k, tri));
  const double blend = std::clamp(params_.patch_blend, 0.0, 1.0);
  const double rho = params_.patch_radius_m;
  if (blend > 0.0 && rho > 0.0) {
    for (int k = 0; k < 3; ++k) {
      const int v = tris(k, tri);
      for (int j = 0; j < topo_.vertex_triangle_count(v); ++j) {
        const int t = topo_.vertex_triangle(v, j);
        for (int m = 0; m < 3; ++m) add(tris(m, t));
      }
    }
  }
  // kernel weights (1 - q^2)^2, q = distance / rho, normalised
  double ksum = 0.0;
  if (blend > 0.0 && rho > 0.0) {
    for (int i = 0; i < patch_size_; ++i) {
      const double q2 =
          (x.col(patch_node_[static_cast<std::size_t>(i)]) - s).squaredNorm() / (rho * rho);
      const double w = q2 < 1.0 ? (1.0 - q2) * (1.0 - q2) : 0.0;
      patch_w_[static_cast<std::size_t>(i)] = w;
      ksum += w;
    }
  }
  const double kb = ksum > 0.0 ? blend / ksum : 0.0;
  const double bb = ksum > 0.0 ? 1.0 - blend : 1.0;
  for (int i = 0; i < patch_size_; ++i) patch_w_[static_cast<std::size_t>(i)] *= kb;
  for (int k = 0; k < 3; ++k) patch_w_[static_cast<std::size_t>(k)] += bb * bary[k];
}

bool TipMeshContact::inside(const Eigen::Vector3d& p, const Eigen::Matrix3Xd& x) const {
  if (!topo_.closed()) return false;
  MeshClosest mc;
  if (!tree_.closest_point(p, x, std::numeric_limits<double>::infinity(), mc)) return false;
  const Eigen::Vector3d pn = topo_.pseudo_normal(x, mc.triangle, mc.feature);
  return (p - mc.point).dot(pn) < 0.0;
}

double TipMeshContact::signed_distance(const Eigen::Vector3d& p, const Eigen::Matrix3Xd& x) const {
  MeshClosest mc;
  if (!tree_.closest_point(p, x, std::numeric_limits<double>::infinity(), mc)) {
    return std::numeric_limits<double>::infinity();
  }
  if (!topo_.closed()) return mc.distance_m;
  const Eigen::Vector3d pn = topo_.pseudo_normal(x, mc.triangle, mc.feature);
  return (p - mc.point).dot(pn) < 0.0 ? -mc.distance_m : mc.distance_m;
}

bool TipMeshContact::detect(const Eigen::Matrix3Xd& x, const Eigen::Vector3d& c0,
                            const Eigen::Vector3d& c1, double r, TipContactResult& res) {
  const double inf = std::numeric_limits<double>::infinity();
  // broad phase: the swept tip must reach the mesh's box
  const Aabb root = tree_.root_box();
  if (!segment_intersects_aabb(c0, c1, root.lo, root.hi, r)) return false;

  const Eigen::Vector3d seg = c1 - c0;
  const double len = seg.norm();
  const double tol = 1e-9 + 1e-7 * r;
  MeshClosest mc;
  bool hit = false;
  Eigen::Vector3d touch_centre = c1;
  // conservative advancement: the distance to the mesh is 1-Lipschitz along the path, so
  // advancing by (distance - r) can never step over the first touch
  double t = 0.0;
  bool concluded = false;
  for (int it = 0; it < kMaxCcdIterations; ++it) {
    ++res.ccd_iterations;
    const Eigen::Vector3d p = c0 + t * seg;
    if (!tree_.closest_point(p, x, inf, mc)) return false;
    const double gap = mc.distance_m - r;
    if (gap <= tol) {
      hit = true;
      touch_centre = p;
      concluded = true;
      break;
    }
    if (len <= 0.0) {
      concluded = true;
      break;
    }
    t += gap / len;
    if (t > 1.0) {
      concluded = true;
      break;
    }
  }
  if (!concluded) {
    // grazing path: fall back to the paper's eq. (8) on the centre path, then the end point
    MeshSegmentHit sh;
    if (tree_.first_segment_hit(c0, c1, x, sh)) {
      hit = true;
      mc.triangle = sh.triangle;
      mc.bary = Eigen::Vector3d(1.0 - sh.u - sh.v, sh.u, sh.v);
      mc.point = sh.point;
      touch_centre = sh.point;
    } else if (tree_.closest_point(c1, x, r, mc)) {
      hit = true;
      touch_centre = c1;
    }
  }
  if (hit) {
    set_anchor(x, mc.triangle, mc.bary);
    if (topo_.closed()) {
      side_ = 1.0;
    } else {
      const Eigen::Vector3d n = topo_.smooth_normal(x, tri_, bary_);
      side_ = (touch_centre - mc.point).dot(n) >= 0.0 ? 1.0 : -1.0;
    }
    return true;
  }
  // a closed mesh has an inside: a tip found there is in contact with its nearest surface
  if (topo_.closed() && tree_.closest_point(c1, x, inf, mc)) {
    const Eigen::Vector3d pn = topo_.pseudo_normal(x, mc.triangle, mc.feature);
    if ((c1 - mc.point).dot(pn) < 0.0) {
      set_anchor(x, mc.triangle, mc.bary);
      side_ = 1.0;
      res.inside = true;
      return true;
    }
  }
  return false;
}

TipContactResult TipMeshContact::update(const Eigen::Matrix3Xd& x,
                                        const Eigen::Vector3d& tip_prev_m,
                                        const Eigen::Vector3d& tip_now_m, double tip_radius_m,
                                        const Eigen::Vector3d& tip_velocity_mps, double dt_s,
                                        Eigen::Matrix3Xd& node_forces_n) {
  return update(x, nullptr, tip_prev_m, tip_now_m, tip_radius_m, tip_velocity_mps, dt_s,
                node_forces_n);
}

struct TipMeshContact::Proxy {
  Eigen::Vector3d a;       ///< anchor [m]
  Eigen::Vector3d n;       ///< surface normal at the anchor, towards the free side
  Eigen::Vector3d d;       ///< tip centre - anchor [m]
  double pen = 0.0;        ///< penetration r - d.n [m]
  double fn = 0.0;         ///< proxy normal force [N]
  double fn_eff = 0.0;     ///< max(proxy, node penalty) normal force [N]
  Eigen::Vector3d dt_vec;  ///< tangential part of d [m]
};

TELEOP_TIP_INLINE Eigen::Vector3d TipMeshContact::patch_velocity(const Eigen::Matrix3Xd& v) const {
  Eigen::Vector3d av = Eigen::Vector3d::Zero();
  for (int i = 0; i < patch_size_; ++i) {
    av += patch_w_[static_cast<std::size_t>(i)] * v.col(patch_node_[static_cast<std::size_t>(i)]);
  }
  return av;
}

TELEOP_TIP_INLINE bool TipMeshContact::keep_or_find_contact(
    const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd* v, const Eigen::Vector3d& tip_prev_m,
    const Eigen::Vector3d& tip_now_m, double r, double dt_s, bool was_in_contact,
    TipContactResult& res, Eigen::Vector3d& anchor_vel) {
  const Eigen::Vector3d& c = tip_now_m;
  if (in_contact_) {
    const Eigen::Vector3d a = anchor_position(x);
    if (v != nullptr) {
      anchor_vel = patch_velocity(*v);
    } else if (anchor_velocity_valid_) {
      anchor_vel = (a - anchor_prev_m_) / dt_s;
    }
    const Eigen::Vector3d n = side_ * topo_.smooth_normal(x, tri_, bary_);
    if (r - (c - a).dot(n) <= 0.0) in_contact_ = false;  // the tip has left the surface
  }
  if (!in_contact_) {
    if (!detect(x, tip_prev_m, tip_now_m, r, res)) {
      res.ended = was_in_contact;
      return false;
    }
    in_contact_ = true;
    anchor_velocity_valid_ = false;
    anchor_vel = v != nullptr ? patch_velocity(*v) : Eigen::Vector3d::Zero();
    entry_point_m_ = anchor_position(x);
    res.began = !was_in_contact;
  }
  return true;
}

TELEOP_TIP_INLINE double TipMeshContact::normal_force(double pen_m, double pen_rate) const {
  const double ramp =
      params_.damping_ramp_m > 0.0 ? std::min(1.0, pen_m / params_.damping_ramp_m) : 1.0;
  return std::max(0.0,
                  params_.stiffness_n_per_m * pen_m + params_.damping_ns_per_m * ramp * pen_rate);
}

// Surface nodes inside the tip sphere, on the body side of its centre, are pushed radially out
// of it (area contact of a large tip on a fine mesh). Only while the centre is outside the
// surface (pen < r).
TELEOP_TIP_INLINE Eigen::Vector3d TipMeshContact::node_penalty(
    const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd* v, const Eigen::Vector3d& c, double r,
    const Eigen::Vector3d& n, double pen, const Eigen::Vector3d& tip_velocity_mps,
    double& max_node_depth) {
  Eigen::Vector3d f_nodes_tip = Eigen::Vector3d::Zero();
  node_contacts_ = 0;
  max_node_depth = 0.0;
  if (!(params_.node_stiffness_n_per_m > 0.0 && pen < r)) return f_nodes_tip;
  tree_.query_sphere(c, r, x, hit_tris_);
  if (++stamp_counter_ == 0) {
    std::fill(stamp_.begin(), stamp_.end(), 0u);
    stamp_counter_ = 1;
  }
  const Eigen::Matrix3Xi& tris = topo_.triangles();
  for (const int t : hit_tris_) {
    for (int kk = 0; kk < 3; ++kk) {
      const int vi = tris(kk, t);
      if (stamp_[static_cast<std::size_t>(vi)] == stamp_counter_) continue;
      stamp_[static_cast<std::size_t>(vi)] = stamp_counter_;
      const Eigen::Vector3d dv = x.col(vi) - c;
      const double dist = dv.norm();
      if (dist >= r || dist < 1e-12) continue;
      const Eigen::Vector3d u = dv / dist;
      if (u.dot(n) >= 0.0) continue;  // not between the tip centre and the body
      const double depth = r - dist;
      double rate = 0.0;  // compression rate
      if (v != nullptr) rate = -(v->col(vi) - tip_velocity_mps).dot(u);
      const double ramp =
          params_.damping_ramp_m > 0.0 ? std::min(1.0, depth / params_.damping_ramp_m) : 1.0;
      // a pressure per depth: the node's share of the surface over the reference area
      const double w = params_.node_reference_area_m2 > 0.0 && vi < node_area_m2_.size()
                           ? node_area_m2_(vi) / params_.node_reference_area_m2
                           : 1.0;
      const double mag = std::max(0.0, w * (params_.node_stiffness_n_per_m * depth +
                                            params_.node_damping_ns_per_m * ramp * rate));
      if (node_contacts_ < static_cast<int>(node_list_.size())) {
        node_list_[static_cast<std::size_t>(node_contacts_)] = vi;
        node_force_.col(node_contacts_) = mag * u;
        ++node_contacts_;
        f_nodes_tip -= mag * u;
        max_node_depth = std::max(max_node_depth, depth);
      }
    }
  }
  return f_nodes_tip;
}

TELEOP_TIP_INLINE bool TipMeshContact::slide_proxy(const Eigen::Matrix3Xd& x,
                                                   const Eigen::Vector3d& c, double r,
                                                   double pen_rate, double fn_nodes, double mu_k,
                                                   Proxy& pr) {
  const double k = params_.stiffness_n_per_m;
  for (int it = 0; it < 3; ++it) {
    const double len = pr.dt_vec.norm();
    const double keep = k > 0.0 ? mu_k * pr.fn_eff / k : 0.0;
    if (len <= keep + 1e-7) break;
    const Eigen::Vector3d target = pr.a + pr.dt_vec * (1.0 - keep / len);
    MeshClosest mc;
    if (!tree_.closest_point(target, x, std::numeric_limits<double>::infinity(), mc)) break;
    set_anchor(x, mc.triangle, mc.bary);
    pr.a = anchor_position(x);
    pr.n = side_ * topo_.smooth_normal(x, tri_, bary_);
    pr.d = c - pr.a;
    pr.pen = r - pr.d.dot(pr.n);
    if (pr.pen <= 0.0 && node_contacts_ == 0) break;
    pr.fn = pr.pen > 0.0 ? normal_force(pr.pen, pen_rate) : 0.0;
    pr.fn_eff = std::max(pr.fn, fn_nodes);
    pr.dt_vec = pr.d - pr.d.dot(pr.n) * pr.n;
    if ((pr.a - target).norm() < 1e-9) break;
  }
  return !(pr.pen <= 0.0 && node_contacts_ == 0);
}

// Equal and opposite: node penalty forces to their nodes, the proxy's share to the patch nodes
// with the anchor's weights; the node forces sum to exactly -f.
TELEOP_TIP_INLINE void TipMeshContact::apply_reaction(const Eigen::Vector3d& f_patch,
                                                      double node_scale,
                                                      Eigen::Matrix3Xd& node_forces_n) const {
  for (int i = 0; i < patch_size_; ++i) {
    node_forces_n.col(patch_node_[static_cast<std::size_t>(i)]) -=
        patch_w_[static_cast<std::size_t>(i)] * f_patch;
  }
  if (node_scale > 0.0) {
    for (int i = 0; i < node_contacts_; ++i) {
      node_forces_n.col(node_list_[static_cast<std::size_t>(i)]) += node_scale * node_force_.col(i);
    }
  }
}

TELEOP_TIP_INLINE void TipMeshContact::set_contact_result(const Eigen::Vector3d& f, const Proxy& pr,
                                                          TipContactResult& res) const {
  res.in_contact = true;
  res.force_on_tip_n = f;
  res.contact_point_m = pr.a;
  res.normal = pr.n;
  res.entry_point_m = entry_point_m_;
  res.penetration_m = pr.pen;
  res.normal_force_n = f.dot(pr.n);
  res.tangential_force_n = (f - f.dot(pr.n) * pr.n).norm();
  res.triangle = tri_;
}

TELEOP_TIP_INLINE TipContactResult TipMeshContact::drop_on_fault(bool was_in_contact) {
  in_contact_ = false;
  ++faults_;
  TipContactResult res;
  res.fault = true;
  res.ended = was_in_contact;
  return res;
}

TELEOP_TIP_INLINE bool TipMeshContact::friction_force(const Eigen::Matrix3Xd& x,
                                                      const Eigen::Vector3d& c, double r,
                                                      double pen_rate, double fn_nodes, Proxy& pr,
                                                      Eigen::Vector3d& ft, TipContactResult& res) {
  const double k = params_.stiffness_n_per_m;
  pr.dt_vec = pr.d - pr.d.dot(pr.n) * pr.n;
  ft = -k * pr.dt_vec;
  const double mu_s = std::max(0.0, params_.friction_static);
  const double mu_k = std::clamp(params_.friction_kinetic, 0.0, mu_s);
  if (ft.norm() > mu_s * pr.fn_eff) {
    // kinetic friction: the proxy slides along the surface until |F_t| = mu_k F_n
    res.sliding = true;
    if (!slide_proxy(x, c, r, pen_rate, fn_nodes, mu_k, pr)) return false;
    ft = -k * pr.dt_vec;
    const double ftn = ft.norm();
    if (ftn > mu_k * pr.fn_eff && ftn > 0.0) ft *= mu_k * pr.fn_eff / ftn;
  }
  return true;
}

TELEOP_TIP_INLINE void TipMeshContact::blend_weights(double fn_nodes, double fn_proxy, double& a,
                                                     double& s) {
  const double ratio = fn_proxy > 1e-12 ? fn_nodes / fn_proxy : 2.0;
  const double u = std::clamp((ratio - 0.25) / 1.5, 0.0, 1.0);
  a = u * u * (3.0 - 2.0 * u);
  const double blended_n = a * fn_nodes + (1.0 - a) * fn_proxy;
  if (blended_n > 1e-12) s = std::max(fn_nodes, fn_proxy) / blended_n;
}

TipContactResult TipMeshContact::update(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd* v,
                                        const Eigen::Vector3d& tip_prev_m,
                                        const Eigen::Vector3d& tip_now_m, double tip_radius_m,
                                        const Eigen::Vector3d& tip_velocity_mps, double dt_s,
                                        Eigen::Matrix3Xd& node_forces_n) {
  TipContactResult res;
  const bool was_in_contact = in_contact_;
  // faults: non-finite input drops the contact and gives no force
  if (!tip_prev_m.allFinite() || !tip_now_m.allFinite() || !tip_velocity_mps.allFinite() ||
      !(tip_radius_m >= 0.0) || !(dt_s > 0.0) || !x.allFinite() ||
      x.cols() != topo_.vertex_count()) {
    return drop_on_fault(was_in_contact);
  }
  tree_.rebuild_if_degraded(x);

  const double r = tip_radius_m;
  const Eigen::Vector3d& c = tip_now_m;
  Eigen::Vector3d anchor_vel = Eigen::Vector3d::Zero();
  if (v != nullptr && v->cols() != x.cols()) v = nullptr;
  if (!keep_or_find_contact(x, v, tip_prev_m, tip_now_m, r, dt_s, was_in_contact, res,
                            anchor_vel)) {
    return res;
  }

  // contact law on the current anchor
  Proxy pr;
  pr.a = anchor_position(x);
  pr.n = side_ * topo_.smooth_normal(x, tri_, bary_);
  pr.d = c - pr.a;
  pr.pen = r - pr.d.dot(pr.n);
  const double pen_rate = -(tip_velocity_mps - anchor_vel).dot(pr.n);
  pr.fn = pr.pen > 0.0 ? normal_force(pr.pen, pen_rate) : 0.0;

  // node penalty (area contact of a large tip on a fine mesh)
  double max_node_depth = 0.0;
  const Eigen::Vector3d f_nodes_tip =
      node_penalty(x, v, c, r, pr.n, pr.pen, tip_velocity_mps, max_node_depth);
  if (pr.pen <= 0.0 && node_contacts_ == 0) {
    // touched during the step but already clear of the surface at its end
    in_contact_ = false;
    res.began = false;
    res.ended = was_in_contact;
    return res;
  }
  const double fn_nodes = f_nodes_tip.dot(pr.n);
  pr.fn_eff = std::max(pr.fn, fn_nodes);

  Eigen::Vector3d ft;
  if (!friction_force(x, c, r, pen_rate, fn_nodes, pr, ft, res)) {
    in_contact_ = false;
    res.ended = was_in_contact;
    res.began = false;
    return res;
  }

  // the node penalty (area contact) takes over from the proxy spring (a face touched between
  // nodes, a thin sheet, a tip through the surface) smoothly: share a of the node response,
  // 1 - a of the proxy's, a = smoothstep of their ratio over [0.25, 1.75], both scaled by s so
  // that the normal force is still the larger of the two (file comment)
  double a = 0.0, s = 1.0;
  if (node_contacts_ > 0) blend_weights(fn_nodes, pr.fn, a, s);
  const bool use_nodes = a > 0.0;
  Eigen::Vector3d f = s * (a * f_nodes_tip + (1.0 - a) * pr.fn * pr.n) + ft;
  double scale = 1.0;
  if (params_.max_force_n > 0.0) {
    const double fm = f.norm();
    if (fm > params_.max_force_n) scale = params_.max_force_n / fm;
    f *= scale;
  }
  if (!f.allFinite()) return drop_on_fault(was_in_contact);
  apply_reaction(scale * (s * (1.0 - a) * pr.fn * pr.n + ft), scale * s * a, node_forces_n);
  res.node_contacts = use_nodes ? node_contacts_ : 0;
  res.max_node_depth_m = max_node_depth;
  anchor_prev_m_ = pr.a;
  anchor_velocity_valid_ = true;
  set_contact_result(f, pr, res);
  return res;
}

void push_contact_events(const TipContactResult& result, int object_id, double sim_time_s,
                         EventQueue& events) {
  char msg[96];
  if (result.fault) {
    std::snprintf(msg, sizeof(msg), "tip contact with object %d: non-finite data, contact dropped",
                  object_id);
    events.push(EventKind::kFault, Severity::kWarning, sim_time_s, object_id, msg);
  }
  if (result.began) {
    std::snprintf(msg, sizeof(msg), "tip touches object %d (triangle %d)", object_id,
                  result.triangle);
    events.push(EventKind::kContactBegin, Severity::kInfo, sim_time_s, result.normal_force_n, msg);
  }
  if (result.ended) {
    std::snprintf(msg, sizeof(msg), "tip leaves object %d", object_id);
    events.push(EventKind::kContactEnd, Severity::kInfo, sim_time_s, 0.0, msg);
  }
}

std::uint64_t TipMeshContact::touch() const {
  return tree_.touch() + teleop::touch(hit_tris_) + teleop::touch(stamp_) +
         teleop::touch(node_list_) + teleop::touch(node_force_);
}

}  // namespace teleop::sim::collision

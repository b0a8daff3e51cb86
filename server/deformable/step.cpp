// The step of the deformable body: input checks, held nodes, the dispatch to the pass that
// advances the model (kernels.hpp), the fault checks (blow-up: reset to the rest shape), sleep,
// and the automatic sub-steps. Nothing here allocates: every buffer lives in DeformableState and
// was sized by make_state().
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "server/deformable/deformable.hpp"
#include "server/deformable/fem.hpp"
#include "server/deformable/integrators.hpp"
#include "server/deformable/kernels.hpp"

namespace teleop::sim::deformable {

namespace {

// One pass over the caller's loads, on their bits (vectorised): all finite? all zero (+-0)?
struct LoadScan {
  bool finite = true;
  bool zero = true;
};
TELEOP_HOT_CLONES __attribute__((optimize("O3"))) LoadScan scan_loads(const Eigen::Matrix3Xd& f) {
  constexpr std::uint64_t kExponent = 0x7ff0000000000000ull;
  const double* d = f.data();
  const Eigen::Index count = f.size();
  std::uint64_t non_finite = 0, bits = 0;
  for (Eigen::Index k = 0; k < count; ++k) {
    std::uint64_t b;
    std::memcpy(&b, d + k, sizeof b);
    non_finite |= static_cast<std::uint64_t>((b & kExponent) == kExponent);
    bits |= b << 1;  // drops the sign: -0 counts as zero
  }
  return {non_finite == 0, bits == 0};
}

bool loaded(const DeformableModel& m, const DeformableState& s, bool loads_zero) {
  if (s.wake_request) return true;
  if (!loads_zero) return true;
  for (int i = 0; i < m.state_node_count(); ++i) {
    if (s.pinned[static_cast<std::size_t>(i)] && s.pin_target.col(i) != s.x.col(i)) return true;
  }
  return false;
}

void reset_to_rest(const DeformableModel& m, DeformableState& s) {
  if (m.params.model == ModelKind::kFem) {
    const Eigen::Vector3d shift = s.last_good_centroid - m.rest_centre_m;
    s.x = m.fem.rest;
    s.x.colwise() += shift;
    s.v.setZero();
    for (int i = 0; i < m.fem.node_count; ++i) {
      if (s.pinned[static_cast<std::size_t>(i)] && s.pin_target.col(i).allFinite()) {
        s.x.col(i) = s.pin_target.col(i);
      }
    }
    for (int t = 0; t < m.fem.tet_count; ++t) {
      double* q = s.fem_q.data() + 4 * t;
      q[0] = 1.0;
      q[1] = q[2] = q[3] = 0.0;
    }
    s.still_time_s = 0.0;
    return;
  }
  const Eigen::Vector3d shift =
      s.last_good_centroid -
      (m.mesh.vertices * m.mass_kg + m.centre_mass_kg * m.rest_centre_m) / m.total_mass_kg;
  s.x = m.mesh.vertices;
  s.x.colwise() += shift;
  s.v.setZero();
  s.centre_x = m.rest_centre_m + shift;
  s.centre_v.setZero();
  for (int i = 0; i < m.node_count; ++i) {
    if (s.pinned[static_cast<std::size_t>(i)] && s.pin_target.col(i).allFinite()) {
      s.x.col(i) = s.pin_target.col(i);
    }
    s.rotation[static_cast<std::size_t>(i)].setIdentity();
    s.rotation_q[static_cast<std::size_t>(i)].setIdentity();
  }
  s.still_time_s = 0.0;
}

// Held nodes: sets the velocity that takes each one to its target in this step (a non-finite
// target releases the node) and counts them (s.pinned_count, the released ones included).
// Returns whether any held node moves.
TELEOP_ALWAYS_INLINE bool drive_held_nodes(const DeformableModel& m, DeformableState& s, double h) {
  bool pin_moving = false;
  s.pinned_count = 0;
  const std::uint8_t* flags = s.pinned.data();
  const int nodes = m.state_node_count();
  for (int i = 0; i < nodes; ++i) {
    if (i + 8 <= nodes) {  // eight flags at once: usually no node is held
      std::uint64_t word;
      std::memcpy(&word, flags + i, sizeof word);
      if (word == 0) {
        i += 7;
        continue;
      }
    }
    if (!flags[i]) continue;
    ++s.pinned_count;
    if (!s.pin_target.col(i).allFinite()) {
      s.pinned[static_cast<std::size_t>(i)] = 0;  // a bad target releases the node
      continue;
    }
    s.v.col(i) = (s.pin_target.col(i) - s.x.col(i)) / h;
    pin_moving = pin_moving || s.pin_target.col(i) != s.x.col(i);
  }
  return pin_moving;
}

// The fault event of a blow-up: names the first non-finite node, else the fastest one (largest
// squared speed fastest2 [m^2/s^2]).
TELEOP_ALWAYS_INLINE void report_blow_up(const DeformableModel& m, const DeformableState& s,
                                         double fastest2, bool finite,
                                         teleop::sim::EventQueue& events) {
  int fastest = 0;
  for (int i = 0; i < m.state_node_count(); ++i) {
    const double sp2 = s.v.col(i).squaredNorm();
    if (!std::isfinite(sp2) || !s.x.col(i).allFinite()) {
      fastest = i;
      fastest2 = sp2;
      break;
    }
    if (sp2 >= fastest2) fastest = i;
  }
  char msg[128];
  std::snprintf(msg, sizeof(msg),
                "deformable: blow-up (node %d speed %.3g m/s%s); reset to rest shape", fastest,
                std::sqrt(fastest2), finite ? "" : ", NaN");
  events.push(EventKind::kFault, Severity::kError, s.sim_time_s, std::sqrt(fastest2), msg);
}

// The general passes of a surface model: its forces (compute_forces), the node update
// (integrate), then held nodes onto their targets and the post-step sums (hold_and_sum).
TELEOP_ALWAYS_INLINE void general_passes(const DeformableModel& m, DeformableState& s, double h,
                                         detail::KernelSums& sums) {
  const int n = m.node_count;
  detail::ForceFlags flags;
  flags.jacobian = m.params.integrator == IntegratorKind::kImplicitEuler;
  detail::compute_forces(m, s, h, flags);
  s.force = s.work_f.leftCols(n);
  detail::integrate(m, s, h);
  detail::hold_and_sum(m.mass_kg, n, s, sums);
}

TELEOP_HOT_CLONES
StepStatus step_impl(const DeformableModel& m, DeformableState& s, double h,
                     teleop::sim::EventQueue* events, bool allow_fused, LoadScan loads,
                     bool more_substeps = false, double tip_alpha = 1.0) {
  if (!(h > 0.0) || !std::isfinite(h) || !loads.finite) {
    if (events) {
      events->push(EventKind::kFault, Severity::kWarning, s.sim_time_s, h,
                   "deformable: step refused (dt <= 0 or non-finite, or non-finite f_ext)");
    }
    return StepStatus::kBadInput;
  }
  if (s.sleeping) {
    if (!loaded(m, s, loads.zero)) {
      s.sim_time_s += h;
      ++s.sleeping_steps;
      return StepStatus::kSleeping;
    }
    s.sleeping = false;
    s.still_time_s = 0.0;
  }
  s.wake_request = false;

  // held nodes: the velocity that takes them to their target in this step
  const bool pin_moving = drive_held_nodes(m, s, h);

  detail::KernelSums sums;
  if (m.params.model == ModelKind::kFem) {
    detail::fem_step(m, s, h, tip_alpha, sums);
  } else if (allow_fused && m.params.kernel == KernelKind::kSimd) {
    detail::step_mass_spring_simd(m, s, h, loads.zero, more_substeps, sums);
  } else if (allow_fused && m.params.model == ModelKind::kMassSpring &&
             m.params.integrator == IntegratorKind::kSymplecticEuler) {
    detail::step_mass_spring_symplectic(m, s, h, sums);
  } else {
    general_passes(m, s, h, sums);
  }
  s.sim_time_s += h;
  ++s.steps;
  const double vmax2 = m.params.max_speed_mps * m.params.max_speed_mps;
  const double fastest2 = sums.fastest2;
  const double sum_x = sums.sum_x, sum_v = sums.sum_v;
  const Eigen::Vector3d mx =
      Eigen::Vector3d(sums.mx[0], sums.mx[1], sums.mx[2]) + m.centre_mass_kg * s.centre_x;
  const bool finite = std::isfinite(sum_x) && std::isfinite(sum_v) && s.centre_x.allFinite() &&
                      s.centre_v.allFinite();
  if (!finite || !(fastest2 <= vmax2) || !(s.centre_v.squaredNorm() <= vmax2)) {
    ++s.fault_count;
    if (events) report_blow_up(m, s, fastest2, finite, *events);
    reset_to_rest(m, s);
    s.simd_pack_fresh = false;
    return StepStatus::kFaultReset;
  }
  s.last_good_centroid = mx / m.total_mass_kg;

  // sleeping: still, unloaded and no held node moving for sleep_time_s
  const double sleep2 = m.params.sleep_speed_mps * m.params.sleep_speed_mps;
  const bool tip_present = m.params.model == ModelKind::kFem && s.tip_radius_m > 0.0;
  if (fastest2 < sleep2 && s.centre_v.squaredNorm() < sleep2 && !pin_moving && loads.zero &&
      !tip_present) {
    s.still_time_s += h;
    if (s.still_time_s >= m.params.sleep_time_s) {
      s.sleeping = true;
      s.v.setZero();
      s.centre_v.setZero();
      s.simd_pack_fresh = false;  // the pack holds the velocities before this
    }
  } else {
    s.still_time_s = 0.0;
  }
  return StepStatus::kOk;
}

// dt split into n equal sub-steps of step_impl: the caller's loads are held, pinned nodes move
// linearly from where they are to their targets (each sub-step ends on its share of the way), the
// first fault or bad input ends the step. Allocation-free: the caller's targets are kept in
// s.pin_goal while the sub-steps overwrite s.pin_target.
// f_ext is the caller's and does not change during a step: scanned once (scan_loads) for all
// its sub-steps.
StepStatus step_substeps(const DeformableModel& m, DeformableState& s, double dt, int n,
                         teleop::sim::EventQueue* events, bool allow_fused) {
  const LoadScan loads = scan_loads(s.f_ext);
  s.simd_pack_fresh = false;  // x and v may have been changed since the last call
  const double h = dt / n;
  if (!s.substeps_announced && events != nullptr && std::isfinite(dt)) {
    const int needed = m.substeps_needed(dt);
    char msg[128];
    if (needed < n) {  // params.min_substeps: accuracy, not stability
      std::snprintf(msg, sizeof(msg),
                    "deformable: %d sub-steps of %.3g ms (min_substeps, for accuracy; stable step "
                    "%.3g ms)",
                    n, h * 1e3, m.stable_step_s * 1e3);
    } else if (needed > n) {
      std::snprintf(msg, sizeof(msg),
                    "deformable: dt %.3g ms needs %d sub-steps, capped at %d (max_substeps): "
                    "may blow up",
                    dt * 1e3, needed, n);
    } else {
      std::snprintf(msg, sizeof(msg),
                    "deformable: dt %.3g ms > stable step %.3g ms (w_max %.0f rad/s): "
                    "%d sub-steps of %.3g ms",
                    dt * 1e3, m.stable_step_s * 1e3, m.omega_max_rad_per_s, n, h * 1e3);
    }
    events->push(EventKind::kInfo, needed > n ? Severity::kWarning : Severity::kInfo, s.sim_time_s,
                 static_cast<double>(n), msg);
    s.substeps_announced = true;
  }
  s.last_substeps = n;
  const int nodes = m.state_node_count();
  bool any_pin = false;  // eight flags at a time: usually no node is held
  const std::uint8_t* flags = s.pinned.data();
  int i0 = 0;
  for (; i0 + 8 <= nodes && !any_pin; i0 += 8) {
    std::uint64_t word;
    std::memcpy(&word, flags + i0, sizeof word);
    any_pin = word != 0;
  }
  for (; i0 < nodes && !any_pin; ++i0) any_pin = flags[i0] != 0;
  if (any_pin) {
    s.pin_goal = s.pin_target;  // same size: no allocation
    s.pin_start = s.x;          // where the held nodes start (same size: no allocation)
  }
  StepStatus result = StepStatus::kOk;
  for (int k = 1; k <= n; ++k) {
    if (any_pin) {
      const double frac = static_cast<double>(k) / n;
      for (int i = 0; i < nodes; ++i) {
        if (!s.pinned[static_cast<std::size_t>(i)]) continue;
        s.pin_target.col(i) =
            k == n ? Eigen::Vector3d(s.pin_goal.col(i))
                   : Eigen::Vector3d(s.pin_start.col(i) +
                                     frac * (s.pin_goal.col(i) - s.pin_start.col(i)));
      }
    }
    const StepStatus st =
        step_impl(m, s, h, events, allow_fused, loads, k < n, static_cast<double>(k) / n);
    if (st == StepStatus::kFaultReset || st == StepStatus::kBadInput) {
      result = st;
      break;
    }
    if (st == StepStatus::kSleeping) {
      s.sim_time_s += (n - k) * h;  // asleep for the rest of dt
      if (k == 1) result = st;
      break;
    }
  }
  if (any_pin) s.pin_target = s.pin_goal;
  s.simd_pack_fresh = false;  // never outlives the call
  return result;
}

StepStatus step_any(const DeformableModel& m, DeformableState& s, double h,
                    teleop::sim::EventQueue* events) {
  const int n = m.substeps_for(h);
  if (n <= 1) {
    s.last_substeps = 1;
    if (!(m.stable_step_s > 0.0) && !s.substeps_announced && events != nullptr) {
      events->push(EventKind::kInfo, Severity::kWarning, s.sim_time_s, 0.0,
                   "deformable: explicit Euler without damping is unstable at any step; use "
                   "symplectic_euler or implicit_euler");
      s.substeps_announced = true;
    }
    return step_impl(m, s, h, events, true, scan_loads(s.f_ext));
  }
  return step_substeps(m, s, h, n, events, true);
}

}  // namespace

StepStatus step(const DeformableModel& m, DeformableState& s, double h,
                teleop::sim::EventQueue* events) {
  if (m.params.model != ModelKind::kFem) return step_any(m, s, h, events);
  // the tip sphere's reaction: impulses summed over the sub-steps, then the mean force
  s.tip_force_n.setZero();
  s.tip_node_count = 0;
  s.tip_depth_m = 0.0;
  if (s.tip_radius_m > 0.0 && s.sleeping) wake(s);  // a tip near the body: it may be touched
  const StepStatus st = step_any(m, s, h, events);
  if (st == StepStatus::kOk && h > 0.0) {
    s.tip_force_n /= h;
  } else {
    s.tip_force_n.setZero();
  }
  return st;
}

StepStatus detail::step_general(const DeformableModel& m, DeformableState& s, double h,
                                teleop::sim::EventQueue* events) {
  const int n = m.substeps_for(h);
  if (n <= 1) {
    s.last_substeps = 1;
    return step_impl(m, s, h, events, false, scan_loads(s.f_ext));
  }
  return step_substeps(m, s, h, n, events, false);
}

StepStatus detail::step_once(const DeformableModel& m, DeformableState& s, double h,
                             teleop::sim::EventQueue* events) {
  s.last_substeps = 1;
  return step_impl(m, s, h, events, true, scan_loads(s.f_ext));
}

}  // namespace teleop::sim::deformable
#pragma once
// Wave variables (Anderson & Spong 1989; Niemeyer & Slotine 1991, 2004) for a delayed
// bilateral channel, one transform per port, each Cartesian axis on its own.
//
// With the wave impedance b [N s/m], at a port with velocity xdot [m/s] and force F [N]
// (F . xdot is the power flowing INTO the channel at that port):
//
//     u = (b xdot + F) / sqrt(2b)      forward wave, master -> slave   [sqrt(W)]
//     v = (b xdot - F) / sqrt(2b)      backward wave, slave -> master  [sqrt(W)]
//
// so that F . xdot = (u^2 - v^2) / 2. A channel that only delays the waves stores the energy
// in transit and is passive for any constant delay.
//
// Master port (impedance causality: xdot_m measured, v_m received):
//     F_m = b xdot_m - sqrt(2b) v_m,     u_m = sqrt(2b) xdot_m - v_m
//   F_m is the force the operator pushes into the channel with; the device renders -F_m.
// Slave port (admittance causality: u_s received, the environment force measured). The
// slave tool presses the environment with F_e = -f_e (f_e: contact force ON the tool).
//   unmatched (the port force is F_e):
//     xdot_sd = (sqrt(2b) u_s - F_e) / b,            v_s = u_s - sqrt(2/b) F_e
//   matched (a virtual damper b in parallel with the tool, port force F_e + b xdot_sd):
//     xdot_sd = (sqrt(2b) u_s - F_e) / (2b),         v_s = -F_e / sqrt(2b)
//   The matched termination returns no wave in free space (no reflection, no echo); the
//   price is a damping b felt at the master in free motion. Unmatched, free space reflects
//   v_s = u_s: the operator feels the echo of their own motion every round trip.
//
// Drift: waves carry velocities; integrating them at the slave drifts under loss and jitter.
// The sender therefore transmits the integral W = sum dt w and the energy E = sum dt w^2 / 2
// (per axis) with every sample. The receiver (WaveReceiver) reconstructs the wave that closes
// the gap between the received integral and the integral it has used, limited so that the
// energy it uses never exceeds the energy sent (Niemeyer & Slotine 2004, wave integrals): the
// channel stays passive under loss, jitter and holds, and the slave's position follows the
// master's without drift (x_sd - x0 = (x_m - x_m0)(t - T) in free space with the matched
// termination; in contact the offset is the wave spring's deflection, about F T / b).
//
// Everything here is allocation-free and deterministic.
#include <Eigen/Core>
#include <cmath>

namespace teleop::passivity {

using Vec3 = Eigen::Vector3d;

/// sqrt(2 b) for b [N s/m].
inline double wave_scale(double b) { return std::sqrt(2.0 * b); }

/// Waves of a port from its power variables: u = (b xdot + F)/sqrt(2b), v = (b xdot - F)/sqrt(2b).
inline void wave_encode(double b, const Vec3& xdot, const Vec3& force, Vec3& u, Vec3& v) {
  const double s = wave_scale(b);
  u = (b * xdot + force) / s;
  v = (b * xdot - force) / s;
}

/// Power variables of a port from its waves: xdot = (u + v)/sqrt(2b), F = sqrt(b/2) (u - v).
inline void wave_decode(double b, const Vec3& u, const Vec3& v, Vec3& xdot, Vec3& force) {
  const double s = wave_scale(b);
  xdot = (u + v) / s;
  force = 0.5 * s * (u - v);
}

/// Master port: from the measured velocity and the received backward wave, the force the
/// operator pushes into the channel with (F_m; the device renders -F_m) and the forward wave.
inline void wave_master(double b, const Vec3& xdot, const Vec3& v, Vec3& force, Vec3& u) {
  const double s = wave_scale(b);
  force = b * xdot - s * v;
  u = s * xdot - v;
}

/// Slave port: from the received forward wave and the force the tool exerts on the
/// environment (F_e = -contact force on the tool), the commanded velocity and the backward
/// wave; `matched` adds the virtual damper b (see the file comment). `port_force` is the force
/// of the channel's port (F_e, or F_e + b xdot_sd when matched), so that
/// port_force . xdot_sd = (u^2 - v^2) / 2.
inline void wave_slave(double b, bool matched, const Vec3& u, const Vec3& env_force, Vec3& xdot,
                       Vec3& v, Vec3& port_force) {
  const double s = wave_scale(b);
  if (matched) {
    xdot = (s * u - env_force) / (2.0 * b);
    v = -env_force / s;
    port_force = env_force + b * xdot;
  } else {
    xdot = (s * u - env_force) / b;
    v = u - (2.0 / s) * env_force;
    port_force = env_force;
  }
}

/// Largest wave magnitude a receiver reconstructs in one sample: the wave of a port moving
/// at `speed_mps` while pushing with `force_n`, (b speed + force) / sqrt(2b). Limiting the
/// reconstruction only removes energy, so it is passive.
inline double wave_limit(double b, double speed_mps, double force_n) {
  return (b * speed_mps + force_n) / wave_scale(b);
}

/// Energy-bounded reconstruction of a wave from its transmitted integral and energy, per
/// axis (see the file comment). One receiver per direction and port.
///
/// Each step the receiver has an outstanding integral G (received, not yet used) and an unused
/// energy B (received, not yet used). Closing G evenly over n steps costs G^2 / (2 n dT) in
/// total, so the fastest even schedule the energy pays for is n = ceil(G^2 / (2 B dT)); the
/// receiver puts out w = G / (n dT) this step, which costs at most B / n. In steady streaming
/// n = 1 and w is the sent wave; after a loss or a burst (jitter) of k samples, n <= k (the
/// mean square is at least the squared mean) and less when their waves differ, so a backlog
/// drains as fast as passivity allows; it never stalls (each step closes 1/n of G for at most
/// 1/n of B, so G^2 / B, hence n, shrinks). The energy used never exceeds the energy sent, and
/// the integral, hence the position, catches up without drift.
class WaveReceiver {
 public:
  /// Forgets everything (new session).
  void reset() {
    used_integral_.setZero();
    used_energy_j_.setZero();
  }
  /// One sample. `sent_integral` [sqrt(W) s] and `sent_energy_j` [J] are the sender's
  /// cumulative integral and energy per axis from the newest sample received (the same
  /// values again if nothing new arrived); `dt_s` the receiver's period; |w| <= `limit`.
  /// Returns the wave to use this sample. Allocation-free.
  Vec3 receive(const Vec3& sent_integral, const Vec3& sent_energy_j, double dt_s, double limit) {
    Vec3 w;
    for (int i = 0; i < 3; ++i) {
      const double gap = sent_integral[i] - used_integral_[i];
      const double budget = sent_energy_j[i] - used_energy_j_[i];
      double wi = 0.0;
      if (budget > 0.0 && gap != 0.0) {
        // steps of the fastest even schedule the unused energy pays for (1 + 1e-6: rounding
        // of the sums must not turn a streaming sample into two)
        const double x = gap * gap / (2.0 * budget * dt_s);
        const double n = x <= 1.0 + 1e-6 ? 1.0 : std::ceil(x);
        const double cap = std::fmin(std::sqrt(2.0 * budget / dt_s), limit);
        wi = std::fmax(-cap, std::fmin(cap, gap / (n * dt_s)));
      }
      w[i] = wi;
      used_integral_[i] += dt_s * wi;
      used_energy_j_[i] += 0.5 * dt_s * wi * wi;
    }
    return w;
  }
  /// Integral of the waves used so far [sqrt(W) s].
  const Vec3& used_integral() const { return used_integral_; }
  /// Energy of the waves used so far [J] (never more than the energy sent).
  const Vec3& used_energy_j() const { return used_energy_j_; }

 private:
  Vec3 used_integral_ = Vec3::Zero();
  Vec3 used_energy_j_ = Vec3::Zero();
};

/// Cumulative integral and energy of the waves a port sends.
struct WaveSender {
  Vec3 integral = Vec3::Zero();  ///< sum dt w [sqrt(W) s]
  Vec3 energy_j = Vec3::Zero();  ///< sum dt w^2 / 2 per axis [J]
  void reset() {
    integral.setZero();
    energy_j.setZero();
  }
  /// Records the wave sent this sample.
  void add(const Vec3& w, double dt_s) {
    integral += dt_s * w;
    energy_j += 0.5 * dt_s * w.cwiseProduct(w);
  }
};

/// Master side of a wave channel (state of one session). Positions and velocities are in the
/// slave frame (the caller maps the device's).
class WaveMasterPort {
 public:
  /// b [N s/m] > 0; `limit` bounds the reconstructed backward wave [sqrt(W)];
  /// `filter_hz` the cutoff of the first-order low-pass on the backward wave (0: none).
  void configure(double impedance_ns_per_m, double limit, double filter_hz = 0.0) {
    b_ = impedance_ns_per_m;
    limit_ = limit;
    filter_hz_ = filter_hz;
  }
  /// Starts a session at master position `x0_m`.
  void reset(const Vec3& x0_m) {
    x0_ = x0_m;
    sent_integral_prev_.setZero();
    rx_.reset();
    tx_.reset();
    force_.setZero();
    u_.setZero();
    v_.setZero();
    v_integral_.setZero();
  }
  /// One haptic cycle. `x_m`, `xdot_m`: master position [m] and velocity [m/s];
  /// `v_integral`, `v_energy_j`: the newest backward wave integral and energy received
  /// (`have_wave` false: none of this session yet). Allocation-free.
  ///
  /// The forward wave is sent as the increment of U = sqrt(2b)(x_m - x0) - V_used, which is
  /// sqrt(2b) xdot_m - v_m when xdot_m is the position's rate: the slave's position follows
  /// the master's position, not the integral of a velocity estimate.
  void update(const Vec3& x_m, const Vec3& xdot_m, const Vec3& v_integral, const Vec3& v_energy_j,
              bool have_wave, double dt_s) {
    const Vec3 w = have_wave ? rx_.receive(v_integral, v_energy_j, dt_s, limit_) : Vec3::Zero();
    // wave filter: a first-order low-pass (impulse response >= 0, unit area) never puts out
    // more energy than it took in, so it keeps the channel passive; it removes the
    // high-frequency echo between a stiff contact and the device
    const double a = filter_hz_ > 0.0 ? 1.0 - std::exp(-2.0 * M_PI * filter_hz_ * dt_s) : 1.0;
    v_ += a * (w - v_);
    v_integral_ += dt_s * v_;
    const double s = wave_scale(b_);
    force_ = b_ * xdot_m - s * v_;
    const Vec3 integral = s * (x_m - x0_) - v_integral_;
    u_ = (integral - sent_integral_prev_) / dt_s;
    sent_integral_prev_ = integral;
    tx_.add(u_, dt_s);
  }
  /// Force the operator pushes into the channel with, slave frame [N] (device renders -F).
  const Vec3& force_n() const { return force_; }
  /// Forward wave sent this cycle [sqrt(W)].
  const Vec3& u() const { return u_; }
  /// Backward wave used this cycle [sqrt(W)].
  const Vec3& v() const { return v_; }
  /// What goes on the wire: cumulative forward integral and energy.
  const WaveSender& sent() const { return tx_; }
  /// The backward receiver (used integral and energy).
  const WaveReceiver& received() const { return rx_; }
  double impedance_ns_per_m() const { return b_; }

 private:
  double b_ = 1.0;
  double limit_ = 1e9;
  double filter_hz_ = 0.0;
  Vec3 v_integral_ = Vec3::Zero();
  Vec3 x0_ = Vec3::Zero();
  Vec3 sent_integral_prev_ = Vec3::Zero();
  WaveReceiver rx_;
  WaveSender tx_;
  Vec3 force_ = Vec3::Zero();
  Vec3 u_ = Vec3::Zero();
  Vec3 v_ = Vec3::Zero();
};

/// Slave side of a wave channel (state of one session): the desired tool position and
/// velocity from the forward wave and the measured contact force.
class WaveSlavePort {
 public:
  void configure(double impedance_ns_per_m, bool matched, double limit) {
    b_ = impedance_ns_per_m;
    matched_ = matched;
    limit_ = limit;
  }
  /// Starts a session; the first update() places x_sd.
  void reset() {
    started_ = false;
    rx_.reset();
    tx_.reset();
    x_sd_.setZero();
    xdot_sd_.setZero();
    v_.setZero();
    port_force_.setZero();
    dissipated_j_ = 0.0;
  }
  /// One slave step. `u_integral`, `u_energy_j`: the newest forward integral and energy
  /// received; `x_cmd_m`: the master's mapped position carried by the same command (used once,
  /// to place x_sd so that it equals x_cmd once the received integral has been used);
  /// `contact_force_n`: the environment's force on the tool measured at the last step [N].
  void update(const Vec3& u_integral, const Vec3& u_energy_j, const Vec3& x_cmd_m,
              const Vec3& contact_force_n, double dt_s) {
    const double s = wave_scale(b_);
    if (!started_) {
      // x_sd = x0 + sqrt(2b) U_used / (kappa b) - impulse / (kappa b), kappa = 2 matched
      const double kappa_b = (matched_ ? 2.0 : 1.0) * b_;
      x_sd_ = x_cmd_m - s * u_integral / kappa_b;
      started_ = true;
    }
    const Vec3 u = rx_.receive(u_integral, u_energy_j, dt_s, limit_);
    const Vec3 env_force = -contact_force_n;
    wave_slave(b_, matched_, u, env_force, xdot_sd_, v_, port_force_);
    x_sd_ += dt_s * xdot_sd_;
    tx_.add(v_, dt_s);
    if (matched_) dissipated_j_ += dt_s * b_ * xdot_sd_.squaredNorm();
  }
  bool started() const { return started_; }
  /// Desired tool position [m] and velocity [m/s] for the slave's tracking controller.
  const Vec3& position_m() const { return x_sd_; }
  const Vec3& velocity_mps() const { return xdot_sd_; }
  /// Backward wave sent this step, and the cumulative integral/energy on the wire.
  const Vec3& v() const { return v_; }
  const WaveSender& sent() const { return tx_; }
  const WaveReceiver& received() const { return rx_; }
  /// Force of the channel's slave port this step [N] (F_e, + b xdot_sd when matched).
  const Vec3& port_force_n() const { return port_force_; }
  /// Energy dissipated by the matching damper so far [J].
  double dissipated_j() const { return dissipated_j_; }

 private:
  double b_ = 1.0;
  bool matched_ = true;
  double limit_ = 1e9;
  bool started_ = false;
  WaveReceiver rx_;
  WaveSender tx_;
  Vec3 x_sd_ = Vec3::Zero();
  Vec3 xdot_sd_ = Vec3::Zero();
  Vec3 v_ = Vec3::Zero();
  Vec3 port_force_ = Vec3::Zero();
  double dissipated_j_ = 0.0;
};

}  // namespace teleop::passivity

#pragma once
// Time-domain passivity (Hannaford & Ryu 2002) for a delayed two-port, in the energy-exchange
// form of Ryu, Artigas & Preusche (2010): each port observes the energy that enters and leaves
// the network through it, sends its input energy to the other side, and dissipates exactly
// the energy by which its output would exceed the input energy received from the other side.
//
// The network is everything between the operator's device and the slave's tracking
// controller: the master's coupling law (position-position spring or force reflection), both
// directions of the delayed channel. Its ports:
//   master port  (v_m, f_m): device velocity and the force the controller applies to the
//                device; power out of the network P_m = f_m . v_m (> 0: it pushes the hand
//                along its motion).
//   slave port   (v_c, f_c): rate of the position command handed to the slave's tracking
//                controller and the force that controller applies to the tool (its spring-
//                damper pulls the tool towards the command); power out P_s = f_c . v_c.
// The slave's PD with its feed-forward velocity equal to v_c, the tool and the environment
// form a passive termination (a spring-damper between the command point and a mass in contact
// with passive objects), as do the device and the hand at the master.
//
// Energies, cumulative from the start of a session (sum over samples of dT times the power):
//   E_in  = sum dT max(0, -P),  E_out = sum dT max(0, P)      at each port.
// Passivity of the network, E_in_m + E_in_s - E_out_m - E_out_s >= 0, follows from the two
// local conditions, each checked with what has arrived from the other side:
//   E_out_s(n) <= E_in_m(n - D_f)     at the slave,      E_out_m(n) <= E_in_s(n - D_b)   at the
//   master
// since the received energies are delayed values of non-decreasing sums.
//
// Passivity controllers (PC):
//   master (impedance causality, velocity in, force out): parallel, adaptive damping
//     W = E_in_s,rx - E_out_m(n-1) - dT f . v;  W < 0:  alpha = -W / (dT |v|^2),
//     f' = f - alpha v   (so dT f' . v = dT f . v + W and the observer ends at exactly 0);
//     |f' - f| <= |f| always: it removes at most the force component along the velocity.
//   slave (admittance causality, force in, velocity out): series, on the position command.
//     The command point would move from x_c(n-1) to the tentative x_t at v_t; the PD force
//     f_c = K_p (x - x_s) + K_d (v - v_s) is linear in the command, so moving the command
//     back by lambda v_t dT (0 <= lambda <= 1) gives the power (1 - lambda)(a - lambda b')
//     with a = f_t . v_t, b' = (K_p dT + K_d) |v_t|^2; the smallest lambda that brings it down
//     to the budget solves a quadratic. lambda = 1 stops the command point (zero power), so
//     the budget is always met when the tracking law is as modelled.
//   The slave's PC leaves the command behind the master's: an offset delta = x_c' - x_c. It
//   decays with time constant tau (a tentative x_t = x_c + delta (1 - dT/tau)) whenever the
//   energy budget allows, which is the passive drift correction.
//
// Limits: the observers are exact for the sampled power at the ports; the device's and the
// tool's motion within a sample is not seen (sampled-data energy leaks are those of any
// 1 kHz haptic rendering). The slave's PC predicts the tracking force with the linear PD law:
// a slave whose controller differs (saturation, the robot's joint-space PD) makes the
// observer err by the prediction error for one sample; the next sample's budget absorbs it.
// The master's PC acts on the controller's force; the safety layer scales the force written
// after it, which only lowers the output energy but is not fed back into the observer.
//
// Everything here is allocation-free and deterministic.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace teleop::passivity {

/// Energy that entered and left a network through one port [J], cumulative.
struct PortEnergy {
  double in_j = 0.0;          ///< sum dT max(0, -P)
  double out_j = 0.0;         ///< sum dT max(0, P)
  double dissipated_j = 0.0;  ///< removed by the passivity controller at this port
  void reset() { *this = PortEnergy{}; }
  /// Records the power P [W] (> 0: out of the network) for dT [s].
  void add(double power_w, double dt_s) {
    if (power_w > 0.0) {
      out_j += dt_s * power_w;
    } else {
      in_j -= dt_s * power_w;
    }
  }
};

/// Master-side (impedance) passivity controller. Units of the frame it is used in.
class ImpedancePassivityController {
 public:
  void reset() {
    energy_.reset();
    last_alpha_ = 0.0;
  }
  /// The force to apply instead of `force` at velocity `velocity`, given the remote input
  /// energy received so far [J] (cumulative, the other port's E_in). Does not record: call
  /// commit() with the force finally applied.
  Eigen::Vector3d filter(const Eigen::Vector3d& force, const Eigen::Vector3d& velocity,
                         double remote_in_j, double dt_s) {
    last_alpha_ = 0.0;
    const double p = force.dot(velocity);
    const double budget_w = std::max(0.0, remote_in_j - energy_.out_j) / dt_s;
    const double v2 = velocity.squaredNorm();
    if (p <= budget_w || v2 <= 0.0) return force;
    last_alpha_ = (p - budget_w) / v2;  // = -W / (dT |v|^2)
    return force - last_alpha_ * velocity;
  }
  /// Records the force applied this sample (after filter() and any saturation) and the force
  /// the network wanted (before the PC) for the dissipation count.
  void commit(const Eigen::Vector3d& applied, const Eigen::Vector3d& wanted,
              const Eigen::Vector3d& velocity, double dt_s) {
    energy_.add(applied.dot(velocity), dt_s);
    energy_.dissipated_j += dt_s * std::max(0.0, (wanted - applied).dot(velocity));
  }
  const PortEnergy& energy() const { return energy_; }
  /// Damping the PC added in the last filter() [N s/m] (0: inactive).
  double last_alpha() const { return last_alpha_; }

 private:
  PortEnergy energy_;
  double last_alpha_ = 0.0;
};

/// Slave-side (admittance) passivity controller on the position command.
class AdmittancePassivityController {
 public:
  /// tau [s] of the drift decay (0 = no drift correction).
  void configure(double drift_time_constant_s) { tau_s_ = drift_time_constant_s; }
  /// Starts a session; the first filter() places the command point at the first command.
  void reset() {
    energy_.reset();
    started_ = false;
    delta_.setZero();
    x_prev_.setZero();
    v_cmd_.setZero();
    last_lambda_ = 0.0;
  }
  /// Modifies the command before the slave steps. `x_cmd_m`: the received (delayed) master
  /// position; `remote_in_j`: the master's E_in received [J]; `x_s`, `v_s`: the tool's state
  /// before the step; `kp`, `kd`: its tracking law f = kp (x - x_s) + kd (v - v_s).
  /// Writes the command position and velocity to hand to the tracking controller.
  void filter(const Eigen::Vector3d& x_cmd_m, double remote_in_j, const Eigen::Vector3d& x_s,
              const Eigen::Vector3d& v_s, double kp, double kd, double dt_s, Eigen::Vector3d& x_out,
              Eigen::Vector3d& v_out) {
    if (!started_) {
      x_prev_ = x_cmd_m;
      started_ = true;
    }
    const double decay = tau_s_ > 0.0 ? std::max(0.0, 1.0 - dt_s / tau_s_) : 1.0;
    const Eigen::Vector3d x_t = x_cmd_m + decay * delta_;
    const Eigen::Vector3d v_t = (x_t - x_prev_) / dt_s;
    const Eigen::Vector3d f_t = kp * (x_t - x_s) + kd * (v_t - v_s);
    const double a = f_t.dot(v_t);
    const double budget_w = std::max(0.0, remote_in_j - energy_.out_j) / dt_s;
    double lambda = 0.0;
    if (a > budget_w) {
      const double bq = (kp * dt_s + kd) * v_t.squaredNorm();
      const double disc = std::sqrt((a - bq) * (a - bq) + 4.0 * bq * budget_w);
      // smallest root of bq l^2 - (a + bq) l + (a - budget) = 0, cancellation-free form
      lambda = 2.0 * (a - budget_w) / ((a + bq) + disc);
      lambda = std::clamp(lambda, 0.0, 1.0);
      energy_.dissipated_j += dt_s * (a - (1.0 - lambda) * (a - lambda * bq));
    }
    last_lambda_ = lambda;
    x_out = x_t - lambda * dt_s * v_t;
    v_out = (1.0 - lambda) * v_t;
    delta_ = x_out - x_cmd_m;
    x_prev_ = x_out;
    v_cmd_ = v_out;
  }
  /// Keeps the command point where it is (hold): no power, no drift change.
  void hold(Eigen::Vector3d& x_out, Eigen::Vector3d& v_out) {
    x_out = x_prev_;
    v_out.setZero();
    v_cmd_.setZero();
  }
  /// Records the tracking force the slave actually applied this step [N].
  void commit(const Eigen::Vector3d& tracking_force_n, double dt_s) {
    energy_.add(tracking_force_n.dot(v_cmd_), dt_s);
  }
  bool started() const { return started_; }
  const PortEnergy& energy() const { return energy_; }
  /// Offset of the command from the master's position (drift) [m].
  const Eigen::Vector3d& drift_m() const { return delta_; }
  /// lambda of the last filter() (0: inactive, 1: command point stopped).
  double last_lambda() const { return last_lambda_; }

 private:
  PortEnergy energy_;
  double tau_s_ = 0.5;
  bool started_ = false;
  Eigen::Vector3d delta_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d x_prev_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_cmd_ = Eigen::Vector3d::Zero();
  double last_lambda_ = 0.0;
};

}  // namespace teleop::passivity

#include "server/robot/robot_sim.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <stdexcept>

namespace teleop::sim::robot {

namespace {

// ODE's per-thread data (collision caches): allocated once on each thread that builds or
// steps a world (a no-op when ODE was built without thread-local storage).
void ode_thread_init() {
  thread_local bool allocated = false;
  if (!allocated) {
    dAllocateODEDataForThread(dAllocateMaskAll);
    allocated = true;
  }
}

void ode_init_once() {
  static std::once_flag once;
  std::call_once(once, [] { dInitODE2(0); });
  ode_thread_init();
}

void to_ode(const Eigen::Matrix3d& R, dMatrix3 out) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out[4 * r + c] = R(r, c);
    out[4 * r + 3] = 0.0;
  }
}

Eigen::Matrix3d from_ode(const dReal* R) {
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = R[4 * r + c];
  }
  return m;
}

Eigen::Vector3d vec(const dReal* v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

double wrap_pi(double a) {
  a = std::fmod(a + M_PI, 2.0 * M_PI);
  if (a < 0) a += 2.0 * M_PI;
  return a - M_PI;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

std::vector<Plane> default_robot_planes(double stiffness_n_per_m, double damping_ns_per_m) {
  Plane floor;
  floor.id = 100;
  floor.name = "floor";
  floor.normal = Eigen::Vector3d::UnitZ();
  floor.offset_m = 0.0;
  floor.stiffness_n_per_m = stiffness_n_per_m;
  floor.damping_ns_per_m = damping_ns_per_m;
  floor.friction = 0.3;
  Plane wall = floor;
  wall.id = 101;
  wall.name = "wall";
  wall.normal = -Eigen::Vector3d::UnitY();
  wall.offset_m = -0.6;  // -y . x = -0.6  <=>  y = 0.6
  return {floor, wall};
}

/// The ODE world: its own self-threaded step, gravity, the joint ERP/CFM, the solver's
/// iterations, and a step arena reserved generously up front so that stepping never grows it.
void RobotSim::make_world() {
  world_ = dWorldCreate();
  // a self-threaded step of its own: worlds stepped on different threads share nothing
  threading_ = dThreadingAllocateSelfThreadedImplementation();
  dWorldSetStepThreadingImplementation(world_, dThreadingImplementationGetFunctions(threading_),
                                       threading_);
  dWorldSetGravity(world_, model_.gravity_mps2.x(), model_.gravity_mps2.y(),
                   model_.gravity_mps2.z());
  dWorldSetERP(world_, options_.joint_erp);
  dWorldSetCFM(world_, options_.joint_cfm);
  dWorldSetQuickStepNumIterations(world_, options_.quick_step_iterations);
  dWorldSetContactSurfaceLayer(world_, 0.0);
  dWorldSetAutoDisableFlag(world_, 0);
  // reserve ODE's step arena generously up front so that stepping never grows it
  dWorldStepReserveInfo reserve{};
  reserve.struct_size = sizeof(reserve);
  reserve.reserve_factor = 2.0f;
  reserve.reserve_minimum = 1u << 20;
  dWorldSetStepMemoryReservationPolicy(world_, &reserve);
  contact_group_ = dJointGroupCreate(0);
}

/// One body per link (mass and inertia at its COM, its collision box), and the tip's sphere on
/// the last link.
void RobotSim::make_bodies() {
  const int n = model_.n;
  for (int i = 0; i < n; ++i) {
    const LinkModel& l = model_.links[i];
    dBodyID b = dBodyCreate(world_);
    dMass mass;
    const Eigen::Matrix3d& I = l.inertia_kgm2;
    dMassSetParameters(&mass, l.mass_kg, 0, 0, 0, I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2),
                       I(1, 2));
    dBodySetMass(b, &mass);
    dBodySetGyroscopicMode(b, 1);
    bodies_[i] = b;

    boxes_[i] = dCreateBox(nullptr, l.box_size_m.x(), l.box_size_m.y(), l.box_size_m.z());
    dGeomSetBody(boxes_[i], b);
    const Eigen::Vector3d off = l.box_center_m - l.com_m;  // body frame = link axes at COM
    dGeomSetOffsetPosition(boxes_[i], off.x(), off.y(), off.z());
  }
  tip_geom_ = dCreateSphere(nullptr, model_.tip_radius_m);
  dGeomSetBody(tip_geom_, bodies_[n - 1]);
  const Eigen::Vector3d tip_off = model_.tool_offset_m - model_.links[n - 1].com_m;
  dGeomSetOffsetPosition(tip_geom_, tip_off.x(), tip_off.y(), tip_off.z());
}

/// A hinge per joint at the build configuration `q_build` (frames `f`), with stops where the
/// range is below a full turn, and a Coulomb friction motor where the link has one.
void RobotSim::make_joints(const JointVector& q_build, const Frames& f) {
  const int n = model_.n;
  for (int i = 0; i < n; ++i) {
    const LinkModel& l = model_.links[i];
    dBodyID parent = i == 0 ? nullptr : bodies_[i - 1];
    const Eigen::Vector3d z = f.T[i].linear().col(2);
    const Eigen::Vector3d p = f.T[i].translation();
    dJointID h = dJointCreateHinge(world_, nullptr);
    dJointAttach(h, bodies_[i], parent);
    dJointSetHingeAnchor(h, p.x(), p.y(), p.z());
    dJointSetHingeAxis(h, z.x(), z.y(), z.z());
    hinge_zero_[i] = q_build(i);
    const double range = l.q_max_rad - l.q_min_rad;
    has_stops_[i] = range < 2.0 * M_PI - 0.35;  // below 340 deg
    if (has_stops_[i]) {
      dJointSetHingeParam(h, dParamLoStop, l.q_min_rad - q_build(i));
      dJointSetHingeParam(h, dParamHiStop, l.q_max_rad - q_build(i));
      dJointSetHingeParam(h, dParamBounce, 0.0);
    }
    dJointSetHingeParam(h, dParamFMax, 0.0);
    hinges_[i] = h;

    coulomb_[i] = nullptr;
    if (l.coulomb_nm > 0.0) {
      dJointID a = dJointCreateAMotor(world_, nullptr);
      dJointAttach(a, bodies_[i], parent);
      dJointSetAMotorMode(a, dAMotorUser);
      dJointSetAMotorNumAxes(a, 1);
      dJointSetAMotorAxis(a, 0, 1, z.x(), z.y(), z.z());
      dJointSetAMotorParam(a, dParamVel, 0.0);
      dJointSetAMotorParam(a, dParamFMax, l.coulomb_nm);
      coulomb_[i] = a;
    }
  }
}

/// Grows the contact joint group's arena to its largest size once (it keeps its memory when
/// emptied), and runs one step with every contact so that ODE's step arena is sized too.
void RobotSim::reserve_contact_arenas() {
  for (int k = 0; k < kMaxContacts; ++k) {
    dContact c{};
    c.geom.normal[2] = 1.0;
    dJointAttach(dJointCreateContact(world_, contact_group_, &c), bodies_[0], nullptr);
  }
  dWorldStep(world_, 1e-6);
  dWorldQuickStep(world_, 1e-6);
  dJointGroupEmpty(contact_group_);
}

RobotSim::RobotSim(const RobotModel& model, const std::vector<Plane>& planes,
                   const RobotSimOptions& options)
    : model_(model), options_(options), planes_(planes) {
  if (model_.n < 1 || model_.n > kMaxJoints) {
    throw std::invalid_argument("RobotSim: the model has " + std::to_string(model_.n) +
                                " joints; 1 to " + std::to_string(kMaxJoints) + " allowed");
  }
  if (planes_.size() > static_cast<std::size_t>(kMaxPlanes)) {
    throw std::invalid_argument("RobotSim: " + std::to_string(planes_.size()) +
                                " planes; at most " + std::to_string(kMaxPlanes));
  }
  ode_init_once();
  const int n = model_.n;

  make_world();

  // build the chain at the mid-range configuration: hinge angles then read q - q_mid, which
  // keeps every joint's range inside ODE's (-pi, pi] hinge-angle interval
  JointVector q_build(n);
  for (int i = 0; i < n; ++i) q_build(i) = model_.q_mid(i);
  Frames f;
  forward_kinematics(model_, q_build, f);

  make_bodies();

  JointVector zero = JointVector::Zero(n);
  place_bodies(q_build, zero);

  make_joints(q_build, f);

  for (std::size_t k = 0; k < planes_.size(); ++k) {
    const Plane& pl = planes_[k];
    const Eigen::Vector3d nrm = pl.normal.normalized();
    plane_geoms_[k] = dCreatePlane(nullptr, nrm.x(), nrm.y(), nrm.z(), pl.offset_m);
  }

  reserve_contact_arenas();

  state_.n = n;
  reset(model_.q_home);
}

RobotSim::~RobotSim() {
  for (int i = 0; i < model_.n; ++i) {
    if (boxes_[i]) dGeomDestroy(boxes_[i]);
  }
  if (tip_geom_) dGeomDestroy(tip_geom_);
  for (std::size_t k = 0; k < planes_.size(); ++k) {
    if (plane_geoms_[k]) dGeomDestroy(plane_geoms_[k]);
  }
  if (contact_group_) dJointGroupDestroy(contact_group_);
  if (world_) dWorldDestroy(world_);  // destroys bodies and joints
  if (threading_) dThreadingFreeImplementation(threading_);
}

void RobotSim::place_bodies(const JointVector& q, const JointVector& qd) {
  Frames f;
  forward_kinematics(model_, q, f);
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  for (int i = 0; i < model_.n; ++i) {
    const Eigen::Vector3d c = f.com[i];
    dMatrix3 R;
    to_ode(f.T[i + 1].linear(), R);
    dBodySetPosition(bodies_[i], c.x(), c.y(), c.z());
    dBodySetRotation(bodies_[i], R);
    // velocity of the COM: sum over joints j <= i of qd_j z_j x (c - p_j)
    w += qd(i) * f.T[i].linear().col(2);
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (int j = 0; j <= i; ++j) {
      v += qd(j) * f.T[j].linear().col(2).cross(c - f.T[j].translation());
    }
    dBodySetLinearVel(bodies_[i], v.x(), v.y(), v.z());
    dBodySetAngularVel(bodies_[i], w.x(), w.y(), w.z());
    dBodySetForce(bodies_[i], 0, 0, 0);
    dBodySetTorque(bodies_[i], 0, 0, 0);
  }
}

void RobotSim::reset(const JointVector& q0) {
  const int n = model_.n;
  JointVector q = q0;
  for (int i = 0; i < n; ++i)
    q(i) = std::clamp(q(i), model_.links[i].q_min_rad, model_.links[i].q_max_rad);
  place_bodies(q, JointVector::Zero(n));
  state_.q = q;  // read_state unwraps around the previous value
  state_.qd.setZero(n);
  state_.tau.setZero(n);
  state_.tau_gravity.setZero(n);
  state_.tau_external.setZero(n);
  state_.external_wrench.setZero();
  state_.tip_contact_force_n.setZero();
  state_.tip_contact_torque_nm.setZero();
  state_.link_contact_force_n.setZero();
  state_.tip_penetration_m = 0.0;
  state_.tip_in_contact = false;
  state_.tip_contact_plane = -1;
  state_.link_contacts = 0;
  contact_count_ = 0;
  dJointGroupEmpty(contact_group_);
  read_state();
  controller_reset(model_, state_.controller, state_.q);
  state_.command.q_ref = state_.q;
  state_.command.qd_ref.setZero(n);
  state_.command.kp.setZero(n);
  state_.command.kd.setZero(n);
  state_.command.tau_ff.setZero(n);
  state_.command.tau_gravity.setZero(n);
  last_good_q_ = state_.q;
}

void RobotSim::read_state() {
  const int n = model_.n;
  for (int i = 0; i < n; ++i) {
    const double raw = dJointGetHingeAngle(hinges_[i]) + hinge_zero_[i];
    // unwrap around the previous value (joints with ranges over 2 pi)
    const double prev = state_.q.size() == n ? state_.q(i) : raw;
    state_.q(i) = prev + wrap_pi(raw - prev);
    state_.qd(i) = dJointGetHingeAngleRate(hinges_[i]);
  }
  forward_kinematics(model_, state_.q, state_.frames);
  geometric_jacobian(model_, state_.frames, state_.jacobian);

  // the tip as ODE sees it (the body may drift from FK by the joint error correction)
  dBodyID last = bodies_[n - 1];
  const Eigen::Matrix3d R = from_ode(dBodyGetRotation(last));
  const Eigen::Vector3d com = vec(dBodyGetPosition(last));
  const Eigen::Vector3d tip = com + R * (model_.tool_offset_m - model_.links[n - 1].com_m);
  state_.tip_pose.linear() = R;
  state_.tip_pose.translation() = tip;
  dVector3 v;
  dBodyGetPointVel(last, tip.x(), tip.y(), tip.z(), v);
  state_.tip_twist.head<3>() = vec(v);
  state_.tip_twist.tail<3>() = vec(dBodyGetAngularVel(last));
}

void RobotSim::collide(double dt_s) {
  dJointGroupEmpty(contact_group_);
  contact_count_ = 0;
  const int n = model_.n;
  double deepest = 0.0;
  int deepest_plane = -1;
  for (std::size_t k = 0; k < planes_.size(); ++k) {
    const Plane& pl = planes_[k];
    // contact softness from the plane's physical stiffness k and damping c (ODE manual)
    const double hk = dt_s * pl.stiffness_n_per_m;
    const double denom = hk + pl.damping_ns_per_m;
    const double erp = denom > 0.0 ? hk / denom : 0.2;
    const double cfm = denom > 0.0 ? 1.0 / denom : 1e-9;
    for (int g = -1; g < n; ++g) {
      if (g >= 0 && !options_.link_plane_collisions) continue;
      dGeomID geom = g < 0 ? tip_geom_ : boxes_[g];
      const int found = dCollide(geom, plane_geoms_[k], static_cast<int>(scratch_.size()),
                                 scratch_.data(), sizeof(dContactGeom));
      for (int c = 0; c < found && contact_count_ < kMaxContacts; ++c) {
        dContact contact{};
        contact.geom = scratch_[c];
        contact.surface.mode = dContactSoftERP | dContactSoftCFM | dContactApprox1;
        contact.surface.mu = pl.friction;
        contact.surface.soft_erp = erp;
        contact.surface.soft_cfm = cfm;
        dJointID j = dJointCreateContact(world_, contact_group_, &contact);
        dJointAttach(j, dGeomGetBody(geom), nullptr);
        feedback_[contact_count_] = dJointFeedback{};
        dJointSetFeedback(j, &feedback_[contact_count_]);
        contact_kind_[contact_count_] = g;
        contact_plane_[contact_count_] = pl.id;
        contact_pos_[contact_count_] = vec(scratch_[c].pos);
        if (g < 0 && scratch_[c].depth > deepest) {
          deepest = scratch_[c].depth;
          deepest_plane = pl.id;
        }
        if (g < 0 && deepest_plane < 0) deepest_plane = pl.id;
        ++contact_count_;
      }
    }
  }
  state_.tip_penetration_m = deepest;
  state_.tip_contact_plane = deepest_plane;
}

// Step 2: PD + viscous friction in each hinge's motor row, the feed-forward as a torque.
void RobotSim::actuate(const JointCommand& cmd) {
  const int n = model_.n;
  for (int i = 0; i < n; ++i) {
    const LinkModel& l = model_.links[i];
    const double lim = l.torque_limit_nm;
    const double ff = std::clamp(cmd.tau_ff(i), -lim, lim);
    const double kd = cmd.kd(i);
    const double kd_total = kd + l.viscous_nms_per_rad;
    if (kd_total > 0.0) {
      const double v_target =
          kd > 0.0 ? cmd.qd_ref(i) + cmd.kp(i) / kd * (cmd.q_ref(i) - state_.q(i)) : 0.0;
      const double fmax = kd > 0.0 ? std::max(0.0, lim - std::abs(ff)) : dInfinity;
      dJointSetHingeParam(hinges_[i], dParamVel, kd * v_target / kd_total);
      dJointSetHingeParam(hinges_[i], dParamCFM, 1.0 / kd_total);
      dJointSetHingeParam(hinges_[i], dParamFMax, fmax);
    } else {
      dJointSetHingeParam(hinges_[i], dParamFMax, 0.0);
    }
    dJointAddHingeTorque(hinges_[i], ff);
  }
}

// Step 3: the external tip wrench (contact with the deformable body, computed elsewhere) on the
// last body, and its joint torques; a non-finite wrench is dropped.
void RobotSim::apply_external_wrench(const RobotInput& in) {
  const int n = model_.n;
  state_.external_wrench.head<3>() = in.external_force_n;
  state_.external_wrench.tail<3>() = in.external_torque_nm;
  if (!state_.external_wrench.allFinite()) state_.external_wrench.setZero();
  wrench_to_joint_torque(state_.jacobian, state_.external_wrench, state_.tau_external);
  {
    const Eigen::Vector3d p = state_.tip_pose.translation();
    const Eigen::Vector3d& F = state_.external_wrench.head<3>();
    const Eigen::Vector3d& M = state_.external_wrench.tail<3>();
    dBodyAddForceAtPos(bodies_[n - 1], F.x(), F.y(), F.z(), p.x(), p.y(), p.z());
    dBodyAddTorque(bodies_[n - 1], M.x(), M.y(), M.z());
  }
}

// Step 6: the plane contacts' forces from their joint feedback, summed for the tip (force and
// torque about the tip) and for the links.
void RobotSim::sum_contact_forces() {
  state_.tip_contact_force_n.setZero();
  state_.tip_contact_torque_nm.setZero();
  state_.link_contact_force_n.setZero();
  state_.link_contacts = 0;
  int tip_contacts = 0;
  const Eigen::Vector3d tip = state_.tip_pose.translation();
  for (int c = 0; c < contact_count_; ++c) {
    const Eigen::Vector3d f = vec(feedback_[c].f1);  // plane on the robot body
    if (contact_kind_[c] < 0) {
      state_.tip_contact_force_n += f;
      state_.tip_contact_torque_nm += (contact_pos_[c] - tip).cross(f);
      ++tip_contacts;
    } else {
      state_.link_contact_force_n += f;
      ++state_.link_contacts;
    }
  }
  state_.tip_in_contact = tip_contacts > 0;
  if (!state_.tip_in_contact) state_.tip_contact_plane = -1;
}

// Step 6: the actuator torque actually applied (the motor row reconstructed from the new joint
// rate) and the command's gravity torque, into the state.
void RobotSim::applied_torque(const JointCommand& cmd) {
  const int n = model_.n;
  for (int i = 0; i < n; ++i) {
    const LinkModel& l = model_.links[i];
    const double lim = l.torque_limit_nm;
    const double ff = std::clamp(cmd.tau_ff(i), -lim, lim);
    double pd = 0.0;
    if (cmd.kd(i) > 0.0) {
      pd =
          cmd.kp(i) * (cmd.q_ref(i) - last_good_q_(i)) + cmd.kd(i) * (cmd.qd_ref(i) - state_.qd(i));
      const double fmax = std::max(0.0, lim - std::abs(ff));
      pd = std::clamp(pd, -fmax, fmax);
    }
    state_.tau(i) = ff + pd;
  }
  state_.tau_gravity = cmd.tau_gravity;
}

// Step 7: a non-finite or runaway state (joint faster than max_joint_speed_radps) restores the
// last good pose at rest; otherwise the pose becomes the last good one.
void RobotSim::handle_faults(double t, EventQueue* ev) {
  const int n = model_.n;
  bool bad =
      !state_.q.allFinite() || !state_.qd.allFinite() || !state_.tip_pose.translation().allFinite();
  for (int i = 0; i < n && !bad; ++i) {
    bad = std::abs(state_.qd(i)) > options_.max_joint_speed_radps;
  }
  if (bad) {
    ++state_.faults;
    if (ev) {
      ev->push(EventKind::kFault, Severity::kError, t, static_cast<double>(state_.faults),
               "robot: non-finite or runaway joint state; restored the last good pose at rest");
    }
    state_.q = last_good_q_;
    place_bodies(last_good_q_, JointVector::Zero(n));
    read_state();
    controller_reset(model_, state_.controller, state_.q);
    state_.tip_contact_force_n.setZero();
    state_.tip_contact_torque_nm.setZero();
  } else {
    last_good_q_ = state_.q;
  }
}

void RobotSim::step(const RobotInput& in, double dt_s, EventQueue* ev) {
  ode_thread_init();  // the server may step on another thread than the one that built us
  const double t = state_.sim_time_s;
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) {
    ++state_.faults;
    if (ev) ev->push(EventKind::kFault, Severity::kError, t, dt_s, "robot: step with bad dt");
    return;
  }

  // 1. controller: joint reference, gains and feed-forward from the measured state
  controller_update(model_, state_.controller, in, state_.q, state_.frames, dt_s, t, ev,
                    state_.command);
  const JointCommand& cmd = state_.command;

  // 2. actuation: PD + viscous friction in the hinge motor row, feed-forward as torque
  actuate(cmd);

  // 3. external tip wrench (contact with the deformable body, computed elsewhere)
  apply_external_wrench(in);

  // 4. collision with the planes: contact joints with feedback
  auto t0 = std::chrono::steady_clock::now();
  collide(dt_s);
  last_collision_s_ = seconds_since(t0);

  // 5. dynamics, eq. (3)
  t0 = std::chrono::steady_clock::now();
  if (options_.stepper == OdeStepper::kWorldQuickStep) {
    dWorldQuickStep(world_, dt_s);
  } else {
    dWorldStep(world_, dt_s);
  }
  last_ode_step_s_ = seconds_since(t0);

  // 6. read back joints, tip and contact forces
  read_state();
  sum_contact_forces();

  // actuator torque actually applied: reconstruct the motor row from the new joint rate
  applied_torque(cmd);

  // 7. numerical faults: non-finite or runaway state -> restore the last good pose at rest
  handle_faults(t, ev);

  // contact begin / end events are the world's (server/world/world.cpp), one place for
  // every slave and object

  state_.sim_time_s = t + dt_s;
  ++state_.steps;
}

}  // namespace teleop::sim::robot

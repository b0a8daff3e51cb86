// Tip (sphere) against a deformable closed mesh: detection, continuity, momentum, energy.
#include "server/collision/tip_mesh_contact.hpp"

#include <gtest/gtest.h>

#include <random>

#include "tests/support/alloc_counter.hpp"
#include "tests/unit/server/collision/test_meshes.hpp"

namespace tc = teleop::sim::collision;
using Eigen::Vector3d;

namespace {

constexpr double kDt = 1e-3;

// A toy deformable body for the energy tests (the real one lives in server/deformable): every
// node is held to its rest position by a spring and a damper, plus springs along the edges,
// integrated with symplectic Euler in sub-steps.
struct ToyBody {
  Eigen::Matrix3Xd rest, x, v, f;
  std::vector<std::pair<int, int>> edges;
  std::vector<double> rest_len;
  double mass = 0.002, k_anchor = 200.0, k_edge = 100.0, c = 0.05;

  explicit ToyBody(const tc::testing::Mesh& m) : rest(m.x), x(m.x), v(m.x), f(m.x) {
    v.setZero();
    f.setZero();
    for (int t = 0; t < m.tris.cols(); ++t) {
      for (int k = 0; k < 3; ++k) {
        const int a = m.tris(k, t), b = m.tris((k + 1) % 3, t);
        if (a < b) {
          edges.emplace_back(a, b);
          rest_len.push_back((m.x.col(a) - m.x.col(b)).norm());
        }
      }
    }
  }
  void step(const Eigen::Matrix3Xd& f_ext, double dt, int sub = 4) {
    const double h = dt / sub;
    for (int s = 0; s < sub; ++s) {
      f = f_ext - k_anchor * (x - rest) - c * v;
      for (std::size_t e = 0; e < edges.size(); ++e) {
        const auto [a, b] = edges[e];
        const Vector3d d = x.col(b) - x.col(a);
        const double l = d.norm();
        const Vector3d fe = k_edge * (l - rest_len[e]) * d / l;
        f.col(a) += fe;
        f.col(b) -= fe;
      }
      v += h / mass * f;
      x += h * v;
    }
  }
  double energy() const {
    double e = 0.5 * mass * v.squaredNorm() + 0.5 * k_anchor * (x - rest).squaredNorm();
    for (std::size_t i = 0; i < edges.size(); ++i) {
      const double l = (x.col(edges[i].second) - x.col(edges[i].first)).norm() - rest_len[i];
      e += 0.5 * k_edge * l * l;
    }
    return e;
  }
};

struct PressLog {
  double work_on_tip_j = 0.0;     // trapezoid sum of F . dc over the whole run
  double max_force_jump_n = 0.0;  // max |F(n) - F(n-1)|
  double peak_force_n = 0.0;
  double peak_pen_m = 0.0;
  int contact_steps = 0;
  int begins = 0;
  double body_energy_end_j = 0.0;
};

// Kinematic tip pressed along -z into the top of the sphere at speed v to `depth` below the
// first-touch position, then withdrawn. With a body, the body is stepped each ms.
PressLog press_cycle(tc::TipMeshContact& contact, tc::testing::Mesh& m, ToyBody* body, double speed,
                     double depth, double r, const Vector3d& start) {
  PressLog log;
  Eigen::Matrix3Xd fn(3, m.x.cols());
  const double travel = (start.z() - 0.25 - r) + depth;  // from start to deepest point
  const int n_half = static_cast<int>(std::ceil(travel / (speed * kDt)));
  Vector3d prev = start, f_prev = Vector3d::Zero();
  for (int i = 1; i <= 2 * n_half + 200; ++i) {
    const double s = i <= n_half ? i : std::max(0, 2 * n_half - i);
    const Vector3d now = start - Vector3d(0, 0, s * speed * kDt);
    const Vector3d vel = (now - prev) / kDt;
    fn.setZero();
    const Eigen::Matrix3Xd& xs = body ? body->x : m.x;
    const tc::TipContactResult res =
        body ? contact.update(body->x, &body->v, prev, now, r, vel, kDt, fn)
             : contact.update(xs, prev, now, r, vel, kDt, fn);
    EXPECT_FALSE(res.fault);
    // equal and opposite, every step
    EXPECT_NEAR((fn.rowwise().sum() + res.force_on_tip_n).norm(), 0.0, 1e-9);
    log.work_on_tip_j += 0.5 * (res.force_on_tip_n + f_prev).dot(now - prev);
    if (std::getenv("TIP_DEBUG") && (res.force_on_tip_n - f_prev).norm() > 1.0) {
      std::printf("jump at %d: z %.4f |F| %.3f -> %.3f nodes %d pen %.4f contact %d\n", i, now.z(),
                  f_prev.norm(), res.force_on_tip_n.norm(), res.node_contacts, res.penetration_m,
                  res.in_contact);
    }
    log.max_force_jump_n = std::max(log.max_force_jump_n, (res.force_on_tip_n - f_prev).norm());
    log.peak_force_n = std::max(log.peak_force_n, res.force_on_tip_n.norm());
    log.peak_pen_m = std::max(log.peak_pen_m, res.penetration_m);
    log.contact_steps += res.in_contact ? 1 : 0;
    log.begins += res.began ? 1 : 0;
    f_prev = res.force_on_tip_n;
    prev = now;
    if (body) body->step(fn, kDt);
  }
  if (body) log.body_energy_end_j = body->energy();
  return log;
}

}  // namespace

TEST(TipMeshContact, PressOnRigidSphereIsContinuousConservativeAndBalanced) {
  auto m = tc::testing::icosphere(4, 0.25, Vector3d::Zero());
  tc::TipContactParams p;
  p.stiffness_n_per_m = 2000.0;
  p.damping_ns_per_m = 0.0;
  tc::TipMeshContact contact(p);
  contact.reset(m.x, m.tris);
  const double r = 0.05, v = 0.1;
  const PressLog log = press_cycle(contact, m, nullptr, v, 0.03, r, Vector3d(0, 0, 0.32));
  EXPECT_EQ(log.begins, 1);
  EXPECT_GT(log.contact_steps, 500);
  // a rigid mesh: the tip penetrates the full 30 mm (plus the facet sag below 0.25 m)
  EXPECT_NEAR(log.peak_pen_m, 0.03, 1.5e-3);
  EXPECT_NEAR(log.peak_force_n, 2000.0 * log.peak_pen_m, 1e-6 * 2000.0);
  // continuity: per step the force changes by at most k v dt (0.2 N) plus the small jump of
  // the interpolated normal at onset/across edges
  EXPECT_LE(log.max_force_jump_n, 1.5 * p.stiffness_n_per_m * v * kDt);
  // a conservative spring over a closed path does no net work (trapezoid sum)
  EXPECT_LE(std::abs(log.work_on_tip_j), 1e-3 * 0.5 * 2000.0 * 0.03 * 0.03);
}

TEST(TipMeshContact, PressAndReleaseOnDeformableBodyCreatesNoEnergy) {
  for (double speed : {0.02, 0.1, 0.5}) {
    for (double damping : {0.6, 3.0}) {
      auto m = tc::testing::icosphere(3, 0.25, Vector3d::Zero());
      ToyBody body(m);
      tc::TipContactParams p;
      p.stiffness_n_per_m = 1000.0;
      p.damping_ns_per_m = damping;
      p.friction_static = damping > 1.0 ? 0.5 : 0.0;  // slippery and sticky tips
      p.friction_kinetic = 0.8 * p.friction_static;
      tc::TipMeshContact contact(p);
      contact.reset(m.x, m.tris);
      const PressLog log = press_cycle(contact, m, &body, speed, 0.03, 0.05, Vector3d(0, 0, 0.31));
      ASSERT_GT(log.contact_steps, 0);
      std::printf(
          "speed %.2f b %.1f: work on tip %.5f J, body energy %.5f J, peak F %.2f N, "
          "max jump %.3f N\n",
          speed, damping, log.work_on_tip_j, log.body_energy_end_j, log.peak_force_n,
          log.max_force_jump_n);
      // energy put into the body by the tip is -work_on_tip >= 0: the contact never hands
      // back more than it took (tolerance: 2 % of the peak spring energy k x^2 / 2)
      const double stored = 0.5 * 1000.0 * 0.03 * 0.03;
      EXPECT_LE(log.work_on_tip_j, 0.02 * stored) << "speed " << speed << " b " << damping;
      // and what is left in the body cannot exceed what the tip put in
      EXPECT_LE(log.body_energy_end_j, -log.work_on_tip_j + 0.02 * stored);
      // the body yields: the contact spring and the body are in series
      EXPECT_LT(log.peak_force_n, 1000.0 * 0.035);
    }
  }
}

TEST(TipMeshContact, NoTunnellingThroughThinClosedSlabAt10mps) {
  // a 1 mm thick slab; a 2 mm tip moving 10 m/s crosses it in one 1 ms step
  auto m = tc::testing::box_mesh(Vector3d(-0.5, -0.5, -0.0005), Vector3d(0.5, 0.5, 0.0005));
  tc::TipMeshContact contact;
  contact.reset(m.x, m.tris);
  Eigen::Matrix3Xd fn = Eigen::Matrix3Xd::Zero(3, m.x.cols());
  const Vector3d v(0.0, 0.0, -10.0);
  for (double x0 : {0.0, 0.1234, -0.37}) {
    contact.release();
    const Vector3d prev(x0, 0.05, 0.006), now = prev + v * kDt;  // ends at z = -0.004
    const auto res = contact.update(m.x, prev, now, 0.002, v, kDt, fn);
    ASSERT_TRUE(res.in_contact);
    EXPECT_TRUE(res.began);
    EXPECT_GT(res.force_on_tip_n.z(), 0.0);  // pushed back out through the side it entered
    EXPECT_NEAR(res.entry_point_m.z(), 0.0005, 1e-9);
    EXPECT_NEAR(res.penetration_m, 0.0005 + 0.002 + 0.004, 1e-8);
  }
}

TEST(TipMeshContact, NoTunnellingThroughOpenSheetAndAgainstDenseSampling) {
  // an open 2-triangle sheet: only continuous detection can see a tip that jumps over it
  tc::testing::Mesh sheet;
  sheet.x.resize(3, 4);
  sheet.x << -1, 1, 1, -1, -1, -1, 1, 1, 0, 0, 0, 0;
  sheet.tris.resize(3, 2);
  sheet.tris << 0, 0, 1, 2, 2, 3;
  tc::TipMeshContact contact;
  contact.reset(sheet.x, sheet.tris);
  EXPECT_FALSE(contact.topology().closed());
  Eigen::Matrix3Xd fn = Eigen::Matrix3Xd::Zero(3, 4);
  auto res = contact.update(sheet.x, Vector3d(0.2, 0.1, 0.3), Vector3d(0.2, 0.1, -0.3), 0.05,
                            Vector3d(0, 0, -600), kDt, fn);
  ASSERT_TRUE(res.in_contact);
  EXPECT_GT(res.force_on_tip_n.z(), 0.0);
  // from below the side flips: pushed down
  contact.release();
  res = contact.update(sheet.x, Vector3d(0.2, 0.1, -0.3), Vector3d(0.2, 0.1, 0.3), 0.05,
                       Vector3d(0, 0, 600), kDt, fn);
  ASSERT_TRUE(res.in_contact);
  EXPECT_LT(res.force_on_tip_n.z(), 0.0);

  // random 10 m/s steps against a sphere: contact whenever dense sampling of the path finds
  // the tip sphere overlapping the surface at any instant
  auto m = tc::testing::icosphere(3, 0.25, Vector3d::Zero());
  tc::TipMeshContact c2;
  c2.reset(m.x, m.tris);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Matrix3Xd f2 = Eigen::Matrix3Xd::Zero(3, m.x.cols());
  int touching = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Vector3d a = 0.32 * Vector3d(u(rng), u(rng), u(rng));
    const Vector3d dir = Vector3d(u(rng), u(rng), u(rng)).normalized();
    const double r = 0.002;
    const Vector3d b = a + 0.01 * dir;  // 10 mm in 1 ms
    bool sampled = false;
    for (int s = 0; s <= 1000 && !sampled; ++s) {
      const Vector3d p = a + (s / 1000.0) * (b - a);
      sampled = std::abs(c2.signed_distance(p, m.x)) < r || c2.inside(p, m.x);
    }
    c2.release();
    const auto rr = c2.update(m.x, a, b, r, 10.0 * dir, kDt, f2);
    const bool ends_clear = c2.signed_distance(b, m.x) > r;
    if (sampled) ++touching;
    // a touch during the step that is gone at its end gives no contact; otherwise it must
    if (sampled && !ends_clear) {
      EXPECT_TRUE(rr.in_contact) << trial;
    }
    if (!sampled) {
      EXPECT_FALSE(rr.in_contact) << trial;
    }
  }
  EXPECT_GT(touching, 20);
}

TEST(TipMeshContact, TipInsideHollowSphereIsInside) {
  auto m = tc::testing::icosphere(4, 0.25, Vector3d(0.1, -0.2, 0.3));
  // a smooth bump so the mesh is not a perfect sphere
  for (int i = 0; i < m.x.cols(); ++i) {
    const Vector3d d = m.x.col(i) - Vector3d(0.1, -0.2, 0.3);
    m.x.col(i) += 0.03 * std::sin(8.0 * d.x()) * d.normalized();
  }
  tc::TipMeshContact contact;
  contact.reset(m.x, m.tris);
  contact.tree().refit(m.x);
  Eigen::Matrix3Xd fn = Eigen::Matrix3Xd::Zero(3, m.x.cols());
  const Vector3d c(0.1, -0.2, 0.3);
  const auto res = contact.update(m.x, c, c, 0.05, Vector3d::Zero(), kDt, fn);
  ASSERT_TRUE(res.in_contact);
  EXPECT_TRUE(res.inside);
  EXPECT_GT(res.penetration_m, 0.05 + 0.2);
  EXPECT_TRUE(contact.inside(c, m.x));
  // the pseudo-normal test agrees with the generalised winding number everywhere
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-0.33, 0.33);
  int in = 0;
  for (int i = 0; i < 500; ++i) {
    const Vector3d p = c + Vector3d(u(rng), u(rng), u(rng));
    const bool wn = tc::winding_number(p, m.x, m.tris) > 0.5;
    EXPECT_EQ(contact.inside(p, m.x), wn) << p.transpose();
    EXPECT_EQ(contact.signed_distance(p, m.x) < 0.0, wn);
    in += wn ? 1 : 0;
  }
  EXPECT_GT(in, 50);
}

TEST(TipMeshContact, CoulombFrictionSticksThenSlides) {
  auto m = tc::testing::box_mesh(Vector3d(-1, -1, -0.2), Vector3d(1, 1, 0.0));
  tc::TipContactParams p;
  p.stiffness_n_per_m = 1000.0;
  p.damping_ns_per_m = 0.0;
  p.friction_static = 0.5;
  p.friction_kinetic = 0.3;
  tc::TipMeshContact contact(p);
  contact.reset(m.x, m.tris);
  Eigen::Matrix3Xd fn = Eigen::Matrix3Xd::Zero(3, m.x.cols());
  const double r = 0.05;
  // press 10 mm: F_n = 10 N
  Vector3d prev(0.1, 0.05, 0.06), now(0.1, 0.05, 0.04);
  auto res = contact.update(m.x, prev, now, r, Vector3d(0, 0, -20), kDt, fn);
  ASSERT_TRUE(res.in_contact);
  EXPECT_NEAR(res.normal_force_n, 10.0, 1e-9);
  // small tangential moves: stick, F_t = -k dx
  prev = now;
  now = prev + Vector3d(0.003, 0, 0);
  res = contact.update(m.x, prev, now, r, Vector3d(3, 0, 0), kDt, fn);
  EXPECT_FALSE(res.sliding);
  EXPECT_NEAR(res.force_on_tip_n.x(), -3.0, 1e-9);
  // past mu_s F_n = 5 N: slide back to |F_t| = mu_k F_n = 3 N, then stick again (stick-slip);
  // the tangential force always opposes the motion and stays within [mu_k, mu_s] F_n
  int slides = 0;
  for (int i = 0; i < 20; ++i) {
    prev = now;
    now = prev + Vector3d(0.001, 0, 0);
    res = contact.update(m.x, prev, now, r, Vector3d(1, 0, 0), kDt, fn);
    if (res.sliding) {
      ++slides;
      EXPECT_NEAR(res.force_on_tip_n.x(), -3.0, 1e-6);
      EXPECT_NEAR(res.contact_point_m.x(), now.x() - 0.003, 1e-6);  // trails by mu_k F_n / k
    }
    EXPECT_LE(res.force_on_tip_n.x(), -3.0 + 1e-6);
    EXPECT_GE(res.force_on_tip_n.x(), -5.0 - 1e-6);
    EXPECT_NEAR(res.normal_force_n, 10.0, 1e-9);
  }
  EXPECT_GE(slides, 6);
  // frictionless ("slippery"): no tangential force at all
  p.friction_static = p.friction_kinetic = 0.0;
  contact.set_params(p);
  prev = now;
  now = prev + Vector3d(0.002, 0.001, 0);
  res = contact.update(m.x, prev, now, r, Vector3d(2, 1, 0), kDt, fn);
  EXPECT_TRUE(res.in_contact);
  EXPECT_NEAR(res.tangential_force_n, 0.0, 1e-9);
}

TEST(TipMeshContact, UpdateAllocatesNothing) {
  auto m = tc::testing::icosphere(4, 0.25, Vector3d::Zero());
  tc::TipContactParams p;
  p.friction_static = 0.05;
  p.friction_kinetic = 0.1;
  tc::TipMeshContact contact(p);
  contact.reset(m.x, m.tris);
  Eigen::Matrix3Xd fn = Eigen::Matrix3Xd::Zero(3, m.x.cols());
  Vector3d prev(0.0, 0.0, 0.35);
  Eigen::Matrix3Xd v = Eigen::Matrix3Xd::Zero(3, m.x.cols());
  teleop::sim::EventQueue events;
  teleop::test::NoAllocScope scope;
  int contacts = 0;
  for (int i = 0; i < 600; ++i) {
    const Vector3d now = prev + Vector3d(i > 300 ? 0.0005 : 0.0, 0.0, i > 300 ? 0.0 : -0.0002);
    m.x.col(i % m.x.cols()) *= 0.9999;  // the surface moves: refit every step
    const auto res = contact.update(m.x, prev, now, 0.05, (now - prev) / kDt, kDt, fn);
    contacts += res.in_contact ? 1 : 0;
    prev = now;
  }
  // the overload with node velocities, and the event helper: press and leave once
  contact.release();
  prev = Vector3d(0.0, 0.0, 0.31);
  for (int i = 0; i < 200; ++i) {
    const Vector3d now = prev + Vector3d(0.0, 0.0, i < 100 ? -0.0002 : 0.0004);
    const auto res = contact.update(m.x, &v, prev, now, 0.05, (now - prev) / kDt, kDt, fn);
    tc::push_contact_events(res, 3, i * kDt, events);
    prev = now;
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_GT(contacts, 100);
  teleop::sim::SimEvent e;
  int begins = 0, ends = 0;
  while (events.pop(e)) {
    begins += e.kind == teleop::sim::EventKind::kContactBegin;
    ends += e.kind == teleop::sim::EventKind::kContactEnd;
  }
  EXPECT_EQ(begins, 1);
  EXPECT_EQ(ends, 1);
}

TEST(TipMeshContact, NonFiniteInputIsAFaultNotACrash) {
  auto m = tc::testing::icosphere(2, 0.25, Vector3d::Zero());
  tc::TipMeshContact contact;
  contact.reset(m.x, m.tris);
  Eigen::Matrix3Xd fn = Eigen::Matrix3Xd::Zero(3, m.x.cols());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto res = contact.update(m.x, Vector3d(0, 0, 0.3), Vector3d(nan, 0, 0.2), 0.05, Vector3d::Zero(),
                            kDt, fn);
  EXPECT_TRUE(res.fault);
  EXPECT_FALSE(res.in_contact);
  m.x(0, 5) = nan;
  res = contact.update(m.x, Vector3d(0, 0, 0.3), Vector3d(0, 0, 0.2), 0.05, Vector3d::Zero(), kDt,
                       fn);
  EXPECT_TRUE(res.fault);
  EXPECT_EQ(contact.fault_count(), 2u);
  EXPECT_TRUE(fn.isZero());
}

#pragma once
// Shared by the benchmarks that run a peer beside our deformable ball (peers-fem, deformable):
// the coordinate of a Lamb mode in a displacement field, and (with TELEOP_HAVE_BULLET) Bullet's
// deformable FEM (btDeformableMultiBodyDynamicsWorld + btDeformableLinearElasticityForce,
// Debian's libbullet-dev, single precision) built on one of our tetrahedral meshes: no gravity,
// no planes, no damping, the material's Lame coefficients, the mass a quarter of each
// tetrahedron's share on its nodes (setVolumeMass), like ours.
#include <Eigen/Core>
#include <chrono>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "common/mesh/tet_mesh.hpp"
#include "server/world/physics_validation.hpp"

#ifdef TELEOP_HAVE_BULLET
// Bullet's deformable headers instantiate code GCC flags as maybe uninitialized (in Bullet)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <BulletSoftBody/btDeformableBodySolver.h>
#include <BulletSoftBody/btDeformableLinearElasticityForce.h>
#include <BulletSoftBody/btDeformableMultiBodyConstraintSolver.h>
#include <BulletSoftBody/btDeformableMultiBodyDynamicsWorld.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <btBulletDynamicsCommon.h>
#endif

namespace teleop::bench {

/// Mass-weighted projection of the displacement x - x0 (centroid motion removed) on the field phi.
inline double mode_coordinate(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x0,
                              const Eigen::Matrix3Xd& phi, const Eigen::VectorXd& mass) {
  const Eigen::Vector3d c = x * mass / mass.sum(), c0 = x0 * mass / mass.sum();
  double acc = 0.0;
  for (Eigen::Index i = 0; i < x.cols(); ++i) {
    acc += mass(i) * ((x.col(i) - c) - (x0.col(i) - c0)).dot(phi.col(i));
  }
  return acc;
}

/// The velocity field that starts `mode` at the rest positions x0 (about their mean), scaled to
/// 2 cm/s at most: a small-strain vibration, as sim::validation::free_vibration_hz starts it.
inline Eigen::Matrix3Xd mode_field(sim::validation::LambMode mode, const Eigen::Matrix3Xd& x0) {
  const Eigen::Vector3d c0 = x0.rowwise().mean();
  Eigen::Matrix3Xd phi(3, x0.cols());
  for (Eigen::Index i = 0; i < x0.cols(); ++i) {
    phi.col(i) =
        sim::validation::lamb_mode_field(mode, (x0.col(i) - c0) / sim::validation::kBallRadiusM);
  }
  return phi * (0.02 / phi.colwise().norm().maxCoeff());
}

#ifdef TELEOP_HAVE_BULLET
/// Bullet's tetrahedral soft body of a mesh and material, in a world of its own.
class BulletTetBall {
 public:
  /// implicit: Bullet's implicit step (Newton-CG), else its explicit one.
  BulletTetBall(const teleop::mesh::TetMesh& tm, const sim::validation::Material& material,
                double mass_kg, bool implicit) {
    // TetGen's text format, which Bullet reads (0-based indices)
    std::ostringstream node, ele;
    node.precision(17);
    node << tm.node_count() << " 3 0 0\n";
    for (int i = 0; i < tm.node_count(); ++i) {
      node << i << " " << tm.vertices(0, i) << " " << tm.vertices(1, i) << " " << tm.vertices(2, i)
           << "\n";
    }
    ele << tm.tet_count() << " 4 0\n";
    for (int t = 0; t < tm.tet_count(); ++t) {
      ele << t << " " << tm.tets(0, t) << " " << tm.tets(1, t) << " " << tm.tets(2, t) << " "
          << tm.tets(3, t) << "\n";
    }
    config_ = std::make_unique<btSoftBodyRigidBodyCollisionConfiguration>();
    dispatcher_ = std::make_unique<btCollisionDispatcher>(config_.get());
    broadphase_ = std::make_unique<btDbvtBroadphase>();
    body_solver_ = std::make_unique<btDeformableBodySolver>();
    solver_ = std::make_unique<btDeformableMultiBodyConstraintSolver>();
    solver_->setDeformableSolver(body_solver_.get());
    world_ = std::make_unique<btDeformableMultiBodyDynamicsWorld>(
        dispatcher_.get(), broadphase_.get(), solver_.get(), config_.get(), body_solver_.get());
    world_->setGravity(btVector3(0, 0, 0));
    world_->getWorldInfo().m_gravity.setValue(0, 0, 0);
    world_->getWorldInfo().m_sparsesdf.Initialize();
    world_->setImplicit(implicit);
    const std::string ele_text = ele.str(), node_text = node.str();
    body_ = btSoftBodyHelpers::CreateFromTetGenData(world_->getWorldInfo(), ele_text.c_str(),
                                                    nullptr, node_text.c_str(), false, true, true);
    world_->addSoftBody(body_);
    body_->setVolumeMass(static_cast<btScalar>(mass_kg));
    body_->m_cfg.kDF = 0;
    body_->m_sleepingThreshold = 0;
    const double nu = material.poisson_ratio, e = material.youngs_modulus_pa;
    force_ = std::make_unique<btDeformableLinearElasticityForce>(
        static_cast<btScalar>(e / (2 * (1 + nu))),
        static_cast<btScalar>(e * nu / ((1 + nu) * (1 - 2 * nu))), 0, 0);
    world_->addForce(body_, force_.get());
  }
  ~BulletTetBall() {
    world_->removeSoftBody(body_);
    delete body_;
  }
  BulletTetBall(const BulletTetBall&) = delete;
  BulletTetBall& operator=(const BulletTetBall&) = delete;

  int node_count() const { return body_->m_nodes.size(); }
  /// Node positions into x (3 x node_count, sized by the caller).
  void positions(Eigen::Matrix3Xd& x) const {
    for (int i = 0; i < body_->m_nodes.size(); ++i) {
      const btVector3& p = body_->m_nodes[i].m_x;
      x.col(i) = Eigen::Vector3d(p.x(), p.y(), p.z());
    }
  }
  /// Node masses [kg] (1 / Bullet's inverse mass).
  Eigen::VectorXd masses() const {
    Eigen::VectorXd m(body_->m_nodes.size());
    for (int i = 0; i < body_->m_nodes.size(); ++i) {
      const double im = static_cast<double>(body_->m_nodes[i].m_im);
      m(i) = im > 0.0 ? 1.0 / im : 0.0;
    }
    return m;
  }
  void set_velocities(const Eigen::Matrix3Xd& v) {
    for (int i = 0; i < body_->m_nodes.size(); ++i) {
      body_->m_nodes[i].m_v =
          btVector3(static_cast<btScalar>(v(0, i)), static_cast<btScalar>(v(1, i)),
                    static_cast<btScalar>(v(2, i)));
    }
  }
  /// One world step of dt_s (no internal sub-steps).
  void step(double dt_s) { world_->stepSimulation(static_cast<btScalar>(dt_s), 0); }

 private:
  std::unique_ptr<btSoftBodyRigidBodyCollisionConfiguration> config_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btDbvtBroadphase> broadphase_;
  std::unique_ptr<btDeformableBodySolver> body_solver_;
  std::unique_ptr<btDeformableMultiBodyConstraintSolver> solver_;
  std::unique_ptr<btDeformableMultiBodyDynamicsWorld> world_;
  std::unique_ptr<btDeformableLinearElasticityForce> force_;
  btSoftBody* body_ = nullptr;
};

/// One free vibration of Bullet's ball of `tm`, started by the velocity field of `mode`.
struct BulletModeRun {
  std::vector<double> q;        ///< the mode's coordinate after each step
  std::vector<double> step_us;  ///< wall time of each world step
  bool finite = true;           ///< false once a position was not finite (it blew up)
};

inline BulletModeRun run_bullet_mode(const teleop::mesh::TetMesh& tm,
                                     const sim::validation::Material& material, double mass_kg,
                                     sim::validation::LambMode mode, double dt_s, int steps,
                                     bool implicit) {
  BulletTetBall ball(tm, material, mass_kg, implicit);
  Eigen::Matrix3Xd x0(3, ball.node_count()), x(3, ball.node_count());
  ball.positions(x0);
  const Eigen::VectorXd mass = ball.masses();
  const Eigen::Matrix3Xd phi = mode_field(mode, x0);
  ball.set_velocities(phi);
  BulletModeRun r;
  r.q.reserve(static_cast<std::size_t>(steps));
  r.step_us.reserve(static_cast<std::size_t>(steps));
  for (int k = 0; k < steps; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    ball.step(dt_s);
    const auto t1 = std::chrono::steady_clock::now();
    r.step_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    ball.positions(x);
    r.finite = r.finite && x.allFinite();
    r.q.push_back(r.finite ? mode_coordinate(x, x0, phi, mass) : 0.0);
  }
  return r;
}
#endif

}  // namespace teleop::bench

// The automatic step: the highest natural frequency of the body, its damping, and from them
// the largest step the integrator is stable at (see docs/deformable.md, "Automatic step").
//
// w_max^2 is the largest eigenvalue of M^-1 K, K the stiffness linearised at the rest shape
// (edge springs / Navier edges and radial springs, the centre node a free mass; plane contact and
// the caller's loads excluded). It is estimated by Lanczos iteration (a Krylov refinement of power
// iteration: the same matrix-vector products, the top Ritz value of the tridiagonal matrix
// converges in tens of products where plain power iteration needs thousands on this nearly
// degenerate spectrum) on A = M^-1/2 K M^-1/2, which has the same eigenvalues. A Ritz value never
// exceeds the true eigenvalue; the block Gershgorin bound is computed as the upper bracket.
// The co-rotational model uses the linear-strain K: co-rotation removes the stiffness of
// rotation-like motions, so its true w_max is a little lower (0.1-0.4 % on levels 1-2).
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "server/deformable/deformable.hpp"
#include "server/deformable/fem.hpp"

namespace teleop::sim::deformable {

namespace {

// (K_e p, K_r p) at rest for p with 3N (+3 centre) dofs: K_e the edges, K_r the radial springs.
// An edge block is a I + b u u^T (mass-spring: a = 0, b = k; Navier: a = k_iso, b = k_dir).
void apply_rest_stiffness(const DeformableModel& m, const Eigen::VectorXd& p, Eigen::VectorXd& ke,
                          Eigen::VectorXd& kr) {
  const int n = m.node_count;
  ke.setZero(p.size());
  kr.setZero(p.size());
  const bool spring = m.params.model == ModelKind::kMassSpring;
  for (int e = 0; e < m.edges.cols(); ++e) {
    const int i = m.edges(0, e), j = m.edges(1, e);
    const Eigen::Vector3d u = m.rest_dir.col(e);
    const Eigen::Vector3d d = p.segment<3>(3 * i) - p.segment<3>(3 * j);
    const double a = spring ? 0.0 : m.edge_k_iso(e);
    const double b = spring ? m.edge_k_iso(e) : m.edge_k_dir(e);
    const Eigen::Vector3d y = a * d + (b * u.dot(d)) * u;
    ke.segment<3>(3 * i) += y;
    ke.segment<3>(3 * j) -= y;
  }
  if (m.has_centre) {
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d u = (m.mesh.vertices.col(i) - m.rest_centre_m).normalized();
      const Eigen::Vector3d d = p.segment<3>(3 * i) - p.segment<3>(3 * n);
      const Eigen::Vector3d y = (m.radial_k(i) * u.dot(d)) * u;
      kr.segment<3>(3 * i) += y;
      kr.segment<3>(3 * n) -= y;
    }
  }
}

// A fixed pseudo-random start vector (splitmix64): the estimate is deterministic.
double hashed_unit(std::uint64_t k) {
  std::uint64_t z = k + 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

}  // namespace

double gershgorin_omega_bound(const DeformableModel& m) {
  if (m.params.model == ModelKind::kFem) return std::sqrt(detail::fem_gershgorin_lambda(m));
  // Block Gershgorin on M^-1 K (3x3 blocks, spectral norms): lambda <= max over block rows of
  // (||K_ii|| + sum_j ||K_ij||) / m_i. An edge block a I + b u u^T has norm a + b and appears on
  // the diagonal of both ends and once off it; a radial spring k_r u u^T on node i's diagonal,
  // the centre's diagonal and off both. So for node i: 2 (k_r,i + sum_j (a_ij + b_ij)) / m_i
  // (with the radial spring tied to a fixed point instead of a free centre node this is the
  // textbook (k_r + 2 sum_j k_ij) / m_i), for the centre node 2 sum_i k_r,i / m_c.
  const int n = m.node_count;
  Eigen::VectorXd row = Eigen::VectorXd::Zero(n);
  for (int e = 0; e < m.edges.cols(); ++e) {
    const double norm = m.edge_k_iso(e) + m.edge_k_dir(e);
    row(m.edges(0, e)) += norm;
    row(m.edges(1, e)) += norm;
  }
  double lambda = 0.0;
  double centre_row = 0.0;
  for (int i = 0; i < n; ++i) {
    const double kr = m.has_centre ? m.radial_k(i) : 0.0;
    lambda = std::max(lambda, 2.0 * (row(i) + kr) / m.mass_kg(i));
    centre_row += kr;
  }
  if (m.has_centre) lambda = std::max(lambda, 2.0 * centre_row / m.centre_mass_kg);
  return std::sqrt(lambda);
}

namespace {

// The integrator's stability limit [s] for the top mode (angular frequency wmax [rad/s], damping
// ratio zeta); infinite without stiffness and for implicit Euler.
double integrator_step_limit(const DeformableModel& m, double wmax, double zeta) {
  const DeformableParams& prm = m.params;
  const double inf = std::numeric_limits<double>::infinity();
  switch (prm.integrator) {
    case IntegratorKind::kSymplecticEuler:
      // v += h (-w^2 x - 2 zeta w v), x += h v: stable iff h w <= 2 (sqrt(1 + zeta^2) - zeta)
      return wmax > 0.0 ? 2.0 * (std::sqrt(1.0 + zeta * zeta) - zeta) / wmax : inf;
    case IntegratorKind::kExplicitEuler: {
      // |1 + h s|^2 = 1 - 2 zeta w h + w^2 h^2 <= 1 iff h <= 2 zeta / w, for every mode. With
      // C = beta_e K_e + beta_r K_r + alpha M, 2 zeta / w = psi^T C psi / psi^T K psi >=
      // min(beta_e, beta_r) over the spring kinds present: sufficient for all modes at once.
      double tau = inf;
      if (m.params.model == ModelKind::kFem) tau = prm.stiffness_damping_s;
      if (m.edge_k_iso.size() > 0 && m.edge_k_iso.maxCoeff() > 0.0) {
        tau = std::min(tau, prm.stiffness_damping_s);
      }
      if (m.has_centre) tau = std::min(tau, prm.radial_damping_s);
      return wmax > 0.0 ? tau : inf;
    }
    case IntegratorKind::kImplicitEuler:
      return inf;  // unconditionally stable: never sub-steps
  }
  return 0.0;  // not reached: every integrator is handled above
}

/// Top eigenvalue of the symmetric operator `apply` (y = A q) on `dofs` unknowns by Lanczos
/// (a Ritz value: a lower bound that converges to it in tens of products).
template <class Apply>
double lanczos_top(int dofs, int iterations, Apply&& apply) {
  Eigen::VectorXd q(dofs), q_prev = Eigen::VectorXd::Zero(dofs), w(dofs);
  for (int k = 0; k < dofs; ++k) q(k) = hashed_unit(static_cast<std::uint64_t>(k));
  q.normalize();
  std::vector<double> alpha, beta;
  for (int k = 0; k < iterations; ++k) {
    apply(q, w);
    alpha.push_back(q.dot(w));
    w -= alpha.back() * q;
    if (k > 0) w -= beta.back() * q_prev;
    beta.push_back(w.norm());
    if (!(beta.back() > 1e-12 * std::abs(alpha.back()))) break;
    q_prev = q;
    q = w / beta.back();
  }
  const auto used = static_cast<Eigen::Index>(alpha.size());
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(used, used);
  for (Eigen::Index k = 0; k < used; ++k) {
    t(k, k) = alpha[static_cast<std::size_t>(k)];
    if (k + 1 < used) t(k, k + 1) = t(k + 1, k) = beta[static_cast<std::size_t>(k)];
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(t, Eigen::EigenvaluesOnly);
  return used > 0 ? std::max(es.eigenvalues()(used - 1), 0.0) : 0.0;
}

/// Symplectic Euler's limits besides the top mode's [s]: a node on a plane adds its contact
/// spring k_i = m_i w_c^2 (w_c = contact_frequency_rad_per_s; its damping is an implicit
/// impulse), stable for h sqrt(w_max^2 + w_c^2) <= 2 (the top of M^-1 (K + K_c) is at most
/// w_max^2 + w_c^2); and a heavily damped mode below the top frequency (the radial springs' with
/// a large radial_damping_s) needs h c <= 2 for the top c of M^-1 C, C = beta_e K_e + beta_r K_r
/// + alpha M (`apply_damping`: y = M^-1/2 (beta_e K_e + beta_r K_r) M^-1/2 q).
template <class Apply>
double contact_and_damping_limit_s(const DeformableModel& m, double wmax, int dofs, int iterations,
                                   Apply&& apply_damping) {
  double h = std::numeric_limits<double>::infinity();
  if (m.plane_count > 0) {
    const double wc = m.params.contact_frequency_rad_per_s;
    h = 2.0 / std::sqrt(wmax * wmax + wc * wc);
  }
  const double c = m.params.mass_damping_per_s + lanczos_top(dofs, iterations, apply_damping);
  return c > 0.0 ? std::min(h, 2.0 / c) : h;
}

// y = A q = M^-1/2 K M^-1/2 q, with the edge and radial parts apart (for the damping ratio;
// model fem: all of it elastic).
class ScaledStiffness {
 public:
  explicit ScaledStiffness(const DeformableModel& m)
      : m_(m),
        fem_(m.params.model == ModelKind::kFem),
        n_(fem_ ? m.fem.node_count : m.node_count),
        dofs_(3 * n_ + (m.has_centre ? 3 : 0)),
        inv_sqrt_m_(dofs_),
        p_(dofs_),
        ke_(dofs_),
        kr_(dofs_) {
    for (int i = 0; i < n_; ++i) {
      inv_sqrt_m_.segment<3>(3 * i).setConstant(1.0 /
                                                std::sqrt(fem_ ? m.fem.mass_kg(i) : m.mass_kg(i)));
    }
    if (m.has_centre) inv_sqrt_m_.tail<3>().setConstant(1.0 / std::sqrt(m.centre_mass_kg));
  }

  int dofs() const { return dofs_; }
  bool fem() const { return fem_; }

  void apply(const Eigen::VectorXd& q, Eigen::VectorXd& ye, Eigen::VectorXd& yr) {
    p_ = inv_sqrt_m_.cwiseProduct(q);
    if (fem_) {
      detail::fem_apply_rest_stiffness(m_, p_, ke_);
      kr_.setZero(dofs_);
    } else {
      apply_rest_stiffness(m_, p_, ke_, kr_);
    }
    ye = inv_sqrt_m_.cwiseProduct(ke_);
    yr = inv_sqrt_m_.cwiseProduct(kr_);
  }

 private:
  const DeformableModel& m_;
  bool fem_;
  int n_, dofs_;
  Eigen::VectorXd inv_sqrt_m_, p_, ke_, kr_;
};

// The Lanczos tridiagonalisation of A from a fixed start vector, and its largest Ritz pair.
struct LanczosTop {
  Eigen::VectorXd q0, alpha, beta;
  int used = 0;
  double lambda = 0.0;   // the largest Ritz value (>= 0)
  Eigen::VectorXd ritz;  // its eigenvector in the Lanczos basis
};

// Lanczos without reorthogonalisation (its loss of orthogonality only duplicates converged Ritz
// values; the largest one is still a lower bound that converges to lambda_max).
LanczosTop lanczos_top(ScaledStiffness& a, int iterations) {
  const int dofs = a.dofs();
  LanczosTop out;
  out.alpha.resize(iterations);
  out.beta.resize(iterations);
  out.q0.resize(dofs);
  for (int k = 0; k < dofs; ++k) out.q0(k) = hashed_unit(static_cast<std::uint64_t>(k));
  out.q0.normalize();
  Eigen::VectorXd q = out.q0, q_prev = Eigen::VectorXd::Zero(dofs), w(dofs), ye(dofs), yr(dofs);
  for (int k = 0; k < iterations; ++k) {
    a.apply(q, ye, yr);
    w = ye + yr;
    out.alpha(k) = q.dot(w);
    w -= out.alpha(k) * q;
    if (k > 0) w -= out.beta(k - 1) * q_prev;
    out.beta(k) = w.norm();
    ++out.used;
    if (!(out.beta(k) > 1e-12 * std::abs(out.alpha(k)))) break;  // invariant subspace: exact
    q_prev = q;
    q = w / out.beta(k);
  }
  const int used = out.used;
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(used, used);
  for (int k = 0; k < used; ++k) {
    t(k, k) = out.alpha(k);
    if (k + 1 < used) t(k, k + 1) = t(k + 1, k) = out.beta(k);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(t);
  const Eigen::Index top = used - 1;  // eigenvalues ascending
  out.lambda = std::max(es.eigenvalues()(top), 0.0);
  out.ritz = es.eigenvectors().col(top);
  return out;
}

// The top mode's Ritz vector (a second pass regenerates the Lanczos vectors) and the shares of
// its stiffness carried by the edges and by the radial springs.
void top_mode_shares(ScaledStiffness& a, const LanczosTop& l, double& share_e, double& share_r) {
  const int dofs = a.dofs();
  Eigen::VectorXd psi = Eigen::VectorXd::Zero(dofs);
  Eigen::VectorXd q = l.q0, q_prev = Eigen::VectorXd::Zero(dofs), w(dofs), ye(dofs), yr(dofs);
  for (int k = 0; k < l.used; ++k) {
    psi += l.ritz(k) * q;
    if (k + 1 == l.used) break;
    a.apply(q, ye, yr);
    w = ye + yr - l.alpha(k) * q;
    if (k > 0) w -= l.beta(k - 1) * q_prev;
    q_prev = q;
    q = w / l.beta(k);
  }
  const double psi_norm = psi.norm();
  share_e = 1.0;
  share_r = 0.0;
  if (psi_norm > 0.0 && l.lambda > 0.0) {
    psi /= psi_norm;
    a.apply(psi, ye, yr);
    const double e = std::max(psi.dot(ye), 0.0), r = std::max(psi.dot(yr), 0.0);
    if (e + r > 0.0) {
      share_e = e / (e + r);
      share_r = r / (e + r);
    }
  }
}

}  // namespace

StabilityEstimate estimate_stability(const DeformableModel& m) {
  StabilityEstimate out;
  out.omega_bound_rad_per_s = gershgorin_omega_bound(m);
  ScaledStiffness a(m);
  const int dofs = a.dofs();
  const int iterations = std::min(dofs, kStabilityLanczosIterations);
  const LanczosTop l = lanczos_top(a, iterations);
  const double lambda = l.lambda;
  out.omega_max_rad_per_s = std::sqrt(lambda);
  out.lanczos_iterations = l.used;

  // the damping ratio of the top mode
  //   zeta = (beta_e psi^T A_e psi + beta_r psi^T A_r psi + alpha) / (2 w)
  // (C = beta_e K_e + beta_r K_r + alpha M; the drag is relative to the mean velocity, which the
  // top mode does not move, so alpha M is its exact contribution there).
  double share_e = 1.0, share_r = 0.0;
  top_mode_shares(a, l, share_e, share_r);
  const DeformableParams& prm = m.params;
  const double wmax = out.omega_max_rad_per_s;
  out.radial_share = share_r;
  out.damping_ratio = wmax > 0.0
                          ? (prm.stiffness_damping_s * share_e * lambda +
                             prm.radial_damping_s * share_r * lambda + prm.mass_damping_per_s) /
                                (2.0 * wmax)
                          : 0.0;

  // the largest stable step of the integrator for that mode, times the safety factor
  out.limit_step_s = integrator_step_limit(m, out.omega_max_rad_per_s, out.damping_ratio);
  if (!a.fem() && prm.integrator == IntegratorKind::kSymplecticEuler) {
    Eigen::VectorXd ye(dofs), yr(dofs);
    out.limit_step_s =
        std::min(out.limit_step_s,
                 contact_and_damping_limit_s(
                     m, wmax, dofs, iterations, [&](const Eigen::VectorXd& q, Eigen::VectorXd& y) {
                       a.apply(q, ye, yr);
                       y = prm.stiffness_damping_s * ye + prm.radial_damping_s * yr;
                     }));
  }
  out.stable_step_s = kStableStepSafety * out.limit_step_s;
  return out;
}

void update_stable_step(DeformableModel& m) {
  const StabilityEstimate est = estimate_stability(m);
  m.omega_max_rad_per_s = est.omega_max_rad_per_s;
  m.omega_bound_rad_per_s = est.omega_bound_rad_per_s;
  m.damping_ratio_top = est.damping_ratio;
  m.stable_step_s = est.stable_step_s;
}

namespace {
int stability_substeps(const DeformableModel& m, double dt_s) {
  if (!(dt_s > m.stable_step_s)) return 1;  // also: implicit Euler (stable step = inf), bad dt
  if (!(m.stable_step_s > 0.0)) return 1;   // unstable at any step: sub-steps would not help
  const double n = std::ceil(dt_s / m.stable_step_s);
  return n >= static_cast<double>(m.params.max_substeps) ? m.params.max_substeps
                                                         : static_cast<int>(n);
}
}  // namespace

int DeformableModel::substeps_for(double dt_s) const {
  const int n = stability_substeps(*this, dt_s);
  return params.min_substeps > n && dt_s > 0.0 ? params.min_substeps : n;
}

int DeformableModel::substeps_needed(double dt_s) const {
  if (!(dt_s > stable_step_s)) return 1;
  if (!(stable_step_s > 0.0)) return std::numeric_limits<int>::max();
  const double n = std::ceil(dt_s / stable_step_s);
  return n >= 2e9 ? std::numeric_limits<int>::max() : static_cast<int>(n);
}

}  // namespace teleop::sim::deformable

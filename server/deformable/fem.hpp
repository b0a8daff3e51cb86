#pragma once
// Internal: the volumetric model (model fem) of server/deformable/. Not part of the deformable
// API: make_model, make_state, step and the diagnostics of deformable.hpp call these.
//
// The force law: linear tetrahedra (constant strain), each co-rotated by the rotational part R
// of its deformation gradient F = Ds Dm^-1 (polar decomposition, warm-started per element):
//   eps = sym(R^T F) - I,  sigma = 2 mu (eps + beta eps') + lambda tr(eps + beta eps') I,
//   f_j = -V R sigma grad N_j  (j = 1..3),  f_0 = -(f_1 + f_2 + f_3),
// with eps' the same strain of the velocities (stiffness-proportional Rayleigh damping beta =
// params.stiffness_damping_s) and lambda, mu from E and nu. Mass lumped (a quarter of each
// tetrahedron's mass on each of its nodes), gravity on every node, mass-proportional damping
// alpha = params.mass_damping_per_s relative to the body's support (its mean velocity while it
// touches no plane: damps deformation, not free fall; the planes' frame while it rests on one:
// damps its bounce on them as well).
//
// Contact of the surface nodes with the rigid planes and the tip sphere: a pressure per depth
// (k_i = kp A_i, A_i the node's area), integrated implicitly per node within each sub-step, so
// it is stable at any stiffness and its total force is an integral over the contact area that
// converges as the mesh is refined. Implicit Euler puts the same springs into its system.
#include "common/mesh/tet_mesh.hpp"
#include "server/deformable/deformable.hpp"
#include "server/deformable/kernels.hpp"

namespace teleop::sim::deformable::detail {

/// Fills model.fem and the surface arrays of `m` (masses, areas, contact springs, volume,
/// centre) from the tetrahedral mesh; m.params and m.mesh (the boundary) are set by the caller.
/// @throws config::ConfigError for parameters the model cannot use.
void build_fem(DeformableModel& m, const teleop::mesh::TetMesh& tets);

/// Sizes the fem arrays of `s` for `m` (make_state calls it after the common part).
void init_fem_state(const DeformableModel& m, DeformableState& s);

/// One step of h [s] of a fem body (s.tip_* at fraction tip_alpha of the caller's step): forces,
/// contacts, integration, held nodes onto their targets; the sums for the post-step checks.
/// Allocates nothing.
void fem_step(const DeformableModel& m, DeformableState& s, double h, double tip_alpha,
              KernelSums& sums);

/// y = K p with K the stiffness at the rest shape (all nodes, 3 per node), for the stable step.
void fem_apply_rest_stiffness(const DeformableModel& m, const Eigen::VectorXd& p,
                              Eigen::VectorXd& y);
/// Block Gershgorin upper bound of lambda_max(M^-1 K) at rest [1/s^2].
double fem_gershgorin_lambda(const DeformableModel& m);
/// Per node, the bound's row sum of |K| (element law) [N/m].
Eigen::VectorXd fem_gershgorin_rows(const DeformableModel& m);
/// Mass scaling (params.mass_scaling_step_s > 0 and above the stable step): raises the inertial
/// masses of the nodes with the largest stiffness per mass, the fewest (to 2 %) that bring
/// stable_step_s up to the target, and refreshes the stable step. @throws config::ConfigError
/// when that needs more than params.mass_scaling_max_fraction of the body's mass.
void fem_scale_masses(DeformableModel& m);

/// Elastic energy with the current element frames [J].
double fem_elastic_energy(const DeformableModel& m, const DeformableState& s);
/// Internal forces (elastic + damping) on every node into s.work_f (frames refreshed).
void fem_internal_forces(const DeformableModel& m, DeformableState& s, int rotation_iterations,
                         double rotation_tolerance_rad);

}  // namespace teleop::sim::deformable::detail

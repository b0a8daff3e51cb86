#pragma once
// The deformable body of the paper (sections "Geometrical model" and "Dynamical model"):
// a closed triangle surface whose nodes carry mass and move under
//   - a mass-spring model: edge springs plus radial springs to a centre node (the paper's
//     volume-preserving constraint), with damping; or
//   - the finite-difference Navier equation, eq. (2), with Lame coefficients from E and nu,
//     either with the paper's linear strain (not rotation invariant) or co-rotated (each edge
//     measured in the rotated rest frame of its two nodes: invariant under rigid motion);
// integrated by explicit, symplectic (semi-implicit) or linearly implicit (backward) Euler.
// Gravity, external point forces (f_ext), pinned nodes and penalty contact of every node with
// rigid planes (floor, walls) with optional Coulomb friction. A body at rest sleeps.
//
// Model/state split: DeformableModel never changes during a run; DeformableState holds all
// that does, including every scratch buffer; step() allocates nothing and is deterministic.
//
//   auto params = load_deformable_params(scene.at("deformable"));
//   auto mesh = make_mesh_for(params);
//   DeformableModel model = make_model(mesh, params, planes);
//   DeformableState state = make_state(model);
//   // each physics step:
//   state.f_ext.setZero(); state.f_ext.col(i) += contact_force_n;   // caller's loads
//   StepStatus st = step(model, state, 1e-3, &events);
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/config/config.hpp"
#include "common/mesh/tet_mesh.hpp"
#include "common/mesh/tri_mesh.hpp"
#include "common/sim/events.hpp"
#include "common/sim/plane.hpp"

namespace teleop::sim::deformable {

/// Which internal force law the body uses.
enum class ModelKind : std::uint8_t {
  kMassSpring = 0,          ///< edge springs + radial springs to a centre node
  kNavierLinear = 1,        ///< eq. (2), linear strain (the paper's tested model)
  kNavierCorotational = 2,  ///< eq. (2) measured in each edge's rotated rest frame
  /// Volumetric: linear tetrahedra, co-rotated per element, material in SI (server/deformable/
  /// fem.hpp). The surface the other parts of the world see is the tet mesh's boundary.
  kFem = 3,
};

/// Time integrator.
enum class IntegratorKind : std::uint8_t {
  kExplicitEuler = 0,    ///< x += h v(t); v += h a(t): unstable without damping
  kSymplecticEuler = 1,  ///< v += h a(t); x += h v(t+h): stable iff h w_max <= 2
  kImplicitEuler = 2,    ///< (M - hD - h^2 K) dv = h (f + h K v), one Newton step, CG solve
};

/// Which code computes a mass-spring symplectic-Euler step.
enum class KernelKind : std::uint8_t {
  /// One fused scalar pass in double precision (its results are the reference, the same bits
  /// on every CPU; DeformableParams' default, and a scene file's for every other model).
  kScalar = 0,
  /// A packed float copy of the nodes; every node gathers its own edges; edge and radial forces
  /// in single precision, 8 nodes at a time (AVX2 + FMA when the CPU has them, checked once at
  /// run time; portable loops otherwise); integration in double. The default of scene files
  /// for mass_spring + symplectic_euler where AVX2 is present (speed: docs/deformable.md).
  kSimd = 1,
};

/// "mass_spring", "navier_linear", "navier_corotational", "fem".
const char* to_string(ModelKind kind);
/// "explicit_euler", "symplectic_euler", "implicit_euler".
const char* to_string(IntegratorKind kind);
/// Parses the names above. @throws config::ConfigError naming the value and the choices.
ModelKind parse_model_kind(const std::string& name);
/// Parses the names above. @throws config::ConfigError naming the value and the choices.
IntegratorKind parse_integrator_kind(const std::string& name);
/// "scalar", "simd".
const char* to_string(KernelKind kind);
/// True where the simd kernel runs its AVX2 + FMA path (checked once on the running CPU).
bool simd_kernel_vectorised();
/// The kernel a scene file gets when it names none: simd for model mass_spring with integrator
/// symplectic_euler on a CPU with AVX2 and FMA (the accuracy table of docs/deformable.md shows
/// its results equal to the scalar kernel's to 3 digits, at a third of the cost), scalar
/// otherwise. (DeformableParams{} itself keeps kScalar: the double-precision reference.)
KernelKind default_kernel(ModelKind model, IntegratorKind integrator);

/// Parameters of one deformable object (the `deformable:` mapping of a scene). Defaults are the
/// paper's sphere (radius 0.25 m, level 4) made of a soft foam; see docs/deformable.md.
struct DeformableParams {
  ModelKind model = ModelKind::kMassSpring;
  IntegratorKind integrator = IntegratorKind::kSymplecticEuler;
  /// kSimd only for model mass_spring with integrator symplectic_euler (docs/deformable.md).
  /// A scene file without `kernel` gets default_kernel(model, integrator) instead.
  KernelKind kernel = KernelKind::kScalar;

  // geometry: an icosphere unless mesh_file is set (model fem: the shipped ball tet mesh of
  // `level`, unless tet_mesh_file or mesh_file is set)
  /// Icosphere subdivision [0, 6]; model fem: the shipped ball mesh [1, 4] (default 2)
  int level = 4;
  double radius_m = 0.25;                                  ///< icosphere radius [m]
  Eigen::Vector3d centre_m = Eigen::Vector3d(0, 0, 0.25);  ///< icosphere centre / mesh offset [m]
  std::string mesh_file;                                   ///< OBJ/STL/PLY; empty: icosphere
  double mesh_scale = 1.0;                                 ///< file units to metres
  /// Model fem: a gmsh MSH 2.2 tetrahedral mesh (scaled by mesh_scale, offset by centre_m)
  std::string tet_mesh_file;
  /// Model fem with mesh_file: the surface is filled with tetrahedra up to this edge [m] by gmsh;
  /// 0: a sixth of the cube root of the enclosed volume.
  double tet_max_edge_m = 0.0;

  // mass
  double mass_kg = 2.0;  ///< total mass [kg] (density = mass / enclosed volume)
  /// When > 0 it replaces mass_kg: mass = density * enclosed volume [kg/m^3].
  double density_kg_per_m3 = 0.0;
  /// Share of the mass carried by the centre node (only when radial springs exist) [-].
  double centre_mass_fraction = 0.3;

  // mass-spring model
  /// The two springs below are derived from the material (youngs_modulus_pa, poisson_ratio) and
  /// the radius by mass_spring_from_material (material.hpp) when make_model builds the body,
  /// replacing edge_stiffness_n_per_m and radial_stiffness_n_per_m3. A scene file sets it when a
  /// mass-spring body gives its material (docs/deformable.md, "Mass-spring from a material").
  bool springs_from_material = false;
  double edge_stiffness_n_per_m = 150.0;  ///< each edge spring [N/m] (membrane, level invariant)
  /// Radial spring of node i: k_i = this * (area of node i) [N/m per m^2 of surface]; 0 = none.
  /// Default: 1.5e5 for mass_spring (46 N/m per node at level 4), 0 for the Navier models.
  double radial_stiffness_n_per_m3 = 1.5e5;

  // the material: models navier_*, fem, and mass_spring with springs_from_material
  double youngs_modulus_pa = 6000.0;  ///< E [Pa]
  double poisson_ratio = 0.3;         ///< nu [-], in [0, 0.49]

  // damping
  /// Stiffness-proportional damping: every spring/edge has damper c = beta * k [s].
  double stiffness_damping_s = 5e-4;
  /// Damper of each radial spring, c_i = this * k_i [s] (damps the body bouncing on its
  /// radial springs; ~0.7 of critical for a single node at the default stiffness).
  double radial_damping_s = 5e-3;
  /// Drag of each node relative to the body's mean velocity, f_i = -alpha m_i (v_i - v_mean):
  /// damps deformation (slow modes too) but not translation [1/s].
  double mass_damping_per_s = 10.0;

  // loads and contact
  Eigen::Vector3d gravity_mps2 = Eigen::Vector3d(0, 0, -9.81);  ///< [m/s^2]
  /// Node-plane penalty: k_i = m_i w^2, c_i = 2 zeta m_i w (stable for explicit schemes when
  /// h w < ~1; the planes' own stiffness is for the rigid tool). [rad/s]
  double contact_frequency_rad_per_s = 600.0;
  double contact_damping_ratio = 0.7;  ///< zeta [-]
  bool friction = true;                ///< Coulomb friction with the planes' coefficients
  /// Model fem: the volumetric strain averaged over each node's tetrahedra (average nodal
  /// pressure, the remedy for the locking of linear tetrahedra as nu -> 0.5) instead of each
  /// tetrahedron's own (false: the element law). Other models ignore it.
  bool nodal_pressure = true;
  /// Model fem, mass scaling: raise the lumped (inertial) masses of the nodes whose stiffness
  /// limits the stable step, the fewest grams that make stable_step_s at least this [s] (0: off).
  /// Gravity, the centroid and the weight keep the physical masses; the inertia added is
  /// fem.added_mass_kg (docs/deformable.md, "Mass scaling").
  double mass_scaling_step_s = 0.0;
  /// The most mass scaling may add, as a fraction of the body's mass; needing more is an error.
  double mass_scaling_max_fraction = 0.02;
  /// Model fem: contact of the surface with planes and with the tip as a pressure per depth,
  /// node i's spring k_i = this * (area of node i), integrated implicitly per node (stable at
  /// any value; the force converges with the mesh). 0: 1000 E / (1 - nu^2) / (body size),
  /// body size = cube root of the volume [Pa/m].
  double contact_pressure_stiffness_pa_per_m = 0.0;

  // implicit Euler's conjugate-gradient solve
  int cg_max_iterations = 60;  ///< fixed upper bound on iterations per step
  double cg_tolerance = 1e-4;  ///< relative residual at which CG stops early

  // sleeping and fault detection
  double sleep_speed_mps = 2e-4;  ///< a node slower than this is still [m/s]
  double sleep_time_s = 0.2;      ///< still and unloaded this long: sleep [s]
  double max_speed_mps = 50.0;    ///< faster than this is a blow-up [m/s]

  /// Automatic step: at most this many equal sub-steps per step() call (explicit and symplectic
  /// Euler). Beyond it the body runs at a step longer than its stable step and an event says so.
  int max_substeps = 64;
  /// Accuracy sub-steps: at least this many equal sub-steps per step() call, whatever the stable
  /// step (the automatic model selection sets it when the table's entry has a shorter step than
  /// the world's, docs/deformable.md "Automatic model"). 1: only what stability needs.
  int min_substeps = 1;
};

/// Reads and validates the `deformable:` YAML mapping. Unknown keys, wrong types and values out
/// of range throw config::ConfigError naming file, field, value and range. Exactly one of
/// mass_kg and density_kg_per_m3 may be given (density: mass = density * enclosed volume).
DeformableParams load_deformable_params(const teleop::config::Node& node);

/// The mesh the parameters describe: the icosphere (level, radius_m, centre_m) or mesh_file
/// loaded, scaled and translated by centre_m. @throws mesh::MeshError.
teleop::mesh::TriMesh make_mesh_for(const DeformableParams& params);

/// Safety factor of the automatic step: the stable step is this times the limit of the
/// integrator for the highest mode (symplectic Euler: h w = 2 (sqrt(1 + zeta^2) - zeta)), the
/// nodes' plane contact and the top damping rate. It covers what the rest-shape estimate leaves
/// out: the stiffening of stretched springs (the tip's contact forces are held over the sub-steps
/// and checked against the physics step by the world's rate check; docs/deformable.md,
/// "Automatic step").
constexpr double kStableStepSafety = 0.95;
/// Lanczos iterations of the w_max estimate (capped at the number of degrees of freedom).
constexpr int kStabilityLanczosIterations = 80;

/// Highest natural frequency of a body and the step its integrator is stable at.
struct StabilityEstimate {
  double omega_max_rad_per_s = 0.0;    ///< sqrt(lambda_max(M^-1 K)) at rest, Lanczos (<= true)
  double omega_bound_rad_per_s = 0.0;  ///< block Gershgorin upper bound of the same [rad/s]
  double damping_ratio = 0.0;          ///< zeta of the top mode (Rayleigh quotient of C)
  double radial_share = 0.0;           ///< share of the top mode's stiffness in radial springs
  double limit_step_s = 0.0;           ///< the integrator's stability limit for that mode [s]
  double stable_step_s = 0.0;          ///< kStableStepSafety * limit_step_s (inf: implicit) [s]
  int lanczos_iterations = 0;
};

/// Immutable description of one body. Built once by make_model().
struct DeformableModel {
  DeformableParams params;
  teleop::mesh::TriMesh mesh;   ///< topology; mesh.vertices are the rest positions [m]
  int node_count = 0;           ///< surface nodes N
  bool has_centre = false;      ///< a centre node with radial springs exists
  Eigen::VectorXd mass_kg;      ///< node masses [kg], size N
  Eigen::VectorXd inv_mass;     ///< 1 / mass [1/kg]
  Eigen::VectorXd area_m2;      ///< node areas (a third of each adjacent triangle) [m^2]
  double centre_mass_kg = 0.0;  ///< centre node mass [kg] (0 without radial springs)
  double total_mass_kg = 0.0;   ///< [kg]
  double volume_m3 = 0.0;       ///< rest enclosed volume [m^3]
  double density_kg_per_m3 = 0.0;
  double lame_lambda_pa = 0.0;    ///< lambda = E nu / ((1 + nu)(1 - 2 nu)) [Pa]
  double lame_mu_pa = 0.0;        ///< mu = E / (2 (1 + nu)) [Pa]
  Eigen::Vector3d rest_centre_m;  ///< rest position of the centre node / centroid [m]

  // one entry per mesh edge (i < j)
  Eigen::Matrix2Xi edges;         ///< node pairs, sorted (see first_edge_offsets)
  Eigen::VectorXd rest_length_m;  ///< |X_j - X_i| [m]
  Eigen::Matrix3Xd rest_dir;      ///< (X_j - X_i) / |X_j - X_i|
  /// Mass-spring: edge spring k [N/m]. Navier: coefficient a of (d_j - d_i) [N/m].
  Eigen::VectorXd edge_k_iso;
  /// Navier: coefficient b of ((d_j - d_i).u) u [N/m]; mass-spring: unused (0).
  Eigen::VectorXd edge_k_dir;

  /// CSR: the edges incident to node i: node_edges[node_edge_offsets[i] .. [i+1]), each the
  /// edge index e when i is its first node, ~e (bitwise not) when i is its second node.
  std::vector<int> node_edge_offsets, node_edges;
  /// The edges are sorted by first node, then second (first < second); the edges whose first
  /// node is i are [first_edge_offsets[i], first_edge_offsets[i + 1]).
  std::vector<int> first_edge_offsets;
  std::vector<int> second_node3;  ///< 3 * edges(1, e): where the second node's coordinates start

  // radial springs (node i to the centre node)
  Eigen::VectorXd radial_k;       ///< [N/m]
  Eigen::VectorXd radial_rest_m;  ///< rest distance to the centre [m]

  // contact with rigid planes (per node: k_i = m_i w^2, c_i = 2 zeta m_i w)
  std::array<Plane, 8> planes{};
  int plane_count = 0;
  Eigen::VectorXd contact_k;  ///< [N/m]
  Eigen::VectorXd contact_c;  ///< [N s/m]

  // kernel simd: the first neighbours of every node, padded to the largest valence (padding:
  // the node itself with k = 0), slot-major: entry [slot * simd_stride + i]
  int simd_width = 0;               ///< largest valence
  int simd_stride = 0;              ///< node count rounded up to 16
  std::vector<int> simd_neighbour;  ///< the neighbour's pack offset in floats: 8 x its index
  std::vector<float> simd_k, simd_rest, simd_radial_k, simd_radial_rest;
  std::vector<double> simd_dof_mass, simd_dof_inv_mass;  ///< m_i and 1 / m_i per coordinate (3N)

  // co-rotational Navier, explicit and symplectic path (built for that model only): the ring
  // matrix of node i is A_i = sum_j (x_j - c) D_ij^T + (x_i - c) E_i^T, with c the current
  // mass-weighted centroid, D_ij = X_j - X_i over the one-ring and E_i = w_i (X_i - c0) -
  // sum_j D_ij (w_i = sum_j |D_ij|^2 / |X_i - c0|^2, c0 the rest centroid; 3 per node). The
  // one-ring is a table of corot_width entries per node (node-major; the largest valence),
  // padded so that every loop has the same length: a padding neighbour is the node itself with
  // D = 0. The same rest vectors for four nodes at a time (nodes 4g .. 4g + 3, one per lane):
  // corot_ring_rest4[12 (g w + k) + 4 c + l] = D_{4g+l, k}[c], corot_node_e4[12 g + 4 c + l] =
  // E_{4g+l}[c]. Per edge its rest vector D and 1 / |D|^2 (4 doubles per edge).
  int corot_width = 0;
  std::vector<int> corot_nb;
  std::vector<double> corot_ring_rest, corot_node_e, corot_edge;
  std::vector<double> corot_ring_rest4, corot_node_e4;

  // model fem: the volumetric mesh. All nodes (the surface's node_count first, then the
  // interior) are the columns of the state's x, v, f_ext, force, pinned and pin_target;
  // mass_kg / inv_mass / area_m2 / contact_k / contact_c cover the surface nodes.
  struct Fem {
    int node_count = 0;  ///< all nodes
    int tet_count = 0;
    Eigen::Matrix3Xd rest;       ///< rest positions of all nodes [m]
    Eigen::Matrix4Xi tets;       ///< positive orientation
    std::vector<double> dm_inv;  ///< per tet 9: Dm^-1 column-major, Dm = [X1-X0 X2-X0 X3-X0]
    /// The same four tets at a time (tets 4g .. 4g + 3, one per lane): dm_inv4[36 g + 4 k + l] =
    /// dm_inv[9 (4 g + l) + k]; volume4[4 g + l] (the last tet_count % 4 tets are not in it)
    std::vector<double> dm_inv4, volume4;
    Eigen::VectorXd volume_m3;  ///< per tet
    /// Lumped inertial masses of all nodes: a quarter of each tet's mass, plus the mass
    /// scaling's (params.mass_scaling_step_s)
    Eigen::VectorXd mass_kg, inv_mass;
    Eigen::VectorXd weight_kg;        ///< lumped physical masses (gravity, centroid) [kg]
    double added_mass_kg = 0.0;       ///< inertia the mass scaling added: sum(mass_kg - weight_kg)
    Eigen::VectorXd inv_node_volume;  ///< 1 / (a quarter of each adjacent tet's volume) [1/m^3]
    Eigen::Matrix3Xd precond;         ///< diagonal of the rest stiffness (CG preconditioner)
    double pressure_stiffness_pa_per_m = 0.0;  ///< plane and tip contact [Pa/m]
  } fem;

  // automatic step (estimate_stability(); refreshed by make_model and update_stable_step)
  double omega_max_rad_per_s = 0.0;    ///< highest natural frequency at rest [rad/s]
  double omega_bound_rad_per_s = 0.0;  ///< its Gershgorin upper bound [rad/s]
  double damping_ratio_top = 0.0;      ///< damping ratio of the highest mode [-]
  /// Largest step step() takes in one go [s]; a longer dt is split into substeps_for(dt) equal
  /// sub-steps. +inf for implicit Euler (never sub-steps).
  double stable_step_s = 0.0;
  /// Sub-steps step() takes for dt: 1 when dt <= stable_step_s, else ceil(dt / stable_step_s),
  /// at most params.max_substeps; 1 when stable_step_s is 0 (explicit Euler without damping is
  /// unstable at any step: step() warns once); never fewer than params.min_substeps.
  int substeps_for(double dt_s) const;
  /// Like substeps_for without the params.max_substeps cap (what stability would need).
  int substeps_needed(double dt_s) const;
  /// Columns of the state's x, v, f_ext, pinned: the surface nodes, and for model fem the
  /// interior nodes after them.
  int state_node_count() const {
    return params.model == ModelKind::kFem ? fem.node_count : node_count;
  }
};

/// Builds the model from a closed mesh (rest shape), parameters and the rigid planes (at most
/// 8). @throws config::ConfigError for parameters out of range (model fem: it needs a
/// tetrahedral mesh), mesh::MeshError for a bad mesh.
DeformableModel make_model(const teleop::mesh::TriMesh& mesh, const DeformableParams& params,
                           const std::vector<Plane>& planes = {});
/// Model fem from a tetrahedral mesh (its boundary is the model's mesh).
DeformableModel make_model(const teleop::mesh::TetMesh& mesh, const DeformableParams& params,
                           const std::vector<Plane>& planes = {});
/// The model the parameters describe, with the geometry make_mesh_for / make_tet_mesh_for give.
DeformableModel make_model(const DeformableParams& params, const std::vector<Plane>& planes = {});

/// Model fem: the tetrahedral mesh the parameters describe: tet_mesh_file, else mesh_file
/// filled by gmsh (tet_max_edge_m), else the shipped ball of `level` (1-4) scaled to radius_m
/// and centred at centre_m. @throws mesh::MeshError.
teleop::mesh::TetMesh make_tet_mesh_for(const DeformableParams& params);

/// Estimates the highest natural frequency of the model at rest and its integrator's stable step
/// (docs/deformable.md, "Automatic step"). Allocates: for make_model, not the hot loop.
StabilityEstimate estimate_stability(const DeformableModel& model);
/// Block Gershgorin upper bound of sqrt(lambda_max(M^-1 K)) at rest [rad/s].
double gershgorin_omega_bound(const DeformableModel& model);
/// Recomputes the automatic-step fields of `model` (call after changing its stiffnesses,
/// masses or damping in place; make_model already does).
void update_stable_step(DeformableModel& model);

/// Result of one step.
enum class StepStatus : std::uint8_t {
  kOk = 0,          ///< advanced
  kSleeping = 1,    ///< at rest and unloaded: no work done
  kFaultReset = 2,  ///< NaN or blow-up detected: the body was reset to its rest shape, at rest
  kBadInput = 3,    ///< dt not finite or <= 0, or a non-finite f_ext/pin target: nothing done
};

/// Mutable state of one body: positions, velocities, loads, outputs and all scratch memory.
struct DeformableState {
  Eigen::Matrix3Xd x;      ///< node positions [m], 3 x N
  Eigen::Matrix3Xd v;      ///< node velocities [m/s]
  Eigen::Matrix3Xd f_ext;  ///< external forces [N], written by the caller; step() keeps it
  std::vector<std::uint8_t> pinned;  ///< 1: node i follows pin_target (held by the caller)
  Eigen::Matrix3Xd pin_target;       ///< targets of pinned nodes [m]
  Eigen::Vector3d centre_x = Eigen::Vector3d::Zero();  ///< centre node position [m]
  Eigen::Vector3d centre_v = Eigen::Vector3d::Zero();  ///< centre node velocity [m/s]

  bool sleeping = false;      ///< at rest and unloaded: step() does nothing until a load comes
  bool wake_request = false;  ///< set by the caller to force a wake-up; cleared by step()
  double still_time_s = 0.0;  ///< how long the body has been still and unloaded [s]
  double sim_time_s = 0.0;    ///< simulated time [s]

  // outputs of the last step
  Eigen::Matrix3Xd force;  ///< total force on each node at the start of the step [N]
  int contact_count = 0;   ///< node-plane contacts in the last step
  int pinned_count = 0;    ///< pinned nodes in the last step
  Eigen::Vector3d plane_force_n = Eigen::Vector3d::Zero();  ///< sum of plane forces on the body
  int cg_iterations = 0;                                    ///< implicit Euler: CG iterations
  double cg_residual = 0.0;  ///< implicit Euler: final relative residual
  std::uint64_t steps = 0;
  std::uint64_t sleeping_steps = 0;
  std::uint64_t fault_count = 0;
  Eigen::Vector3d last_good_centroid = Eigen::Vector3d::Zero();  ///< [m]

  // scratch (sized by make_state; never resized by step)
  Eigen::Matrix3Xd work_f;  ///< forces, 3 x (N + 1): last column is the centre node
  Eigen::Matrix3Xd work_dv, work_r, work_z, work_p, work_ap, work_diag, work_b;
  Eigen::VectorXd edge_scratch;  ///< per edge scalar (1 / length)
  Eigen::VectorXd edge_length2;  ///< per edge squared length [m^2]
  Eigen::VectorXd node_length2;  ///< per node squared distance to the centre [m^2]
  Eigen::Matrix3Xd edge_force;   ///< per edge force on its first node [N]
  Eigen::VectorXd node_scratch;  ///< per node scalar (1 / distance to the centre)
  Eigen::Matrix3Xd edge_dir;     ///< per edge direction w of the Jacobian block
  Eigen::Matrix4Xd edge_coef;    ///< per edge (k_iso, k_dir, c_iso, c_dir) of the Jacobian
  Eigen::Matrix3Xd radial_dir;
  Eigen::Matrix4Xd radial_coef;
  std::vector<int> contact_node;  ///< implicit Euler: contact list (capacity N * planes)
  Eigen::Matrix3Xd contact_normal;
  Eigen::Matrix4Xd contact_coef;          ///< (k, c, spring force, friction mu) of each contact
  std::vector<Eigen::Matrix3d> rotation;  ///< co-rotational frame of each node
  std::vector<Eigen::Quaterniond> rotation_q;  ///< warm start of the polar decomposition
  // co-rotational Navier, explicit and symplectic path: 4 doubles per node (x - c, 0), then 4
  // per node (q = x - c + beta v, 0); per node 24 (the frame's columns, then its rows, each
  // padded to 4); per node 4 (the edge reactions gathered so far in a step)
  std::vector<double> corot_pack, corot_frame, corot_force;

  // model fem: per tet its frame (quaternion warm start, 4; its matrix, 9, column-major, kept
  // for the implicit solve only); the implicit solve's contact count (s.contact_*: plane
  // contacts, then the tip's as ~node)
  std::vector<double> fem_q, fem_r;
  int fem_contacts = 0;
  // params.nodal_pressure: each tet's volumetric strain, and each node's average of them
  std::vector<double> fem_theta, fem_node_theta;
  /// Model fem: a rigid sphere the surface nodes are kept out of within step() (the slave's
  /// tip): its centre moves linearly from tip_from_m to tip_to_m over the step. Set by the
  /// caller before step(); tip_radius_m <= 0: none.
  double tip_radius_m = 0.0;
  Eigen::Vector3d tip_from_m = Eigen::Vector3d::Zero(), tip_to_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d tip_velocity_mps = Eigen::Vector3d::Zero();
  /// Model fem: Coulomb friction between the sphere and the surface nodes it touches (static
  /// mu_s: a node sliding slower than mu_s times its normal impulse allows is stopped relative
  /// to the sphere; otherwise kinetic mu_k <= mu_s opposes its sliding). 0: frictionless.
  double tip_friction_static = 0.0, tip_friction_kinetic = 0.0;
  /// Outputs of the last step (model fem): the force of the body on the sphere [N] (mean over
  /// the sub-steps), the surface nodes it touched at the end, the deepest node [m].
  Eigen::Vector3d tip_force_n = Eigen::Vector3d::Zero();
  int tip_node_count = 0;
  double tip_depth_m = 0.0;

  // kernel simd: per node 8 floats (x, y, z relative to the centre node, -, v relative to its
  // velocity, -), model.simd_stride nodes (the padding at zero)
  std::vector<float> simd_pack;
  // set by a sub-step of the simd kernel that wrote simd_pack (and the mass-weighted velocity
  // sum simd_vm) for the next sub-step of the same step() call; cleared when a step() call
  // starts, so it never outlives the call (x and v may be changed between calls)
  bool simd_pack_fresh = false;
  double simd_vm[3] = {0.0, 0.0, 0.0};

  // automatic step
  int last_substeps = 1;            ///< sub-steps of the last step() call
  bool substeps_announced = false;  ///< the info event about sub-stepping was pushed
  Eigen::Matrix3Xd pin_goal;        ///< scratch: the caller's pin targets while sub-stepping
  Eigen::Matrix3Xd pin_start;       ///< scratch: positions at the start of a sub-stepped step
};

/// A state at rest in the rest shape, no loads, nothing pinned, scratch allocated.
DeformableState make_state(const DeformableModel& model);

/// Advances the body by dt_s [s] with the model's integrator. Never allocates, never throws.
/// When dt_s > model.stable_step_s it takes model.substeps_for(dt_s) equal sub-steps (loads held,
/// pinned nodes moved linearly to their targets) and pushes one kInfo event the first time.
/// Faults (NaN, speed above max_speed_mps) reset the body and push a kFault event on `events`
/// (may be null). Sleeping bodies return kSleeping at once unless f_ext is non-zero, a pinned
/// node is away from its target or wake_request is set.
StepStatus step(const DeformableModel& model, DeformableState& state, double dt_s,
                teleop::sim::EventQueue* events);

namespace detail {
/// step() without the fused kernel that mass-spring bodies with symplectic Euler normally take:
/// the general force and integration passes. The reference that kernel is tested against.
StepStatus step_general(const DeformableModel& model, DeformableState& state, double dt_s,
                        teleop::sim::EventQueue* events);
/// step() without the automatic step: one step of dt_s whatever the stable step (the code path
/// step() takes when substeps_for(dt_s) == 1).
StepStatus step_once(const DeformableModel& model, DeformableState& state, double dt_s,
                     teleop::sim::EventQueue* events);
}  // namespace detail

/// Internal forces (elastic + damping, no gravity, contact or f_ext) on each node at the
/// current state [N], into `out` (3 x N, resized only if its size differs). Also refreshes the
/// co-rotational frames in `state`. Not for the hot loop of other bodies: it writes scratch.
void internal_forces(const DeformableModel& model, DeformableState& state, Eigen::Matrix3Xd& out);

/// Kinetic energy of nodes and centre [J].
double kinetic_energy(const DeformableModel& model, const DeformableState& state);
/// Elastic energy of springs / Navier edges [J] (co-rotational: with the current frames).
double elastic_energy(const DeformableModel& model, const DeformableState& state);
/// Elastic + gravitational (relative to z = 0 along -g) + plane penalty energy [J].
double potential_energy(const DeformableModel& model, const DeformableState& state);

/// Centre of the body: the centre node when there is one, else the mass-weighted centroid [m].
Eigen::Vector3d body_centre(const DeformableModel& model, const DeformableState& state);
/// Mass-weighted centroid of all nodes (centre node included) [m].
Eigen::Vector3d centroid(const DeformableModel& model, const DeformableState& state);

/// Wakes a sleeping body (the next step integrates).
inline void wake(DeformableState& state) {
  state.sleeping = false;
  state.wake_request = true;
  state.still_time_s = 0.0;
}

}  // namespace teleop::sim::deformable

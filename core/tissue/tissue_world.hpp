#pragma once
// The deformable part of the eye: tissue surfaces, the attachments between them, the globe wall, the
// forces of the environment and the local force functions — and the step that advances them.
//
// Structure after MuJoCo's "constant model, mutable data" idea, kept simple: everything is built
// before the loop (add_surface, add_attachment, add_local_force), then step() is called at a fixed
// rate with dt as a parameter. The world owns no clock; its only threads are an optional worker pool
// with a fixed partition (set_worker_threads). Two worlds built and stepped the same way end in the
// same bits (state_hash()), whatever their thread counts.
//
// The solver is implicit Euler solved by Vertex Block Descent (Chen, Liu, Yang & Yuksel 2024): each
// substep minimises the incremental potential ½|x − x̃|²_M/h² + E(x) by Gauss–Seidel sweeps over the
// vertices, each vertex taking one Newton step on its own energy with its neighbours held. The
// sweeps start from where inertia alone would carry the tissue (x + h v, without this substep's
// external forces), so tissue at rest is already the minimiser and a sweep leaves it there: the
// solver's fixed point is the exact equilibrium of the nominal material for any number of substeps
// and sweeps. Sweeps that do not converge leave the tissue slow (damped), never soft; an XPBD sweep
// started from the prediction x̃ settles many times softer than the material instead
// (core/README.md, "The solver", has the argument and the measurements).
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/common/status.hpp"
#include "core/common/worker_pool.hpp"
#include "core/common/types.hpp"
#include "core/common/units.hpp"
#include "core/tissue/globe_wall.hpp"
#include "core/tissue/spring_groups.hpp"
#include "core/tissue/surface.hpp"
#include "core/tissue/topology_hook.hpp"

namespace vitreo::core {

struct Environment {
  // Eye frame: origin at the globe centre, +z anterior. The patient lies supine, so gravity points
  // to the posterior pole (−z).
  Vec3 gravity_mm_s2{0.0, 0.0, -units::kStandardGravity_mm_s2};
  double fluid_density_g_per_mm3 = 1.0033e-3;  // liquid vitreous (Michels et al. 1990)
  double gas_density_g_per_mm3 = 1.2e-6;       // air after a fluid–gas exchange
  // Below this height the chamber is filled with fluid, above it with gas (thesis ch. 2.6.2.4).
  double fluid_level_z_mm = std::numeric_limits<double>::infinity();
  double intraocular_pressure_pa = units::mmhg_to_pa(15.0);
  // Pressure acts only where it has something to push against: set false for free-floating tests.
  bool apply_pressure = true;

  void validate() const;
};

struct SolverSettings {
  int substeps = 2;    // per step, 1..64
  int iterations = 1;  // constraint sweeps per substep, 1..64
  // Instrument contact: the tissue is kept out of an instrument by a stiff one-sided spring
  // (µN/mm; 2e5 lets 1 mN of contact force press 5 µm in), whose force is the contact force the
  // metrics report; a hard projection after the sweeps catches what a fast instrument would still
  // push through (stage_instruments.cpp).
  double contact_stiffness_un_per_mm = 2e5;
  int max_tears_per_step = 8;
  double wall_offset_mm = 0.0;  // tissue keeps this distance inside the wall
  // Mass-proportional velocity damping (1/s) on top of fluid drag: used to settle a case to
  // equilibrium on load and by tests; 0 during surgery.
  double settling_damping_per_s = 0.0;
  // Sleeping (see Surface::kSleepBlock): a block whose vertices all stay below sleep_speed for
  // sleep_after_steps consecutive steps stops being simulated until something wakes it.
  bool sleeping = true;
  double sleep_speed_mm_s = 0.01;
  int sleep_after_steps = 200;
  // A sleeping vertex wakes when the strain of a spring from an awake neighbour has changed by more
  // than this since its block fell asleep (a change of pull, not the tension it rests under).
  double wake_strain = 0.01;
  // Friction between tissue and the globe wall (retina on the pigment epithelium): a vertex in
  // contact stays put while the tangential load is below this fraction of the normal load.
  double wall_friction = 0.5;
  void validate() const;
};

// Binds a vertex of one surface to a vertex of another (the thesis' instance vertices), or to a fixed
// point of the eye (an adhesion, a laser scar). It breaks when the force holding it exceeds its
// strength: weak attachments let go when pulled, strong ones must be cut.
struct AttachmentDescription {
  static constexpr std::uint32_t kWorld = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t surface_a = 0;
  std::uint32_t vertex_a = 0;
  std::uint32_t surface_b = kWorld;
  std::uint32_t vertex_b = 0;
  Vec3 world_point_mm = Vec3::Zero();  // used when surface_b == kWorld
  double stiffness_un_per_mm = 1e4;    // µN/mm; large values approach a rigid weld
  double break_force_un = std::numeric_limits<double>::infinity();
  // 0: the two ends coincide (instance vertices: a membrane lying on the retina, held where it
  // lies). > 0 (surface to surface only): a stalk of this length between the two layers — a
  // fibrovascular peg holding an elevated membrane off the retina: surface_a's end is held this far
  // inward of surface_b's (toward the globe's centre), so it keeps the layers apart and passes the
  // membrane's pull on to the retina as a coincident attachment does. A stalk is a bridge an
  // instrument can reach: cut_attachments_in() severs it; a coincident attachment goes only with
  // its tissue.
  double rest_length_mm = 0.0;
};

// A force per unit area (Pa) on a set of vertices toward a point: the thesis' detachment force
// (subretinal fluid pushing the retina off the choroid, ch. 2.4), ramped by `scale` — drainage
// ramps it to zero.
struct LocalForceDescription {
  std::string name;
  std::uint32_t surface = 0;
  std::vector<std::uint32_t> vertices;
  std::vector<double> weights;  // per vertex, 0..1; empty = all 1
  Vec3 toward_point_mm = Vec3::Zero();
  double pressure_pa = 0.0;
  double scale = 1.0;
};

// ---- Instruments acting on tissue (filled by core/instruments each step) -----------------------
// A kinematic capsule the tissue cannot enter: an instrument's shaft or tip part, given at the start
// (a0, b0) and the end (a1, b1) of the step; the substeps interpolate between them, so a fast tool
// sweeps instead of jumping.
struct ColliderCapsule {
  Vec3 a0 = Vec3::Zero(), b0 = Vec3::Zero(), a1 = Vec3::Zero(), b1 = Vec3::Zero();
  double radius_mm = 0.0;
};

// A triangle that may touch a collider during the step (from the broad phase in core/collision).
// `side` (+1/−1) is the side of the triangle's plane (along its normal) the collider was on before
// the step: the tissue is pushed to stay on its side, so a triangle can never be crossed.
struct ContactCandidate {
  std::uint32_t collider = 0;
  std::uint32_t surface = 0;
  std::uint32_t triangle = 0;
  std::int8_t side = 1;
};

// A surface point given by barycentric coordinates on a triangle, held to a target point by a stiff
// zero-length spring: a forceps grasp (target = the jaw frame) or a laser adhesion (target fixed).
struct GripDescription {
  std::uint32_t surface = 0;
  TriangleId triangle;
  Vec3 bary{1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0};
  Vec3 target_mm = Vec3::Zero();
  double stiffness_un_per_mm = 1e5;
  double break_force_un = std::numeric_limits<double>::infinity();
};

// Suction of a vitrector port: tissue inside the hemisphere of `radius_mm` in front of `apex_mm`
// (along `axis`) is drawn toward the apex with `pressure_pa` × (cosine of the angle off the axis) on
// its area (thesis ch. 2.6.2.2); nothing outside the hemisphere feels it.
struct SuctionField {
  Vec3 apex_mm = Vec3::Zero();
  Vec3 axis = Vec3::UnitZ();
  double radius_mm = 0.0;
  double pressure_pa = 0.0;
};

enum class TissueEventKind : std::uint8_t { kTear, kAttachmentBroken, kRolledBack, kGripBroken };

struct TissueEvent {
  TissueEventKind kind;
  std::uint32_t surface;
  std::uint32_t item;  // edge torn / attachment index
  Vec3 position_mm;
  double magnitude;  // strain for a tear, force (µN) for a broken attachment
};

struct StepReport {
  bool ok = true;             // false: the step was rolled back
  std::string error;          // why, when !ok
  std::uint32_t tears = 0;
  std::uint32_t attachments_broken = 0;
};

struct Energy {
  double kinetic = 0.0;
  double gravity = 0.0;  // with buoyancy, relative to z = 0
  double elastic = 0.0;  // springs and attachments
  double total() const { return kinetic + gravity + elastic; }
};

// The revision of the solver's arithmetic, bumped by every change that gives other bits for the same
// inputs, so that a settled start cached by an older solver is not reused (rig/scene_io/case_loader.cpp;
// a recording still replays only on the build that made it). 1: bending read as constant rows
// (backed out); 2: the Vertex Block Descent solver of core/README.md as before it; 3: sleep blocks of
// 16 vertices instead of 64, a block sleeping only while its spring neighbours are slow too.
// 4: bending read as constant rows again, on the sleep blocks of 16, and the wall friction
// directed by the contact normal taken once a step (Scratch::contact_normal).
inline constexpr int kSolverRevision = 4;

class TissueWorld {
 public:
  TissueWorld(GlobeWall wall, Environment environment = {}, SolverSettings settings = {});

  // ---- Building (before the loop; throws InvalidArgument on bad data) ------------------------
  std::uint32_t add_surface(const SurfaceDescription& description);
  std::uint32_t add_attachment(const AttachmentDescription& description);
  std::uint32_t add_local_force(const LocalForceDescription& description);

  // How a surface's overstrained springs are torn and its crept springs tidied (topology_hook.hpp;
  // core/topology's install_clean_topology sets it on every surface). Null: Surface::tear_edge, no
  // tidying. Throws InvalidArgument for a surface out of range.
  void set_topology_hook(std::uint32_t surface, std::unique_ptr<TopologyHook> hook);
  TopologyHook* topology_hook(std::uint32_t surface) const { return hooks_.at(surface).get(); }

  // ---- Run-time controls (never throw) --------------------------------------------------------
  Status set_environment(const Environment& environment);
  Status set_local_force_scale(std::uint32_t force, double scale);
  double local_force_scale(std::uint32_t force) const { return local_forces_.at(force).d.scale; }
  std::uint32_t local_force_count() const { return static_cast<std::uint32_t>(local_forces_.size()); }
  const LocalForceDescription& local_force(std::uint32_t force) const { return local_forces_.at(force).d; }
  // Sum of the current detachment pressures (Pa, scaled, weighted) acting on a vertex.
  double local_pressure_on(std::uint32_t surface, std::uint32_t vertex) const;

  // ---- Instruments (never throw, never allocate) -------------------------------------------------
  static constexpr std::uint32_t kMaxColliders = 32;
  static constexpr std::uint32_t kMaxContactCandidates = 32768;
  static constexpr std::uint32_t kMaxGrips = 4096;
  static constexpr std::uint32_t kMaxSuctionFields = 4;
  // Triangles an instrument presses on in one substep (contact terms of the solve; beyond this the
  // hard projection alone keeps the tissue out).
  static constexpr std::uint32_t kMaxContactTerms = 8192;
  // Colliders and candidates for the next step (copied; extra entries beyond capacity are refused).
  Status set_colliders(std::span<const ColliderCapsule> colliders);
  Status set_contact_candidates(std::span<const ContactCandidate> candidates);
  Status set_suction_fields(std::span<const SuctionField> fields);
  std::uint32_t collider_count() const { return collider_count_; }
  // Force the tissue of `surface` exerted on collider c during the last step (µN, from the contact
  // multipliers averaged over the substeps); and summed over all surfaces.
  Vec3 contact_force(std::uint32_t collider, std::uint32_t surface) const;
  Vec3 contact_force(std::uint32_t collider) const;
  // Deepest penetration any candidate had before it was resolved in the last step (mm).
  double max_contact_depth(std::uint32_t collider) const;
  // Grips: returns the grip index or kNone (full, stale triangle, bad data).
  std::uint32_t add_grip(const GripDescription& grip);
  Status set_grip_target(std::uint32_t grip, const Vec3& target_mm);
  void release_grip(std::uint32_t grip);
  bool grip_active(std::uint32_t grip) const { return grip < grips_.size() && grips_[grip].active; }
  double grip_force(std::uint32_t grip) const { return grip < grips_.size() ? grips_[grip].last_force_un : 0.0; }
  const GripDescription& grip(std::uint32_t g) const { return grips_.at(g).d; }
  // Current position of the gripped surface point (its barycentric point on the deformed triangle).
  Vec3 grip_point(std::uint32_t grip) const;

  // Advances the world by dt_s (0 < dt ≤ 0.02 s). Topology changes (tears) and broken attachments
  // happen at the end, at the step boundary. If the state would become non-finite, the whole step is
  // rolled back and reported.
  StepReport step(double dt_s);

  // ---- Settling (the scene builder settles a case with other settings, then starts the clock) --
  // Throws InvalidArgument for bad settings.
  void replace_settings(const SolverSettings& settings);
  // While a case settles (core/scene settle_world), nothing breaks and nothing tears: the build
  // starts the pathology at its rest lengths at once, and the transient of that start is not surgery
  // (a contracting membrane snapped 56 of its attachments off before it stood still). Not part of
  // the state: settle_world turns it back on before the start state is taken.
  void set_breaking(bool on) { breaking_ = on; }
  bool breaking() const { return breaking_; }
  // Step count and time back to zero (the settled start is time zero of the case).
  void reset_clock();

  // ---- State I/O (snapshots, core/scene/snapshot.hpp) ------------------------------------------
  // Every bit of mutable state, each field listed once in state_io() (tissue_world_state.cpp) for
  // both directions; surfaces list theirs in Surface::state_io.
  void write_state(std::vector<std::uint8_t>& out) const;
  // Reads it back into a world built from the same scene (same surfaces, capacities, attachments
  // and forces); refuses anything that does not fit, leaving the world unchanged.
  Status read_state(const std::uint8_t* data, std::size_t size);

  // ---- Inspection -----------------------------------------------------------------------------
  std::uint32_t surface_count() const { return static_cast<std::uint32_t>(surfaces_.size()); }
  Surface& surface(std::uint32_t i) { return *surfaces_.at(i); }
  const Surface& surface(std::uint32_t i) const { return *surfaces_.at(i); }
  const GlobeWall& wall() const { return wall_; }
  const Environment& environment() const { return environment_; }
  const SolverSettings& settings() const { return settings_; }
  // For tests: lay the vertex sweep's terms out afresh every step instead of keeping the layout
  // while the topology and the awake region stand (the results are the same, bit for bit).
  void set_relayout_every_step(bool on) { relayout_every_step_ = on; }
  // Threads the step's independent per-vertex and per-stencil passes are split over (1..64, the
  // calling thread included; the vertex sweep itself stays on the calling thread). The state is the
  // same bit for bit at any count (core/common/worker_pool.hpp); not part of it. Throws
  // InvalidArgument outside 1..64.
  void set_worker_threads(unsigned threads);
  unsigned worker_threads() const { return workers_ ? workers_->threads() : 1; }
  // How many times a surface's layout was kept (its values refreshed) instead of rebuilt. Not state.
  std::uint64_t layouts_kept() const { return layouts_kept_; }
  std::uint32_t attachment_count() const { return static_cast<std::uint32_t>(attachments_.size()); }
  bool attachment_intact(std::uint32_t i) const { return attachments_.at(i).intact; }
  // Intact and both ends still exist (a removed or cut-away end is only marked broken at the next step).
  bool attachment_holds(std::uint32_t i) const;
  // Severs every intact stalk (an attachment with a rest length, both ends on surfaces) for which
  // `severs(top, base)` is true — given the strand's two ends, surface_a's (the elevated layer's)
  // and surface_b's — the one mechanism by which any instrument cuts a bridge between two layers:
  // the guillotine's reach, the scissors' closing jaws, a blade's sweep (core/instruments
  // topology_adapter.cpp). The attachments break at the next step boundary, reported like any
  // broken attachment (magnitude: the force they last carried), and their ends are woken. Returns
  // how many it severed. A coincident attachment (rest length 0) goes only with its tissue.
  template <class Severs>
  std::uint32_t cut_attachments_if(Severs&& severs);
  // cut_attachments_if for the stalks whose midpoint lies in the hemisphere of `radius_mm` about
  // `center_mm` on the side `normal` points to — what a vitrector's cut reaches in front of its port.
  std::uint32_t cut_attachments_in(const Vec3& center_mm, const Vec3& normal, double radius_mm);
  // Force the attachment carried during the last step (µN): the constraint multiplier over h².
  double attachment_force(std::uint32_t i) const { return attachments_.at(i).last_force_un; }
  double attachment_break_force(std::uint32_t i) const { return attachments_.at(i).d.break_force_un; }
  // The slot of the attachment's first end (surface_a's vertex) now (cuts move vertices to new slots).
  std::uint32_t attachment_vertex_a(std::uint32_t i) const { return attachments_.at(i).a.index; }
  // The slot of its second end (surface_b's vertex; unused when surface_b is kWorld).
  std::uint32_t attachment_vertex_b(std::uint32_t i) const { return attachments_.at(i).b.index; }
  // Events of the last step (valid until the next step).
  const std::vector<TissueEvent>& events() const { return events_; }
  std::uint64_t step_count() const { return step_count_; }
  double time_s() const { return time_s_; }

  double total_mass() const;
  // Mass the topology hooks' cleanup removed as lone sliver fragments after the solver's tears and
  // creep (g, since the world was built): total_mass() = initial − this − what tools removed.
  double cleanup_removed_mass_g() const { return cleanup_removed_mass_g_; }
  Energy energy() const;
  std::uint64_t state_hash() const;

  // Wakes every sleeping vertex within radius of a point (instruments call this where they act).
  void wake_sphere(const Vec3& center_mm, double radius_mm);
  void wake_all();
  // Awake vertex blocks over all surfaces (for diagnostics and benchmarks).
  std::uint32_t awake_blocks() const;
  // Ok when the solver's sleep groups of every surface, as the last step left them, are what a
  // rebuild from the surface's springs would give (spring_groups.hpp; for tests).
  Status check_spring_groups() const;
  // Times the solver rebuilt its sleep groups from every spring, over all surfaces (benchmarks).
  std::uint64_t spring_group_rebuilds() const;
  std::uint32_t total_blocks() const;

 private:
  template <class IO>
  void state_io(IO& io);
  struct Attachment {
    AttachmentDescription d;
    VertexId a, b;
    bool intact = true;
    bool cut = false;  // severed by an instrument since the last step boundary (cut_attachments_if)
    double last_force_un = 0.0;
    double peak_force_un = 0.0;
  };
  struct LocalForce {
    LocalForceDescription d;
  };

  // ---- What the vertex sweep reads (pack_terms, every step: laid out afresh or its values refreshed; stage_solve.cpp) -------
  // A spring as seen from one of its movable ends (each spring appears once per movable end).
  struct SpringTerm {
    std::uint32_t other;       // the vertex at the far end
    std::uint32_t wake_block;  // 1 + the block of a sleeping far end (the pull may wake it); 0: none
    double k;                  // µN/mm
    double rest_len;
    double damping;            // k τ / h: the dashpot's coefficient over a substep
    double wake_length;        // the spring's length when that block fell asleep
  };
  // A bending stencil (Surface::BendStencil) as the step sees it: its energy is
  // ½ k |Σ_c K_c x_c − target|², the target fixed for the step (build_bend_rows turns the stencils
  // of each vertex into one row of constant coefficients).
  struct Stencil {
    std::array<std::uint32_t, 4> v;  // a, b (the spring's ends), c, d (opposite vertices)
    std::array<double, 4> K;
    double k;       // µN/mm
    Vec3 target;    // h₀ n̂: the rest curvature along this step's stencil normal
  };
  struct StencilRef {
    std::uint32_t stencil;
    std::uint32_t corner;  // 0..3
  };
  // A point p = Σ b_j x_j of up to three vertices (of any surfaces) held to a target: an
  // attachment (isotropic, p = x_a − x_b, target 0, or x_a to a world point), a grip (the
  // barycentric point of a triangle to the jaws) or a contact (one-sided: n·(p − target) ≥ offset,
  // the tissue kept out of an instrument capsule).
  enum class PointKind : std::uint8_t { kAttachment, kGrip, kContact };
  struct PointTerm {
    PointKind kind;
    std::uint8_t count;
    std::uint32_t owner;                        // attachment, grip or collider index
    std::array<std::uint32_t, 3> surface{}, vertex{};
    std::array<double, 3> b{};
    Vec3 target = Vec3::Zero();
    Vec3 normal = Vec3::Zero();                 // contacts: the push direction
    double offset = 0.0;                        // contacts: the capsule radius
    double k = 0.0;
    Vec3 point(const TissueWorld& w) const;     // p with the current positions
  };
  struct PointRef {  // a vertex's share of a point term, in a per-vertex chain
    std::uint32_t term;
    std::uint32_t corner;
    std::uint32_t next;
  };
  struct Scratch {  // per surface, sized to capacity once
    std::vector<Vec3> previous, acceleration, rollback_x, rollback_v;
    std::vector<double> drag_rate;
    std::vector<double> velocity_keep;  // 1 / (1 + h·drag_rate): the implicit drag's factor per substep
    // Inverse mass seen by the constraints during this step: 1 / (m + h·c). Treating drag
    // implicitly adds h·c to the mass in the substep's equations; using the same effective mass
    // in prediction and projection keeps static equilibria and force estimates unbiased by drag.
    std::vector<double> effective_inverse_mass;
    std::vector<double> current_area;  // each vertex's share of the current (stretched) area
    // Twice each triangle's current area, computed once per step for the triangles of awake
    // vertices (area_epoch tells which are this step's), shared by its three corners.
    std::vector<double> triangle_area2;
    std::vector<std::uint64_t> triangle_epoch;
    std::uint64_t area_epoch = 0;
    // Normal load (acceleration) with which a vertex lies on the globe wall; 0 when not in contact.
    std::vector<double> contact_load;
    // Where contact_load > 0: the wall's outward unit normal under the vertex at the step's start,
    // used for the contact's friction in every substep (the normal turns by ~1e-4 rad over the
    // micrometres a vertex on the wall moves in a step; taking it once saves a root and a division
    // per vertex and substep in the prediction and again in the sweep). Set with contact_load.
    std::vector<Vec3> contact_normal;
    // Set when the wall moved the vertex in this substep: its velocity into the wall is then
    // removed (an inelastic contact, as in the velocity pass of Müller et al. 2020) so it cannot
    // bounce between wall and springs from one substep to the next.
    std::vector<std::uint8_t> wall_touched;
    // Where a vertex's next substep starts (see integrate_and_predict); state: it decides the next
    // step. kStartCarried: its motion continued undamped; kStartDamped: continued with the fluid's
    // drag; kStartInertial: the inertial target x̃ (springs far stiffer than its inertia).
    static constexpr std::uint8_t kStartDamped = 0, kStartCarried = 1, kStartInertial = 2;
    std::vector<std::uint8_t> momentum;  // kStart* (see integrate_and_predict)

    // Sleeping bookkeeping, per vertex block.
    std::vector<std::uint8_t> block_was_awake;  // awake during the previous step
    // This step's awake blocks in order (listed at its start: blocks wake and sleep only between
    // the substeps and the step's end), the items the worker pool splits (for_awake_blocks).
    std::vector<std::uint32_t> awake_blocks;
    std::uint32_t awake_block_count = 0;
    std::vector<std::uint8_t> wake_request;     // set during a step, applied at its end
    std::vector<double> block_max_speed2;
    // What decides each block's sleep (finish_sleep): the largest of block_max_speed2 over the block
    // and every block it shares a spring with. Not state: recomputed at the end of every step.
    std::vector<double> block_sleep_speed2;
    // Largest displacement² of each block's vertices in the current substep, and their sum (of
    // the roots) over this step's substeps: how far any vertex of the block can have moved, for
    // Surface::block_drift_mm. Not state: reset at the start of every step.
    std::vector<double> block_max_move2, block_step_drift_mm;
    // What a sleeping block's springs to awake vertices looked like when it fell asleep: each
    // block counts its sleeps, and a spring remembers its length for (block, count) — the first
    // step it is packed with that block asleep (pack_terms). A sleeping block wakes when the
    // length changes, not because it rests under tension (a detached retina always does).
    std::vector<std::uint32_t> block_sleep_serial;
    std::vector<std::uint64_t> wake_key;
    std::vector<double> wake_length;
    // Springs grouped by sleep block, so a sweep can skip whole groups that touch only sleeping
    // blocks (spring_groups.hpp). Derived from the topology, not state.
    SpringGroups groups;
    // The vertex sweep's input (pack_terms): the movable vertices of awake blocks in sweep
    // (mesh) order, and for each its springs and stencils, contiguous (CSR: the terms of
    // active[i] are [spring_begin[i], spring_begin[i + 1]) and likewise for stencils).
    std::vector<std::uint32_t> active;
    std::uint32_t active_count = 0;
    std::vector<std::uint32_t> slot;  // per vertex: its index in active, or kNone
    std::vector<std::uint32_t> spring_begin, stencil_begin;
    std::vector<SpringTerm> spring_terms;
    std::vector<StencilRef> stencil_refs;
    std::vector<Stencil> stencils;
    std::uint32_t stencil_count = 0;
    std::vector<std::uint32_t> fill;  // scratch for the CSR fill
    // The layout above (which vertices, which springs and stencils, where) depends only on the
    // topology, the awake blocks and which of their vertices are movable; while none of them
    // changes, pack_terms keeps it and refreshes the values from the springs and stencils they
    // came from (spring_edge, stencil_edge: the spring of each term and stencil).
    std::vector<std::uint32_t> spring_edge, stencil_edge;
    // The bending energy's Hessian Q = Σ k K Kᵀ over the stencils is constant while the stencils'
    // K and k are, so each active vertex's bending force is bend_force[i] − bend_diag[i] x_i −
    // Σ_j Q_ij x_j: a row of its stencils' other corners (bend_begin CSR over bend_other and
    // bend_coef), laid out with the layout and whenever the springs' values change
    // (build_bend_rows), and bend_force = Σ k K_i target once a step (bend_rest_forces).
    std::vector<std::uint32_t> bend_begin, bend_other;
    std::vector<double> bend_coef, bend_diag;
    std::vector<Vec3> bend_force;
    bool layout_valid = false;
    std::uint64_t layout_topology = 0, layout_awake = 0;
    // The surface's spring values and the dashpot factor the spring terms were last filled from.
    std::uint64_t layout_spring_values = 0;
    double layout_damping_per_k = 0.0;
    std::vector<Vec3> target;         // the inertial target x̃ of the substep
    std::vector<std::uint32_t> point_head;  // per vertex: its first PointRef, or kNone
  };
  struct TearCandidate {
    std::uint32_t surface;
    EdgeId edge;
    double strain;
  };

  // Stages of a step (one file each: stage_forces.cpp, stage_solve.cpp, stage_instruments.cpp,
  // stage_step.cpp).
  void compute_external_accelerations(double h);
  void integrate_and_predict(double h);
  void pack_terms(double h);
  bool refresh_packed_values(std::uint32_t si, double h);
  void add_point_terms(double fraction);
  void add_point_term(const PointTerm& term);
  void clear_point_terms();
  void reserve_point_terms();
  void build_bend_rows(std::uint32_t si);
  void bend_rest_forces(std::uint32_t si);
  void sweep_vertices(double h);
  void measure_point_forces(double fraction_of_step);
  void project_contacts(double h, double fraction);
  void break_grips();
  void rebind_grips();
  bool update_velocities(double h);
  void break_attachments();
  void find_overstrained();
  void tear_overstrained();
  void creep_and_tidy(double dt_s);
  // Calls f(block, first vertex, end vertex) for each of surface si's awake blocks of this step,
  // split over the worker pool's threads: only for passes whose blocks are independent.
  template <class F>
  void for_awake_blocks(std::uint32_t si, F&& f);
  // The same per vertex: f(v) for every vertex slot of the awake blocks.
  template <class F>
  void for_awake_vertices(std::uint32_t si, F&& f) {
    for_awake_blocks(si, [&](std::uint32_t, std::uint32_t first, std::uint32_t end) {
      for (std::uint32_t v = first; v < end; ++v) f(v);
    });
  }
  void prepare_sleep_groups();
  void finish_sleep();
  template <class F>
  void for_each_active_edge(std::uint32_t si, F&& f);
  void save_rollback();
  void restore_rollback();

  GlobeWall wall_;
  Environment environment_;
  SolverSettings settings_;
  bool relayout_every_step_ = false;
  std::unique_ptr<WorkerPool> workers_;  // null: the step runs on the calling thread alone
  std::uint64_t layouts_kept_ = 0;
  std::vector<std::unique_ptr<Surface>> surfaces_;
  std::vector<std::unique_ptr<TopologyHook>> hooks_;  // per surface, may be null
  std::vector<Scratch> scratch_;
  std::vector<std::uint32_t> crept_short_;  // vertices of springs that crept below the floor this step
  double cleanup_removed_mass_g_ = 0.0;
  std::vector<Attachment> attachments_;
  bool breaking_ = true;  // see set_breaking()
  std::vector<LocalForce> local_forces_;
  std::vector<TissueEvent> events_;
  std::vector<TearCandidate> tear_candidates_;

  struct Grip {
    GripDescription d;
    Vec3 previous_target = Vec3::Zero();  // target at the start of the step (substeps interpolate)
    Vec3 last_point = Vec3::Zero();       // where the gripped point was at the end of the last step
    std::array<std::uint32_t, 3> vertices{};  // of the gripped triangle (to follow it through tears)
    bool active = false;
    double last_force_un = 0.0;
    double peak_force_un = 0.0;
  };
  std::vector<ColliderCapsule> colliders_;
  std::uint32_t collider_count_ = 0;
  std::vector<ContactCandidate> candidates_;
  std::vector<SuctionField> suction_;
  std::vector<Vec3> contact_force_;     // kMaxColliders × surfaces, accumulated over a step
  std::vector<double> contact_depth_;   // kMaxColliders
  std::vector<Grip> grips_;
  std::uint32_t grip_high_water_ = 0;
  // The point terms of the step (attachments and grips) and of the substep (contacts), and each
  // vertex's chain of references to them (Scratch::point_head). Sized once.
  std::vector<PointTerm> point_terms_;
  std::vector<PointRef> point_refs_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> point_vertices_;  // (surface, vertex) with a chain
  std::uint64_t step_count_ = 0;
  double time_s_ = 0.0;
};

// Calls f(edge) for every spring in a group that touches an awake block (prepare_sleep_groups()
// decides which), in a fixed order: mesh order within a group, groups in block order.
template <class F>
void TissueWorld::for_each_active_edge(std::uint32_t si, F&& f) {
  scratch_[si].groups.for_each_active(f);
}

template <class F>
void TissueWorld::for_awake_blocks(std::uint32_t si, F&& f) {
  const Scratch& sc = scratch_[si];
  const std::uint32_t n = surfaces_[si]->vertex_slots();
  run_sliced(workers_.get(), sc.awake_block_count, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::uint32_t b = sc.awake_blocks[i];
      f(b, b * Surface::kSleepBlock, std::min(n, (b + 1) * Surface::kSleepBlock));
    }
  });
}

template <class Severs>
std::uint32_t TissueWorld::cut_attachments_if(Severs&& severs) {
  std::uint32_t severed = 0;
  for (Attachment& at : attachments_) {
    if (!at.intact || at.cut || !(at.d.rest_length_mm > 0.0)) continue;
    Surface& sa = *surfaces_[at.d.surface_a];
    Surface& sb = *surfaces_[at.d.surface_b];
    if (!sa.is_current(at.a) || !sb.is_current(at.b)) continue;
    if (!severs(sa.position(at.a.index), sb.position(at.b.index))) continue;
    at.cut = true;
    sa.wake_vertex(at.a.index);
    sb.wake_vertex(at.b.index);
    ++severed;
  }
  return severed;
}

}  // namespace vitreo::core

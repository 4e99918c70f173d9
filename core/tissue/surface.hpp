#pragma once
// One physical tissue surface (retina, membrane, gel layer): vertices joined by springs, grouped into
// triangles, with stable handles and fixed-capacity pools.
//
// Memory is reserved once when the surface is built (with room for cuts and tears) and never grows:
// topology changes take slots from free lists and refuse, with an error, when the pools are full.
// That keeps allocation out of the physics step. Vertex data is stored as parallel arrays in mesh
// order (the order of the generating rings), which is the order the solver sweeps.
//
// The model: springs along the triangles' edges keep their rest length (stiffness weighted by the
// adjacent rest area, so a triangulation reproduces the membrane modulus — the thesis' ch. 2.3 after
// Wilhelms & Van Gelder; a triangle's three springs also hold its in-plane shape, so shear is
// resisted without any direction in the world frame), bending stencils across interior springs keep
// the rest curvature (see BendStencil), and vertex mass comes from the adjacent rest area, so total
// mass is conserved when triangles are subdivided and drops in proportion to removed area. Every
// elastic term depends only on lengths and curvatures: turning the tissue rigidly stores no energy.
// Springs still carry a rest *vector* (the thesis' vector springs): the rest shape, which new
// springs inherit by vector addition when topology changes (see below) and from which the rest
// curvature is measured; its direction in the world plays no part in the forces.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/common/state_io.hpp"
#include "core/common/status.hpp"
#include "core/common/types.hpp"
#include "core/geometry/triangle_mesh.hpp"
#include "core/tissue/handles.hpp"
#include "core/tissue/material.hpp"

namespace vitreo::core {

struct SurfaceCapacity {
  // Slots reserved beyond the initial mesh, as a fraction of its size, plus a fixed minimum.
  double growth_fraction = 0.5;
  std::uint32_t minimum_extra = 1024;
};

// A spring that is not an edge of any triangle (a chain, a suture): explicit stiffness, no area.
struct LineSpring {
  std::uint32_t a;
  std::uint32_t b;
  double stiffness_un_per_mm;
};

struct SurfaceDescription {
  TissueMaterial material;
  TriangleMesh mesh;
  std::vector<LineSpring> line_springs;
  // Mass added to individual vertices (g), e.g. the beads of a chain; empty or one per vertex.
  std::vector<double> extra_vertex_mass_g;
  // True when the globe wall must keep this surface inside the eye.
  bool contained_by_globe = true;
  // True when intraocular pressure presses this surface outward onto the globe wall (the retina
  // onto the choroid). A membrane floating in vitreous has fluid on both sides: false.
  bool pressurised = false;
  SurfaceCapacity capacity;
};

class Surface {
 public:
  // Throws InvalidArgument for an invalid material, non-finite positions, out-of-range indices,
  // degenerate (zero-area) triangles, or non-manifold input (an edge shared by more than two triangles).
  explicit Surface(const SurfaceDescription& description);

  const TissueMaterial& material() const { return material_; }
  bool contained_by_globe() const { return contained_by_globe_; }
  bool pressurised() const { return pressurised_; }

  // ---- Vertices ----------------------------------------------------------------------------
  std::uint32_t vertex_slots() const { return static_cast<std::uint32_t>(vertex_alive_.size()); }
  std::uint32_t vertex_capacity() const { return static_cast<std::uint32_t>(x_.capacity()); }
  std::uint32_t vertex_count() const { return live_vertices_; }
  bool vertex_alive(std::uint32_t v) const { return v < vertex_slots() && vertex_alive_[v] != 0; }
  VertexId vertex_id(std::uint32_t v) const { return {v, vertex_generation_[v]}; }
  bool is_current(VertexId id) const {
    return id.index < vertex_slots() && vertex_alive_[id.index] && vertex_generation_[id.index] == id.generation;
  }

  const Vec3& position(std::uint32_t v) const { return x_[v]; }
  const Vec3& velocity(std::uint32_t v) const { return v_[v]; }
  const Vec3& rest_position(std::uint32_t v) const { return rest_[v]; }
  double mass(std::uint32_t v) const { return mass_[v]; }
  double extra_mass(std::uint32_t v) const { return extra_mass_[v]; }
  double inverse_mass(std::uint32_t v) const { return inverse_mass_[v]; }
  bool is_fixed(std::uint32_t v) const { return fixed_[v] != 0; }
  double vertex_rest_area(std::uint32_t v) const { return vertex_area_[v]; }

  // Anchors a vertex (ora serrata, optic disc) or frees it. Anchored vertices keep their position
  // unless moved with set_fixed_position.
  Status set_fixed(VertexId v, bool fixed);
  Status set_fixed_position(VertexId v, const Vec3& position_mm);
  // Moves a free vertex (e.g. to place a scene); velocity is unchanged. Refuses non-finite values.
  Status set_position(VertexId v, const Vec3& position_mm);
  Status set_velocity(VertexId v, const Vec3& velocity_mm_s);

  // ---- Springs (edges) -----------------------------------------------------------------------
  std::uint32_t edge_slots() const { return static_cast<std::uint32_t>(edge_alive_.size()); }
  std::uint32_t edge_count() const { return live_edges_; }
  std::uint32_t edge_capacity() const { return static_cast<std::uint32_t>(edge_v_.capacity()); }
  bool edge_alive(std::uint32_t e) const { return e < edge_slots() && edge_alive_[e] != 0; }
  EdgeId edge_id(std::uint32_t e) const { return {e, edge_generation_[e]}; }
  bool is_current(EdgeId id) const {
    return id.index < edge_slots() && edge_alive_[id.index] && edge_generation_[id.index] == id.generation;
  }
  std::array<std::uint32_t, 2> edge_vertices(std::uint32_t e) const { return edge_v_[e]; }
  std::array<std::uint32_t, 2> edge_triangles(std::uint32_t e) const { return edge_t_[e]; }
  // Rest length including traction scaling.
  double edge_rest_length(std::uint32_t e) const { return rest_len_[e]; }
  // Tension of the spring now (µN, positive when stretched).
  double edge_force(std::uint32_t e) const;
  // Bending across an interior spring (one shared by two triangles): the stencil of the spring's
  // ends and the two opposite vertices, after the quadratic bending model of Bergou, Wardetzky,
  // Harmon, Zorin & Grinspun 2006 ("A quadratic bending model for inextensible surfaces").
  // The curvature vector of the stencil, H = Σ K_i x_i, is held at `rest_curvature` along the
  // stencil's normal with stiffness D / (A_0 + A_1) (D = material bending modulus, A the rest areas
  // of the two triangles): energy ½ k |H − h₀ n̂|², which is rotation invariant (H turns with the
  // tissue, and so does n̂) and equals ½ D (κ₁ + κ₂)² per unit area on smooth bending
  // (tests/core/bending_test.cpp checks it against a cylinder and a sphere).
  struct BendStencil {
    std::array<double, 4> K{};   // weights of a, b (the spring's ends), c, d (opposite in its triangles 0, 1)
    double stiffness = 0.0;      // µN/mm; 0 for boundary and line springs
    double orientation = 1.0;    // +1 when triangle 0 runs a → b, else −1 (see normal)
    // The stencil's unit normal: the sum of its two triangles' area-weighted normals, which for a
    // consistently oriented mesh is ±(b − a) × (c − d) (zero when degenerate).
    Vec3 normal(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) const {
      const Vec3 n = (b - a).cross(c - d) * orientation;
      const double len = n.norm();
      return len > 0.0 ? Vec3(n / len) : Vec3::Zero();
    }
    // The curvature vector H = Σ K_i x_i.
    Vec3 curvature(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) const {
      return K[0] * a + K[1] * b + K[2] * c + K[3] * d;
    }
  };
  const BendStencil& edge_bend(std::uint32_t e) const { return bend_[e]; }
  // h₀: the stencil's curvature vector at rest, along its normal (mm; signed by the triangles'
  // orientation). Taken from the rest vectors when the spring's triangles change; plasticity
  // creeps it toward the current shape. State (snapshots keep it).
  double edge_rest_curvature(std::uint32_t e) const { return bend_rest_[e]; }
  // The vertices opposite spring e in its two triangles (kNone where it has no such triangle).
  std::array<std::uint32_t, 2> edge_opposite_vertices(std::uint32_t e) const {
    std::array<std::uint32_t, 2> o{kNone, kNone};
    for (std::size_t i = 0; i < 2; ++i) {
      const std::uint32_t t = edge_t_[e][i];
      if (t != kNone) o[i] = tri_v_[t][0] + tri_v_[t][1] + tri_v_[t][2] - edge_v_[e][0] - edge_v_[e][1];
    }
    return o;
  }
  const Vec3& edge_rest_vector(std::uint32_t e) const { return rest_vec_[e]; }
  double edge_stiffness(std::uint32_t e) const { return stiffness_[e]; }
  double edge_strain(std::uint32_t e) const;

  // Traction (thesis ch. 2.3.1, 2.4): contracting tissue is modelled by scaling rest lengths down.
  // The effective rest vector is base × surface scale × spring scale. Scales must lie in [0.2, 2].
  Status set_surface_traction(double scale);
  Status set_edge_traction(EdgeId e, double scale);
  double surface_traction() const { return surface_traction_; }

  // ---- Triangles -----------------------------------------------------------------------------
  std::uint32_t triangle_slots() const { return static_cast<std::uint32_t>(tri_alive_.size()); }
  std::uint32_t triangle_count() const { return live_triangles_; }
  std::uint32_t triangle_capacity() const { return static_cast<std::uint32_t>(tri_v_.capacity()); }
  bool triangle_alive(std::uint32_t t) const { return t < triangle_slots() && tri_alive_[t] != 0; }
  TriangleId triangle_id(std::uint32_t t) const { return {t, tri_generation_[t]}; }
  std::array<std::uint32_t, 3> triangle_vertices(std::uint32_t t) const { return tri_v_[t]; }
  std::array<std::uint32_t, 3> triangle_edges(std::uint32_t t) const { return tri_e_[t]; }
  double triangle_rest_area(std::uint32_t t) const { return tri_rest_area_[t]; }

  // Calls f(triangle, corner) for every live triangle using vertex v (corner = 0..2: where v sits).
  template <class F>
  void for_each_triangle_of(std::uint32_t v, F&& f) const {
    for (std::uint32_t c = first_corner_[v]; c != kNone; c = next_corner_[c]) f(c / 3, c % 3);
  }
  // The edge joining a and b, or kNone.
  std::uint32_t find_edge(std::uint32_t a, std::uint32_t b) const;

  // ---- Totals --------------------------------------------------------------------------------
  double total_mass() const;       // g, sum over live vertices
  double total_rest_area() const;  // mm², sum over live triangles

  // ---- Topology: tearing ---------------------------------------------------------------------
  // Splits spring e at its midpoint and opens a crack across it into the adjacent triangles
  // (thesis ch. 2.6.2.3: a fractured spring becomes two sub-springs with independent fracture
  // vertices; adjacent triangles are subdivided). The crack is placed exactly at the strained spring,
  // never at a far vertex. Mass is redistributed from rest areas, so the total is unchanged.
  // Refuses (and changes nothing) when e is stale or the pools are full. Returns the two new vertices.
  struct TearResult {
    Status status = Status::ok();
    std::uint32_t vertex_a_side = kNone;
    std::uint32_t vertex_b_side = kNone;
  };
  TearResult tear_edge(EdgeId e);

  // ---- Topology: low-level primitives (core/topology builds cuts, tears and removal on them) --
  // Every primitive refuses (changing nothing) on a stale handle, an out-of-range parameter or a
  // full pool; on success it bumps topology_version(), wakes what it touched, keeps check_surface()
  // passing and keeps the mass exact (vertex mass = areal density × adjacent rest area / 3 + extra).
  // Rest vectors of new springs are built from the springs' rest vectors by vector addition (the
  // undeformed, possibly plastically crept, configuration), never from current positions.
  struct SplitResult {
    Status status = Status::ok();
    std::uint32_t vertex = kNone;  // the new vertex
  };
  // split_edge / split_triangle refuse to create a spring with a shorter rest length than this
  // (a sliver whose rest shape puts the new vertex on an existing one).
  static constexpr double kMinNewSpringRest_mm = 1e-6;
  // True when the pools can take this many more vertices, springs and triangles.
  bool has_room(std::uint32_t vertices, std::uint32_t edges, std::uint32_t triangles) const;
  // Inserts a vertex on spring e at parameter t ∈ (0, 1) measured from edge_vertices(e)[0] and splits
  // each adjacent triangle in two (rest areas t·A and (1 − t)·A, exactly). e's handle goes stale.
  SplitResult split_edge(EdgeId e, double t);
  // Inserts a vertex inside triangle t at barycentric coordinates (all > 0, sum 1) and splits it
  // into three (rest areas λ·A, exactly).
  SplitResult split_triangle(TriangleId t, const std::array<double, 3>& barycentric);
  // Gives the second triangle of interior spring e its own copy of the spring, so the two
  // triangles no longer share it (the first half of opening a cut). Rest vector, traction and the
  // fan of each end vertex are unchanged until separate_vertex_fans splits them. Refuses a boundary
  // spring or a line spring.
  struct DisconnectResult {
    Status status = Status::ok();
    std::uint32_t copy = kNone;  // the second triangle's new spring
  };
  DisconnectResult disconnect_edge(EdgeId e);
  // Where v's triangles form several fans (after disconnect_edge or remove_triangle), every fan
  // after the first moves to a new copy of v (same position, velocity, rest position, fixed flag;
  // extra mass and attachments stay with v). Returns the number of copies made.
  // When copies is given, the new vertices are appended to it (within its reserved capacity).
  std::uint32_t separate_vertex_fans(VertexId v, std::vector<std::uint32_t>* copies = nullptr);
  struct RemoveResult {
    Status status = Status::ok();
    double removed_area_mm2 = 0.0;
    double removed_mass_g = 0.0;  // exact: total_mass() drops by this much
    std::uint32_t vertices_removed = 0;
  };
  // Removes triangle t, the springs left without triangles and the vertices left without any
  // triangle (with their extra mass; line springs to them go too), and separates bow-tie fans —
  // unless separate_fans is false: a caller removing many triangles at once then calls
  // separate_vertex_fans on the corners itself, after the last one (check_surface fails until then).
  RemoveResult remove_triangle(TriangleId t, bool separate_fans = true);
  // Collapses spring e into its end `keep` (mesh cleanup, core/topology/quality.hpp): the other
  // end goes (its handle goes stale), the one or two triangles on e go, and in each of them the
  // two springs to the opposite vertex become one (keep's). Rules: keep's position, rest position,
  // fixed flag and handle stay; the removed vertex's extra mass moves to keep and keep takes the
  // mass-weighted mean velocity (momentum kept); springs of the removed vertex are re-homed to keep
  // with rest vectors by vector addition; the rest area of each removed triangle goes to the
  // triangle across its removed spring (or, on a boundary, across the kept one), so rest area and
  // mass stay exact. Refuses, changing nothing: a stale handle, keep not an end of e, a line
  // spring or one without triangles, a removed vertex that is fixed (unless keep is too) or on the
  // boundary while keep is not, an interior spring joining two boundary vertices (it would pinch
  // the surface), the link condition failing (a vertex adjacent to both ends other than the
  // opposite vertices: the result would not be manifold), a triangle that would flip or become
  // degenerate (rest or current shape), or one whose smallest rest angle would fall below
  // min_result_angle_rad.
  struct CollapseResult {
    Status status = Status::ok();
    std::uint32_t removed_vertex = kNone;
    std::uint32_t triangles_removed = 0;
  };
  // allow_pinch: collapse an interior spring between two boundary vertices anyway and give each
  // fan of the kept vertex its own vertex afterwards (the surface parts there: for necks narrower
  // than the minimum spring, which would tear at once).
  // min_result_spring_mm: refuse, too, when a spring moved from the removed vertex to keep would get
  // a shorter rest length than this (the cleanup's floor: a collapse must not make another sliver).
  CollapseResult collapse_edge(EdgeId e, std::uint32_t keep, double min_result_angle_rad = 0.0, bool allow_pinch = false,
                               double min_result_spring_mm = 0.0);
  // Merges triangle t into `receiver`, a triangle sharing a spring with it: t goes (springs left
  // without a triangle go, bow-ties are separated) and its rest area is added to the receiver's,
  // so mass stays exact; where t lay the surface opens (for slivers no collapse can remove).
  // A corner with no other triangle goes with t. Refuses, changing nothing: stale handles,
  // triangles that share no spring, such a corner being fixed or carrying extra mass, full pools.
  Status dissolve_triangle(TriangleId t, TriangleId receiver);
  // Smallest angle of triangle t measured on its springs' rest vectors (radians).
  double triangle_min_rest_angle(std::uint32_t t) const;
  bool is_boundary_vertex(std::uint32_t v) const;
  bool edge_is_line(std::uint32_t e) const { return edge_is_line_[e] != 0; }
  double edge_traction(std::uint32_t e) const { return edge_traction_[e]; }

  // ---- Sleeping ------------------------------------------------------------------------------
  // Vertices are grouped in blocks of kSleepBlock consecutive slots (mesh order, so a block is a
  // compact strip of surface). A block at rest for a while sleeps: the solver skips it and its
  // neighbours see its vertices as anchored, until something wakes it (a pull from an awake
  // neighbour, a changed force, an instrument, a topology change). Retina lying on the choroid is
  // most of the eye and at rest most of the time; this is what lets a 1 ms step afford it.
  // 16, not more: on a revolved mesh a block is a strip of one ring, and a longer strip (64 was a
  // third of a ring 60° from the pole) keeps still tissue beside any moving region awake.
  static constexpr std::uint32_t kSleepBlock = 16;
  std::uint32_t block_count() const { return static_cast<std::uint32_t>(block_awake_.size()); }
  bool block_awake(std::uint32_t b) const { return block_awake_[b] != 0; }
  bool vertex_awake(std::uint32_t v) const { return block_awake_[v / kSleepBlock] != 0; }
  // Waking does not move anything: what places a vertex (a new slot, set_position, a restore)
  // bumps block_motion itself.
  void wake_vertex(std::uint32_t v) {
    std::uint8_t& awake = block_awake_[v / kSleepBlock];
    awake_version_ += awake == 0;
    awake = 1;
    block_quiet_steps_[v / kSleepBlock] = 0;
  }
  // Changes whenever a block wakes or falls asleep (or a snapshot replaces them all), so the
  // solver knows when the awake region it laid out is still the same. Not part of the state.
  std::uint64_t awake_version() const { return awake_version_; }
  void wake_all();
  // Motion bounds for spatial indexes (core/topology/vertex_index.hpp), in two parts:
  //  - block_motion(b) changes whenever b's vertices may have moved other than by the solver's
  //    steps: a vertex was added in one of its slots (every new vertex is placed there: a split,
  //    a tear, a separated copy) or placed by hand (set_position), or a snapshot was restored.
  //    Where it changed, an index knows nothing and must look again. Waking a block, or changing
  //    its vertices' springs, masses or links, moves nothing and leaves it as it was.
  //  - block_drift_mm(b) only grows, by at least how far any vertex of b moved during each step
  //    (the solver reports each substep's largest displacement: note_awake_blocks_moved). Where
  //    block_motion(b) is unchanged since an index read drift d0, every vertex of b lies within
  //    block_drift_mm(b) − d0 of where the index saw it: a box grown by that much still holds
  //    them, so a query far from it need not look again (tissue that only settles by micrometres
  //    a step is not re-read every step).
  // Not part of the state: a restored snapshot bumps every block_motion.
  std::uint32_t block_motion(std::uint32_t b) const { return block_motion_[b]; }
  double block_drift_mm(std::uint32_t b) const { return block_drift_mm_[b]; }
  void note_awake_blocks_moved(std::span<const double> step_drift_mm);
  void note_all_blocks_moved();
  // Called by the solver at the end of a step with each block's largest squared speed.
  void update_sleep(std::span<const double> block_max_speed2, double sleep_speed2, std::uint32_t steps_to_sleep);
  std::uint32_t awake_block_count() const;
  // Incremented by every topology change, so solver-side indexes know when to rebuild.
  std::uint64_t topology_version() const { return topology_version_; }
  // Changes whenever a spring's rest length or stiffness may have changed (creep, traction, a
  // stiffness recomputed, a snapshot restored), so the solver knows when the values it copied
  // into its sweep layout still stand. Not part of the state.
  std::uint64_t spring_values_version() const { return spring_values_version_; }

  // ---- Spring log ------------------------------------------------------------------------------
  // Every spring added, removed or moved to another vertex is logged by its slot (a slot may
  // appear several times), so a structure derived from the springs — the solver's sleep groups —
  // can follow a topology change by looking at those slots instead of every spring. The log is a
  // ring of kSpringLogSize entries under a position that only grows: a reader remembers the
  // position it has read to (spring_log_end()) and reads the entries from there; where it has
  // fallen more than the ring behind, or the surface's springs were replaced wholesale (a restored
  // snapshot: forget_spring_log), spring_log_lost says so and the reader rebuilds from every spring.
  // Not part of the state.
  static constexpr std::uint32_t kSpringLogSize = 8192;
  std::uint64_t spring_log_end() const { return spring_log_end_; }
  bool spring_log_lost(std::uint64_t from) const {
    return from < spring_log_kept_from_ || spring_log_end_ - from > kSpringLogSize;
  }
  std::uint32_t spring_log_at(std::uint64_t position) const { return spring_log_[position % kSpringLogSize]; }
  void forget_spring_log() { spring_log_kept_from_ = ++spring_log_end_; }  // every reader's position is lost

  // ---- State I/O (snapshots, core/scene/snapshot.hpp) ------------------------------------------
  // The mutable state, every field listed once in state_io() (surface_state.cpp) for both
  // directions. read_state on a surface built from the same description: the check pass
  // (in.applying() false) changes nothing; after the apply pass spatial indexes refit everything and
  // the spring log is forgotten (derived structures rebuild from every spring).
  void write_state(StateWriter& out) const;
  void read_state(StateReader& in);

  // ---- Solver access -------------------------------------------------------------------------
  // The solver works on the raw arrays; these are for it and for the topology code only.
  struct SolverView;
  SolverView solver_view();

  // Plastic flow, where the deformation exceeds the material's yield: rest lengths creep toward the
  // current lengths (the rest vector keeps its direction) and rest curvatures toward the current
  // curvatures, so a membrane released after a pull or a fold stays roughly where it was left.
  // Both measures are rotation invariant. Called by the solver once per step. With `crept_short`, the two ends of each
  // spring whose rest length crept from at least `floor_mm` to below it this step are appended
  // (while the list has capacity: nothing allocates), so the topology layer can tidy there.
  void apply_plasticity(double dt_s, double floor_mm = 0.0, std::vector<std::uint32_t>* crept_short = nullptr);

  // ---- Batched edits --------------------------------------------------------------------------
  // Vertex mass and spring stiffness are computed from the rest areas of the adjacent triangles.
  // Every topology edit notes the vertices and springs whose triangles it changed and recomputes
  // each of them, once, when it ends. While an EditBatch is open the notes collect instead, and
  // each noted vertex and spring is recomputed once when the outermost batch closes: a blade
  // stroke makes dozens of splits whose fans overlap, and recomputing after each would redo most
  // of them several times. Inside a batch the masses, inverse masses and stiffnesses around the
  // edits are stale (topology, rest vectors, rest areas and positions are always current); an edit
  // that reads masses (collapse_edge) brings them up to date first. The result is the same, bit for
  // bit, as making the edits one at a time: each value depends only on the final mesh.
  class EditBatch {
   public:
    explicit EditBatch(Surface& surface) : surface_(surface) { ++surface_.open_batches_; }
    ~EditBatch() {
      if (--surface_.open_batches_ == 0) surface_.refresh_noted();
    }
    EditBatch(const EditBatch&) = delete;
    EditBatch& operator=(const EditBatch&) = delete;

   private:
    Surface& surface_;
  };

  // Recomputes mass and inverse mass of vertex v from its adjacent rest area.
  void update_vertex_mass(std::uint32_t v);
  // Recomputes the stiffness of triangle edge e from its adjacent rest areas (line springs keep
  // theirs), and its bending stencil from the rest shape of its two triangles (rest curvature
  // included; the bending force starts again from zero).
  void update_edge_stiffness(std::uint32_t e);

 private:
  template <class IO>
  void state_io(IO& io);
  std::uint32_t allocate_vertex();
  std::uint32_t allocate_edge();
  std::uint32_t allocate_triangle();
  void free_edge(std::uint32_t e);
  void free_triangle(std::uint32_t t);
  std::uint32_t add_edge(std::uint32_t a, std::uint32_t b, const Vec3& base_rest_vector, double traction);
  std::uint32_t add_triangle(std::array<std::uint32_t, 3> v, double rest_area);
  void link_corner(std::uint32_t t, std::uint32_t k);
  void unlink_corner(std::uint32_t t, std::uint32_t k);
  void attach_triangle_to_edge(std::uint32_t e, std::uint32_t t);
  void detach_triangle_from_edge(std::uint32_t e, std::uint32_t t);
  void refresh_rest(std::uint32_t e);
  void update_edge_bending(std::uint32_t e);
  double triangle_spring_share(std::uint32_t t, std::uint32_t e) const;
  // The rest vector of triangle t's spring from vertex `from` to vertex `to` (zero if none).
  Vec3 rest_vector_between(std::uint32_t t, std::uint32_t from, std::uint32_t to) const;
  std::uint32_t separate_fans(std::uint32_t v, std::vector<std::uint32_t>* copies = nullptr);
  void free_vertex(std::uint32_t v);
  // Notes for the batched recomputation (see EditBatch): v's triangles changed; e's triangles
  // or rest vector changed; t's rest area changed (its corners and springs).
  void note_vertex(std::uint32_t v) {
    if (vertex_noted_[v]) return;
    vertex_noted_[v] = 1;
    noted_vertices_.push_back(v);
  }
  void note_edge(std::uint32_t e) {
    if (edge_noted_[e]) return;
    edge_noted_[e] = 1;
    noted_edges_.push_back(e);
  }
  void note_triangle_area(std::uint32_t t);
  void log_spring(std::uint32_t e) { spring_log_[spring_log_end_++ % kSpringLogSize] = e; }
  // Recomputes every noted spring's stiffness and vertex's mass (waking the vertex), and clears the notes.
  void refresh_noted();
  // The spring's rest vector oriented from vertex `from` (which must be one of its ends).
  Vec3 oriented_rest(std::uint32_t e, std::uint32_t from) const {
    return edge_v_[e][0] == from ? base_rest_vec_[e] : Vec3(-base_rest_vec_[e]);
  }

  TissueMaterial material_;
  bool contained_by_globe_ = true;
  bool pressurised_ = false;
  double surface_traction_ = 1.0;

  // Vertices.
  std::vector<Vec3> x_, v_, rest_;
  std::vector<double> mass_, inverse_mass_, extra_mass_, vertex_area_;
  std::vector<std::uint8_t> vertex_alive_, fixed_;
  std::vector<std::uint32_t> vertex_generation_, first_corner_, free_vertices_;
  std::uint32_t live_vertices_ = 0;

  // Springs.
  std::vector<std::array<std::uint32_t, 2>> edge_v_, edge_t_;
  std::vector<Vec3> base_rest_vec_, rest_vec_;
  std::vector<double> rest_len_, stiffness_, edge_traction_;
  std::vector<BendStencil> bend_;     // derived from the rest shape (update_edge_stiffness)
  std::vector<double> bend_rest_;     // state: h₀ (plasticity moves it)
  std::vector<std::uint8_t> edge_alive_, edge_is_line_;
  std::vector<std::uint32_t> edge_generation_, free_edges_;
  std::uint32_t live_edges_ = 0;

  // Triangles.
  std::vector<std::array<std::uint32_t, 3>> tri_v_, tri_e_;
  std::vector<std::uint32_t> next_corner_;  // per corner (3 per triangle slot)
  std::vector<double> tri_rest_area_;
  std::vector<std::uint8_t> tri_alive_;
  std::vector<std::uint32_t> tri_generation_, free_triangles_;
  std::uint32_t live_triangles_ = 0;

  // Sleeping.
  std::vector<std::uint8_t> block_awake_;
  std::uint64_t awake_version_ = 0;
  std::vector<std::uint16_t> block_quiet_steps_;
  std::vector<std::uint32_t> block_motion_;  // see block_motion()
  std::vector<double> block_drift_mm_;       // see block_drift_mm()
  std::uint64_t topology_version_ = 0;
  std::uint64_t spring_values_version_ = 0;  // see spring_values_version()
  std::uint32_t line_springs_ = 0;

  // Batched edits (see EditBatch): flags and lists of the noted vertices and springs.
  std::vector<std::uint8_t> vertex_noted_, edge_noted_;
  std::vector<std::uint32_t> noted_vertices_, noted_edges_;
  std::uint32_t open_batches_ = 0;

  // The spring log (see spring_log_end): a ring, the position after its last entry, and the
  // first position that is still valid (entries before it describe springs since replaced).
  std::vector<std::uint32_t> spring_log_ = std::vector<std::uint32_t>(kSpringLogSize, 0);
  std::uint64_t spring_log_end_ = 0, spring_log_kept_from_ = 0;
};

// Raw arrays handed to the solver (no copies). Valid until the next topology change.
struct Surface::SolverView {
  std::span<Vec3> x, v;
  std::span<const double> inverse_mass;
  std::span<const std::uint8_t> vertex_alive;
  std::span<const std::array<std::uint32_t, 2>> edge_v;
  std::span<const Vec3> rest_vec;
  std::span<const double> rest_len, stiffness;
  std::span<const BendStencil> bend;
  std::span<const double> bend_rest;
  std::span<const std::uint8_t> edge_alive;
  std::span<const std::array<std::uint32_t, 2>> edge_t;
  std::span<const std::array<std::uint32_t, 3>> tri_v;
  std::span<const std::uint8_t> tri_alive;
  std::span<const double> vertex_area;  // lumped rest area per vertex (for drag and local forces)
};

// Inline: the solver takes views in its per-attachment and per-stage loops.
inline Surface::SolverView Surface::solver_view() {
  return SolverView{x_,     v_,         inverse_mass_, vertex_alive_, edge_v_, rest_vec_, rest_len_, stiffness_,
                    bend_,  bend_rest_, edge_alive_,   edge_t_,       tri_v_,  tri_alive_, vertex_area_};
}

}  // namespace vitreo::core

#pragma once
// The instruments in the eye: their state, their collision shapes and what they do to the tissue.
// The simulation step (core/sim/simulation.hpp) calls the instruments' stages in order — place them
// in the eye frame (stage_place.cpp), find the tissue they may touch (stage_contacts.cpp), act
// (stage_act.cpp: grasps, laser, vitrector suction, blades), then after the tissue step feel what the
// tissue did (stage_sense.cpp: contact forces, events) and hand over cuts and removals.
//
// Cutting and removal are topology changes, which belong to core/topology: the blades and scissors
// hand their cutting edges' pose every step (CuttingPose: core/topology follows each incision pose by
// pose, so what is cut does not depend on the step length) and the vitrector what it draws in
// (RemovalRequest) to a TopologyActions implementation at the step boundary; without one they are
// still listed each step for the rig and the tests, with each blade's swept quad (BladeSweep).
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/collision/collision_scene.hpp"
#include "core/common/status.hpp"
#include "core/instruments/instrument.hpp"
#include "core/instruments/instrument_events.hpp"
#include "core/tissue/tissue_world.hpp"
#include "core/topology/vitrector.hpp"

namespace vitreo::core {

// The quad a blade's sharp edge swept during one step: the edge (a, b) at the start of the step and
// at its end. A cut is everything the quad crosses. For scissors the edge is the closed part of the
// blades (hinge → crossing point), so the quad is the strip closed during the step.
struct BladeSweep {
  std::uint32_t instrument = 0;
  InstrumentKind kind = InstrumentKind::kBlade;
  Vec3 a0 = Vec3::Zero(), b0 = Vec3::Zero();  // edge at the start of the step (eye frame)
  Vec3 a1 = Vec3::Zero(), b1 = Vec3::Zero();  // edge at the end of the step
};

// A cutting instrument's edges at the end of a step, handed over every step while it is in the eye
// and once more, with in_eye false, the step it leaves (its incisions end there).
struct CuttingPose {
  std::uint32_t instrument = 0;
  InstrumentKind kind = InstrumentKind::kBlade;
  bool in_eye = true;
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();  // blades: the sharp edge (eye frame)
  // Scissors: the hinge, the bisector of the jaws and the normal of their plane, the opening between
  // the jaws (rad) and their length.
  Vec3 hinge = Vec3::Zero();
  Vec3 bisector = Vec3::UnitX();
  Vec3 normal = Vec3::UnitZ();
  double opening_rad = 0.0;
  double jaw_length_mm = 0.0;
};

// Vitrector removal for one step: tissue inside the removal hemisphere (radius, in front of the port
// along its normal) is cut away at the cut rate; suction (the outer hemisphere) is already applied.
struct RemovalRequest {
  std::uint32_t instrument = 0;
  Vec3 port_center_mm = Vec3::Zero();
  Vec3 port_normal = Vec3::UnitZ();
  double removal_radius_mm = 0.0;
  double suction_radius_mm = 0.0;
  double vacuum = 0.0;         // 0..1 of maximum (pedal)
  double cut_rate_cpm = 0.0;   // cuts per minute; 0: not cutting
  double dt_s = 0.0;
};

// Consumer of cuts and removals: core/topology implements it (the adapter point). Called after
// TissueWorld::step, at the step boundary, once per cutting pose/request.
class TopologyActions {
 public:
  virtual ~TopologyActions() = default;
  virtual void cut(TissueWorld& world, const CuttingPose& pose) = 0;
  virtual void remove(TissueWorld& world, const RemovalRequest& request) = 0;
};

struct BurnSpot {
  std::uint32_t instrument = 0;
  std::uint32_t surface = 0;
  TriangleId triangle;
  Vec3 bary = Vec3::Zero();
  Vec3 position_mm = Vec3::Zero();  // where it was burnt (eye frame); the spot moves with the tissue
  double diameter_mm = 0.0;
  double power_mw = 0.0;
  double duration_s = 0.0;
  bool adhered = false;
  double time_s = 0.0;
};

// A retinal break with subretinal fluid behind it (the detachment's local force).
struct DrainageSite {
  std::uint32_t local_force = 0;
  Vec3 break_point_mm = Vec3::Zero();
  double reach_mm = 1.5;  // the needle drains when its tip is this close to the break
};

struct InstrumentDescription {
  InstrumentKind kind = InstrumentKind::kLightPipe;
  Gauge gauge = Gauge::k23;
  std::uint32_t port = 0;  // index into InstrumentSceneOptions::ports_mm
  InstrumentDimensions dimensions;
};

struct InstrumentSceneOptions {
  std::vector<Vec3> ports_mm;  // sclerotomies, eye frame
  std::uint32_t retina_surface = kNone;
  // Tissue the endolaser's beam passes through: the vitreous gel is optically clear, so the beam
  // burns the retina (its pigment epithelium) behind it; the gel neither stops nor takes a burn.
  // The instruments pass through it too (CollisionOptions::pass_through_mask): only the vitrector's
  // suction and cutter act on the gel.
  std::uint32_t vitreous_surface = kNone;
  std::optional<Vec3> macula_mm;
  std::vector<DrainageSite> drainage_sites;
  RigidAnatomy anatomy;
  CollisionOptions collision;

  // Eye rotation (quasi-static): the sclera at a port pushed sideways by the shaft (stiffness) and
  // the orbit's restoring torque (per radian).
  double port_stiffness_un_per_mm = 2e5;
  double eye_rotation_stiffness_un_mm_per_rad = 5e6;

  double retina_force_limit_un = 3000.0;  // contact force above which the retina is damaged
  double grasp_radius_mm = 0.15;          // tissue this close to the jaws' grasp point is grasped
  double grasp_close_actuation = 0.8;     // handle closed past this: grasp; below release_actuation: let go
  double release_actuation = 0.5;
  double grasp_stiffness_un_per_mm = 1e5;
  double grasp_break_force_un = 8000.0;   // tissue slips out of the jaws above this
  double adhesion_gap_mm = 0.05;          // retina within this of the choroid can adhere
  double adhesion_max_pressure_pa = 1.0;  // ... unless a detachment force above this acts on it
  double adhesion_stiffness_un_per_mm = 2e5;
  double laser_spot_mm = 0.2;             // aiming-beam spot; burn diameter scales with energy
  double laser_reference_energy_mj = 20.0;
  VitrectorSettings vitrector;            // suction, removal and cut rate: one model (core/topology/vitrector.hpp)
  double aspiration_level_rate_mm_s = 2.0;
  double drainage_rate_per_s = 0.5;       // detachment scale drained per second at full aspiration
  double light_half_angle_deg = 40.0;
  double light_safe_distance_mm = 4.0;
  double light_dose_limit_j_cm2 = 10.0;
};

struct InstrumentState {
  InstrumentDescription description;
  InstrumentInput input;
  InstrumentFrame frame;
  TipGeometry tip;
  bool inside = false;
  Vec3 contact_force_un = Vec3::Zero();  // tissue on the instrument, all surfaces (µN)
  double retina_force_un = 0.0;          // magnitude of the retina's part
  std::uint32_t grip = kNone;            // active grasp (forceps)
  Vec3 grip_local = Vec3::Zero();        // grasped point in the jaw frame
  double grip_force_un = 0.0;
  // Endolaser aiming beam: from the tip to the hit (or max range).
  bool aim_hit = false;
  Vec3 aim_point_mm = Vec3::Zero();
};

class InstrumentSystem {
 public:
  // Throws InvalidArgument on bad options (ports out of range, non-finite data).
  InstrumentSystem(TissueWorld& world, InstrumentSceneOptions options, std::vector<InstrumentDescription> instruments);
  ~InstrumentSystem();

  // Per step, before the step: never throws, refuses non-finite input.
  Status set_input(std::uint32_t instrument, const InstrumentInput& input);

  // ---- The instruments' stages, in the order the simulation step calls them ----------------------
  // Clears the step's lists (sweeps, removals, suction).
  void begin_step();
  // Frames and tips in the eye frame (fixture_to_eye: the eye's rotation, inverted) and the
  // colliders, swept from the last step's tips (stage_place.cpp).
  void place(const Quat& fixture_to_eye);
  // The tissue triangles the colliders may touch, and their vertices woken (stage_contacts.cpp).
  void find_contacts();
  // Grasps, laser shots, vitrector suction and removal requests, blade sweeps; hands colliders,
  // contact candidates and suction fields to the tissue world (stage_act.cpp).
  void act(double dt, InstrumentEvents& events);
  // After the tissue step: contact and grip forces, overload, the tissue's events as the instruments'
  // (tears, lost grasps, broken attachments), lens, wall and instrument–instrument contacts
  // (stage_sense.cpp).
  void sense(const StepReport& tissue, InstrumentEvents& events);
  // Cuts and removals to core/topology, at the step boundary (stage_sense.cpp).
  void hand_over_topology(TopologyActions& topology);
  // This step's inputs and tips become the last step's (blade sweeps, grasp edges).
  void end_step();

  // ---- State ----------------------------------------------------------------------------------------
  std::uint32_t instrument_count() const { return static_cast<std::uint32_t>(state_.size()); }
  const InstrumentState& instrument(std::uint32_t i) const { return state_.at(i); }
  const std::vector<BurnSpot>& burns() const { return burns_; }
  const std::vector<BladeSweep>& blade_sweeps() const { return sweeps_; }
  const std::vector<CuttingPose>& cutting_poses() const { return poses_; }
  const std::vector<RemovalRequest>& removal_requests() const { return removals_; }
  const InstrumentSceneOptions& options() const { return options_; }
  const CollisionStats& collision_stats() const { return collision_->stats(); }
  const CollisionScene& collision() const { return *collision_; }
  // Current position of a burn spot on the deformed tissue.
  Vec3 burn_position(const BurnSpot& burn) const;

 private:
  void update_grasps(InstrumentEvents& events);
  void update_laser(InstrumentEvents& events);
  void draw_in_and_sweep(double dt);
  CuttingPose cutting_pose(std::uint32_t instrument) const;
  void rigid_contacts(InstrumentEvents& events);

  TissueWorld& world_;
  InstrumentSceneOptions options_;
  std::unique_ptr<CollisionScene> collision_;
  std::vector<InstrumentState> state_;
  std::vector<InstrumentInput> previous_input_;
  std::vector<TipGeometry> previous_tip_;
  std::vector<std::uint8_t> was_inside_;

  std::vector<ColliderCapsule> colliders_;
  std::vector<std::uint32_t> collider_owner_;
  std::vector<ContactCandidate> candidates_;
  std::vector<SuctionField> suction_;
  std::vector<BurnSpot> burns_;
  std::vector<BladeSweep> sweeps_;
  std::vector<CuttingPose> poses_;
  std::vector<RemovalRequest> removals_;
  std::vector<std::uint8_t> pair_touching_, lens_touching_, wall_touching_, retina_overloaded_;
};

}  // namespace vitreo::core

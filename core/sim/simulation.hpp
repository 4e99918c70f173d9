#pragma once
// One physics step of the whole eye: Simulation::step(dt) is one short, ordered list of named
// stages, read top to bottom like MuJoCo's mj_forwardSkip (src/engine/engine_forward.c) — each
// stage is a call into the part of the model whose state it changes, defined in its own file:
//
//   1. eye rotation           the eye in its orbit, measured or simulated    sim/eye_rotation.cpp
//   2. place instruments      tips and capsules in the eye frame             instruments/stage_place.cpp
//   3. collision              the tissue the capsules may touch, woken       instruments/stage_contacts.cpp
//   4. instruments act        grasps, laser, vitrector suction, blade sweeps instruments/stage_act.cpp
//   5. fluid and light        fluid level and drainage, the macular dose     sim/fluid.cpp, sim/light.cpp
//   6. tissue                 the deformable model's step                    tissue/stage_*.cpp (TissueWorld::step)
//   7. what instruments feel  contact forces, grasps lost, contacts, events  instruments/stage_sense.cpp
//   8. topology               cuts and removals at the step boundary         topology/ (through TopologyActions)
//   9. metrics                the session's observers (core/metrics)         metrics/session_metrics.cpp
//
// The fluid stage runs before the tissue step because the level and the drainage it sets are the
// buoyancy and the detachment force this step's tissue feels.
//
// The rig sets each instrument's input (tracked tip and shaft in the eye-fixture frame, handle,
// pedal, trigger), the fixture's measured rotation and the infusion (fluid or air) before the step;
// everything after it reads the step's outputs here. Like all of core: no clock, no I/O, nothing
// allocated in step(); the same inputs give the same state bit for bit.
#include <cstdint>
#include <optional>
#include <vector>

#include "core/instruments/instrument_system.hpp"
#include "core/sim/eye_rotation.hpp"
#include "core/sim/fluid.hpp"
#include "core/sim/light.hpp"

namespace vitreo::core {

// Something that watches every step from outside the physics (the session's metrics): called
// last, with the step's dt, once the step's outputs are final.
class StepObserver {
 public:
  virtual ~StepObserver() = default;
  virtual void after_step(double dt_s) = 0;
};

struct SimulationStepReport {
  StepReport tissue;
  std::uint32_t candidates = 0;     // contact candidate triangles handed to the tissue step
  std::uint32_t patches_refit = 0;  // collision patches refit this step
};

class Simulation {
 public:
  // Throws InvalidArgument on bad options (ports out of range, non-finite data).
  Simulation(TissueWorld& world, InstrumentSceneOptions options, std::vector<InstrumentDescription> instruments);

  // Where cuts and removals go (core/topology through TopologyAdapter); nullptr: listed only.
  void set_topology(TopologyActions* topology) { topology_ = topology; }
  // Called after every step (the session's metrics); nullptr: none.
  void set_observer(StepObserver* observer) { observer_ = observer; }

  // ---- Inputs, set before step() ---------------------------------------------------------------------
  // Never throws, refuses non-finite input (the last one stays).
  Status set_input(std::uint32_t instrument, const InstrumentInput& input) { return instruments_.set_input(instrument, input); }
  // A rig whose mock eye really rotates reports it here; otherwise (nullopt) the rotation is simulated.
  void set_eye_fixture_rotation(std::optional<Quat> rotation) { eye_.set_fixture_rotation(rotation); }
  void set_air_infusion(bool on) { fluid_.set_air_infusion(on); }

  // The step: the stages above, in order.
  SimulationStepReport step(double dt_s);

  // Optional timing hook for benchmarks and the rig's profiler (core reads no clock): called with
  // phase 0 at the start of step(), 1 before the tissue step, 2 after it, 3 after the topology stage.
  using PhaseProbe = void (*)(int phase, void* user);
  void set_phase_probe(PhaseProbe probe, void* user) {
    probe_ = probe;
    probe_user_ = user;
  }

  // ---- Outputs of the last step --------------------------------------------------------------------
  const InstrumentSystem& instruments() const { return instruments_; }
  std::uint32_t instrument_count() const { return instruments_.instrument_count(); }
  const InstrumentState& instrument(std::uint32_t i) const { return instruments_.instrument(i); }
  const std::vector<InstrumentEvent>& events() const { return events_.all(); }
  const std::vector<BurnSpot>& burns() const { return instruments_.burns(); }
  const std::vector<BladeSweep>& blade_sweeps() const { return instruments_.blade_sweeps(); }
  const std::vector<RemovalRequest>& removal_requests() const { return instruments_.removal_requests(); }
  const EyeRotation& eye_rotation() const { return eye_.state(); }
  const LightExposure& light() const { return light_.exposure(); }
  // The fluid–gas boundary (+infinity: all fluid).
  double fluid_level_z_mm() const { return fluid_.level_z_mm(); }
  const InstrumentSceneOptions& options() const { return instruments_.options(); }
  const CollisionStats& collision_stats() const { return instruments_.collision_stats(); }
  const CollisionScene& collision() const { return instruments_.collision(); }
  Vec3 burn_position(const BurnSpot& burn) const { return instruments_.burn_position(burn); }
  const TissueWorld& world() const { return world_; }

 private:
  void at_phase(int phase) {
    if (probe_) probe_(phase, probe_user_);
  }

  TissueWorld& world_;
  InstrumentSystem instruments_;
  EyeRotationModel eye_;
  FluidModel fluid_;
  LightModel light_;
  InstrumentEvents events_;
  TopologyActions* topology_ = nullptr;
  StepObserver* observer_ = nullptr;
  PhaseProbe probe_ = nullptr;
  void* probe_user_ = nullptr;
};

}  // namespace vitreo::core

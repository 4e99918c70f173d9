#include "core/sim/simulation.hpp"

#include <utility>


namespace vitreo::core {

Simulation::Simulation(TissueWorld& world, InstrumentSceneOptions options, std::vector<InstrumentDescription> instruments)
    : world_(world),
      instruments_(world, std::move(options), std::move(instruments)),
      eye_(instruments_.options().port_stiffness_un_per_mm, instruments_.options().eye_rotation_stiffness_un_mm_per_rad),
      fluid_(world, instruments_.options()),
      light_(instruments_.options()) {}

SimulationStepReport Simulation::step(double dt) {
  SimulationStepReport report;
  at_phase(0);
  events_.clear();
  instruments_.begin_step();

  eye_.solve(instruments_);                            // 1. eye rotation
  instruments_.place(eye_.state().rotation().conjugate());  // 2. place instruments (fixture → eye)
  instruments_.find_contacts();                        // 3. collision
  instruments_.act(dt, events_);                       // 4. instruments act
  fluid_.step(dt, instruments_);                       // 5. fluid and light
  light_.step(dt, instruments_, events_);
  report.candidates = instruments_.collision_stats().candidates;
  report.patches_refit = instruments_.collision_stats().patches_refit;

  at_phase(1);
  report.tissue = world_.step(dt);                     // 6. tissue
  at_phase(2);
  instruments_.sense(report.tissue, events_);          // 7. what the instruments feel
  if (topology_) instruments_.hand_over_topology(*topology_);  // 8. topology
  instruments_.end_step();
  at_phase(3);
  if (observer_) observer_->after_step(dt);            // 9. metrics
  return report;
}

}  // namespace vitreo::core

#pragma once
// The eye's rotation in its orbit. The mock eye of a rig with an eyeball fixture turns in its socket
// and the fixture reports it; without one the rotation is simulated, quasi-statically: each
// inserted shaft holds its sclerotomy on its line with the sclera's stiffness, the orbit resists
// with a torsional stiffness, and the rotation is where the torques balance. Either way the
// instruments, tracked in the fixture's frame, are placed in the eye's frame through it.
#include <optional>

#include "core/common/types.hpp"
#include "core/instruments/instrument_system.hpp"

namespace vitreo::core {

struct EyeRotation {
  Vec3 rotation_vector_rad = Vec3::Zero();  // eye relative to the fixture (axis × angle)
  Vec3 torque_un_mm = Vec3::Zero();         // of the ports on the eye
  bool from_rig = false;                    // the fixture measured it (set_fixture_rotation)
  Quat rotation() const;
};

class EyeRotationModel {
 public:
  // Stiffnesses from InstrumentSceneOptions: the sclera at a port (µN/mm), the orbit (µN·mm/rad).
  EyeRotationModel(double port_stiffness_un_per_mm, double orbit_stiffness_un_mm_per_rad);
  // The fixture's measured rotation, or nullopt to simulate it.
  void set_fixture_rotation(std::optional<Quat> rotation) { fixture_ = rotation; }
  // This step's rotation from the instruments' inputs (ports, tips and shafts in the fixture frame):
  // a few preconditioned fixed-point iterations, warm-started from the last step.
  void solve(const InstrumentSystem& instruments);
  const EyeRotation& state() const { return eye_; }

 private:
  double port_stiffness_, orbit_stiffness_;
  std::optional<Quat> fixture_;
  EyeRotation eye_;
};

}  // namespace vitreo::core

// Stage: the eye's rotation (eye_rotation.hpp).
#include "core/sim/eye_rotation.hpp"

#include <utility>

namespace vitreo::core {

namespace {
Quat quat_from_rotation_vector(const Vec3& r) {
  const double angle = r.norm();
  if (!(angle > 1e-15)) return Quat::Identity();
  return Quat(Eigen::AngleAxisd(angle, r / angle));
}
}  // namespace

Quat EyeRotation::rotation() const { return quat_from_rotation_vector(rotation_vector_rad); }

EyeRotationModel::EyeRotationModel(double port_stiffness_un_per_mm, double orbit_stiffness_un_mm_per_rad)
    : port_stiffness_(port_stiffness_un_per_mm), orbit_stiffness_(orbit_stiffness_un_mm_per_rad) {}

void EyeRotationModel::solve(const InstrumentSystem& instruments) {
  if (fixture_) {
    const Eigen::AngleAxisd aa(*fixture_);
    eye_.rotation_vector_rad = aa.angle() * aa.axis();
    eye_.from_rig = true;
  } else {
    eye_.from_rig = false;
  }
  const double kp = port_stiffness_;
  const double ke = orbit_stiffness_;
  const std::vector<Vec3>& ports = instruments.options().ports_mm;
  auto torque_at = [&](const Vec3& theta) {
    const Quat r = quat_from_rotation_vector(theta);
    Vec3 torque = Vec3::Zero();
    double lever2 = 0.0;
    for (std::uint32_t i = 0; i < instruments.instrument_count(); ++i) {
      const InstrumentState& st = instruments.instrument(i);
      if (!st.input.present) continue;
      const Vec3 port = r * ports[st.description.port];
      const Vec3& a = st.input.axis_fixture;
      const Vec3 rel = port - st.input.tip_fixture_mm;
      if (rel.dot(-a) <= 0.0) continue;  // tip not past the port: not inserted
      const Vec3 offset = rel - rel.dot(a) * a;
      torque += port.cross(-kp * offset);
      lever2 += port.squaredNorm();
    }
    return std::pair{torque, lever2};
  };
  Vec3 theta = eye_.rotation_vector_rad;
  if (!eye_.from_rig) {
    for (int it = 0; it < 8; ++it) {
      const auto [tq, lever2] = torque_at(theta);
      theta += (tq - ke * theta) / (ke + kp * lever2);
    }
    eye_.rotation_vector_rad = theta;
  }
  eye_.torque_un_mm = torque_at(theta).first;
}

}  // namespace vitreo::core

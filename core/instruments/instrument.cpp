#include "core/instruments/instrument.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace vitreo::core {

double shaft_radius_mm(Gauge g) {
  switch (g) {
    case Gauge::k20: return 0.9081 / 2.0;
    case Gauge::k23: return 0.6414 / 2.0;
    case Gauge::k25: return 0.5144 / 2.0;
  }
  return 0.3207;
}

const char* to_string(InstrumentKind k) {
  switch (k) {
    case InstrumentKind::kLightPipe: return "light pipe";
    case InstrumentKind::kForceps: return "forceps";
    case InstrumentKind::kPick: return "pick";
    case InstrumentKind::kBlade: return "blade";
    case InstrumentKind::kSidewaysBlade: return "sideways blade";
    case InstrumentKind::kScissors: return "scissors";
    case InstrumentKind::kVitrector: return "vitrector";
    case InstrumentKind::kEndolaser: return "endolaser";
    case InstrumentKind::kDrainageNeedle: return "drainage needle";
  }
  return "?";
}

InstrumentInput InstrumentInput::through_port(const Vec3& port, const Vec3& direction, double insertion_mm, double twist) {
  InstrumentInput in;
  in.axis_fixture = direction.normalized();
  in.tip_fixture_mm = port + insertion_mm * in.axis_fixture;
  in.twist_rad = twist;
  return in;
}

InstrumentFrame make_frame(const Vec3& tip, const Vec3& axis, double twist, const Vec3& port) {
  InstrumentFrame f;
  f.tip = tip;
  f.u = axis.normalized();
  // Twist reference: the direction of the globe's +z (anterior) projected off the axis, or +x when
  // the shaft is along z; the twist rolls it about the axis.
  Vec3 ref = Vec3::UnitZ() - Vec3::UnitZ().dot(f.u) * f.u;
  if (ref.norm() < 1e-6) ref = Vec3::UnitX() - Vec3::UnitX().dot(f.u) * f.u;
  ref.normalize();
  const Vec3 side = f.u.cross(ref);
  f.v = std::cos(twist) * ref + std::sin(twist) * side;
  f.w = f.u.cross(f.v);
  f.inserted_mm = (tip - port).dot(f.u);
  f.port = tip - f.inserted_mm * f.u;
  return f;
}

TipGeometry tip_geometry(InstrumentKind kind, Gauge gauge, const InstrumentFrame& f, const InstrumentInput& in,
                         const InstrumentDimensions& dim) {
  TipGeometry g;
  const double r = shaft_radius_mm(gauge);
  const double act = std::clamp(in.actuation, 0.0, 1.0);
  auto add = [&](const Vec3& a, const Vec3& b, double radius, bool pushes) {
    if (g.count < TipGeometry::kMaxParts) g.parts[g.count++] = {a, b, radius, pushes};
  };
  // The shaft runs from the port to the start of the tip part.
  auto shaft_to = [&](double setback) {
    const double len = std::max(f.inserted_mm - setback, 0.0);
    const Vec3 end = f.tip - setback * f.u;
    add(end - len * f.u, end, r, true);
    return end;
  };
  switch (kind) {
    case InstrumentKind::kLightPipe: {
      shaft_to(0.0);
      if (in.trigger) add(f.tip, f.tip + dim.pick_length_mm * f.v, dim.pick_radius_mm, true);
      break;
    }
    case InstrumentKind::kPick: {
      const Vec3 base = shaft_to(dim.pick_length_mm);
      add(base, f.tip, dim.pick_radius_mm * 1.6, true);
      add(f.tip, f.tip + dim.pick_length_mm * f.v, dim.pick_radius_mm, true);
      break;
    }
    case InstrumentKind::kForceps:
    case InstrumentKind::kScissors: {
      const Vec3 hinge = shaft_to(dim.jaw_length_mm);
      const double half = dim.jaw_open_deg * std::numbers::pi / 180.0 * (1.0 - act);
      const Vec3 d1 = std::cos(half) * f.u + std::sin(half) * f.v;
      const Vec3 d2 = std::cos(half) * f.u - std::sin(half) * f.v;
      const Vec3 t1 = hinge + dim.jaw_length_mm * d1, t2 = hinge + dim.jaw_length_mm * d2;
      add(hinge, t1, dim.jaw_radius_mm, false);
      add(hinge, t2, dim.jaw_radius_mm, false);
      g.hinge = hinge;
      g.grasp_point = 0.5 * (t1 + t2);
      g.jaw_gap_mm = std::max((t1 - t2).norm() - 2.0 * dim.jaw_radius_mm, 0.0);
      // Scissors cut where the blades have closed: from the hinge out to their crossing.
      g.edge_a = hinge;
      g.edge_b = hinge + act * dim.jaw_length_mm * f.u;
      break;
    }
    case InstrumentKind::kBlade: {
      const Vec3 base = shaft_to(dim.blade_length_mm);
      add(base, f.tip, 0.02, false);
      g.edge_a = base;
      g.edge_b = f.tip;
      break;
    }
    case InstrumentKind::kSidewaysBlade: {
      shaft_to(0.0);
      add(f.tip, f.tip + dim.sideways_blade_mm * f.v, 0.02, false);
      g.edge_a = f.tip;
      g.edge_b = f.tip + dim.sideways_blade_mm * f.v;
      break;
    }
    case InstrumentKind::kVitrector: {
      shaft_to(0.0);
      g.port_center = f.tip - dim.vitrector_port_setback_mm * f.u + r * f.v;
      g.port_normal = f.v;
      break;
    }
    case InstrumentKind::kEndolaser:
    case InstrumentKind::kDrainageNeedle: {
      shaft_to(0.0);
      break;
    }
  }
  return g;
}

}  // namespace vitreo::core

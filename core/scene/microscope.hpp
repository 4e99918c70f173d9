#pragma once
// The operating microscope as simulation state: where its field looks on the fundus (X–Y), its
// magnification (zoom), where its focal plane lies (focus), and the wide-angle viewing system with
// its image re-inverter. Stepped once per physics step from the microscope pedal (joystick X–Y as a
// speed, zoom and focus as targets the motors drive to) and the operator's commands; read by the
// metrics (is the work in the field, in focus?) and drawn by the renderer.
//
// Like the rest of core: no clock (dt is given), no I/O; the same inputs give the same state bit
// for bit, and hash_into() puts all of it into the session's state hash.
//
// Coordinates: the field centre lives in the fundus plane of the EyeModel (mm from the posterior
// pole, +x nasal, +y superior; EyeModel::fundus_coords), so X–Y pan moves it across the fundus the
// way the microscope head moves its field, whatever the eye's curvature. The image is drawn with
// fundus +x to the right and +y up at the field centre, so the joystick's right/up are the image's.
// Focus is the offset of the focal plane from the fundus at the field centre, + toward the
// microscope (into the vitreous: an elevated retina or a membrane comes into focus).
#include <cmath>

#include "core/common/state_hasher.hpp"
#include "core/common/types.hpp"

namespace vitreo::core {

struct MicroscopeSettings {
  double zoom_min = 1.0;
  double zoom_max = 25.0;
  double zoom_rate_per_s = 1.5;     // motorised zoom: log-magnification per second (×4.5 per second)
  double focus_range_mm = 6.0;      // the focal plane travels ±half of this about the fundus
  double focus_speed_mm_s = 4.0;    // motorised focus
  double pan_speed_mm_s = 8.0;      // X–Y at full joystick deflection and zoom 1 (∝ 1/zoom, as rigs couple it)
  double pan_travel_mm = 20.0;      // the field centre stays within this of the posterior pole (fundus plane)
  double field_deg = 40.0;          // field angle at zoom 1 through the contact lens (standard view)
  double wide_field_deg = 110.0;    // field angle at zoom 1 through the wide-angle (BIOM-like) system
  // The optics behind the depth of field (MicroscopeView::depth_of_field_mm): the numerical
  // aperture of one stereo channel on the object side (a pupil of about 9 mm at a 180 mm working
  // distance) and the total visual magnification at zoom 1 (ophthalmic microscopes start at about
  // 4× with 12.5× eyepieces).
  double numerical_aperture = 0.025;
  double magnification_at_zoom_1 = 4.0;

  void validate() const;  // throws InvalidArgument naming the field
};

// What the microscope sees now, in the eye frame, as the renderer draws it
// (rig/session/frame_source.cpp builds its camera from this): the view through the eye's optics is
// a centre of projection on the optical axis just behind the lens, aimed at the field centre on the
// retina's inner surface, with a circular field of half-angle atan(tan(field at zoom 1 / 2) / zoom).
// The refraction of the contact lens or the wide-angle system is not modelled (the renderer does
// not either); it enters only the depth of field, through the view's lateral magnification.
struct MicroscopeView {
  Vec3 eye_point_mm = Vec3::Zero();  // centre of projection
  Vec3 target_mm = Vec3::Zero();     // field centre, on the retina's inner surface
  Vec3 axis = -Vec3::UnitZ();        // unit, from the eye point toward the target
  Vec3 up = Vec3::UnitY();           // unit, normal to the axis: fundus +y at the field centre
  double half_tan = 1.0;             // tan of the field's half angle
  double focal_distance_mm = 0.0;    // eye point to the focal plane, along the axis
  double depth_of_field_mm = 0.0;    // total, centred on the focal plane

  // Where p lies across the field: 0 on the axis, 1 at the field's edge (tan of its angle off the
  // axis over half_tan); +infinity for a point not in front of the eye point.
  double field_radius(const Vec3& p) const;
  // Its distance from the focal plane along the axis, + beyond it (toward the fundus).
  double defocus_mm(const Vec3& p) const { return (p - eye_point_mm).dot(axis) - focal_distance_mm; }
  bool in_field(const Vec3& p) const { return field_radius(p) <= 1.0; }
  bool in_focus(const Vec3& p) const { return std::abs(defocus_mm(p)) <= 0.5 * depth_of_field_mm; }
};

// The visual depth of field (mm) at the fundus: Berek's formula for the microscope at its total
// magnification, T = λ/(2·NA²) + 0.34 mm/(NA·M) (λ = 0.55 µm), carried into the eye through the
// viewing optics: axial magnification is the square of the lateral one, and the object lies in the
// vitreous cavity (n = 1.336), so T_eye = n · T / m². m = 1 through the contact lens; the wide-angle
// system fits a wider field into the same image, m = tan(field/2) / tan(wide field/2).
double depth_of_field_mm(const MicroscopeSettings& settings, double zoom, bool wide_angle);

struct EyeModel;

// The microscope pedal's joystick for one step: deflection −1..1 per axis (after the dead band),
// +x toward the image's right, +y toward its top.
struct MicroscopeInput {
  Vec2 pan = Vec2::Zero();
};

class Microscope {
 public:
  // Starts centred on the case's region of interest (fundus-plane mm), in focus on the fundus, at
  // the lowest magnification, in the standard or the wide-angle view, re-inverter engaged.
  Microscope(const MicroscopeSettings& settings, const Vec2& region_of_interest_mm, bool wide_angle = false);

  // Targets the motors drive toward (each clamped to its range; non-finite values are ignored).
  void set_zoom(double zoom);
  void set_focus(double focus_mm);
  // The field centre goes to the region of interest plus `offset_mm` (fundus plane).
  void pan_to(const Vec2& offset_mm);
  // The wide-angle viewing system swung in or out (its image is inverted: the re-inverter, engaged
  // by default as modern rigs couple it, turns it upright again).
  void toggle_wide_angle() { wide_angle_ = !wide_angle_; }
  void toggle_reinverter() { reinverter_ = !reinverter_; }

  void step(double dt_s, const MicroscopeInput& input);

  const Vec2& center_mm() const { return center_; }   // field centre, fundus plane
  const Vec2& region_of_interest_mm() const { return roi_; }
  double zoom() const { return zoom_; }
  double focus_mm() const { return focus_; }
  bool wide_angle() const { return wide_angle_; }
  bool reinverter() const { return reinverter_; }
  // What reaches the eyepieces is inverted (rotated 180°, the stereo pair swapped: pseudoscopic)
  // when the wide-angle system is in and its re-inverter is not.
  bool image_inverted() const { return wide_angle_ && !reinverter_; }
  // Full field angle now (deg): the optics' field over the magnification.
  double field_deg() const;
  // The view now, on this eye (see MicroscopeView).
  MicroscopeView view(const EyeModel& eye) const;
  double depth_of_field_mm() const { return vitreo::core::depth_of_field_mm(settings_, zoom_, wide_angle_); }
  const MicroscopeSettings& settings() const { return settings_; }

  void hash_into(StateHasher& h) const;

 private:
  MicroscopeSettings settings_;
  Vec2 roi_;
  Vec2 center_, center_target_;
  double zoom_ = 1.0, zoom_target_ = 1.0;
  double focus_ = 0.0, focus_target_ = 0.0;
  bool wide_angle_ = false;
  bool reinverter_ = true;
};

}  // namespace vitreo::core

#include "vitreo/render/camera.hpp"

#include <algorithm>
#include <cmath>

namespace vitreo::render {

StereoViews stereo_views(const Microscope& m, float globe_radius_mm, int width, int height) {
  StereoViews out;
  const float zoom = std::max(m.zoom, 1e-3f);
  const float aspect = static_cast<float>(width) / static_cast<float>(std::max(height, 1));
  Vec3 forward{0, 0, -1};  // the external microscope looks down −z (patient supine)
  Vec3 centre;             // midpoint between the two eyes' centres of projection
  float distance = 0;      // centre to target along the axis
  float half_tan = 0;      // tan(half vertical field angle)
  float base = 0;          // stereo base
  if (m.wide_angle) {
    // Through the eye's optics (a contact lens or a wide-angle system): a short-distance view from
    // the viewpoint toward the target, with the stereo base scaled down with the distance so the
    // depth impression stays like the microscope's.
    const Vec3 from = m.view_point_mm ? *m.view_point_mm : Vec3{m.target_mm.x, m.target_mm.y, m.wide_distance_mm};
    const Vec3 to_target = m.target_mm - from;
    distance = std::max(length(to_target), 1e-3f);
    forward = to_target * (1.0f / distance);
    centre = from;
    half_tan = std::tan(0.5f * m.wide_field_deg * 3.14159265f / 180.0f) / zoom;
    base = m.stereo_base_mm * distance / std::max(m.working_distance_mm, 1.0f);
  } else {
    distance = m.working_distance_mm;
    half_tan = 0.5f * m.field_mm / zoom / distance;
    base = m.stereo_base_mm;
    centre = m.target_mm - forward * distance;
  }
  // image_up projected onto the image plane; a degenerate choice falls back to +y, then +x.
  Vec3 up = m.image_up - forward * dot(m.image_up, forward);
  if (length(up) < 1e-4f) up = Vec3{0, 1, 0} - forward * forward.y;
  if (length(up) < 1e-4f) up = Vec3{1, 0, 0} - forward * forward.x;
  up = normalize(up);
  const Vec3 right = normalize(cross(forward, up));
  out.forward = forward;
  out.right = right;
  out.up = up;

  const float convergence = m.convergence_distance_mm > 0 ? m.convergence_distance_mm : distance;
  const float focus = m.focus_distance_mm > 0 ? m.focus_distance_mm : distance;
  // Depth range: the whole globe (and a margin for instruments outside it) around the target.
  const float depth_extent = 2.0f * globe_radius_mm + 20.0f;
  const float far_plane = distance + depth_extent;
  const float near_plane = std::max(distance - depth_extent, 0.5f);

  // Without a re-inverter the wide-angle system's image is rotated 180° in each eyepiece and its
  // depth is reversed: each eye keeps its own viewpoint, but sees it with the image axes turned, so
  // its stereo offset lies on the other side of its image (Microscope::image_inverted).
  const float flip = m.image_inverted ? -1.0f : 1.0f;
  for (int e = 0; e < 2; ++e) {
    const float s = (e == 0 ? -0.5f : 0.5f) * base;  // left eye at −base/2 along the (upright) image x
    EyeView& v = out.eye[e];
    v.position_mm = centre + right * s;
    v.view = look_at(v.position_mm, v.position_mm + forward, up * flip);
    const float top = near_plane * half_tan;
    const float half_w = top * aspect;
    const float shift = flip * s * near_plane / convergence;  // shear so both frusta meet at `convergence`
    // The display's alignment: the picture moved by whole frustum-window pixels on its display.
    const float dx = m.display_offset_px[e].x * 2.0f * half_w / static_cast<float>(std::max(width, 1));
    const float dy = m.display_offset_px[e].y * 2.0f * top / static_cast<float>(std::max(height, 1));
    v.projection = frustum(-half_w - shift - dx, half_w - shift - dx, -top - dy, top - dy, near_plane, far_plane);
    v.view_projection = v.projection * v.view;
    v.near_mm = near_plane;
    v.far_mm = far_plane;
    v.focus_distance_mm = focus;
  }
  if (m.image_inverted) {
    out.right = -right;
    out.up = -up;
  }
  return out;
}

}  // namespace vitreo::render

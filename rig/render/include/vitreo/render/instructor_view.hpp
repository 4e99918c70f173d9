#pragma once
// The instructor's view: the surgeon's picture (the left eye) with a live overlay — the case's score
// and criteria, the retina contact force as a bar against its damage limit, and the latest events —
// so an instructor can follow the surgery on a monitor without looking into the eyepieces. The
// render thread composes it after each frame and writes it to its own shared-memory ring
// (RenderThreadOptions::instructor_ring_name) and beside the PNGs.
#include "vitreo/render/frame_scene.hpp"
#include "vitreo/render/renderer.hpp"

namespace vitreo::render {

/// Where the overlay's parts lie in the instructor image (pixels, rows from the top): tests and
/// viewers can find them.
struct InstructorLayout {
  int scale = 1;           // text pixels per font texel
  int line_height = 0;
  int panel_x = 0, panel_y = 0, panel_w = 0, panel_h = 0;   // score and criteria, top left
  int bar_x = 0, bar_y = 0, bar_w = 0, bar_h = 0;           // retina force bar, bottom
  int events_x = 0, events_y = 0;                           // latest events, top right (right-aligned)
};
InstructorLayout instructor_layout(int width, int height, const InstructorOverlay& overlay);

/// The left eye of `frame` with `overlay` drawn over it.
Image compose_instructor_view(const StereoFrame& frame, const InstructorOverlay& overlay);

}  // namespace vitreo::render

#pragma once
// The rig's displays: stereo frames scanned out through Linux KMS (DRM modesetting), no window
// system. Issue 8 asks for output "to the display (GBM/KMS) through the same renderer": the renderer
// draws off-screen through EGL as it does headless, and a KmsDisplay puts the finished frame on a
// connector — side by side on one stereo panel, or one eye per eyepiece display (two KmsDisplays on
// two connectors).
//
// How: two CPU-mapped "dumb" scan-out buffers per display (double buffering); present() converts the
// RGBA frame into the back buffer (aspect kept, letterboxed in black) and page-flips to it, waiting at
// most flip_timeout_ms for the previous flip, so a stuck display never stalls the render thread for
// long. Drivers without page flips get a mode set per frame instead. A zero-copy GBM surface would
// save the copy (~10 MB per 1280×1024 stereo frame) on a real GPU; the dumb-buffer path works on every
// KMS driver, including qemu's bochs-display that the tests run on (tests/rig/render/kms-vm/).
//
// Depends on libdrm only (no EGL, no core/), so it links statically into the VM test binary.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace vitreo::render {

struct KmsError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class DisplayLayout : std::uint8_t {
  SideBySide,  // both eyes on one panel (left eye on the left)
  LeftEye,     // the left eyepiece's display
  RightEye,    // the right eyepiece's display
};

struct KmsOptions {
  std::string card = "/dev/dri/card0";
  std::string connector;  // e.g. "HDMI-A-1", "Virtual-1"; empty: the first connected one
  int width = 0, height = 0;  // mode to use; 0: the connector's preferred mode
  DisplayLayout layout = DisplayLayout::SideBySide;
  int flip_timeout_ms = 100;  // longest wait for the previous page flip
};

// A display as the tools name it: CARD[:CONNECTOR[:sbs|left|right]], e.g. /dev/dri/card0:HDMI-A-1:left.
// Throws std::runtime_error naming the spec when the layout is unknown or the card missing.
KmsOptions parse_display_spec(const std::string& spec);

// An RGBA8 image, rows top to bottom.
struct RgbaView {
  const std::uint8_t* pixels = nullptr;
  int width = 0, height = 0;
  std::size_t stride_bytes = 0;
};

// Where an image of src_w×src_h lands on a dst_w×dst_h screen: as large as fits with its aspect
// ratio kept, centred (the rest is black).
struct ScreenRect {
  int x = 0, y = 0, width = 0, height = 0;
};
ScreenRect fit_rect(int src_w, int src_h, int dst_w, int dst_h);

// Writes `image` scaled into `rect` of an XRGB8888 buffer (the scan-out format: bytes B, G, R, X in
// memory) and clears the rest to black. Each screen pixel takes the source pixel under its centre.
void blit_letterboxed(const RgbaView& image, std::uint32_t* dst, int dst_w, int dst_h, std::size_t dst_stride_bytes);

// The part of a side-by-side stereo frame a layout shows.
RgbaView select_layout(const RgbaView& side_by_side, DisplayLayout layout);

class KmsDisplay {
 public:
  // Opens the card, picks the connector, mode and CRTC, creates the scan-out buffers and shows black.
  // Throws KmsError naming the card and the cause (no such device, not a KMS device, no connected
  // connector — listing those it found —, no such mode, another program is DRM master…).
  explicit KmsDisplay(const KmsOptions& options);
  ~KmsDisplay();  // waits for a pending flip, restores what the CRTC showed before, frees the buffers
  KmsDisplay(const KmsDisplay&) = delete;
  KmsDisplay& operator=(const KmsDisplay&) = delete;

  // Shows a frame (for SideBySide/LeftEye/RightEye, pass the side-by-side stereo frame: the layout
  // selects the part). Throws KmsError if the display went away (e.g. unplugged).
  void present(const RgbaView& side_by_side);

  int width() const { return width_; }
  int height() const { return height_; }
  double refresh_hz() const { return refresh_hz_; }
  const std::string& connector_name() const { return connector_name_; }
  std::string description() const;  // "card0 Virtual-1 1024x768@60 (page flip)"
  std::uint64_t frames_presented() const { return frames_; }
  std::uint64_t flips_timed_out() const { return flip_timeouts_; }
  bool page_flips() const { return page_flip_; }

 private:
  struct Buffer {
    std::uint32_t handle = 0, fb = 0;
    std::uint32_t pitch = 0;
    std::size_t size = 0;
    void* map = nullptr;
  };
  void create_buffer(Buffer& b);
  void destroy_buffer(Buffer& b);
  void wait_for_flip();
  void release();

  KmsOptions options_;
  int fd_ = -1;
  std::uint32_t connector_id_ = 0, crtc_id_ = 0;
  std::vector<std::uint8_t> mode_;  // drmModeModeInfo, kept opaque here
  void* saved_crtc_ = nullptr;      // drmModeCrtc* to restore
  Buffer buffers_[2];
  int front_ = 0;
  bool flip_pending_ = false;
  bool page_flip_ = true;
  int width_ = 0, height_ = 0;
  double refresh_hz_ = 0;
  std::string connector_name_;
  std::uint64_t frames_ = 0, flip_timeouts_ = 0;
};

}  // namespace vitreo::render

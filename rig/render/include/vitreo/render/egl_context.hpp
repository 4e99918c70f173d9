#pragma once
// Headless EGL context for the renderer: desktop OpenGL 4.5 core, rendering into FBOs (no window
// system). Platforms, tried in this order by Platform::Auto:
//   1. EGL_MESA_platform_surfaceless — works on Mesa with or without a GPU (llvmpipe here);
//   2. EGL_EXT_platform_device — each EGL device in turn (NVIDIA's headless path, Mesa's software device).
// Platform::Gbm opens a DRM render node through GBM: the path on a rig with a GPU and a display. It
// cannot be exercised on the development machines (no /dev/dri); only its failure path is tested.
// eglGetDisplay(EGL_DEFAULT_DISPLAY) is never used: on Mesa it tries X11 and fails without a display.
//
// Every failure throws EglError with a one-line message naming the platform, the call that failed
// and the EGL error code; nothing here waits or retries, so a failure cannot hang.
#include <stdexcept>
#include <string>

namespace vitreo::render {

class EglError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class EglPlatform { Auto, Surfaceless, Device, Gbm };

struct EglOptions {
  EglPlatform platform = EglPlatform::Auto;
  int device_index = -1;                        // Device: -1 = first that works
  std::string gbm_node = "/dev/dri/renderD128";  // Gbm only
  /// Read VITREO_EGL_PLATFORM (auto|surfaceless|device|gbm) and VITREO_EGL_DEVICE (index) to
  /// override the fields above; an unknown value is an error, not silently ignored.
  bool honour_environment = true;
};

/// Parses "auto", "surfaceless", "device", "gbm"; throws EglError on anything else.
EglPlatform parse_egl_platform(const std::string& name);

class EglContext {
 public:
  /// Creates a display and a GL 4.5 core context and makes it current on the calling thread.
  explicit EglContext(EglOptions options = {});
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  /// Binds the context to the calling thread (it must not be current on another thread).
  void make_current();
  void release_current();
  /// e.g. "surfaceless: EGL 1.5 Mesa Project; GL 4.5 (Core Profile) Mesa 22.3.6; llvmpipe (LLVM 15.0.6, 256 bits)"
  const std::string& description() const { return description_; }

 private:
  void* display_ = nullptr;  // EGLDisplay
  void* context_ = nullptr;  // EGLContext
  void* gbm_device_ = nullptr;
  int drm_fd_ = -1;
  std::string description_;
};

}  // namespace vitreo::render

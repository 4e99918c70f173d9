#include "vitreo/render/egl_context.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
#include <fcntl.h>
#include <gbm.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace vitreo::render {
namespace {

std::string egl_error_name(EGLint e) {
  switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    default: {
      char buf[32];
      std::snprintf(buf, sizeof buf, "0x%04X", static_cast<unsigned>(e));
      return buf;
    }
  }
}

[[noreturn]] void fail(const std::string& platform, const std::string& what) {
  throw EglError("EGL (" + platform + "): " + what);
}

[[noreturn]] void fail_egl(const std::string& platform, const char* call) {
  fail(platform, std::string(call) + " failed: " + egl_error_name(eglGetError()));
}

bool has_extension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

struct Created {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
};

// Initialises `dpy` and creates a GL 4.5 core context on it, current without a surface.
Created init_context(const std::string& platform, EGLDisplay dpy) {
  if (dpy == EGL_NO_DISPLAY) fail_egl(platform, "eglGetPlatformDisplay");
  EGLint major = 0, minor = 0;
  if (!eglInitialize(dpy, &major, &minor)) fail_egl(platform, "eglInitialize");
  auto give_up = [&](const char* call) {
    const EGLint err = eglGetError();
    eglTerminate(dpy);
    fail(platform, std::string(call) + " failed: " + egl_error_name(err));
  };
  const char* exts = eglQueryString(dpy, EGL_EXTENSIONS);
  if (!has_extension(exts, "EGL_KHR_surfaceless_context")) {
    eglTerminate(dpy);
    fail(platform, "display lacks EGL_KHR_surfaceless_context (needed to render into FBOs only)");
  }
  if (!eglBindAPI(EGL_OPENGL_API)) give_up("eglBindAPI(EGL_OPENGL_API)");
  const EGLint cfg_attr[] = {EGL_SURFACE_TYPE, 0, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig cfg = nullptr;
  EGLint n = 0;
  if (!eglChooseConfig(dpy, cfg_attr, &cfg, 1, &n) || n < 1) give_up("eglChooseConfig(OpenGL)");
  const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                             EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                             EGL_NONE};
  EGLContext ctx = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, ctx_attr);
  if (ctx == EGL_NO_CONTEXT) give_up("eglCreateContext(OpenGL 4.5 core)");
  if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
    const EGLint err = eglGetError();
    eglDestroyContext(dpy, ctx);
    eglTerminate(dpy);
    fail(platform, "eglMakeCurrent failed: " + egl_error_name(err));
  }
  return {dpy, ctx};
}

template <typename Fn>
Fn egl_proc(const char* name) {
  return reinterpret_cast<Fn>(eglGetProcAddress(name));
}

Created create_surfaceless() {
  const std::string platform = "surfaceless";
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!has_extension(client, "EGL_MESA_platform_surfaceless"))
    fail(platform, "client extension EGL_MESA_platform_surfaceless not available");
  EGLDisplay dpy = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  return init_context(platform, dpy);
}

Created create_device(int index) {
  std::string platform = "device";
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!has_extension(client, "EGL_EXT_platform_device"))
    fail(platform, "client extension EGL_EXT_platform_device not available");
  auto query_devices = egl_proc<PFNEGLQUERYDEVICESEXTPROC>("eglQueryDevicesEXT");
  if (query_devices == nullptr) fail(platform, "eglQueryDevicesEXT not exported");
  EGLDeviceEXT devices[16];
  EGLint count = 0;
  if (!query_devices(16, devices, &count)) fail_egl(platform, "eglQueryDevicesEXT");
  if (count == 0) fail(platform, "no EGL devices found");
  if (index >= count || index < -1) {
    fail(platform, "device index " + std::to_string(index) + " out of range (" + std::to_string(count) +
                       " device(s) found)");
  }
  std::string reasons;
  for (int i = (index >= 0 ? index : 0); i < (index >= 0 ? index + 1 : count); ++i) {
    try {
      return init_context(platform + " #" + std::to_string(i),
                          eglGetPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr));
    } catch (const EglError& e) {
      reasons += std::string(reasons.empty() ? "" : "; ") + e.what();
    }
  }
  throw EglError(reasons);
}

}  // namespace

EglPlatform parse_egl_platform(const std::string& name) {
  if (name == "auto") return EglPlatform::Auto;
  if (name == "surfaceless") return EglPlatform::Surfaceless;
  if (name == "device") return EglPlatform::Device;
  if (name == "gbm") return EglPlatform::Gbm;
  throw EglError("EGL: unknown platform '" + name + "' (expected auto, surfaceless, device or gbm)");
}

EglContext::EglContext(EglOptions options) {
  if (options.honour_environment) {
    if (const char* p = std::getenv("VITREO_EGL_PLATFORM"); p != nullptr && *p != '\0')
      options.platform = parse_egl_platform(p);
    if (const char* d = std::getenv("VITREO_EGL_DEVICE"); d != nullptr && *d != '\0') {
      char* end = nullptr;
      const long v = std::strtol(d, &end, 10);
      if (end == d || *end != '\0') throw EglError(std::string("EGL: VITREO_EGL_DEVICE is not an integer: '") + d + "'");
      options.device_index = static_cast<int>(v);
    }
  }

  Created c;
  std::string platform_name;
  switch (options.platform) {
    case EglPlatform::Surfaceless:
      c = create_surfaceless();
      platform_name = "surfaceless";
      break;
    case EglPlatform::Device:
      c = create_device(options.device_index);
      platform_name = "device";
      break;
    case EglPlatform::Gbm: {
      platform_name = "gbm";
      drm_fd_ = ::open(options.gbm_node.c_str(), O_RDWR | O_CLOEXEC);
      if (drm_fd_ < 0) fail("gbm", "cannot open " + options.gbm_node + ": " + std::strerror(errno));
      gbm_device_ = gbm_create_device(drm_fd_);
      if (gbm_device_ == nullptr) {
        ::close(drm_fd_);
        drm_fd_ = -1;
        fail("gbm", "gbm_create_device(" + options.gbm_node + ") failed");
      }
      try {
        c = init_context("gbm", eglGetPlatformDisplay(EGL_PLATFORM_GBM_KHR, gbm_device_, nullptr));
      } catch (...) {
        gbm_device_destroy(static_cast<gbm_device*>(gbm_device_));
        ::close(drm_fd_);
        throw;
      }
      break;
    }
    case EglPlatform::Auto: {
      try {
        c = create_surfaceless();
        platform_name = "surfaceless";
      } catch (const EglError& first) {
        try {
          c = create_device(options.device_index);
          platform_name = "device";
        } catch (const EglError& second) {
          throw EglError(std::string("no headless EGL platform works: ") + first.what() + "; " + second.what());
        }
      }
      break;
    }
  }
  display_ = c.display;
  context_ = c.context;
  description_ = platform_name + ": EGL " + eglQueryString(c.display, EGL_VERSION) + " " +
                 eglQueryString(c.display, EGL_VENDOR) + "; GL " +
                 reinterpret_cast<const char*>(glGetString(GL_VERSION)) + "; " +
                 reinterpret_cast<const char*>(glGetString(GL_RENDERER));
}

EglContext::~EglContext() {
  if (display_ != nullptr) {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    eglTerminate(display_);
    eglReleaseThread();
  }
  if (gbm_device_ != nullptr) gbm_device_destroy(static_cast<gbm_device*>(gbm_device_));
  if (drm_fd_ >= 0) ::close(drm_fd_);
}

void EglContext::make_current() {
  if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
    throw EglError("EGL: eglMakeCurrent failed: " + egl_error_name(eglGetError()));
}

void EglContext::release_current() {
  eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

}  // namespace vitreo::render

// KMS scan-out with two dumb buffers (see kms_display.hpp for why this path).
#include "vitreo/render/kms_display.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/mman.h>
#include <unistd.h>
#include <xf86drm.h>
#include <xf86drmMode.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <memory>

namespace vitreo::render {

namespace {

[[noreturn]] void fail(const std::string& card, const std::string& what) { throw KmsError("KMS display " + card + ": " + what); }

std::string errno_text(int e) { return std::strerror(e); }

std::string connector_name_of(const drmModeConnector& c) {
  const char* type = drmModeGetConnectorTypeName(c.connector_type);
  return std::string(type != nullptr ? type : "Unknown") + "-" + std::to_string(c.connector_type_id);
}

struct ResourcesDeleter {
  void operator()(drmModeRes* r) const { drmModeFreeResources(r); }
};
struct ConnectorDeleter {
  void operator()(drmModeConnector* c) const { drmModeFreeConnector(c); }
};
struct EncoderDeleter {
  void operator()(drmModeEncoder* e) const { drmModeFreeEncoder(e); }
};
using Resources = std::unique_ptr<drmModeRes, ResourcesDeleter>;
using Connector = std::unique_ptr<drmModeConnector, ConnectorDeleter>;
using Encoder = std::unique_ptr<drmModeEncoder, EncoderDeleter>;

void on_page_flip(int, unsigned, unsigned, unsigned, void* user) { *static_cast<bool*>(user) = false; }

}  // namespace

ScreenRect fit_rect(int src_w, int src_h, int dst_w, int dst_h) {
  if (src_w <= 0 || src_h <= 0 || dst_w <= 0 || dst_h <= 0) return {};
  // Compare aspect ratios in integers: src_w/src_h ≥ dst_w/dst_h ⇔ the width is the limit.
  ScreenRect r;
  if (std::int64_t{src_w} * dst_h >= std::int64_t{dst_w} * src_h) {
    r.width = dst_w;
    r.height = std::max<int>(1, static_cast<int>(std::int64_t{dst_w} * src_h / src_w));
  } else {
    r.height = dst_h;
    r.width = std::max<int>(1, static_cast<int>(std::int64_t{dst_h} * src_w / src_h));
  }
  r.x = (dst_w - r.width) / 2;
  r.y = (dst_h - r.height) / 2;
  return r;
}

void blit_letterboxed(const RgbaView& image, std::uint32_t* dst, int dst_w, int dst_h, std::size_t dst_stride_bytes) {
  const ScreenRect r = fit_rect(image.width, image.height, dst_w, dst_h);
  // Source column of each screen column in the rect: the pixel under the screen pixel's centre.
  std::vector<int> src_x(static_cast<std::size_t>(std::max(r.width, 0)));
  for (int i = 0; i < r.width; ++i)
    src_x[static_cast<std::size_t>(i)] = static_cast<int>((2 * std::int64_t{i} + 1) * image.width / (2 * std::int64_t{r.width}));
  for (int y = 0; y < dst_h; ++y) {
    auto* row = reinterpret_cast<std::uint32_t*>(reinterpret_cast<std::uint8_t*>(dst) + static_cast<std::size_t>(y) * dst_stride_bytes);
    if (y < r.y || y >= r.y + r.height) {
      std::fill(row, row + dst_w, 0u);
      continue;
    }
    const int sy = static_cast<int>((2 * std::int64_t{y - r.y} + 1) * image.height / (2 * std::int64_t{r.height}));
    const std::uint8_t* src = image.pixels + static_cast<std::size_t>(sy) * image.stride_bytes;
    std::fill(row, row + r.x, 0u);
    for (int i = 0; i < r.width; ++i) {
      const std::uint8_t* p = src + 4 * static_cast<std::size_t>(src_x[static_cast<std::size_t>(i)]);
      row[r.x + i] = (std::uint32_t{p[0]} << 16) | (std::uint32_t{p[1]} << 8) | std::uint32_t{p[2]};
    }
    std::fill(row + r.x + r.width, row + dst_w, 0u);
  }
}

RgbaView select_layout(const RgbaView& sbs, DisplayLayout layout) {
  if (layout == DisplayLayout::SideBySide) return sbs;
  RgbaView eye = sbs;
  eye.width = sbs.width / 2;
  if (layout == DisplayLayout::RightEye) eye.pixels = sbs.pixels + 4 * static_cast<std::size_t>(eye.width);
  return eye;
}

KmsDisplay::KmsDisplay(const KmsOptions& options) : options_(options) {
  const std::string& card = options.card;
  fd_ = ::open(card.c_str(), O_RDWR | O_CLOEXEC);
  if (fd_ < 0) fail(card, "cannot open: " + errno_text(errno));
  try {
    Resources res(drmModeGetResources(fd_));
    if (!res) fail(card, "not a KMS device (no mode-setting resources: " + errno_text(errno) + ")");
    std::uint64_t dumb = 0;
    if (drmGetCap(fd_, DRM_CAP_DUMB_BUFFER, &dumb) != 0 || dumb == 0) fail(card, "the driver has no dumb scan-out buffers");

    // The connector: the one named, else the first connected one with modes.
    Connector chosen;
    std::string found;
    for (int i = 0; i < res->count_connectors; ++i) {
      Connector c(drmModeGetConnector(fd_, res->connectors[i]));
      if (!c) continue;
      const std::string name = connector_name_of(*c);
      const bool connected = c->connection == DRM_MODE_CONNECTED && c->count_modes > 0;
      found += (found.empty() ? "" : ", ") + name + (connected ? " (connected)" : " (not connected)");
      if (chosen) continue;
      if (options.connector.empty() ? connected : name == options.connector) chosen = std::move(c);
    }
    if (!chosen)
      fail(card, (options.connector.empty() ? std::string("no connected display") : "no connector named " + options.connector) +
                     "; connectors: " + (found.empty() ? "none" : found));
    connector_name_ = connector_name_of(*chosen);
    if (chosen->connection != DRM_MODE_CONNECTED || chosen->count_modes == 0)
      fail(card, connector_name_ + " has no display connected");
    connector_id_ = chosen->connector_id;

    // The mode: the one asked for, else the preferred one, else the first listed.
    const drmModeModeInfo* mode = nullptr;
    for (int i = 0; i < chosen->count_modes; ++i) {
      const drmModeModeInfo& m = chosen->modes[i];
      if (options.width > 0) {
        if (m.hdisplay == options.width && m.vdisplay == options.height) {
          mode = &m;
          break;
        }
      } else if ((m.type & DRM_MODE_TYPE_PREFERRED) != 0) {
        mode = &m;
        break;
      }
    }
    if (mode == nullptr && options.width > 0) {
      std::string modes;
      for (int i = 0; i < chosen->count_modes && i < 12; ++i)
        modes += (i ? ", " : "") + std::to_string(chosen->modes[i].hdisplay) + "x" + std::to_string(chosen->modes[i].vdisplay);
      fail(card, connector_name_ + " has no " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                     " mode; it offers " + modes);
    }
    if (mode == nullptr) mode = &chosen->modes[0];
    mode_.assign(reinterpret_cast<const std::uint8_t*>(mode), reinterpret_cast<const std::uint8_t*>(mode) + sizeof(drmModeModeInfo));
    width_ = mode->hdisplay;
    height_ = mode->vdisplay;
    refresh_hz_ = mode->vrefresh;

    // The CRTC: the one already driving the connector, else the first free one an encoder can use.
    if (chosen->encoder_id != 0) {
      Encoder e(drmModeGetEncoder(fd_, chosen->encoder_id));
      if (e && e->crtc_id != 0) crtc_id_ = e->crtc_id;
    }
    for (int i = 0; i < chosen->count_encoders && crtc_id_ == 0; ++i) {
      Encoder e(drmModeGetEncoder(fd_, chosen->encoders[i]));
      if (!e) continue;
      for (int j = 0; j < res->count_crtcs; ++j)
        if ((e->possible_crtcs & (1u << j)) != 0) {
          crtc_id_ = res->crtcs[j];
          break;
        }
    }
    if (crtc_id_ == 0) fail(card, "no display controller (CRTC) can drive " + connector_name_);

    saved_crtc_ = drmModeGetCrtc(fd_, crtc_id_);
    for (Buffer& b : buffers_) create_buffer(b);
    // Start black on the front buffer.
    for (Buffer& b : buffers_) std::memset(b.map, 0, b.size);
    auto* m = reinterpret_cast<drmModeModeInfo*>(mode_.data());
    if (drmModeSetCrtc(fd_, crtc_id_, buffers_[front_].fb, 0, 0, &connector_id_, 1, m) != 0) {
      const int e = errno;
      fail(card, "cannot set the mode on " + connector_name_ + ": " + errno_text(e) +
                     (e == EACCES || e == EPERM ? " (another program, e.g. a desktop session, is DRM master)" : ""));
    }
  } catch (...) {
    release();
    throw;
  }
}

KmsDisplay::~KmsDisplay() {
  if (flip_pending_) wait_for_flip();
  if (saved_crtc_ != nullptr) {
    auto* c = static_cast<drmModeCrtc*>(saved_crtc_);
    // Give the connector back to whatever showed before (the console, or nothing).
    if (c->buffer_id != 0) drmModeSetCrtc(fd_, c->crtc_id, c->buffer_id, c->x, c->y, &connector_id_, 1, &c->mode);
  }
  release();
}

void KmsDisplay::release() {
  for (Buffer& b : buffers_) destroy_buffer(b);
  if (saved_crtc_ != nullptr) drmModeFreeCrtc(static_cast<drmModeCrtc*>(saved_crtc_));
  saved_crtc_ = nullptr;
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void KmsDisplay::create_buffer(Buffer& b) {
  drm_mode_create_dumb create{};
  create.width = static_cast<std::uint32_t>(width_);
  create.height = static_cast<std::uint32_t>(height_);
  create.bpp = 32;
  if (drmIoctl(fd_, DRM_IOCTL_MODE_CREATE_DUMB, &create) != 0) fail(options_.card, "cannot create a scan-out buffer: " + errno_text(errno));
  b.handle = create.handle;
  b.pitch = create.pitch;
  b.size = create.size;
  if (drmModeAddFB(fd_, create.width, create.height, 24, 32, b.pitch, b.handle, &b.fb) != 0)
    fail(options_.card, "cannot register a framebuffer: " + errno_text(errno));
  drm_mode_map_dumb map{};
  map.handle = b.handle;
  if (drmIoctl(fd_, DRM_IOCTL_MODE_MAP_DUMB, &map) != 0) fail(options_.card, "cannot map a scan-out buffer: " + errno_text(errno));
  void* p = ::mmap(nullptr, b.size, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, static_cast<off_t>(map.offset));
  if (p == MAP_FAILED) fail(options_.card, "cannot map a scan-out buffer: " + errno_text(errno));
  b.map = p;
}

void KmsDisplay::destroy_buffer(Buffer& b) {
  if (b.map != nullptr) ::munmap(b.map, b.size);
  if (b.fb != 0) drmModeRmFB(fd_, b.fb);
  if (b.handle != 0) {
    drm_mode_destroy_dumb d{};
    d.handle = b.handle;
    drmIoctl(fd_, DRM_IOCTL_MODE_DESTROY_DUMB, &d);
  }
  b = Buffer{};
}

void KmsDisplay::wait_for_flip() {
  drmEventContext ev{};
  ev.version = 2;
  ev.page_flip_handler = on_page_flip;
  pollfd p{fd_, POLLIN, 0};
  while (flip_pending_) {
    const int n = ::poll(&p, 1, options_.flip_timeout_ms);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      // The flip event never came (a display that stopped answering): count it and go on rather
      // than stall the render thread; the next flip may then be refused as busy and falls back.
      ++flip_timeouts_;
      flip_pending_ = false;
      return;
    }
    // drmHandleEvent reads the event; its handler clears flip_pending_ through the user data.
    drmHandleEvent(fd_, &ev);
  }
}

void KmsDisplay::present(const RgbaView& side_by_side) {
  if (side_by_side.pixels == nullptr || side_by_side.width <= 1 || side_by_side.height <= 0)
    throw KmsError("KMS display " + options_.card + ": empty frame");
  if (flip_pending_) wait_for_flip();
  const int back = 1 - front_;
  Buffer& b = buffers_[back];
  blit_letterboxed(select_layout(side_by_side, options_.layout), static_cast<std::uint32_t*>(b.map), width_, height_, b.pitch);
  bool shown = false;
  if (page_flip_) {
    if (drmModePageFlip(fd_, crtc_id_, b.fb, DRM_MODE_PAGE_FLIP_EVENT, &flip_pending_) == 0) {
      flip_pending_ = true;
      shown = true;
    } else if (errno == EINVAL || errno == ENOSYS || errno == EOPNOTSUPP) {
      page_flip_ = false;  // this driver cannot flip: set the mode per frame from now on
    } else if (errno != EBUSY) {  // busy: a flip whose event timed out is still queued; set this frame
      fail(options_.card, "page flip on " + connector_name_ + " failed: " + errno_text(errno));
    }
  }
  if (!shown) {
    auto* m = reinterpret_cast<drmModeModeInfo*>(mode_.data());
    if (drmModeSetCrtc(fd_, crtc_id_, b.fb, 0, 0, &connector_id_, 1, m) != 0)
      fail(options_.card, "cannot show a frame on " + connector_name_ + ": " + errno_text(errno));
  }
  front_ = back;
  ++frames_;
}

std::string KmsDisplay::description() const {
  const auto slash = options_.card.find_last_of('/');
  return options_.card.substr(slash == std::string::npos ? 0 : slash + 1) + " " + connector_name_ + " " + std::to_string(width_) + "x" +
         std::to_string(height_) + "@" + std::to_string(static_cast<int>(refresh_hz_ + 0.5)) + (page_flip_ ? " (page flip)" : " (mode set per frame)");
}

KmsOptions parse_display_spec(const std::string& spec) {
  KmsOptions o;
  const auto a = spec.find(':');
  o.card = spec.substr(0, a);
  if (a != std::string::npos) {
    const auto b = spec.find(':', a + 1);
    o.connector = spec.substr(a + 1, b == std::string::npos ? std::string::npos : b - a - 1);
    if (b != std::string::npos) {
      const std::string layout = spec.substr(b + 1);
      if (layout == "left") o.layout = DisplayLayout::LeftEye;
      else if (layout == "right") o.layout = DisplayLayout::RightEye;
      else if (layout != "sbs") throw std::runtime_error("--display " + spec + ": layout must be sbs, left or right");
    }
  }
  if (o.card.empty()) throw std::runtime_error("--display " + spec + ": no card (e.g. /dev/dri/card0)");
  return o;
}

}  // namespace vitreo::render

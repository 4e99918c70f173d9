#include "drivers/usb.hpp"

#include <libusb.h>

#include <cstdio>
#include <cstring>

#include "firmware-protocol/vp.hpp"

namespace vitreo::drivers {
namespace {
constexpr unsigned char kEpIn = 0x81, kEpOut = 0x02;
constexpr int kInTransfers = 4;  // keep several IN requests queued so a 1 kHz stream never waits on us
constexpr int kInSize = 64;
}  // namespace

bool list_usb_devices(std::vector<UsbDeviceEntry>& out, std::string* error) {
  libusb_context* ctx = nullptr;
  int r = libusb_init(&ctx);
  if (r != 0) {
    if (error) *error = std::string("libusb_init: ") + libusb_error_name(r);
    return false;
  }
  libusb_device** list = nullptr;
  ssize_t n = libusb_get_device_list(ctx, &list);
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0 || d.idVendor != kVitreoUsbVid) continue;
    UsbDeviceEntry e;
    e.vid = d.idVendor;
    e.pid = d.idProduct;
    e.bus = libusb_get_bus_number(list[i]);
    e.address = libusb_get_device_address(list[i]);
    libusb_device_handle* h = nullptr;
    if (libusb_open(list[i], &h) == 0) {
      unsigned char s[128] = {};
      if (d.iProduct && libusb_get_string_descriptor_ascii(h, d.iProduct, s, sizeof s) > 0) e.product = reinterpret_cast<char*>(s);
      std::memset(s, 0, sizeof s);
      if (d.iSerialNumber && libusb_get_string_descriptor_ascii(h, d.iSerialNumber, s, sizeof s) > 0)
        e.serial = reinterpret_cast<char*>(s);
      libusb_close(h);
    }
    out.push_back(e);
  }
  if (n >= 0) libusb_free_device_list(list, 1);
  libusb_exit(ctx);
  return true;
}

UsbDevice::UsbDevice(std::uint16_t vid, std::uint16_t pid, Clock& clock, SessionConfig cfg, std::string serial_number)
    : vid_(vid), pid_(pid), serial_number_(std::move(serial_number)), clock_(clock), session_(cfg) {
  session_.set_send([this](const vp_message& m) { send(m); });
}

UsbDevice::~UsbDevice() {
  close_handle();
  if (ctx_) {
    if (hotplug_) libusb_hotplug_deregister_callback(ctx_, hotplug_handle_);
    libusb_exit(ctx_);
  }
}

bool UsbDevice::init(std::string* error) {
  int r = libusb_init(&ctx_);
  if (r != 0) {
    ctx_ = nullptr;
    if (error) *error = std::string("libusb_init: ") + libusb_error_name(r);
    return false;
  }
  if (libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) {
    libusb_hotplug_callback_handle hh = 0;
    r = libusb_hotplug_register_callback(
        ctx_, static_cast<libusb_hotplug_event>(LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED | LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT),
        LIBUSB_HOTPLUG_NO_FLAGS, vid_, pid_, LIBUSB_HOTPLUG_MATCH_ANY,
        [](libusb_context* c, libusb_device* d, libusb_hotplug_event ev, void* self) {
          return on_hotplug(c, d, static_cast<int>(ev), self);
        },
        this, &hh);
    hotplug_ = r == 0;
    hotplug_handle_ = hh;
  }
  return true;
}

int UsbDevice::on_hotplug(libusb_context*, libusb_device*, int event, void* self) {
  auto* d = static_cast<UsbDevice*>(self);
  if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED) {
    ++d->arrivals_;
    d->arrived_ = true;
  } else {
    ++d->departures_;
    if (d->h_) d->gone_ = true;
  }
  return 0;  // stay registered
}

void UsbDevice::on_in(libusb_transfer* t) {
  auto* d = static_cast<UsbDevice*>(t->user_data);
  const std::uint64_t now = d->clock_.now_us();
  switch (t->status) {
    case LIBUSB_TRANSFER_COMPLETED: {
      std::span<const std::uint8_t> bytes(t->buffer, static_cast<std::size_t>(t->actual_length));
      if (d->raw_tap_) d->raw_tap_(bytes);
      d->session_.on_bytes(bytes.size());
      vp_message m{};
      int st = vp_usb_decode(bytes.data(), bytes.size(), &m);
      d->session_.on_frame(st, m, now);
      if (d->closing_) break;  // completed just before the cancel: not resubmitted
      if (!d->gone_ && libusb_submit_transfer(t) == 0) return;
      d->gone_ = true;
      break;
    }
    case LIBUSB_TRANSFER_TIMED_OUT:
      if (d->closing_) break;
      if (!d->gone_ && libusb_submit_transfer(t) == 0) return;
      d->gone_ = true;
      break;
    case LIBUSB_TRANSFER_CANCELLED: break;
    default: d->gone_ = true; break;  // NO_DEVICE, ERROR, STALL, OVERFLOW: the link is unusable
  }
  --d->outstanding_;
}

void UsbDevice::on_out(libusb_transfer* t) {
  auto* d = static_cast<UsbDevice*>(t->user_data);
  if (t->status == LIBUSB_TRANSFER_NO_DEVICE) d->gone_ = true;
  --d->outstanding_;
  // buffer and transfer are freed by libusb (LIBUSB_TRANSFER_FREE_BUFFER | FREE_TRANSFER)
}

void UsbDevice::send(const vp_message& m) {
  if (!h_ || gone_) return;
  auto bytes = proto::encode_usb(m);
  if (bytes.empty()) return;
  libusb_transfer* t = libusb_alloc_transfer(0);
  auto* buf = static_cast<unsigned char*>(std::malloc(bytes.size()));
  if (!t || !buf) {
    std::free(buf);
    if (t) libusb_free_transfer(t);
    return;
  }
  std::memcpy(buf, bytes.data(), bytes.size());
  libusb_fill_bulk_transfer(t, h_, kEpOut, buf, static_cast<int>(bytes.size()), &UsbDevice::on_out, this, 100);
  t->flags = LIBUSB_TRANSFER_FREE_BUFFER | LIBUSB_TRANSFER_FREE_TRANSFER;
  if (libusb_submit_transfer(t) == 0) {
    ++outstanding_;
  } else {
    libusb_free_transfer(t);  // frees the buffer too (FREE_BUFFER)
    gone_ = true;
  }
}

std::string UsbDevice::uri() const {
  char ids[16];
  std::snprintf(ids, sizeof ids, "%04x:%04x", vid_, pid_);
  return std::string("usb:") + ids + (serial_number_.empty() ? "" : "/" + serial_number_);
}

libusb_device_handle* UsbDevice::open_matching() {
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(ctx_, &list);
  libusb_device_handle* found = nullptr;
  for (ssize_t i = 0; i < n && !found; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0 || d.idVendor != vid_ || d.idProduct != pid_) continue;
    libusb_device_handle* h = nullptr;
    if (libusb_open(list[i], &h) != 0) continue;
    if (!serial_number_.empty()) {
      // the serial number string tells two devices of one kind apart; a device without one, or
      // with another, is not ours
      unsigned char s[128] = {};
      const int len = d.iSerialNumber ? libusb_get_string_descriptor_ascii(h, d.iSerialNumber, s, sizeof s - 1) : -1;
      if (len <= 0 || serial_number_ != std::string(reinterpret_cast<char*>(s), static_cast<std::size_t>(len))) {
        libusb_close(h);
        continue;
      }
    }
    found = h;
  }
  if (n >= 0) libusb_free_device_list(list, 1);
  return found;
}

bool UsbDevice::try_open(std::uint64_t now_us) {
  if (opened_once_) session_.reconnect_attempt(now_us);
  opened_once_ = true;
  arrived_ = false;
  libusb_device_handle* h = open_matching();
  if (!h) {
    session_.transport_down(now_us, serial_number_.empty() ? "no such USB device" : "no USB device with this serial number");
    return false;
  }
  if (libusb_claim_interface(h, 0) != 0) {
    libusb_close(h);
    session_.transport_down(now_us, "cannot claim USB interface 0");
    return false;
  }
  h_ = h;
  gone_ = false;
  for (int i = 0; i < kInTransfers; ++i) {
    libusb_transfer* t = libusb_alloc_transfer(0);
    auto* buf = static_cast<unsigned char*>(std::malloc(kInSize));
    libusb_fill_interrupt_transfer(t, h_, kEpIn, buf, kInSize, &UsbDevice::on_in, this, 0);
    t->flags = LIBUSB_TRANSFER_FREE_BUFFER;
    if (libusb_submit_transfer(t) == 0) {
      ++outstanding_;
      in_.push_back(t);
    } else {
      libusb_free_transfer(t);
      gone_ = true;
    }
  }
  session_.transport_up(now_us);
  return true;
}

void UsbDevice::close_handle() {
  if (!h_) return;
  // No callback may resubmit from here on: a transfer that completes between the cancel and its
  // callback would otherwise go back in flight and be freed under libusb's feet.
  closing_ = true;
  for (auto* t : in_) libusb_cancel_transfer(t);  // errors for completed ones are harmless
  timeval tv{0, 2000};
  for (int i = 0; i < 2500 && outstanding_ > 0; ++i) libusb_handle_events_timeout_completed(ctx_, &tv, nullptr);
  // A transfer still in flight after 5 s (a wedged host controller) is leaked, never freed while
  // libusb may still touch it.
  if (outstanding_ == 0) {
    for (auto* t : in_) libusb_free_transfer(t);
  }
  in_.clear();
  outstanding_ = 0;
  closing_ = false;
  libusb_release_interface(h_, 0);
  libusb_close(h_);
  h_ = nullptr;
}

void UsbDevice::poll(int timeout_ms) {
  if (!ctx_) return;
  std::uint64_t now = clock_.now_us();
  if (!h_ && (!opened_once_ || arrived_ || now >= session_.next_reconnect_us())) try_open(now);
  timeval tv{timeout_ms / 1000, (timeout_ms % 1000) * 1000};
  libusb_handle_events_timeout_completed(ctx_, &tv, nullptr);
  now = clock_.now_us();
  if (h_ && gone_) {
    close_handle();
    session_.transport_down(now, "USB device gone");
  }
  if (h_ && session_.tick(now)) close_handle();
}

}  // namespace vitreo::drivers

#include "drivers/sim/usb_sim.hpp"

#include <linux/ioctl.h>
#include <linux/usbdevice_fs.h>
#include <umockdev.h>

#include <cerrno>
#include <cstring>

namespace vitreo::drivers::sim {

namespace {
struct Urb {
  UMockdevIoctlData* urb;
  UMockdevIoctlData* buf;
};
constexpr std::size_t kMaxQueued = 512;  // device-side FIFO; beyond it reports are lost (counted)

std::string hex(const std::uint8_t* p, std::size_t n) {
  std::string s;
  char b[3];
  for (std::size_t i = 0; i < n; ++i) {
    std::snprintf(b, sizeof b, "%02X", p[i]);
    s += b;
  }
  return s;
}
}  // namespace

struct UsbSimDevice::Impl {
  UMockdevTestbed* tb = nullptr;
  UMockdevIoctlBase* handler = nullptr;
  std::string syspath, devnode;
  std::uint16_t pid = 0;
  FirmwareEmulator* emu = nullptr;
  std::uint64_t now_us = 0;

  std::mutex m;
  bool gone = false;
  std::deque<proto::Bytes> reports;
  std::deque<Urb> pending_in, done;
  std::uint64_t dropped = 0, handled = 0;
  std::uint64_t bytes_delivered = 0;  // report bytes copied into the host's URBs
  proto::Bytes host_rx;

  static gboolean on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self) {
    return static_cast<Impl*>(self)->handle(client);
  }

  void complete(UMockdevIoctlClient* c, int ret, int err) { umockdev_ioctl_client_complete(c, ret, err); }

  gboolean handle(UMockdevIoctlClient* client) {
    std::lock_guard<std::mutex> l(m);
    ++handled;
    const gulong req = umockdev_ioctl_client_get_request(client);
    UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
    switch (req) {
      case USBDEVFS_GET_CAPABILITIES: {
        UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(guint32), nullptr);
        *reinterpret_cast<guint32*>(d->data) = USBDEVFS_CAP_BULK_CONTINUATION | USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                                               USBDEVFS_CAP_REAP_AFTER_DISCONNECT | USBDEVFS_CAP_ZERO_PACKET;
        complete(client, 0, 0);
        return TRUE;
      }
      case USBDEVFS_CLAIMINTERFACE:
      case USBDEVFS_RELEASEINTERFACE:
      case USBDEVFS_CLEAR_HALT:
      case USBDEVFS_RESET:
      case USBDEVFS_RESETEP:
      case USBDEVFS_SETINTERFACE:
        if (gone && req == USBDEVFS_CLAIMINTERFACE) {
          complete(client, -1, ENODEV);
        } else {
          complete(client, 0, 0);
        }
        return TRUE;
      case USBDEVFS_GETDRIVER: complete(client, -1, ENODATA); return TRUE;
      case USBDEVFS_SUBMITURB: {
        if (gone) {
          complete(client, -1, ENODEV);
          return TRUE;
        }
        UMockdevIoctlData* ud = umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr);
        auto* u = reinterpret_cast<usbdevfs_urb*>(ud->data);
        UMockdevIoctlData* bd = u->buffer_length ? umockdev_ioctl_data_resolve(
                                                       ud, G_STRUCT_OFFSET(usbdevfs_urb, buffer), u->buffer_length, nullptr)
                                                 : nullptr;
        Urb urb{umockdev_ioctl_data_ref(ud), bd};
        u->status = 0;
        if (u->type == USBDEVFS_URB_TYPE_CONTROL) {
          control(urb);
        } else if (u->type == USBDEVFS_URB_TYPE_INTERRUPT && u->endpoint == 0x81) {
          pending_in.push_back(urb);
        } else if (u->type == USBDEVFS_URB_TYPE_BULK && u->endpoint == 0x02 && bd) {
          vp_message msg{};
          if (vp_usb_decode(bd->data, static_cast<std::size_t>(u->buffer_length), &msg) == VP_OK)
            emu->on_host_message(msg, now_us);
          u->actual_length = u->buffer_length;
          done.push_back(urb);
        } else {
          umockdev_ioctl_data_unref(ud);
          complete(client, -1, EINVAL);
          return TRUE;
        }
        pump();
        complete(client, 0, 0);
        return TRUE;
      }
      case USBDEVFS_REAPURB:
      case USBDEVFS_REAPURBNDELAY: {
        if (done.empty()) {
          complete(client, -1, gone ? ENODEV : EAGAIN);
          return TRUE;
        }
        Urb urb = done.front();
        done.pop_front();
        UMockdevIoctlData* p = umockdev_ioctl_data_resolve(arg, 0, sizeof(gpointer), nullptr);
        umockdev_ioctl_data_set_ptr(p, 0, urb.urb);
        complete(client, 0, 0);
        umockdev_ioctl_data_unref(urb.urb);
        return TRUE;
      }
      case USBDEVFS_DISCARDURB: {
        const gulong addr = reinterpret_cast<gulong>(*reinterpret_cast<void**>(arg->data));
        for (auto it = pending_in.begin(); it != pending_in.end(); ++it) {
          if (it->urb->client_addr == addr) {
            reinterpret_cast<usbdevfs_urb*>(it->urb->data)->status = -ENOENT;
            done.push_back(*it);
            pending_in.erase(it);
            complete(client, 0, 0);
            return TRUE;
          }
        }
        complete(client, -1, EINVAL);
        return TRUE;
      }
      default: return FALSE;
    }
  }

  void control(Urb& urb) {
    auto* u = reinterpret_cast<usbdevfs_urb*>(urb.urb->data);
    std::uint8_t* b = urb.buf->data;  // setup packet + data
    const std::uint16_t wValue = static_cast<std::uint16_t>(b[2] | b[3] << 8);
    const std::uint16_t wLength = static_cast<std::uint16_t>(b[6] | b[7] << 8);
    int n = 0;
    if (b[0] == 0x80 && b[1] == 6 && (wValue >> 8) == 3) {  // GET_DESCRIPTOR(STRING)
      proto::Bytes d;
      const int idx = wValue & 0xff;
      if (idx == 0) {
        d = {4, 3, 0x09, 0x04};
      } else {
        std::string s = idx == 1 ? "vitreo" : idx == 2 ? std::string("vitreo ") + to_string(emu->script().kind)
                                                       : std::to_string(emu->script().serial);
        d = {static_cast<std::uint8_t>(2 + 2 * s.size()), 3};
        for (char c : s) d.insert(d.end(), {static_cast<std::uint8_t>(c), 0});
      }
      n = static_cast<int>(std::min<std::size_t>(d.size(), wLength));
      std::memcpy(b + 8, d.data(), static_cast<std::size_t>(n));
    } else {
      u->status = -EPIPE;  // STALL, as a device does for requests it does not know
    }
    u->actual_length = n;
    done.push_back(urb);
  }

  void pump() {
    while (!pending_in.empty() && !reports.empty()) {
      Urb urb = pending_in.front();
      pending_in.pop_front();
      auto* u = reinterpret_cast<usbdevfs_urb*>(urb.urb->data);
      const proto::Bytes& r = reports.front();
      const std::size_t n = std::min<std::size_t>(r.size(), static_cast<std::size_t>(u->buffer_length));
      std::memcpy(urb.buf->data, r.data(), n);
      u->actual_length = static_cast<int>(n);
      u->status = 0;
      bytes_delivered += n;
      done.push_back(urb);
      reports.pop_front();
    }
  }

  void fail_pending() {
    for (auto& urb : pending_in) {
      reinterpret_cast<usbdevfs_urb*>(urb.urb->data)->status = -ENODEV;
      done.push_back(urb);
    }
    pending_in.clear();
  }
};

namespace {
// One testbed per process: a second umockdev_testbed_new() points $UMOCKDEV_DIR at a fresh, empty
// sysfs and hides the devices of the first. It lives as long as the process.
UMockdevTestbed* shared_testbed() {
  static UMockdevTestbed* tb = umockdev_testbed_new();
  return tb;
}
}  // namespace

bool UsbSimDevice::mock_environment_available() {
  shared_testbed();  // in_mock_environment() is only true once a testbed exists
  return umockdev_in_mock_environment();
}

UsbSimDevice::UsbSimDevice(Script s, std::uint16_t pid, int address) : emu_(std::move(s)), impl_(new Impl) {
  Impl& d = *impl_;
  d.emu = &emu_;
  d.pid = pid;
  d.tb = shared_testbed();
  if (!umockdev_in_mock_environment()) {
    error_ = "not running under umockdev-wrapper";
    return;
  }
  char addr[8];
  std::snprintf(addr, sizeof addr, "%03d", address);
  d.devnode = std::string("/dev/bus/usb/001/") + addr;
  const std::string port = "1-" + std::to_string(address);
  d.handler = umockdev_ioctl_base_new();
  g_signal_connect(d.handler, "handle-ioctl", G_CALLBACK(&Impl::on_ioctl), &d);
  GError* err = nullptr;
  if (!umockdev_testbed_attach_ioctl(d.tb, d.devnode.c_str(), d.handler, &err)) {
    error_ = std::string("attach_ioctl: ") + (err ? err->message : "?");
    return;
  }
  // device descriptor (VID 0x1209, PID, strings 1..3) + configuration: one vendor interface with
  // interrupt IN 0x81 (64 B, 1 ms) and bulk OUT 0x02 (64 B)
  const std::uint8_t desc[] = {0x12, 0x01, 0x00, 0x02, 0x00, 0x00, 0x00, 0x40, 0x09, 0x12,
                               static_cast<std::uint8_t>(pid), static_cast<std::uint8_t>(pid >> 8), 0x00, 0x01, 0x01, 0x02, 0x03, 0x01,
                               0x09, 0x02, 0x20, 0x00, 0x01, 0x01, 0x00, 0x80, 0x32,
                               0x09, 0x04, 0x00, 0x00, 0x02, 0xFF, 0x00, 0x00, 0x00,
                               0x07, 0x05, 0x81, 0x03, 0x40, 0x00, 0x01,
                               0x07, 0x05, 0x02, 0x02, 0x40, 0x00, 0x00};
  char product[64];
  std::snprintf(product, sizeof product, "1209/%x/100", pid);
  std::string dev = "P: /devices/pci0000:00/0000:00:14.0/usb1/" + port + "\nN: bus/usb/001/" + addr +
                    "\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\nE: DRIVER=usb\nE: BUSNUM=001\nE: DEVNUM=" + addr +
                    "\nE: DEVNAME=" + d.devnode + "\nE: PRODUCT=" + product + "\nA: busnum=1\\n\nA: devnum=" +
                    std::to_string(address) + "\\n\nA: speed=12\\n\nA: bConfigurationValue=1\\n\nA: idVendor=1209\\n\n" +
                    "A: idProduct=" + [&] {
                      char b[8];
                      std::snprintf(b, sizeof b, "%04x", pid);
                      return std::string(b);
                    }() + "\\n\nH: descriptors=" + hex(desc, sizeof desc) + "\n";
  if (!umockdev_testbed_add_from_string(d.tb, dev.c_str(), &err)) {
    error_ = std::string("add_from_string: ") + (err ? err->message : "?");
    return;
  }
  d.syspath = "/sys/devices/pci0000:00/0000:00:14.0/usb1/" + port;
  ok_ = true;
}

UsbSimDevice::~UsbSimDevice() {
  Impl& d = *impl_;
  {
    std::lock_guard<std::mutex> l(d.m);
    for (auto& u : d.pending_in) umockdev_ioctl_data_unref(u.urb);
    for (auto& u : d.done) umockdev_ioctl_data_unref(u.urb);
    d.pending_in.clear();
    d.done.clear();
  }
  if (d.tb && ok_) {
    umockdev_testbed_uevent(d.tb, d.syspath.c_str(), "remove");
    umockdev_testbed_remove_device(d.tb, d.syspath.c_str());
  }
  if (d.tb && d.handler) umockdev_testbed_detach_ioctl(d.tb, d.devnode.c_str(), nullptr);
  if (d.handler) g_object_unref(d.handler);
}

void UsbSimDevice::step(std::uint64_t now_us) {
  Impl& d = *impl_;
  bool scripted = false;
  {
    std::lock_guard<std::mutex> l(d.m);
    scripted = emu_.disconnected(now_us);
  }
  if (scripted != scripted_down_) {
    scripted_down_ = scripted;
    if (!manual_unplug_) set_present(!scripted);
  }
  std::vector<proto::Bytes> packets;
  std::lock_guard<std::mutex> l(d.m);
  d.now_us = now_us;
  emu_.step(now_us, packets);
  if (d.gone) return;
  for (auto& p : packets) {
    proto::Bytes f = proto::frame_usb(p);
    emu_.corrupt(f);
    if (d.reports.size() >= kMaxQueued) {
      d.reports.pop_front();
      ++d.dropped;
    }
    d.reports.push_back(std::move(f));
  }
  d.pump();
}

void UsbSimDevice::unplug() {
  if (manual_unplug_) return;
  manual_unplug_ = true;
  if (!scripted_down_) set_present(false);
}

void UsbSimDevice::plug() {
  if (!manual_unplug_) return;
  manual_unplug_ = false;
  if (!scripted_down_) set_present(true);
}

void UsbSimDevice::set_present(bool present) {
  Impl& d = *impl_;
  if (present) {
    {
      std::lock_guard<std::mutex> l(d.m);
      d.gone = false;
      emu_.reset_link();
    }
    umockdev_testbed_uevent(d.tb, d.syspath.c_str(), "add");
    return;
  }
  {
    std::lock_guard<std::mutex> l(d.m);
    d.gone = true;
    d.reports.clear();
    d.fail_pending();
  }
  umockdev_testbed_uevent(d.tb, d.syspath.c_str(), "remove");
}

std::uint64_t UsbSimDevice::reports_dropped() const {
  std::lock_guard<std::mutex> l(impl_->m);
  return impl_->dropped;
}
std::uint64_t UsbSimDevice::urbs_handled() const {
  std::lock_guard<std::mutex> l(impl_->m);
  return impl_->handled;
}

std::uint64_t UsbSimDevice::bytes_sent() const {
  std::lock_guard<std::mutex> l(impl_->m);
  return impl_->bytes_delivered;
}

}  // namespace vitreo::drivers::sim

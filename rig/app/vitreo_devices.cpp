// vitreo-devices: the technicians' tool for the rig's devices — list and identify them, watch
// decoded samples and link statistics live, dump raw frames, and run simulated devices.
#include <dirent.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "drivers/can.hpp"
#include "drivers/open_device.hpp"
#include "drivers/serial.hpp"
#include "drivers/sim/can_sim.hpp"
#include "drivers/sim/pty_sim.hpp"
#include "drivers/usb.hpp"
#include "rig/app/cli_checks.hpp"
#include "rig/files/read_text_file.hpp"

namespace {

using namespace vitreo::drivers;

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

// Which device to talk to: a URI (--device, drivers/device_uri.hpp), or one of the shorthands
// --serial, --usb, --can, which name the same URIs.
struct LinkOptions {
  std::string uri;
  std::string serial;
  std::string usb;  // tracker | pedals | eyeball
  std::string can;
  int node = -1;
  bool fd = false;
  int baud = 921600;
};

void add_link_options(CLI::App* cmd, LinkOptions& o) {
  auto* d = cmd->add_option("--device", o.uri,
                            "the device's URI: serial:/dev/ttyACM0, can:can0?node=5, usb:1209:7a11[/SERIAL], "
                            "sim:tracker?transport=pty&link=PATH");
  auto* s = cmd->add_option("--serial", o.serial, "serial port (or the link a simulator created): serial:PATH");
  auto* u = cmd->add_option("--usb", o.usb, "USB device kind: usb:1209:7a1N")->check(CLI::IsMember({"tracker", "pedals", "eyeball"}));
  auto* c = cmd->add_option("--can", o.can, "CAN interface (e.g. can0, vcan0): can:IF?node=N");
  d->excludes(s)->excludes(u)->excludes(c);
  s->excludes(u)->excludes(c);
  u->excludes(c);
  cmd->add_option("--node", o.node, "CAN node id of the device (1..127)")->check(CLI::Range(1, 127));
  cmd->add_flag("--fd", o.fd, "CAN FD (default: classic 8-byte CAN)");
  cmd->add_option("--baud", o.baud, "serial baud rate")->check(CLI::IsMember({115200, 230400, 460800, 921600, 1000000, 2000000}));
}

// The URI the options name; empty with a one-line reason in *why.
std::string link_uri(const LinkOptions& o, std::string* why) {
  if (!o.uri.empty()) return o.uri;
  if (!o.serial.empty()) {
    // A path that is not a serial port (a file, /dev/null) would never connect: say so now.
    if (std::string bad = vitreo::app::serial_port_problem(o.serial); !bad.empty()) {
      *why = bad;
      return {};
    }
    return "serial:" + o.serial + (o.baud != 921600 ? "?baud=" + std::to_string(o.baud) : "");
  }
  if (!o.usb.empty()) {
    char b[32];
    std::snprintf(b, sizeof b, "usb:%04x:%04x", kVitreoUsbVid, o.usb == "tracker" ? kTrackerPid : o.usb == "pedals" ? kPedalsPid : kEyeballPid);
    return b;
  }
  if (!o.can.empty()) {
    if (o.node < 0) {
      *why = "--can needs --node";
      return {};
    }
    return "can:" + o.can + "?node=" + std::to_string(o.node) + (o.fd ? "&fd=1" : "");
  }
  *why = "give one of --device, --serial, --usb, --can";
  return {};
}

// nullptr with a one-line reason in *why on bad options.
std::unique_ptr<Device> open_link(const LinkOptions& o, Clock& clock, std::string* why) {
  const std::string uri = link_uri(o, why);
  if (uri.empty()) return nullptr;
  return vitreo::drivers::open_device(uri, clock, {}, why);
}

std::string describe(const Sample& s) {
  char b[256];
  if (auto* p = std::get_if<PoseSample>(&s)) {
    std::snprintf(b, sizeof b, "pose  t_dev=%llu us inst=%u tool=%u tip_mm=(%.3f %.3f %.3f) q=(%.4f %.4f %.4f %.4f) act=%.3f%s",
                  (unsigned long long)p->t.device_us, p->instrument_id, p->tool_type, p->tip_mm[0], p->tip_mm[1],
                  p->tip_mm[2], p->q_wxyz[0], p->q_wxyz[1], p->q_wxyz[2], p->q_wxyz[3], p->actuation,
                  p->stuck ? " STUCK" : "");
  } else if (auto* q = std::get_if<PedalSample>(&s)) {
    std::snprintf(b, sizeof b, "pedal t_dev=%llu us id=%u axes=(%.3f %.3f %.3f %.3f) switches=0x%04x",
                  (unsigned long long)q->t.device_us, q->pedal_id, q->axes[0], q->axes[1], q->axes[2], q->axes[3],
                  q->switches);
  } else {
    auto& e = std::get<EyeballSample>(s);
    std::snprintf(b, sizeof b, "eye   t_dev=%llu us q=(%.4f %.4f %.4f %.4f) ports=%u depth_mm=(%.2f%s %.2f%s %.2f%s)",
                  (unsigned long long)e.t.device_us, e.q_wxyz[0], e.q_wxyz[1], e.q_wxyz[2], e.q_wxyz[3], e.port_count,
                  e.depth_mm[0], e.inserted[0] ? "*" : "", e.depth_mm[1], e.inserted[1] ? "*" : "", e.depth_mm[2],
                  e.inserted[2] ? "*" : "");
  }
  return b;
}

std::string hex(std::span<const std::uint8_t> b) {
  std::string s;
  char x[4];
  for (auto c : b) std::snprintf(x, sizeof x, "%02x ", c), s += x;
  return s;
}

int cmd_list() {
  std::printf("serial ports:\n");
  for (const char* dir : {"/dev/serial/by-id", "/dev"}) {
    if (DIR* d = opendir(dir)) {
      while (dirent* e = readdir(d)) {
        std::string n = e->d_name;
        if (std::string(dir) == "/dev" && n.rfind("ttyUSB", 0) != 0 && n.rfind("ttyACM", 0) != 0) continue;
        if (n[0] == '.') continue;
        std::printf("  %s/%s\n", dir, n.c_str());
      }
      closedir(d);
    }
  }
  std::printf("USB devices (VID %04x):\n", kVitreoUsbVid);
  std::vector<UsbDeviceEntry> usb;
  std::string err;
  if (!list_usb_devices(usb, &err)) std::printf("  (%s)\n", err.c_str());
  for (auto& u : usb)
    std::printf("  bus %d addr %d  %04x:%04x  %s  serial %s\n", u.bus, u.address, u.vid, u.pid, u.product.c_str(),
                u.serial.c_str());
  std::printf("CAN interfaces:\n");
  if (DIR* d = opendir("/sys/class/net")) {
    while (dirent* e = readdir(d)) {
      std::ifstream t(std::string("/sys/class/net/") + e->d_name + "/type");
      int type = 0;
      if (t >> type && type == 280) std::printf("  %s\n", e->d_name);  // ARPHRD_CAN
    }
    closedir(d);
  }
  return 0;
}

int cmd_watch(const LinkOptions& o, double duration_s, double print_hz, bool raw, bool identify_only) {
  SteadyClock clock;
  std::string why;
  auto dev = open_link(o, clock, &why);
  if (!dev) {
    std::fprintf(stderr, "vitreo-devices: %s\n", why.c_str());
    return 2;
  }
  dev->session().set_on_state([](LinkState from, LinkState to, const char* reason) {
    spdlog::info("link {} -> {} ({})", to_string(from), to_string(to), reason);
  });
  const std::uint64_t start = clock.now_us();
  const std::uint64_t print_every = print_hz > 0 ? static_cast<std::uint64_t>(1e6 / print_hz) : ~0ull;
  std::uint64_t next_print = 0, next_stats = start + 1'000'000;
  dev->session().set_on_sample([&](const Sample& s) {
    const std::uint64_t now = clock.now_us();
    if (!raw && !identify_only && now >= next_print) {
      std::printf("%s\n", describe(s).c_str());
      next_print = now + print_every;
    }
  });
  if (raw) {
    auto tap = [](std::span<const std::uint8_t> b) { std::printf("rx %3zu B: %s\n", b.size(), hex(b).c_str()); };
    if (auto* serial = dynamic_cast<SerialDevice*>(dev.get())) serial->set_raw_tap(tap);
    if (auto* usb = dynamic_cast<UsbDevice*>(dev.get())) usb->set_raw_tap(tap);
    if (auto* can = dynamic_cast<CanDevice*>(dev.get()))
      can->set_raw_tap([](const CanRxFrame& f) {
        std::printf("rx %s%s %08x [%2u] %s\n", f.error ? "ERR " : "", f.fd ? "FD" : "  ", f.id, f.len,
                    hex({f.data, f.len}).c_str());
      });
  }
  while (!g_stop && clock.now_us() - start < static_cast<std::uint64_t>(duration_s * 1e6)) {
    dev->poll(5);
    if (identify_only && dev->session().has_device_info()) {
      const auto& i = dev->session().device_info();
      static const char* kinds[] = {"host", "tracker", "pedals", "eyeball fixture"};
      std::printf("%s serial %u hw rev %u firmware %u.%u.%u protocol %u.%u sample rate %u Hz\n",
                  i.device_type < 4 ? kinds[i.device_type] : "?", i.serial, i.hw_revision, i.fw_major, i.fw_minor,
                  i.fw_patch, i.proto_major, i.proto_minor, i.sample_rate_hz);
      return 0;
    }
    if (!identify_only && clock.now_us() >= next_stats) {
      std::printf("[%s] %s\n", to_string(dev->session().state()), to_string(dev->session().stats()).c_str());
      std::fflush(stdout);
      next_stats += 1'000'000;
    }
  }
  if (identify_only) {
    std::fprintf(stderr, "vitreo-devices: no device answered within %.1f s (%s)\n", duration_s,
                 dev->session().last_error().empty() ? "no reply" : dev->session().last_error().c_str());
    return 1;
  }
  std::printf("[%s] %s\n", to_string(dev->session().state()), to_string(dev->session().stats()).c_str());
  if (dev->session().stats().frames == 0) {
    std::fprintf(stderr, "vitreo-devices: no frame from the device in %.1f s (%s)\n", duration_s,
                 dev->session().last_error().empty() ? "is it connected and powered?" : dev->session().last_error().c_str());
    return 1;
  }
  return 0;
}

int cmd_simulate(const std::string& kind, const std::string& script_path, const std::string& link, const std::string& can_if,
                 int node, bool fd, double duration_s) {
  sim::Script s;
  if (!script_path.empty()) {
    const auto file = vitreo::files::read_text_file(script_path);
    if (!file.text) {
      std::fprintf(stderr, "vitreo-devices: script: %s\n", file.error.c_str());
      return 2;
    }
    std::string err;
    if (!sim::parse_script(*file.text, s, &err)) {
      std::fprintf(stderr, "vitreo-devices: %s: %s\n", script_path.c_str(), err.c_str());
      return 2;
    }
  } else {
    s = sim::default_script(kind == "tracker" ? sim::DeviceKind::tracker
                            : kind == "pedals" ? sim::DeviceKind::pedals
                                               : sim::DeviceKind::eyeball);
  }
  SteadyClock clock;
  const std::uint64_t start = clock.now_us();
  auto running = [&] { return !g_stop && clock.now_us() - start < static_cast<std::uint64_t>(duration_s * 1e6); };
  if (!can_if.empty()) {
    if (node < 1) {
      std::fprintf(stderr, "vitreo-devices: --can needs --node\n");
      return 2;
    }
    sim::CanSimDevice dev(s, can_if, static_cast<std::uint8_t>(node), fd);
    if (!dev.ok()) {
      std::fprintf(stderr, "vitreo-devices: %s\n", dev.error().c_str());
      return 1;
    }
    spdlog::info("simulated {} on {} node {} ({})", sim::to_string(s.kind), can_if, node, fd ? "CAN FD" : "classic CAN");
    while (running()) {
      dev.step(clock.now_us());
      usleep(500);
    }
    return 0;
  }
  sim::PtySimDevice dev(s, link);
  spdlog::info("simulated {} on {} -> {}", sim::to_string(s.kind), link, dev.slave_path());
  std::printf("%s\n", link.c_str());
  std::fflush(stdout);
  while (running()) {
    dev.step(clock.now_us());
    usleep(500);
  }
  const auto& c = dev.emulator().counters();
  spdlog::info("sent {} frames ({} samples), corrupted {}, dropped {}", c.frames_sent, c.samples_sent,
               c.frames_corrupted, c.frames_dropped);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vitreo-devices: list, identify, watch and simulate the rig's devices "
               "(tracker, pedals, eyeball fixture) over serial, USB and CAN"};
  app.require_subcommand(1);
  // log to stderr: stdout carries the data (identities, samples, dumps) so it can be piped
  spdlog::set_default_logger(spdlog::stderr_color_mt("vitreo-devices"));
  spdlog::set_pattern("[%H:%M:%S.%e] %^%l%$ %v");

  app.add_subcommand("list", "list serial ports, vitreo USB devices and CAN interfaces");

  LinkOptions id_opts, watch_opts, dump_opts;
  double id_timeout = 2, watch_s = 1e9, watch_hz = 10, dump_s = 1e9;
  auto* identify = app.add_subcommand("identify", "connect and print the device's identity");
  add_link_options(identify, id_opts);
  identify->add_option("--timeout-s", id_timeout, "give up after this long")->check(vitreo::app::finite_range(0.001, 86400));

  auto* watch = app.add_subcommand("watch", "live view of decoded samples and link statistics");
  add_link_options(watch, watch_opts);
  watch->add_option("--duration-s", watch_s, "stop after this long")->check(vitreo::app::finite_range(0.001, 1e9));
  watch->add_option("--print-hz", watch_hz, "samples printed per second (the rest are counted)")
      ->check(vitreo::app::finite_range(0, 100000));

  auto* dump = app.add_subcommand("dump", "raw frame dump (hex), with link statistics each second");
  add_link_options(dump, dump_opts);
  dump->add_option("--duration-s", dump_s, "stop after this long")->check(vitreo::app::finite_range(0.001, 1e9));

  std::string kind = "tracker", script, link = "/tmp/vitreo-sim-tty", sim_can;
  int sim_node = -1;
  bool sim_fd = false;
  double sim_s = 1e9;
  auto* simulate = app.add_subcommand("simulate", "run a simulated device (firmware emulator) over a pty or CAN");
  simulate->add_option("--device", kind, "device kind")->check(CLI::IsMember({"tracker", "pedals", "eyeball"}));
  simulate->add_option("--script", script, "script file (see drivers/sim/emulator.hpp); default: built-in");
  simulate->add_option("--link", link, "path of the serial link to create (symlink to the pty)");
  simulate->add_option("--can", sim_can, "simulate on this CAN interface instead of a pty");
  simulate->add_option("--node", sim_node, "CAN node id")->check(CLI::Range(1, 127));
  simulate->add_flag("--fd", sim_fd, "CAN FD frames");
  simulate->add_option("--duration-s", sim_s, "stop after this long")->check(vitreo::app::finite_range(0.001, 1e9));

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "vitreo-devices: %s\n", e.what());
    return 2;
  }
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  if (app.got_subcommand("list")) return cmd_list();
  if (app.got_subcommand("identify")) return cmd_watch(id_opts, id_timeout, 0, false, true);
  if (app.got_subcommand("watch")) return cmd_watch(watch_opts, watch_s, watch_hz, false, false);
  if (app.got_subcommand("dump")) return cmd_watch(dump_opts, dump_s, 0, true, false);
  if (app.got_subcommand("simulate")) return cmd_simulate(kind, script, link, sim_can, sim_node, sim_fd, sim_s);
  return 2;
}

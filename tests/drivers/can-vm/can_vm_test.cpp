// SocketCAN tests. Runs inside the qemu VM (tests/vm/run-in-vm.sh) as PID 1's child, with vcan0 up at MTU
// 72, can-utils in /bin and the protocol test vectors in /data. A plain main, not GoogleTest: it
// is one static binary and one CTest test (the VM boots once for all of it).
#include <fcntl.h>
#include <linux/can.h>
#include <net/if.h>
#include <linux/can/error.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "drivers/can.hpp"
#include "drivers/sim/can_sim.hpp"
#include "vm_checks.hpp"

extern char** environ;

namespace {

using namespace vitreo::drivers;
using vitreo::proto::Bytes;


const char* kIf = "vcan0";
std::string g_data = "/data";

sim::Script script(const std::string& text) {
  sim::Script s;
  std::string err;
  if (!sim::parse_script(text, s, &err)) std::printf("script error: %s\n", err.c_str());
  return s;
}

// Tracker (CAN FD), pedals and eyeball (classic, segmented) on one bus, each with its driver.
void test_three_devices_stream() {
  std::printf("== three devices on vcan0 (FD tracker, classic pedals and eyeball)\n");
  ManualClock clock;
  sim::CanSimDevice tracker(sim::default_script(sim::DeviceKind::tracker), kIf, 5, true);
  sim::CanSimDevice pedals(sim::default_script(sim::DeviceKind::pedals), kIf, 17, false);
  sim::CanSimDevice eye(sim::default_script(sim::DeviceKind::eyeball), kIf, 33, false);
  CHECK(tracker.ok() && pedals.ok() && eye.ok(), "sim sockets: %s %s %s", tracker.error().c_str(),
        pedals.error().c_str(), eye.error().c_str());
  CanDevice dt(kIf, 5, true, clock), dp(kIf, 17, false, clock), de(kIf, 33, false, clock);
  std::map<std::uint64_t, vp_message> sent;
  tracker.emulator().set_on_sample_sent([&](const vp_message& m) { sent[m.u.pose.timestamp_us] = m; });
  std::vector<Sample> gt, gp, ge;
  dt.session().set_on_sample([&](const Sample& s) { gt.push_back(s); });
  dp.session().set_on_sample([&](const Sample& s) { gp.push_back(s); });
  de.session().set_on_sample([&](const Sample& s) { ge.push_back(s); });
  for (int i = 0; i < 1000; ++i) {
    clock.advance_us(1000);
    tracker.step(clock.now_us());
    pedals.step(clock.now_us());
    eye.step(clock.now_us());
    dt.poll(0);
    dp.poll(0);
    de.poll(0);
  }
  for (auto* d : {&dt, &dp, &de}) {
    std::printf("  %s | %s\n", to_string(d->session().state()), to_string(d->session().stats()).c_str());
    CHECK(d->session().state() == LinkState::streaming, "state %s", to_string(d->session().state()));
    CHECK(d->session().stats().rejected() == 0, "rejected %llu", (unsigned long long)d->session().stats().rejected());
    CHECK(d->session().stats().drops == 0, "drops");
    CHECK(d->can_stats().foreign_frames == 0, "kernel filter lets only our node through");
  }
  CHECK(gt.size() > 900, "tracker samples %zu", gt.size());
  CHECK(gp.size() > 450, "pedal samples %zu", gp.size());
  CHECK(ge.size() > 200, "eyeball samples %zu", ge.size());
  CHECK(dt.session().device_info().serial == 1001 && dp.session().device_info().serial == 2001 &&
            de.session().device_info().serial == 3001,
        "each driver identified its own device");
  int bad = 0;
  for (auto& s : gt) {
    auto& p = std::get<PoseSample>(s);
    auto it = sent.find(p.t.device_us);
    if (it == sent.end() || std::memcmp(it->second.u.pose.tip_mm, p.tip_mm.data(), 12) != 0) ++bad;
  }
  CHECK(bad == 0, "invalid delivered %d", bad);
  bool pressed = false, inserted = false;
  for (auto& s : gp) pressed |= std::get<PedalSample>(s).axes[0] > 0.5f;  // the script presses to 0.6 by 500 ms
  for (auto& s : ge) inserted |= std::get<EyeballSample>(s).inserted[0];
  CHECK(pressed && inserted, "pedal press and port insertion seen through classic-CAN reassembly");
}

void test_faults_over_can() {
  std::printf("== faults over CAN: NaN, wrong version, dropped frames\n");
  ManualClock clock;
  sim::CanSimDevice dev(script("device tracker\nautostream 1\nkey 0 0 0 20 0 0 0 0\nkey 1000 2 2 12 0 0 0 1\n"
                               "fault 100 30 nan\nfault 200 10 version\nfault 300 20 drop\n"),
                        kIf, 6, false);
  CanDevice drv(kIf, 6, false, clock);
  int nan_delivered = 0;
  drv.session().set_on_sample([&](const Sample& s) {
    for (float x : std::get<PoseSample>(s).tip_mm) nan_delivered += !std::isfinite(x);
  });
  for (int i = 0; i < 500; ++i) {
    clock.advance_us(1000);
    dev.step(clock.now_us());
    drv.poll(0);
  }
  const auto& st = drv.session().stats();
  std::printf("  %s\n", to_string(st).c_str());
  CHECK(st.range_rejected == 30, "NaN samples rejected: %llu", (unsigned long long)st.range_rejected);
  CHECK(st.version_errors >= 10, "wrong-version frames: %llu", (unsigned long long)st.version_errors);
  CHECK(st.drops >= 20, "sequence gaps counted: %llu", (unsigned long long)st.drops);
  CHECK(nan_delivered == 0, "NaN delivered");
  CHECK(drv.session().state() == LinkState::streaming, "still streaming");
}

// Error frames come from CAN controllers; vcan has none, so they are injected as a controller
// driver would deliver them (CAN_ERR_FLAG frames) and must be counted, bus-off must drop the
// link, and the link must come back.
void test_error_frames_and_bus_off() {
  std::printf("== error frames and bus-off\n");
  ManualClock clock;
  sim::CanSimDevice dev(sim::default_script(sim::DeviceKind::pedals), kIf, 18, false);
  CanDevice drv(kIf, 18, false, clock);
  auto run = [&](int ms) {
    for (int i = 0; i < ms; ++i) {
      clock.advance_us(1000);
      dev.step(clock.now_us());
      drv.poll(0);
    }
  };
  run(200);
  CHECK(drv.session().state() == LinkState::streaming, "streaming before errors");
  int s = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  sockaddr_can a{};
  a.can_family = AF_CAN;
  a.can_ifindex = static_cast<int>(if_nametoindex(kIf));
  bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a);
  can_frame e{};
  e.can_id = CAN_ERR_FLAG | CAN_ERR_CRTL;
  e.len = CAN_ERR_DLC;
  e.data[1] = CAN_ERR_CRTL_RX_WARNING;
  const bool sent_warning = write(s, &e, sizeof e) == sizeof e;
  CHECK(sent_warning, "inject controller warning (errno %d %s)", errno, std::strerror(errno));
  run(5);
  CHECK(drv.can_stats().error_frames == 1 && drv.can_stats().controller_problems == 1, "warning counted: %llu/%llu",
        (unsigned long long)drv.can_stats().error_frames, (unsigned long long)drv.can_stats().controller_problems);
  CHECK(drv.session().state() == LinkState::streaming, "a warning does not drop the link");
  e.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  std::memset(e.data, 0, sizeof e.data);
  CHECK(write(s, &e, sizeof e) == sizeof e, "inject bus-off");
  run(2);
  CHECK(drv.can_stats().bus_off == 1, "bus-off counted");
  CHECK(drv.session().state() == LinkState::lost, "bus-off → lost (state %s)", to_string(drv.session().state()));
  run(400);
  CHECK(drv.session().state() == LinkState::streaming, "back to streaming after restart (state %s)",
        to_string(drv.session().state()));
  CHECK(drv.session().stats().reconnects == 1, "one reconnect");
  close(s);
}

int spawn(std::vector<std::string> args, const char* out_path = nullptr) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  if (out_path) posix_spawn_file_actions_addopen(&fa, 1, out_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  int r = posix_spawnp(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  return r == 0 ? pid : -1;
}
int wait_for(int pid) {
  int st = 0;
  waitpid(pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128;
}

Bytes unhex(const std::string& h) {
  Bytes b;
  for (std::size_t i = 0; i + 1 < h.size(); i += 2) b.push_back(static_cast<std::uint8_t>(std::stoul(h.substr(i, 2), nullptr, 16)));
  return b;
}
std::string hex(const std::uint8_t* p, std::size_t n) {
  std::string s;
  char b[3];
  for (std::size_t i = 0; i < n; ++i) std::snprintf(b, sizeof b, "%02X", p[i]), s += b;
  return s;
}

// candump records what our emulators put on the bus; every line must decode with our decoders.
void test_candump_reads_our_frames() {
  std::printf("== interop: candump -L captures our frames\n");
  const int want = 60;
  int pid = spawn({"candump", "-L", "-n", std::to_string(want), "-T", "5000", std::string(kIf) + ",0:0"}, "/tmp/dump.log");
  CHECK(pid > 0, "spawn candump");
  usleep(300000);  // candump must be listening before frames go out (the one unavoidable wait)
  ManualClock clock;
  sim::CanSimDevice fd(script("device tracker\nautostream 1\nkey 0 1 2 20 0 0 0 0\n"), kIf, 7, true);
  sim::CanSimDevice classic(script("device eyeball\nautostream 1\nrate_hz 1000\nkey 0 10 0 5 0 0\n"), kIf, 40, false);
  std::vector<vp_message> sent;
  fd.emulator().set_on_sample_sent([&](const vp_message& m) { sent.push_back(m); });
  classic.emulator().set_on_sample_sent([&](const vp_message& m) { sent.push_back(m); });
  for (int i = 0; i < 10; ++i) {
    clock.advance_us(1000);
    fd.step(clock.now_us());
    classic.step(clock.now_us());
  }
  CHECK(wait_for(pid) == 0, "candump exit");
  std::ifstream in("/tmp/dump.log");
  std::string line;
  int lines = 0, decoded = 0, segments = 0, errors = 0;
  vp_can_rx rx;
  vp_can_rx_init(&rx);
  std::vector<std::string> got;
  while (std::getline(in, line)) {
    ++lines;
    std::istringstream ls(line);
    std::string ts, iface, frame;
    ls >> ts >> iface >> frame;
    const auto hash = frame.find('#');
    const std::uint32_t id = static_cast<std::uint32_t>(std::stoul(frame.substr(0, hash), nullptr, 16));
    const bool is_fd = frame.size() > hash + 1 && frame[hash + 1] == '#';
    Bytes data = unhex(frame.substr(hash + (is_fd ? 3 : 1)));  // FD: "##<flags nibble><data>"
    vp_message m{};
    std::uint8_t node = 0;
    int st = is_fd ? vp_canfd_decode(id, data.data(), data.size(), &node, &m)
                   : vp_can_rx_push(&rx, id, data.data(), data.size(), &node, &m);
    if (st == VP_OK) {
      ++decoded;
      if (m.type != VP_MSG_HEARTBEAT) got.push_back(vitreo::proto::describe(m));
    } else if (st == VP_NEED_MORE) {
      ++segments;
    } else {
      ++errors;
      std::printf("  undecodable candump line: %s (%s)\n", line.c_str(), vp_status_name(st));
    }
  }
  std::printf("  candump: %d lines, %d messages, %d segments, %d errors\n", lines, decoded, segments, errors);
  CHECK(lines == want, "candump lines %d", lines);
  CHECK(errors == 0, "every captured frame decodes");
  int matched = 0;
  for (auto& g : got)
    for (auto& s : sent) matched += g == vitreo::proto::describe(s);
  CHECK(matched == static_cast<int>(got.size()) && matched > 5, "captured samples equal what was sent (%d of %zu)",
        matched, got.size());
}

// cansend puts the checked-in vector frames (written by the independent Python generator) on the
// bus; our driver's socket and decoders must read the meaning given in vectors.txt.
void test_cansend_vectors_reach_our_decoder() {
  std::printf("== interop: cansend transmits the checked-in CAN vectors\n");
  std::ifstream vt(g_data + "/vectors.txt");
  std::map<std::string, std::string> meaning;
  std::string line;
  while (std::getline(vt, line)) {
    if (line.empty() || line[0] == '#') continue;
    auto bar = line.find(" | ");
    meaning[line.substr(0, line.find(' '))] = line.substr(bar + 3);
  }
  CHECK(!meaning.empty(), "vectors.txt found in %s", g_data.c_str());
  CanSocket sock;
  std::string err;
  CHECK(sock.open(kIf, true, {{CAN_EFF_FLAG | 17u, CAN_EFF_FLAG | 0x7Fu}}, false, &err), "%s", err.c_str());
  int checked = 0;
  for (auto& [file, text] : meaning) {
    if (file.find(".can") == std::string::npos || text.rfind("error", 0) == 0) continue;
    std::ifstream f(g_data + "/" + file, std::ios::binary);
    Bytes b((std::istreambuf_iterator<char>(f)), {});
    vp_can_rx rx;
    vp_can_rx_init(&rx);
    std::string decoded;
    for (std::size_t i = 0; i + 6 <= b.size();) {
      const std::uint32_t id = std::uint32_t(b[i]) << 24 | std::uint32_t(b[i + 1]) << 16 | std::uint32_t(b[i + 2]) << 8 | b[i + 3];
      const bool is_fd = b[i + 4] == 1;
      const std::size_t n = b[i + 5];
      char idbuf[16];
      std::snprintf(idbuf, sizeof idbuf, "%08X", id);
      const std::string arg = std::string(idbuf) + (is_fd ? "##0" : "#") + hex(&b[i + 6], n);
      CHECK(wait_for(spawn({"cansend", kIf, arg})) == 0, "cansend %s", arg.c_str());
      CanRxFrame fr;
      int r = 0;
      for (int k = 0; k < 100 && (r = sock.read(fr)) == 0; ++k) usleep(1000);
      CHECK(r == 1 && fr.id == id && fr.fd == is_fd && fr.len == n, "frame %s came back", arg.c_str());
      vp_message m{};
      std::uint8_t node = 0;
      int st = fr.fd ? vp_canfd_decode(fr.id, fr.data, fr.len, &node, &m) : vp_can_rx_push(&rx, fr.id, fr.data, fr.len, &node, &m);
      if (st == VP_OK) decoded = vitreo::proto::describe(m);
      i += 6 + n;
    }
    CHECK(decoded == text, "%s: got '%s'", file.c_str(), decoded.c_str());
    ++checked;
  }
  std::printf("  %d vector files sent with cansend and decoded\n", checked);
  CHECK(checked == 21, "all 21 CAN vectors (11 FD, 10 classic)");
}

// The technicians' tool on a real (virtual) CAN bus: one instance simulates the eyeball fixture,
// another identifies and watches it.
void test_tool_over_can() {
  if (access("/bin/vitreo-devices", X_OK) != 0) {
    std::printf("== vitreo-devices not in the VM image: tool check skipped\n");
    return;
  }
  std::printf("== vitreo-devices simulate / identify / watch over vcan0\n");
  int sim = spawn({"vitreo-devices", "simulate", "--device", "eyeball", "--can", kIf, "--node", "33", "--duration-s", "8"},
                  "/tmp/tool-sim.log");
  CHECK(sim > 0, "spawn simulate");
  usleep(500000);
  int rc = wait_for(spawn({"vitreo-devices", "identify", "--can", kIf, "--node", "33", "--timeout-s", "3"}, "/tmp/tool-id.log"));
  std::ifstream id("/tmp/tool-id.log");
  std::string idline;
  std::getline(id, idline);
  std::printf("  identify: %s\n", idline.c_str());
  CHECK(rc == 0 && idline.rfind("eyeball fixture serial 3001", 0) == 0, "identify rc=%d '%s'", rc, idline.c_str());
  rc = wait_for(spawn({"vitreo-devices", "watch", "--can", kIf, "--node", "33", "--duration-s", "2", "--print-hz", "2"},
                      "/tmp/tool-watch.log"));
  std::ifstream w("/tmp/tool-watch.log");
  std::string line;
  int eye = 0, streaming = 0;
  while (std::getline(w, line)) {
    eye += line.rfind("eye ", 0) == 0;
    streaming += line.rfind("[streaming]", 0) == 0;
  }
  std::printf("  watch: %d sample lines, %d streaming status lines\n", eye, streaming);
  CHECK(rc == 0 && eye >= 2 && streaming >= 1, "watch rc=%d eye=%d streaming=%d", rc, eye, streaming);
  kill(sim, SIGTERM);
  CHECK(wait_for(sim) == 0, "simulate stops cleanly on SIGTERM");
}

// A USB CAN adapter pulled out and plugged back: the kernel unregisters its interface and
// registers a new one under the same name (another ifindex). The driver must see the interface go
// (lost), keep retrying by name while it is away, and stream again from the fixture behind it
// once it is back — the same as the serial driver reopening its /dev/vitreo path.
void test_interface_removed_and_added_again() {
  std::printf("== the CAN interface removed and added again (an adapter re-plugged)\n");
  ManualClock clock;
  auto fixture = std::make_unique<sim::CanSimDevice>(sim::default_script(sim::DeviceKind::eyeball), kIf, 33, false);
  CanDevice drv(kIf, 33, false, clock);
  auto run = [&](int ms) {
    for (int i = 0; i < ms; ++i) {
      clock.advance_us(1000);
      if (fixture) fixture->step(clock.now_us());
      drv.poll(0);
    }
  };
  run(300);
  CHECK(drv.session().state() == LinkState::streaming, "streaming before the adapter is pulled (state %s)",
        to_string(drv.session().state()));
  const unsigned old_index = if_nametoindex(kIf);
  CHECK(wait_for(spawn({"ip", "link", "delete", "dev", kIf})) == 0, "ip link delete %s", kIf);
  fixture.reset();  // its socket went with the interface
  run(300);
  CHECK(drv.session().state() == LinkState::lost || drv.session().state() == LinkState::reconnecting,
        "interface gone → lost (state %s)", to_string(drv.session().state()));
  const auto samples_before = drv.session().stats().samples_delivered;
  CHECK(wait_for(spawn({"ip", "link", "add", "dev", kIf, "type", "vcan"})) == 0 &&
            wait_for(spawn({"ip", "link", "set", kIf, "mtu", "72"})) == 0 && wait_for(spawn({"ip", "link", "set", kIf, "up"})) == 0,
        "ip link add %s again", kIf);
  CHECK(if_nametoindex(kIf) != 0 && if_nametoindex(kIf) != old_index, "a new interface under the old name (index %u, was %u)",
        if_nametoindex(kIf), old_index);
  fixture = std::make_unique<sim::CanSimDevice>(sim::default_script(sim::DeviceKind::eyeball), kIf, 33, false);
  CHECK(fixture->ok(), "the fixture is on the new interface: %s", fixture->error().c_str());
  run(600);
  CHECK(drv.session().state() == LinkState::streaming, "found again by its interface name and streaming (state %s)",
        to_string(drv.session().state()));
  CHECK(drv.session().stats().reconnects == 1, "one reconnect (%llu)", (unsigned long long)drv.session().stats().reconnects);
  CHECK(drv.session().stats().samples_delivered > samples_before + 50, "samples again: %llu more",
        (unsigned long long)(drv.session().stats().samples_delivered - samples_before));
}

}  // namespace

int main(int argc, char** argv) {
  setvbuf(stdout, nullptr, _IOLBF, 0);
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--data") g_data = argv[i + 1];
  CanSocket probe;
  std::string err;
  if (!probe.open(kIf, true, {}, false, &err)) {
    std::printf("cannot open %s: %s\n", kIf, err.c_str());
    return 2;
  }
  probe.close();
  test_three_devices_stream();
  test_faults_over_can();
  test_error_frames_and_bus_off();
  test_candump_reads_our_frames();
  test_cansend_vectors_reach_our_decoder();
  test_tool_over_can();
  test_interface_removed_and_added_again();  // last: it replaces vcan0
  std::printf("@@CAN %s: %d checks, %d failed@@\n", g_fail ? "FAIL" : "PASS", g_checks, g_fail);
  return g_fail ? 1 : 0;
}

// Writes the checked-in seed corpora of the fuzz targets (tests/fuzz/README.md):
//   make_fuzz_seeds <tests/fuzz/corpus> <tests/firmware-protocol/fuzz/seeds>
// Seeds are real inputs — what the rig sends and records, the packets that crashed it, the
// protocol's test vectors unwrapped to the raw packets the packet and CAN FD decoders take — so
// the suite's short runs start from inputs that reach deep instead of from nothing.
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "rig/scene_io/case_loader.hpp"
#include "rig/session/simulation_model.hpp"
#include "rig/telemetry/commands.hpp"
#include "rig/telemetry/recording.hpp"
#include "tests/rig/telemetry/malformed_packets.hpp"
#include "vitreo_lcm/command_ack_t.hpp"
#include "vitreo_lcm/device_input_t.hpp"
#include "vitreo_lcm/device_status_t.hpp"
#include "vitreo_lcm/event_t.hpp"
#include "vitreo_lcm/instrument_state_t.hpp"
#include "vitreo_lcm/operator_command_t.hpp"
#include "vitreo_lcm/physics_timing_t.hpp"
#include "vitreo_lcm/receive_status_t.hpp"
#include "vitreo_lcm/recording_check_t.hpp"
#include "vitreo_lcm/recording_end_t.hpp"
#include "vitreo_lcm/recording_header_t.hpp"
#include "vitreo_lcm/score_t.hpp"

namespace fs = std::filesystem;
using namespace vitreo;

namespace {

void write(const fs::path& dir, const std::string& name, const std::vector<std::uint8_t>& bytes) {
  fs::create_directories(dir);
  std::ofstream f(dir / name, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}
void write(const fs::path& dir, const std::string& name, const std::string& text) {
  write(dir, name, std::vector<std::uint8_t>(text.begin(), text.end()));
}
std::vector<std::uint8_t> slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

template <class Msg>
std::vector<std::uint8_t> encoded(const Msg& m, int selector = -1) {
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  if (selector >= 0) b.insert(b.begin(), static_cast<std::uint8_t>(selector));
  return b;
}

void lcm_seeds(const fs::path& messages, const fs::path& command) {
  vitreo_lcm::operator_command_t c{};
  c.utime_us = 1700000000000000;
  c.source = "instructor-ui";
  c.arg = "";
  for (std::int8_t code = 1; code <= 9; ++code) {
    c.seq = code;
    c.command = code;
    c.value = code == 9 ? 12.5 : 0.0;
    c.arg = code == 6 ? "before-peel" : "";
    write(messages, "command_" + std::to_string(code), encoded(c, 0));
    write(command, "command_" + std::to_string(code), encoded(c));
  }
  vitreo_lcm::command_ack_t a{};
  a.source = "terminal";
  a.reason = "physics is not paused";
  write(messages, "ack", encoded(a, 1));
  vitreo_lcm::device_input_t in{};
  in.device_kind = 3;  // a pedal (RECORDING.md)
  in.n_values = 7;
  in.values = {0.0, 2.0, 0.5, 0.25, 0.0, 0.0, 1.0};
  write(messages, "device_input", encoded(in, 2));
  vitreo_lcm::recording_header_t h{};
  h.format_version = vitreo_lcm::recording_header_t::FORMAT_VERSION;
  h.step_period_us = 1000;
  h.case_id = "low_membrane_macula";
  h.config_name = "vitreo-cases";
  h.config_text = "vitreo-cases 1\nfirst_case 0\ncase 1 1 0\nab";
  h.snapshot_hash = "0123456789abcdef";
  write(messages, "recording_header", encoded(h, 3));
  vitreo_lcm::score_t s{};
  s.case_id = "low_membrane_macula";
  s.n = 2;
  s.name = {"target_achievement", "efficiency"};
  s.value = {40.0, 75.0};
  s.pass_score = 80.0;
  write(messages, "score", encoded(s, 4));
  vitreo_lcm::device_status_t ds{};
  ds.name = "tracker-0";
  ds.transport = "serial:/dev/ttyACM0";
  ds.detail = "stuck: identical samples for >= 50 ms";
  ds.stuck = true;
  write(messages, "device_status", encoded(ds, 5));
  vitreo_lcm::instrument_state_t is{};
  is.kind = "forceps";
  write(messages, "instrument_state", encoded(is, 6));
  write(messages, "event", encoded(vitreo_lcm::event_t{}, 7));
  write(messages, "physics_timing", encoded(vitreo_lcm::physics_timing_t{}, 8));
  vitreo_lcm::receive_status_t rs{};
  rs.process = "vitreo";
  rs.n = 1;
  rs.channel = {"VITREO_COMMAND"};
  rs.received = {5};
  rs.rejected = {2};
  rs.handler_errors = {0};
  rs.last_error = {"packet refused: malformed (fingerprint, length or count)"};
  write(messages, "receive_status", encoded(rs, 9));
  write(messages, "recording_check", encoded(vitreo_lcm::recording_check_t{}, 10));
  vitreo_lcm::recording_end_t e{};
  e.state_hash = "0123456789abcdef";
  e.stop_reason = "SIGTERM";
  write(messages, "recording_end", encoded(e, 11));
  for (const auto& p : test::malformed_commands()) {
    std::vector<std::uint8_t> sel = p.bytes;
    sel.insert(sel.begin(), 0);
    if (p.bytes.size() < 4096) write(messages, "malformed_" + p.name, sel);
    if (p.bytes.size() < 4096) write(command, "malformed_" + p.name, p.bytes);
  }
  for (const auto& p : test::malformed_acks()) {
    std::vector<std::uint8_t> sel = p.bytes;
    sel.insert(sel.begin(), 1);
    write(messages, "malformed_" + p.name, sel);
  }
}

void command_line_seeds(const fs::path& dir) {
  int i = 0;
  for (const char* line : {"n", "next", "p", "prev", "previous", " ", "pause", "resume", "r", "reset", "s before-peel",
                           "save look.1", "w", "wireframe", "l", "labels", "z 12.5", "zoom 3", "zoom nan", "s ../x", "fly"})
    write(dir, "line_" + std::to_string(i++), std::string(line));
}

void recording_seeds(const fs::path& dir, const std::string& scenes) {
  const fs::path tmp = fs::temp_directory_path() / "vitreo-fuzz-seed.lcmlog";
  telemetry::RecordingHeader h;
  rig::ModelConfig m;
  m.cases.push_back(scene_io::CaseText{"exercise_pull_tissue.toml", "format_version = 1\n", ""});
  (void)scenes;
  h.case_id = "exercise_pull_tissue";
  h.config_name = "vitreo-cases";
  h.config_text = rig::encode_case_list(m);
  h.snapshot_hash = "0123456789abcdef";
  {
    telemetry::RecorderConfig cfg;
    cfg.flush_interval_ns = 0;
    telemetry::Recorder rec(tmp.string(), h, cfg);
    std::int64_t step = 0;
    // Every kind of input once or more (RECORDING.md's codes and fields).
    auto push = [&](telemetry::InputPayload what) {
      telemetry::RecordedInput in;
      in.host_time_us = 1000 + step * 1000;
      in.step = step;
      in.what = what;
      rec.push(in);
      rec.pump(step * 1'000'000);
    };
    push(telemetry::CaseSwitch{0});
    for (; step < 12; ++step) {
      telemetry::TrackerSample t;
      t.tip_mm = {1.0 + 0.01 * static_cast<double>(step), 2, 3};
      t.actuation = 0.5;
      t.quality = 0.98;
      t.tool_type = 3;
      push(t);
    }
    telemetry::PedalSample p;
    p.axis_count = 2;
    p.axes[0] = 0.5;
    p.switches = 1;
    push(p);
    telemetry::EyeFixtureSample e;
    e.port_count = 4;
    e.inserted = {false, true, false, true};
    e.depth_mm = {0, 3, 0, 2.5};
    push(e);
    push(telemetry::LinkChange{telemetry::LinkEvent::Stuck, 1});
    push(telemetry::OperatorCommand{3, 0.0, 0.0});
    push(telemetry::OperatorCommand{10, 1.5, -0.5});
    push(telemetry::LinkChange{telemetry::LinkEvent::Up, 1});
    push(telemetry::SessionEnd{step + 1});
    rec.finish(telemetry::RecordingEnd{step + 1, 0x0123456789abcdefULL, "duration reached"});
  }
  const auto whole = slurp(tmp);
  write(dir, "complete.lcmlog", whole);
  write(dir, "truncated.lcmlog", std::vector<std::uint8_t>(whole.begin(), whole.begin() + static_cast<long>(whole.size() * 2 / 3)));
  auto flipped = whole;
  flipped[flipped.size() / 2] ^= 0x40;
  write(dir, "corrupted.lcmlog", flipped);
  fs::remove(tmp);
}

void case_list_seeds(const fs::path& dir, const std::string& scenes) {
  rig::ModelConfig m;
  m.cases.push_back(scene_io::read_case_text(scenes + "/exercise_pull_tissue.toml"));
  m.cases.push_back(scene_io::CaseText{"b.toml", "format_version = 1\nname = \"b\"\n", ""});
  m.first_case = 1;
  m.load.retina_vertices = 5000;
  write(dir, "two_cases", rig::encode_case_list(m));
  write(dir, "tiny", std::string("vitreo-cases 1\nfirst_case 0\nretina_vertices 0\ntexture_size_px 0\ncase 1 1 0\nab"));
}

void scene_seeds(const fs::path& dir, const std::string& scenes) {
  const auto scene = slurp(scenes + "/exercise_pull_tissue.toml");
  const auto library = slurp(scenes + "/materials.toml");
  std::vector<std::uint8_t> both = scene;
  both.push_back(0);
  both.insert(both.end(), library.begin(), library.end());
  write(dir, "pull_tissue_with_library", both);
}

void pedal_seeds(const fs::path& dir) {
  write(dir, "minimal", std::string("[pedals]\nvacuum_max_mmhg = 500\ncut_rate_axis = -1\n"));
  write(dir, "switches", std::string("[pedals]\nreflux_switch = 4\nlaser_switch = 5\nair_switch = -1\nlight_step = 0.25\n"));
}

void emulator_seeds(const fs::path& dir) {
  write(dir, "tracker",
        std::string("device tracker\nrate_hz 1000\nserial 1001\ntool 3\ninstrument 0\nloop 0\nnoise 1\n"
                    "key 0 -12.5 3.7 6.2 0 0 0 0\nkey 500 -8 0.5 -4.5 0 0 0 0\nkey 1000 -7 -1.5 -3.5 0 0 20 1\n"
                    "fault 200 100 stuck\nfault 400 0 jump 5000\ncorrupt 0.01\ndrop 0.01\nseed 7\n"));
  write(dir, "pedals", std::string("device pedals\nrate_hz 500\nserial 2001\nkey 0 0 0 0\nkey 400 0.7 0.2 4\nkey 1200 0 0 0\n"
                                   "fault 100 50 range\nfault 300 50 nan\n"));
  write(dir, "eyeball", std::string("device eyeball\nrate_hz 250\nserial 3001\nautostream 1\nkey 0 0 0 0 0 0\nkey 1000 15 -5 14 0 10\n"
                                    "fault 500 100 disconnect\nfault 700 50 version\nfault 800 50 unknown\nfault 900 50 drop\n"));
}

// The protocol's vectors unwrapped: a USB transfer is a packet and its CRC-16; a CAN FD vector is
// [ID u32][FD flag][length][data], and the fuzz target takes [ID u32][data].
void protocol_seeds(const fs::path& out, const std::string& vectors) {
  int usb = 0, canfd = 0;
  for (const auto& e : fs::directory_iterator(vectors)) {
    const std::string name = e.path().filename().string();
    const auto b = slurp(e.path());
    if (name.size() > 8 && name.substr(name.size() - 8) == ".usb.bin" && b.size() > 2) {
      write(out / "packet", name.substr(0, name.size() - 8), std::vector<std::uint8_t>(b.begin(), b.end() - 2));
      ++usb;
    } else if (name.size() > 10 && name.substr(name.size() - 10) == ".canfd.bin" && b.size() >= 6) {
      std::vector<std::uint8_t> seed(b.begin(), b.begin() + 4);
      seed.insert(seed.end(), b.begin() + 6, b.end());
      write(out / "canfd", name.substr(0, name.size() - 10), seed);
      ++canfd;
    }
  }
  std::printf("protocol seeds: %d packets, %d CAN FD frames\n", usb, canfd);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: make_fuzz_seeds <tests/fuzz/corpus> <tests/firmware-protocol/fuzz/seeds>\n");
    return 2;
  }
  const fs::path corpus = argv[1];
  const std::string src = VITREO_SOURCE_DIR;
  lcm_seeds(corpus / "lcm_messages", corpus / "lcm_command");
  command_line_seeds(corpus / "command_line");
  recording_seeds(corpus / "recording", src + "/scenes");
  case_list_seeds(corpus / "case_list", src + "/scenes");
  scene_seeds(corpus / "scene_file", src + "/scenes");
  pedal_seeds(corpus / "pedal_config");
  emulator_seeds(corpus / "emulator_script");
  protocol_seeds(argv[2], src + "/firmware-protocol/vectors");
  std::printf("seeds written under %s\n", argv[1]);
  return 0;
}

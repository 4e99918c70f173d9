// KMS scan-out inside the qemu VM (tests/vm/run-in-vm.sh with SCREENDUMP): qemu's bochs-display is a
// real KMS device (/dev/dri/card0, bochs DRM driver). A plain main, not GoogleTest: one static binary,
// one boot. It presents two stereo test frames, asks the host to dump the virtual screen, waits for
// the host's answer on its console, and checks the error paths. The host then compares the dump with
// the second frame (check_screendump.cpp).
#include <poll.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "vm_checks.hpp"
#include "test_pattern.hpp"
#include "vitreo/render/kms_display.hpp"

namespace {
using namespace vitreo::render;
namespace kt = vitreo::kms_test;

KmsOptions options(const char* card, const char* connector = "", int width = 0, int height = 0) {
  KmsOptions o;
  o.card = card;
  o.connector = connector;
  o.width = width;
  o.height = height;
  return o;
}

bool wait_for_host(int timeout_ms) {
  pollfd p{0, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return false;
  char line[64];
  return ::read(0, line, sizeof line) > 0;
}
}  // namespace

int main() {
  {
    KmsOptions o;  // /dev/dri/card0, first connected connector, preferred mode
    KmsDisplay d(o);
    std::printf("display: %s\n", d.description().c_str());
    CHECK(d.width() >= 640 && d.height() >= 400, "mode %dx%d", d.width(), d.height());
    const auto a = kt::stereo_test_frame(0), b = kt::stereo_test_frame(1);
    d.present({a.data(), kt::kW, kt::kH, 4 * static_cast<std::size_t>(kt::kW)});
    d.present({b.data(), kt::kW, kt::kH, 4 * static_cast<std::size_t>(kt::kW)});
    CHECK(d.frames_presented() == 2, "%llu frames", static_cast<unsigned long long>(d.frames_presented()));
    std::printf("flips timed out: %llu\n", static_cast<unsigned long long>(d.flips_timed_out()));
    std::fflush(stdout);
    // What the screen shows now is frame b (the second, after a flip): the host dumps it.
    std::printf("@@SCREENDUMP@@\n");
    std::fflush(stdout);
    CHECK(wait_for_host(60000), "the host never answered the screendump request");
    // Many frames in a row: flips keep completing (or the per-frame fallback works).
    for (int i = 0; i < 30; ++i) d.present({(i % 2 ? a : b).data(), kt::kW, kt::kH, 4 * static_cast<std::size_t>(kt::kW)});
    CHECK(d.frames_presented() == 32, "%llu frames", static_cast<unsigned long long>(d.frames_presented()));
  }
  // Error paths name the card and the cause.
  EXPECT_THROW_CONTAINS(KmsDisplay(options("/dev/dri/card0", "HDMI-A-7")), "no connector named HDMI-A-7");
  EXPECT_THROW_CONTAINS(KmsDisplay(options("/dev/dri/card0", "HDMI-A-7")), "(connected)");
  EXPECT_THROW_CONTAINS(KmsDisplay(options("/dev/dri/card0", "", 123, 45)), "no 123x45 mode");
  EXPECT_THROW_CONTAINS(KmsDisplay(options("/dev/dri/card9")), "cannot open");
  std::printf("%d checks, %d failed\n", g_checks, g_fail);
  return g_fail == 0 ? 0 : 1;
}

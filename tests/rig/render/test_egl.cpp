// Headless EGL: it works here (surfaceless Mesa), and every way of breaking it ends with a clear
// one-line reason — an exception in-process, a non-zero exit for a tool — and never a hang.
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <vector>

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include "vitreo/render/egl_context.hpp"

namespace vr = vitreo::render;
using Clock = std::chrono::steady_clock;

namespace {

// Runs `argv` with `env_overrides` ("NAME=value"; "NAME=" unsets), returns exit code (or -signal,
// or 999 on timeout after killing it) and stderr.
struct RunResult {
  int code = 0;
  std::string err;
  double seconds = 0;
};

RunResult run(const std::vector<std::string>& argv, const std::vector<std::string>& env_overrides, int timeout_s) {
  int errpipe[2];
  if (pipe(errpipe) != 0) return {-1000, "pipe failed", 0};
  const auto start = Clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(errpipe[1], STDERR_FILENO);
    close(errpipe[0]);
    close(errpipe[1]);
    for (const std::string& e : env_overrides) {
      const auto eq = e.find('=');
      const std::string name = e.substr(0, eq), value = e.substr(eq + 1);
      if (value.empty()) unsetenv(name.c_str());
      else setenv(name.c_str(), value.c_str(), 1);
    }
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  close(errpipe[1]);
  RunResult r;
  const auto deadline = start + std::chrono::seconds(timeout_s);
  bool timed_out = false;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      timed_out = true;
      kill(pid, SIGKILL);
      break;
    }
    pollfd p{errpipe[0], POLLIN, 0};
    if (poll(&p, 1, static_cast<int>(left)) <= 0) continue;
    char buf[512];
    const ssize_t n = read(errpipe[0], buf, sizeof buf);
    if (n <= 0) break;  // the child closed stderr: it is exiting
    r.err.append(buf, static_cast<std::size_t>(n));
  }
  close(errpipe[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  r.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (timed_out) r.code = 999;
  else if (WIFEXITED(status)) r.code = WEXITSTATUS(status);
  else r.code = -WTERMSIG(status);
  return r;
}

std::string what_of(const vr::EglOptions& o) {
  try {
    vr::EglContext ctx(o);
  } catch (const vr::EglError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Egl, HeadlessContextIsDesktopGl45Core) {
  unsetenv("VITREO_EGL_PLATFORM");
  vr::EglContext ctx;
  // Asked of the context itself, not read from the version string: Mesa writes "(Core Profile)"
  // there, NVIDIA's driver does not (seen on an H100, 580.159).
  GLint major = 0, minor = 0, profile = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
  EXPECT_GE(major * 10 + minor, 45) << ctx.description();
  EXPECT_NE(profile & GL_CONTEXT_CORE_PROFILE_BIT, 0) << ctx.description();
  EXPECT_NE(ctx.description().find("GL 4."), std::string::npos) << ctx.description();
}

TEST(Egl, DevicePlatformAlsoWorks) {
  vr::EglOptions o;
  o.platform = vr::EglPlatform::Device;
  o.honour_environment = false;
  vr::EglContext ctx(o);
  EXPECT_EQ(ctx.description().rfind("device:", 0), 0u) << ctx.description();
}

TEST(Egl, FailuresNameThePlatformAndTheCause) {
  vr::EglOptions gbm;
  gbm.platform = vr::EglPlatform::Gbm;
  gbm.gbm_node = "/nonexistent/renderD999";
  gbm.honour_environment = false;
  const std::string g = what_of(gbm);
  EXPECT_NE(g.find("EGL (gbm)"), std::string::npos) << g;
  EXPECT_NE(g.find("/nonexistent/renderD999"), std::string::npos) << g;

  vr::EglOptions dev;
  dev.platform = vr::EglPlatform::Device;
  dev.device_index = 99;
  dev.honour_environment = false;
  const std::string d = what_of(dev);
  EXPECT_NE(d.find("device index 99 out of range"), std::string::npos) << d;

  setenv("VITREO_EGL_PLATFORM", "wayland-please", 1);
  const std::string e = what_of({});
  unsetenv("VITREO_EGL_PLATFORM");
  EXPECT_NE(e.find("unknown platform 'wayland-please'"), std::string::npos) << e;
}

TEST(Egl, BrokenSetupExitsNonZeroWithOneLineAndNeverHangs) {
  const std::string tool = VITREO_RENDER_SNAPSHOT;
  const std::string out = ::testing::TempDir() + "vitreo_egl_fail";
  struct Case {
    std::vector<std::string> args;
    std::vector<std::string> env;
    const char* expect;
  };
  const std::vector<Case> cases = {
      {{tool, "--out", out, "--platform", "gbm"}, {"VITREO_EGL_PLATFORM="}, "EGL (gbm)"},
      {{tool, "--out", out}, {"VITREO_EGL_PLATFORM=nonsense"}, "unknown platform 'nonsense'"},
      {{tool, "--out", out, "--platform", "device"}, {"VITREO_EGL_PLATFORM=", "VITREO_EGL_DEVICE=7"}, "out of range"},
  };
  for (const Case& c : cases) {
    const RunResult r = run(c.args, c.env, 30);
    EXPECT_NE(r.code, 999) << "hung: " << c.expect;
    EXPECT_NE(r.code, 0) << c.expect;
    EXPECT_GT(r.code, 0) << "crashed (signal " << -r.code << "): " << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "expected one line, got: " << r.err;
    EXPECT_LT(r.seconds, 20.0);
  }
  // And the working set-up exits 0 (so the failures above are not the tool failing anyway).
  const RunResult ok = run({tool, "--out", out, "--width", "32", "--height", "32", "--triangles", "200"},
                           {"VITREO_EGL_PLATFORM="}, 60);
  EXPECT_EQ(ok.code, 0) << ok.err;
}

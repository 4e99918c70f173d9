// Real-time setup degrades gracefully. Each case runs in a forked child so that a granted SCHED_FIFO
// or mlockall never leaks into the test process (and mlockall never meets a sanitizer's shadow map).
#include <gtest/gtest.h>

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <string>

#include "rig/runtime/clock.hpp"
#include "rig/runtime/fixed_step_loop.hpp"
#include "rig/runtime/realtime.hpp"

using namespace vitreo::runtime;

namespace {
// Runs fn in a child; returns its exit status (or -1 if it did not exit normally).
template <class Fn>
int in_child(Fn fn) {
  const pid_t pid = fork();
  if (pid == 0) _exit(fn());
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

long vm_locked_kb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmLck:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

// Makes the child an ordinary unprivileged process: no real-time priority, no locked memory.
bool become_unprivileged() {
  rlimit zero{0, 0};
  setrlimit(RLIMIT_RTPRIO, &zero);
  setrlimit(RLIMIT_MEMLOCK, &zero);
  if (geteuid() == 0) {
    if (setgid(65534) != 0 || setuid(65534) != 0) return false;
  }
  return geteuid() != 0;
}
}  // namespace

TEST(Realtime, UnprivilegedProcessGetsWarningsAndKeepsRunning) {
  const int rc = in_child([] {
    if (!become_unprivileged()) return 10;
    RealtimeConfig cfg;
    cfg.sched_fifo = true;
    cfg.lock_memory = true;
    cfg.cpu = CPU_SETSIZE + 5;  // a CPU no machine has
    const RealtimeOutcome out = apply_realtime(cfg);
    if (out.fifo || out.memory_locked || out.affinity) return 11;
    if (out.warnings.size() != 3) return 12;
    if (out.all_requested_applied()) return 13;
    // The kernel agrees: still SCHED_OTHER.
    int policy = -1;
    sched_param sp{};
    pthread_getschedparam(pthread_self(), &policy, &sp);
    if (policy != SCHED_OTHER) return 14;
    // And the loop runs regardless.
    SimulatedClock clock;
    std::uint64_t n = 0;
    FixedStepLoop loop(clock, LoopConfig{}, [&](std::uint64_t, double) { ++n; });
    loop.run(100);
    return n == 100 ? 0 : 15;
  });
  EXPECT_EQ(rc, 0) << "child failed at check " << rc;
}

TEST(Realtime, ReportMatchesWhatTheKernelGranted) {
  // Whatever this machine allows (root on a rig, a container, a CI user), the outcome must tell the
  // truth about the calling thread's policy and affinity.
  const int rc = in_child([] {
    RealtimeConfig cfg;
    cfg.sched_fifo = true;
    cfg.fifo_priority = 1;
    cfg.lock_memory = true;  // in this short-lived child only
    cfg.cpu = 0;
    const RealtimeOutcome out = apply_realtime(cfg);
    int policy = -1;
    sched_param sp{};
    pthread_getschedparam(pthread_self(), &policy, &sp);
    if (out.fifo != (policy == SCHED_FIFO)) return 20;
    cpu_set_t set;
    CPU_ZERO(&set);
    pthread_getaffinity_np(pthread_self(), sizeof set, &set);
    const bool pinned = CPU_COUNT(&set) == 1 && CPU_ISSET(0, &set);
    if (out.affinity != pinned) return 21;
    if (out.memory_locked != (vm_locked_kb() > 0)) return 22;
    if (out.all_requested_applied() != (out.fifo && out.affinity && out.timer_slack && out.memory_locked)) return 23;
    return 0;
  });
  EXPECT_EQ(rc, 0) << "child failed at check " << rc;
}

#pragma once
// Real-time setup for the calling thread: SCHED_FIFO, memory locking (process-wide), CPU affinity and
// a 1 ns timer slack. Each step is attempted separately; what the OS refuses (unprivileged user,
// container without CAP_SYS_NICE/CAP_IPC_LOCK, a CPU that does not exist) is logged as a warning and
// reported, and the rig carries on with what it got — a development laptop or CI container still
// runs, just with worse jitter.
#include <string>
#include <vector>

namespace vitreo::runtime {

struct RealtimeConfig {
  bool sched_fifo = true;
  int fifo_priority = 80;    // 1..99; below the kernel's IRQ threads (50 on PREEMPT_RT) is not wanted here
  bool lock_memory = true;   // mlockall(MCL_CURRENT | MCL_FUTURE): no page faults in the loop
  int cpu = -1;              // pin to this CPU; -1 leaves affinity alone
  bool low_timer_slack = true;
};

struct RealtimeOutcome {
  bool fifo = false;
  bool memory_locked = false;
  bool affinity = false;
  bool timer_slack = false;
  std::vector<std::string> warnings;  // one line per refused request, with the OS's reason
  bool all_requested_applied() const { return warnings.empty(); }
};

// Applies `config` to the calling thread (memory locking to the whole process). Never throws for
// refusals; logs each refusal once through spdlog at warning level.
RealtimeOutcome apply_realtime(const RealtimeConfig& config);

}  // namespace vitreo::runtime

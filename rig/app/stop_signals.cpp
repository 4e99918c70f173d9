#include "rig/app/stop_signals.hpp"

#include <signal.h>
#include <unistd.h>

#include <cstring>

namespace vitreo::app {

namespace {
std::atomic<int>* g_flag = nullptr;
static_assert(std::atomic<int>::is_always_lock_free, "the handler may only touch a lock-free atomic");

void write_all(const char* s) {  // async-signal-safe
  std::size_t n = std::strlen(s);
  while (n > 0) {
    const ssize_t w = ::write(STDERR_FILENO, s, n);
    if (w <= 0) return;
    s += w;
    n -= static_cast<std::size_t>(w);
  }
}

void on_stop(int sig) {
  int expected = 0;
  if (g_flag && g_flag->compare_exchange_strong(expected, sig)) {
    write_all(sig == SIGINT ? "\nvitreo: SIGINT — finishing the step, closing the recording (again to stop at once)\n"
                            : "\nvitreo: SIGTERM — finishing the step, closing the recording (again to stop at once)\n");
    return;
  }
  write_all("\nvitreo: second signal — stopping now\n");
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}
}  // namespace

void install_stop_signals(std::atomic<int>& flag) {
  g_flag = &flag;
  struct sigaction sa {};
  sa.sa_handler = on_stop;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  ::sigaction(SIGINT, &sa, nullptr);
  ::sigaction(SIGTERM, &sa, nullptr);
}

}  // namespace vitreo::app

#include "rig/runtime/thread_harness.hpp"

#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <stdexcept>
#include <utility>

#include <spdlog/spdlog.h>

namespace vitreo::runtime {

ThreadHarness::ThreadHarness(Clock& physics_clock, HarnessConfig config, FixedStepLoop::StepFn physics_step)
    : config_(config), loop_(physics_clock, config.loop, std::move(physics_step)) {}

ThreadHarness::~ThreadHarness() {
  try {
    stop();
  } catch (...) {
    spdlog::error("harness: physics error not collected before destruction");
  }
}

void ThreadHarness::add_service(std::string name, std::chrono::nanoseconds period, std::function<void()> fn) {
  if (started_) throw std::logic_error("ThreadHarness: add services before start()");
  auto s = std::make_unique<Service>();
  s->name = std::move(name);
  s->period = period;
  s->fn = std::move(fn);
  services_.push_back(std::move(s));
}

void ThreadHarness::start() {
  if (started_) throw std::logic_error("ThreadHarness: started twice");
  started_ = true;
  // spdlog's registry (the default logger) is a function-local static inside Debian's libspdlog,
  // which is not built for ThreadSanitizer: created by the first thread that logs, its use by the
  // next looks unordered to TSan (it cannot see the library's guard). It is no race — C++ makes the
  // static's initialisation thread-safe — but creating it here, before the harness's threads start,
  // gives it an order TSan sees (thread creation), as run_session does for the session's threads.
  (void)spdlog::default_logger_raw();
  physics_ = std::thread([this] {
    pthread_setname_np(pthread_self(), "vitreo-physics");
    if (config_.physics_realtime) rt_outcome_ = apply_realtime(config_.physics_rt);
    try {
      loop_.run(config_.max_steps);
    } catch (...) {
      // Not std::terminate: the caller decides (the rig logs, saves what it can, exits non-zero).
      physics_error_ = std::current_exception();
      spdlog::error("harness: the physics step threw; physics stopped at step {}", loop_.next_step_index());
    }
    physics_done_.store(true, std::memory_order_release);
  });
  for (auto& sp : services_) {
    Service* s = sp.get();
    s->thread = std::thread([this, s] {
      pthread_setname_np(pthread_self(), s->name.substr(0, 15).c_str());
      if (config_.service_nice != 0) {
        // Linux nice values are per thread (PRIO_PROCESS with a thread id).
        const auto tid = static_cast<id_t>(syscall(SYS_gettid));
        if (setpriority(PRIO_PROCESS, tid, config_.service_nice) != 0)
          spdlog::warn("harness: cannot set nice {} on service '{}'", config_.service_nice, s->name);
      }
      auto next = std::chrono::steady_clock::now();
      auto call = [this, s] {
        try {
          s->fn();
        } catch (const std::exception& e) {
          service_errors_.fetch_add(1, std::memory_order_relaxed);
          spdlog::error("harness: service '{}' threw: {}", s->name, e.what());
        } catch (...) {
          service_errors_.fetch_add(1, std::memory_order_relaxed);
          spdlog::error("harness: service '{}' threw a non-standard exception", s->name);
        }
        ++s->calls;
      };
      std::unique_lock lock(mu_);
      while (!services_stop_) {
        lock.unlock();
        call();
        lock.lock();
        next += s->period;
        cv_.wait_until(lock, next, [this] { return services_stop_; });
      }
      lock.unlock();
      call();  // final drain after physics has stopped
    });
  }
}

void ThreadHarness::join_physics() {
  if (physics_.joinable()) physics_.join();
}

void ThreadHarness::wait_physics() {
  join_physics();
  if (physics_error_) std::rethrow_exception(std::exchange(physics_error_, nullptr));
}

bool ThreadHarness::physics_done() const noexcept { return physics_done_.load(std::memory_order_acquire); }

void ThreadHarness::stop() {
  if (!started_ || stopped_) return;
  stopped_ = true;
  loop_.request_stop();
  join_physics();
  {
    std::lock_guard lock(mu_);
    services_stop_ = true;
  }
  cv_.notify_all();
  for (auto& s : services_) {
    if (s->thread.joinable()) s->thread.join();
  }
  if (physics_error_) std::rethrow_exception(std::exchange(physics_error_, nullptr));
}

}  // namespace vitreo::runtime

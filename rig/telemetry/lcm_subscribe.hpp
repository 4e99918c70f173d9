#pragma once
// Typed LCM subscription to any callable `void(const Msg&)`, through lcm::LCM::subscribeFunction.
// Why not LCM's member-function subscribe(): its callback does `(subs->handler->*method)(...)`, and
// GCC 12's UBSan reports that pointer-to-member call as "member access within null pointer" (a false
// positive that halts every asan test run). The plain function-pointer path is clean.
#include <string>

#include <lcm/lcm-cpp.hpp>

namespace vitreo::telemetry {

// `handler` must outlive the subscription.
template <class Msg, class Handler>
lcm::Subscription* subscribe_to(lcm::LCM& lc, const std::string& channel, Handler* handler) {
  void (*fn)(const lcm::ReceiveBuffer*, const std::string&, const Msg*, Handler*) =
      [](const lcm::ReceiveBuffer*, const std::string&, const Msg* m, Handler* h) { (*h)(*m); };
  return lc.subscribeFunction<Msg, Handler*>(channel, fn, handler);
}

}  // namespace vitreo::telemetry

#pragma once
// Device-to-host clock: offset, drift and latency from the protocol's TIME_SYNC exchanges
// (firmware-protocol/PROTOCOL.md §0x03). Each exchange gives the four NTP timestamps — host send t1,
// device receive t2, device send t3, host receive t4 — so the offset (device minus host) and the
// round-trip delay are θ = ((t2 - t1) + (t3 - t4)) / 2 and δ = (t4 - t1) - (t3 - t2) (D. Mills,
// RFC 5905 §8). Exchanges delayed by queueing are asymmetric and biased, so, as NTP's clock filter
// does, only the quicker half is kept; a line fitted through their offsets against host time gives
// the offset now and the drift.
#include <cstdint>
#include <string>
#include <vector>

namespace vitreo::rig::calibration {

struct TimeSyncExchange {
  std::uint64_t host_tx_us = 0, device_rx_us = 0, device_tx_us = 0, host_rx_us = 0;
};

struct ClockLimits {
  std::size_t min_exchanges = 8;
  double min_span_s = 1.0;  // drift needs the exchanges spread over time
};

struct ClockResult {
  bool ok = false;
  std::string error;
  double offset_ms = 0.0;        // device − host at reference_host_us
  double drift_ppm = 0.0;        // device clock runs fast by this much
  double latency_ms = 0.0;       // median one-way delay (half the round trip) of the kept exchanges
  double rms_ms = 0.0;           // residual of the kept offsets about the fitted line
  std::uint64_t reference_host_us = 0;
  std::size_t exchanges = 0, used = 0;
  // Device time → host time with the fitted line.
  double device_to_host_us(double device_us) const;
};

ClockResult estimate_clock(const std::vector<TimeSyncExchange>& exchanges, const ClockLimits& limits = {});

}  // namespace vitreo::rig::calibration

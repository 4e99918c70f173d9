// Pose-sample decoding throughput (bar: ≥ 1 M frames/s on one core). Each benchmark decodes a
// batch of distinct frames (size in the name) per iteration; items/s is frames/s.
#include <benchmark/benchmark.h>

#include <random>

#include "drivers/session.hpp"
#include "firmware-protocol/vp.hpp"

namespace {

using vitreo::proto::Bytes;

std::vector<vp_message> poses(std::size_t n) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-50, 50);
  std::vector<vp_message> v;
  for (std::size_t i = 0; i < n; ++i) {
    vp_message m = vitreo::proto::make(VP_MSG_POSE_SAMPLE, std::uint8_t(i));
    m.u.pose.timestamp_us = 1'000'000 + i * 1000;
    m.u.pose.tool_type = VP_TOOL_FORCEPS;
    for (float& x : m.u.pose.tip_mm) x = u(rng);
    m.u.pose.q_wxyz[0] = 0.5f, m.u.pose.q_wxyz[1] = -0.5f, m.u.pose.q_wxyz[2] = 0.5f, m.u.pose.q_wxyz[3] = 0.5f;
    m.u.pose.actuation = std::uint16_t(i * 7);
    m.u.pose.quality_pct = 90;
    v.push_back(m);
  }
  return v;
}

void BM_PosePacket(benchmark::State& state) {
  std::vector<Bytes> frames;
  for (auto& m : poses(std::size_t(state.range(0)))) frames.push_back(vitreo::proto::encode_packet(m));
  vp_message out;
  for (auto _ : state)
    for (auto& f : frames) {
      int st = vp_decode_packet(f.data(), f.size(), &out);
      benchmark::DoNotOptimize(st);
      benchmark::DoNotOptimize(out);
    }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

// Serial: one byte stream of COBS frames through the streaming decoder (COBS + CRC + decode +
// validation), as the driver does it.
void BM_PoseSerialStream(benchmark::State& state) {
  Bytes stream;
  for (auto& m : poses(std::size_t(state.range(0)))) {
    Bytes f = vitreo::proto::encode_serial(m);
    stream.insert(stream.end(), f.begin(), f.end());
  }
  vp_serial_rx rx;
  vp_serial_rx_init(&rx);
  vp_message out;
  std::int64_t ok = 0;
  for (auto _ : state) {
    const std::uint8_t* p = stream.data();
    std::size_t left = stream.size();
    while (left) {
      std::size_t used = 0;
      ok += vp_serial_rx_push(&rx, p, left, &used, &out) == VP_OK;
      p += used;
      left -= used;
    }
  }
  if (ok != state.iterations() * state.range(0)) state.SkipWithError("decode failed");
  state.SetItemsProcessed(state.iterations() * state.range(0));
  state.SetBytesProcessed(state.iterations() * std::int64_t(stream.size()));
}

void BM_PoseUsb(benchmark::State& state) {
  std::vector<Bytes> frames;
  for (auto& m : poses(std::size_t(state.range(0)))) frames.push_back(vitreo::proto::encode_usb(m));
  vp_message out;
  for (auto _ : state)
    for (auto& f : frames) benchmark::DoNotOptimize(vp_usb_decode(f.data(), f.size(), &out));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_PoseCanFd(benchmark::State& state) {
  std::vector<vitreo::proto::CanFrame> frames;
  for (auto& m : poses(std::size_t(state.range(0)))) frames.push_back(*vitreo::proto::encode_canfd(m, 3));
  vp_message out;
  std::uint8_t node;
  for (auto _ : state)
    for (auto& f : frames) benchmark::DoNotOptimize(vp_canfd_decode(f.id, f.data.data(), f.data.size(), &node, &out));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

// Classic CAN: 7 segments per pose sample, reassembled; items are pose samples, not CAN frames.
void BM_PoseCan8(benchmark::State& state) {
  std::vector<vitreo::proto::CanFrame> frames;
  std::uint8_t tid = 0;
  for (auto& m : poses(std::size_t(state.range(0))))
    for (auto& f : vitreo::proto::encode_can_classic(m, 3, tid++)) frames.push_back(f);
  vp_can_rx rx;
  vp_can_rx_init(&rx);
  vp_message out;
  std::uint8_t node;
  for (auto _ : state)
    for (auto& f : frames) benchmark::DoNotOptimize(vp_can_rx_push(&rx, f.id, f.data.data(), f.data.size(), &node, &out));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

// The host path after the transport: serial stream → session (sequence, clock mapping, typed
// sample, statistics, callback).
void BM_PoseSerialToTypedSample(benchmark::State& state) {
  Bytes stream;
  for (auto& m : poses(std::size_t(state.range(0)))) {
    Bytes f = vitreo::proto::encode_serial(m);
    stream.insert(stream.end(), f.begin(), f.end());
  }
  vitreo::drivers::DeviceSession session;
  std::uint64_t now = 1'000'000;
  session.transport_up(now);
  vp_message info = vitreo::proto::make(VP_MSG_DEVICE_INFO);
  info.u.device_info.device_type = VP_DEVICE_TRACKER;
  info.u.device_info.proto_major = 1;
  session.on_frame(VP_OK, info, now);
  vp_message ack = vitreo::proto::make(VP_MSG_CONFIG);
  ack.u.config = {VP_CFG_ACK, VP_CFG_KEY_STREAMING, 1};
  session.on_frame(VP_OK, ack, now);
  std::int64_t delivered = 0;
  session.set_on_sample([&](const vitreo::drivers::Sample&) { ++delivered; });
  vitreo::proto::SerialDecoder dec;
  for (auto _ : state) {
    now += 1000;
    dec.feed(stream, [&](int st, const vp_message& m) { session.on_frame(st, m, now); });
  }
  if (delivered == 0) state.SkipWithError("nothing delivered");
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

BENCHMARK(BM_PosePacket)->Arg(1024);
BENCHMARK(BM_PoseSerialStream)->Arg(1024);
BENCHMARK(BM_PoseUsb)->Arg(1024);
BENCHMARK(BM_PoseCanFd)->Arg(1024);
BENCHMARK(BM_PoseCan8)->Arg(1024);
BENCHMARK(BM_PoseSerialToTypedSample)->Arg(1024);

}  // namespace

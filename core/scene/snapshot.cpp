#include "core/scene/snapshot.hpp"

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>


namespace vitreo::core {

namespace {

constexpr char kMagic[8] = {'V', 'T', 'R', 'S', 'N', 'A', 'P', '\0'};
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 8 + 8;
constexpr std::uint64_t kMaxPayload = std::uint64_t{4} << 30;

std::uint64_t fnv1a(const std::uint8_t* p, std::size_t n) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 0x100000001b3ULL;
  }
  return h;
}

void put_bytes(std::vector<std::uint8_t>& out, const void* p, std::size_t n) {
  const std::size_t at = out.size();
  out.resize(at + n);
  if (n) std::memcpy(out.data() + at, p, n);
}

template <class T>
void put(std::vector<std::uint8_t>& out, const T& v) {
  put_bytes(out, &v, sizeof(T));
}

template <class T>
T get(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

}  // namespace

void encode_snapshot(const TissueWorld& world, const std::string& scene_name, std::vector<std::uint8_t>& out) {
  // Header first with size and checksum patched in afterwards, so the payload is written once,
  // straight into `out` (no allocation when its capacity suffices).
  out.clear();
  put_bytes(out, kMagic, sizeof kMagic);
  put(out, kSnapshotVersion);
  put(out, std::uint32_t{0});
  put(out, std::uint64_t{0});
  put(out, std::uint64_t{0});
  put(out, static_cast<std::uint64_t>(scene_name.size()));
  put_bytes(out, scene_name.data(), scene_name.size());
  put(out, world.state_hash());
  world.write_state(out);
  const std::uint64_t size = out.size() - kHeaderBytes;
  const std::uint64_t checksum = fnv1a(out.data() + kHeaderBytes, static_cast<std::size_t>(size));
  std::memcpy(out.data() + 16, &size, sizeof size);
  std::memcpy(out.data() + 24, &checksum, sizeof checksum);
}

std::vector<std::uint8_t> encode_snapshot(const TissueWorld& world, const std::string& scene_name) {
  std::vector<std::uint8_t> out;
  encode_snapshot(world, scene_name, out);
  return out;
}

Status decode_snapshot(TissueWorld& world, std::span<const std::uint8_t> bytes, SnapshotInfo* info) {
  if (bytes.size() < kHeaderBytes) return Status::error("snapshot: file too short");
  if (std::memcmp(bytes.data(), kMagic, 8) != 0) return Status::error("snapshot: not a vitreo snapshot (bad magic)");
  const auto version = get<std::uint32_t>(bytes.data() + 8);
  if (version != kSnapshotVersion) {
    return Status::error("snapshot: version " + std::to_string(version) + " not supported (expected " +
                         std::to_string(kSnapshotVersion) + ")");
  }
  const auto size = get<std::uint64_t>(bytes.data() + 16);
  const auto checksum = get<std::uint64_t>(bytes.data() + 24);
  if (size > kMaxPayload || size != bytes.size() - kHeaderBytes) return Status::error("snapshot: payload size mismatch (truncated?)");
  const std::uint8_t* p = bytes.data() + kHeaderBytes;
  if (fnv1a(p, size) != checksum) return Status::error("snapshot: checksum mismatch (corrupted)");
  if (size < 16) return Status::error("snapshot: payload too short");
  const auto name_len = get<std::uint64_t>(p);
  if (name_len > 4096 || name_len + 16 > size) return Status::error("snapshot: bad scene name");
  SnapshotInfo si;
  si.version = version;
  si.scene_name.assign(reinterpret_cast<const char*>(p + 8), static_cast<std::size_t>(name_len));
  si.state_hash = get<std::uint64_t>(p + 8 + name_len);
  const std::size_t offset = 16 + static_cast<std::size_t>(name_len);
  const Status st = world.read_state(p + offset, static_cast<std::size_t>(size) - offset);
  if (!st) return st;
  if (world.state_hash() != si.state_hash) return Status::error("snapshot: state hash differs after loading");
  if (info) *info = si;
  return Status::ok();
}

Status save_snapshot(const TissueWorld& world, const std::string& scene_name, const std::string& path) {
  return write_snapshot_file(encode_snapshot(world, scene_name), path);
}

Status write_snapshot_file(std::span<const std::uint8_t> bytes, const std::string& path) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) return Status::error("snapshot: cannot write " + tmp);
    f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    f.flush();
    if (!f) {
      std::remove(tmp.c_str());
      return Status::error("snapshot: write failed for " + tmp);
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return Status::error("snapshot: cannot rename " + tmp + " to " + path);
  }
  return Status::ok();
}

Status load_snapshot(TissueWorld& world, const std::string& path, SnapshotInfo* info) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return Status::error("snapshot: cannot open " + path);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const Status st = decode_snapshot(world, bytes, info);
  if (!st) return Status::error(path + ": " + st.message());
  return Status::ok();
}

}  // namespace vitreo::core

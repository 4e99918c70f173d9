#pragma once
// Binary state I/O in both directions through one field list. A class lists its mutable state once,
// in a member template `template <class IO> void state_io(IO& io)`, calling io.pod(field),
// io.vec(pool), io.flag(bit)... on each field in order: with a StateWriter that appends the fields
// to a byte vector, with a StateReader that reads them back. Adding a field is one line, and the
// reading and writing cannot drift apart. (The idea is MuJoCo's mj_getState/mj_setState, which loop
// over one table of state elements; here the table is the function.)
//
// Reading runs twice over the bytes: a check pass (applying() false) that validates everything and
// changes nothing, then an apply pass. So a snapshot that does not fit leaves the object unchanged.
// Values that must be validated as a whole (a material, the solver settings) are records: read into
// a copy, checked, and assigned only on the apply pass (record()).
//
// Layout: little-endian host order, PODs as their bytes, Vec3 as three doubles, vectors and strings
// as a u64 count and their items, bools as one byte.
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "core/common/status.hpp"
#include "core/common/types.hpp"

namespace vitreo::core {

class StateWriter {
 public:
  static constexpr bool kReading = false;
  explicit StateWriter(std::vector<std::uint8_t>& out) : out_(out) {}
  bool applying() const { return false; }

  template <class T>
  void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t at = out_.size();
    out_.resize(at + sizeof(T));
    std::memcpy(out_.data() + at, &v, sizeof(T));
  }
  void vec3(const Vec3& v) {
    pod(v.x());
    pod(v.y());
    pod(v.z());
  }
  void flag(const bool& b) { pod(static_cast<std::uint8_t>(b)); }
  void str(const std::string& s) {
    pod(static_cast<std::uint64_t>(s.size()));
    const std::size_t at = out_.size();
    out_.resize(at + s.size());
    if (!s.empty()) std::memcpy(out_.data() + at, s.data(), s.size());
  }
  // A pool (its size up to the capacity reserved at construction) or, with growable, any size.
  template <class T>
  void vec(const std::vector<T>& v, bool /*growable*/ = false) {
    pod(static_cast<std::uint64_t>(v.size()));
    for (const auto& x : v) item(x);
  }
  // A vector whose size the object's construction fixed (scratch arrays).
  template <class T>
  void fixed_vec(const std::vector<T>& v) {
    vec(v);
  }
  // A marker that starts a section (the reader refuses bytes without it).
  void section(std::uint32_t tag, const char* /*what*/) { pod(tag); }
  // The number of items of a list the reader's object already has (attachments, forces): written.
  void count(std::uint64_t n, const char* /*what*/) { pod(n); }
  // A record validated as a whole: fields(item) lists its fields, check(item) may throw
  // InvalidArgument (used by the reader only).
  template <class T, class Fields, class Check>
  void record(T& item, Fields&& fields, Check&&) {
    fields(item);
  }
  // A list whose length the bytes decide (up to limit items): fields(x) lists an item's fields.
  template <class T, class Fields>
  void list(std::vector<T>& items, std::uint64_t /*limit*/, const char* /*what*/, Fields&& fields) {
    pod(static_cast<std::uint64_t>(items.size()));
    for (T& x : items) fields(x);
  }

 private:
  template <class T>
  void item(const T& x) {
    if constexpr (std::is_same_v<T, Vec3>) {
      vec3(x);
    } else {
      pod(x);
    }
  }
  std::vector<std::uint8_t>& out_;
};

class StateReader {
 public:
  static constexpr bool kReading = true;
  StateReader(const std::uint8_t* data, std::size_t size, bool apply) : p_(data), end_(data + size), apply_(apply) {}
  bool applying() const { return apply_; }
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  bool at_end() const { return p_ == end_; }
  void fail(const std::string& e) {
    if (error_.empty()) error_ = e;
  }

  template <class T>
  T pod_value() {
    static_assert(std::is_trivially_copyable_v<T>);
    T v{};
    if (!ok()) return v;
    if (static_cast<std::size_t>(end_ - p_) < sizeof(T)) {
      fail("snapshot truncated");
      return v;
    }
    std::memcpy(&v, p_, sizeof(T));
    p_ += sizeof(T);
    return v;
  }
  template <class T>
  void pod(T& target) {
    const T v = pod_value<T>();
    if (writes() && ok()) target = v;
  }
  void vec3(Vec3& target) {
    Vec3 v;
    v.x() = pod_value<double>();
    v.y() = pod_value<double>();
    v.z() = pod_value<double>();
    if (writes() && ok()) target = v;
  }
  void flag(bool& target) {
    const bool v = pod_value<std::uint8_t>() != 0;
    if (writes() && ok()) target = v;
  }
  void str(std::string& target) {
    const auto n = pod_value<std::uint64_t>();
    if (!ok()) return;
    if (n > static_cast<std::uint64_t>(end_ - p_) || n > 4096) {
      fail("snapshot: bad string length");
      return;
    }
    if (writes()) target.assign(reinterpret_cast<const char*>(p_), static_cast<std::size_t>(n));
    p_ += n;
  }
  // A pool vector: must fit in the capacity reserved when the object was built (no reallocation),
  // or, with `growable`, any size that fits the bytes.
  template <class T>
  void vec(std::vector<T>& target, bool growable = false) {
    const auto n = pod_value<std::uint64_t>();
    if (!ok()) return;
    const std::size_t item = std::is_same_v<T, Vec3> ? 24 : sizeof(T);
    if (n > static_cast<std::uint64_t>(end_ - p_) / item) {
      fail("snapshot truncated (vector)");
      return;
    }
    if (!growable && n > target.capacity()) {
      fail("snapshot does not fit this scene (pool larger than its capacity)");
      return;
    }
    if (writes()) target.resize(static_cast<std::size_t>(n));
    for (std::size_t i = 0; i < n; ++i) {
      if constexpr (std::is_same_v<T, Vec3>) {
        Vec3 dummy;
        vec3(writes() ? target[i] : dummy);
      } else {
        T dummy{};
        pod(writes() ? target[i] : dummy);
      }
    }
  }
  // A vector whose size the object's construction fixed (scratch arrays): must match exactly.
  template <class T>
  void fixed_vec(std::vector<T>& target) {
    const auto before = p_;
    const auto n = pod_value<std::uint64_t>();
    if (ok() && n != target.size()) {
      fail("snapshot does not fit this scene (array size)");
      return;
    }
    p_ = before;
    vec(target, true);
  }
  void section(std::uint32_t tag, const char* what) {
    if (pod_value<std::uint32_t>() != tag && ok()) fail(std::string("snapshot: ") + what + " section missing");
  }
  // The list has n items in the object (built from the same scene): the bytes must say n too.
  void count(std::uint64_t n, const char* what) {
    if (pod_value<std::uint64_t>() != n && ok()) fail(std::string("snapshot: ") + what + " count differs from the scene");
  }
  // A record validated as a whole: read into a copy even on the check pass, checked there
  // (check(copy) may throw InvalidArgument: the snapshot is refused with its message), assigned on
  // the apply pass.
  template <class T, class Fields, class Check>
  void record(T& item, Fields&& fields, Check&& check) {
    T copy = item;
    staged([&] { fields(copy); });
    if (!apply_ && ok()) {
      try {
        check(static_cast<const T&>(copy));
      } catch (const InvalidArgument& e) {
        fail(std::string("snapshot: ") + e.what());
      }
    }
    if (apply_ && ok()) item = std::move(copy);
  }
  // A list whose length the bytes decide (up to limit items): replaced on the apply pass.
  template <class T, class Fields>
  void list(std::vector<T>& items, std::uint64_t limit, const char* what, Fields&& fields) {
    const auto n = pod_value<std::uint64_t>();
    if (ok() && n > limit) fail(std::string("snapshot: too many ") + what);
    if (apply_ && ok()) items.clear();
    for (std::uint64_t k = 0; k < n && ok(); ++k) {
      T x{};
      staged([&] { fields(x); });
      if (apply_ && ok()) items.push_back(x);
    }
  }

 private:
  template <class F>
  void staged(F&& f) {
    const bool was = staging_;
    staging_ = true;
    f();
    staging_ = was;
  }
  bool writes() const { return apply_ || staging_; }
  const std::uint8_t* p_;
  const std::uint8_t* end_;
  bool apply_;
  bool staging_ = false;
  std::string error_;
};

// Reads state written by write(io) back: the check pass, then, when it passed, the apply pass; the
// whole input must be used. read(io) is the same field list the writer used.
template <class F>
Status read_state_twice(const std::uint8_t* data, std::size_t size, F&& read) {
  for (const bool apply : {false, true}) {
    StateReader in(data, size, apply);
    read(in);
    if (!in.ok()) return Status::error(in.error());
    if (!in.at_end()) return Status::error("snapshot: trailing bytes");
  }
  return Status::ok();
}

}  // namespace vitreo::core

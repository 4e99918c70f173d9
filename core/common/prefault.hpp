#pragma once
// Reserving a vector's capacity does not give it memory yet: the operating system maps each page
// on its first write, about 10 µs apiece here. A pool or scratch buffer that fills up during the
// simulation would pay that inside a step (a blade stroke taking new slots touched several fresh
// pages per stroke). Writing every reserved slot once, at construction, moves that cost to scene
// load. (mlockall in the rig process does the same for the whole process where it is permitted;
// this does not depend on it.)
#include <cstddef>
#include <type_traits>
#include <vector>

namespace vitreo::core {

// Reserves n slots (at least) and writes each once, leaving v empty. Eigen vectors get an explicit
// zero: their default constructor leaves the memory unwritten, so resize() alone would not touch it.
template <class T, class A>
void reserve_touched(std::vector<T, A>& v, std::size_t n) {
  v.clear();
  v.reserve(n);
  if constexpr (requires { T::Zero(); }) {
    v.assign(v.capacity(), T(T::Zero()));
  } else {
    v.assign(v.capacity(), T{});
  }
  v.clear();
}

// The same for vectors already reserved.
template <class... V>
void touch_reserved(V&... vecs) {
  (reserve_touched(vecs, vecs.capacity()), ...);
}

}  // namespace vitreo::core

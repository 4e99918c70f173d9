#pragma once
// Counts global operator new calls while `counting` is set (the replacement lives in
// alloc_counter.cpp, its own translation unit, so the compiler never sees new and delete inlined
// together).
namespace vitreo::core::test {
struct AllocationCounter {
  static inline bool counting = false;
  static inline long allocations = 0;
};
}  // namespace vitreo::core::test

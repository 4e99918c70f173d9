#pragma once
// Minimal checks for the plain-main programs that run inside the test VM (static binaries, one boot
// for all their checks: no GoogleTest) and their host-side checkers.
#include <cstdio>
#include <string>

inline int g_fail = 0, g_checks = 0;
#define CHECK(c, ...)                                          \
  do {                                                         \
    ++g_checks;                                                \
    if (!(c)) {                                                \
      std::printf("FAIL %s:%d: %s: ", __FILE__, __LINE__, #c); \
      std::printf(__VA_ARGS__);                                \
      std::printf("\n");                                       \
      ++g_fail;                                                \
    }                                                          \
  } while (0)
#define EXPECT_THROW_CONTAINS(expr, text)                                                          \
  do {                                                                                             \
    std::string what_;                                                                             \
    try {                                                                                          \
      (void)(expr);                                                                                \
    } catch (const std::exception& e_) {                                                          \
      what_ = e_.what();                                                                           \
    }                                                                                              \
    CHECK(what_.find(text) != std::string::npos, "expected an error containing \"%s\", got \"%s\"", \
          text, what_.c_str());                                                                    \
    if (!what_.empty()) std::printf("error message: %s\n", what_.c_str());                          \
  } while (0)

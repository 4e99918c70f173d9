#pragma once
// Checks used at the core's API boundary. Each throws InvalidArgument naming the offending value,
// so a malformed scene or a bad device value is reported where it enters, not where it explodes.
#include <cmath>
#include <string>
#include <string_view>

#include "core/common/status.hpp"
#include "core/common/types.hpp"

namespace vitreo::core {

inline bool is_finite(const Vec3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

inline void require_finite(double value, std::string_view what) {
  if (!std::isfinite(value)) throw InvalidArgument(std::string(what) + " must be finite, got " + std::to_string(value));
}

inline void require_finite(const Vec3& v, std::string_view what) {
  if (!is_finite(v)) throw InvalidArgument(std::string(what) + " must be finite");
}

inline void require_range(double value, double lo, double hi, std::string_view what) {
  require_finite(value, what);
  if (value < lo || value > hi) {
    throw InvalidArgument(std::string(what) + " = " + std::to_string(value) + " is outside [" + std::to_string(lo) +
                          ", " + std::to_string(hi) + "]");
  }
}

inline void require_positive(double value, std::string_view what) {
  require_finite(value, what);
  if (!(value > 0.0)) throw InvalidArgument(std::string(what) + " must be > 0, got " + std::to_string(value));
}

inline void require_non_negative(double value, std::string_view what) {
  require_finite(value, what);
  if (value < 0.0) throw InvalidArgument(std::string(what) + " must be >= 0, got " + std::to_string(value));
}

}  // namespace vitreo::core

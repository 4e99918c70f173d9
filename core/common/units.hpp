#pragma once
// Units of the core, chosen once and used everywhere (see README "Units").
//
//   length   millimetre (mm)      — an eye is ~24 mm, the retina 0.25 mm thick
//   mass     gram (g)
//   time     second (s)
//   force    g·mm/s² = 1 µN       — so stiffness is µN/mm
//   pressure µN/mm² = 1 Pa        — so 15 mmHg ≈ 2000 Pa needs no conversion factor in the solver
//   density  g/mm³ (1 g/ml = 1e-3 g/mm³)
//
// Names carry their unit as a suffix (`radius_mm`, `pressure_pa`, `dt_s`) wherever a value crosses
// an API; inside tight loops the unit is implied by these rules.

#include <numbers>

namespace vitreo::core::units {

// Angles: radians inside the core; files a person writes give degrees (`angle_deg * kDeg`).
inline constexpr double kPi = std::numbers::pi;
inline constexpr double kDeg = kPi / 180.0;  // one degree in radians

inline constexpr double kPascalPerMmHg = 133.322387415;
inline constexpr double kGramPerMm3PerGramPerMl = 1e-3;
inline constexpr double kStandardGravity_mm_s2 = 9806.65;

constexpr double mmhg_to_pa(double mmhg) { return mmhg * kPascalPerMmHg; }
constexpr double g_per_ml_to_g_per_mm3(double g_per_ml) { return g_per_ml * kGramPerMm3PerGramPerMl; }

}  // namespace vitreo::core::units

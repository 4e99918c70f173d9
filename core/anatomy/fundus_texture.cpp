#include "core/anatomy/fundus_texture.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "core/common/status.hpp"
#include "core/common/units.hpp"

namespace vitreo::core {

namespace {

using units::kPi;
// Vessel colours (linear 0..1): oxygenated arterial blood is a brighter red, venous blood darker
// and bluer.
constexpr double kArtery[3] = {0.74, 0.14, 0.10};
constexpr double kVein[3] = {0.42, 0.05, 0.09};

// splitmix64: tiny, portable, and the same bits everywhere (std distributions are not).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : s_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (s_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

 private:
  std::uint64_t s_;
};

std::uint64_t hash2(std::int64_t x, std::int64_t y, std::uint64_t seed) {
  std::uint64_t h = seed ^ (static_cast<std::uint64_t>(x) * 0x9e3779b97f4a7c15ULL) ^
                    (static_cast<std::uint64_t>(y) * 0xc2b2ae3d27d4eb4fULL);
  h ^= h >> 33;
  h *= 0xff51afd7ed558ccdULL;
  h ^= h >> 33;
  return h;
}

// Value noise in [0, 1] on a lattice of unit spacing, smoothly interpolated.
double value_noise(double x, double y, std::uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const double tx = x - fx, ty = y - fy;
  const double sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  const auto v = [&](std::int64_t a, std::int64_t b) { return static_cast<double>(hash2(a, b, seed) >> 11) * 0x1.0p-53; };
  const double a = v(ix, iy) + sx * (v(ix + 1, iy) - v(ix, iy));
  const double b = v(ix, iy + 1) + sx * (v(ix + 1, iy + 1) - v(ix, iy + 1));
  return a + sy * (b - a);
}

double fractal(double x, double y, std::uint64_t seed) {
  double sum = 0.0, amp = 0.5, f = 1.0;
  for (int o = 0; o < 4; ++o) {
    sum += amp * value_noise(x * f, y * f, seed + static_cast<std::uint64_t>(o) * 7919);
    amp *= 0.5;
    f *= 2.0;
  }
  return sum / 0.9375;
}

// The retinal vessel tree, grown as walks whose heading is steered toward a wanted direction plus
// seeded wander. The layout follows fundus anatomy (e.g. Hogan & Feeney 1963; any atlas of the
// fundus): four artery–vein pairs leave the optic disc; the superior and inferior temporal
// arcades arch around the macula (passing ~4–6 mm above and below the fovea) and run on to the
// temporal periphery, the nasal vessels fan out toward the nasal periphery; branches leave every
// few millimetres, narrower than their parent, heading away from the disc; small macular branches
// reach toward the fovea and stop at its avascular zone. Arteries are narrower than veins (about
// 2:3) and drawn brighter red with a central light reflex; veins darker and wider.
struct TreeBuilder {
  Rng& rng;
  double exclusion_mm;   // no vessel point comes closer to the fovea than this
  double extent_mm;      // fundus radius
  Vec2 disc;
  std::vector<VesselSegment>& out;
  static constexpr double kStep = 0.15;
  static constexpr std::size_t kMaxSegments = 80000;

  // Where a vessel wants to go from p: a main trunk follows its waypoints (an arcade: up out of
  // the disc, over the macula, on to the temporal periphery), heading for each in turn; other
  // vessels head away from the disc.
  struct Steer {
    std::array<Vec2, 6> waypoints{};
    int count = 0;
    int next = 0;
  };

  Vec2 wanted(const Vec2& p, const Vec2& dir, Steer& st) const {
    while (st.next < st.count) {
      const Vec2 to = st.waypoints[static_cast<std::size_t>(st.next)] - p;
      const bool reached = to.norm() < 0.8 ||
                           (st.next + 1 < st.count && (st.waypoints[static_cast<std::size_t>(st.next + 1)] - p).norm() < to.norm());
      if (!reached) return to.normalized();
      ++st.next;
    }
    if (st.count > 0) return dir;  // past the last waypoint: on as it goes
    const Vec2 away = p - disc;
    return away.norm() > 1e-9 ? Vec2((0.3 * away.normalized() + 0.7 * dir).normalized()) : dir;
  }

  void grow(Vec2 p, double heading, double width, bool artery, int depth, Steer st, double length_mm,
            double wander = 0.10) {
    double travelled = 0.0;
    double next_branch = rng.uniform(1.2, 2.8);
    while (travelled < length_mm && out.size() < kMaxSegments) {
      const Vec2 dir(std::cos(heading), std::sin(heading));
      const Vec2 w = wanted(p, dir, st);
      heading += 0.22 * std::remainder(std::atan2(w.y(), w.x()) - heading, 2.0 * kPi);
      heading += rng.uniform(-wander, wander);
      const Vec2 q = p + kStep * Vec2(std::cos(heading), std::sin(heading));
      // Never into the foveal avascular zone; never past the ora.
      if (q.norm() < exclusion_mm + 0.5 * width || q.norm() > extent_mm * 0.98) return;
      out.push_back({p, q, width, artery, depth});
      p = q;
      travelled += kStep;
      width = std::max(0.015, width * (1.0 - 0.0015));
      if (travelled >= next_branch && depth < 5 && width > 0.025) {
        next_branch = travelled + rng.uniform(1.2, 2.8) * (1.0 + 0.3 * depth);
        // Branch to the side away from the fovea mostly; toward it (macular branches) sometimes.
        const Vec2 to_fovea = -p;
        const double cross_z = std::cos(heading) * to_fovea.y() - std::sin(heading) * to_fovea.x();
        const double toward = cross_z > 0.0 ? 1.0 : -1.0;
        const bool macular = p.norm() < 7.0 && rng.uniform() < 0.45;
        const double side = macular ? toward : (rng.uniform() < 0.7 ? -toward : toward);
        const double child_heading = heading + side * rng.uniform(0.5, 1.0);
        const double child_width = width * rng.uniform(0.55, 0.75);
        width *= 0.93;
        const double reach = macular ? rng.uniform(1.0, 3.0) : rng.uniform(4.0, 11.0) * (6 - depth) / 6.0 + 1.0;
        grow(p, child_heading, child_width, artery, depth + 1, Steer{}, reach, 0.16);
      }
    }
  }
};

void blend(std::uint8_t* px, double r, double g, double b, double a) {
  // "Over" compositing with straight alpha.
  const double da = px[3] / 255.0;
  const double oa = a + da * (1.0 - a);
  if (oa <= 0.0) return;
  const double c[3] = {r, g, b};
  for (int k = 0; k < 3; ++k) {
    const double dc = px[k] / 255.0;
    px[k] = static_cast<std::uint8_t>(std::lround(std::clamp((c[k] * a + dc * da * (1.0 - a)) / oa, 0.0, 1.0) * 255.0));
  }
  px[3] = static_cast<std::uint8_t>(std::lround(std::clamp(oa, 0.0, 1.0) * 255.0));
}

}  // namespace

double distance_to_segment(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

FundusTextures generate_fundus(const EyeModel& eye, const FundusOptions& o) {
  if (o.size_px < 64 || o.size_px > 8192) throw InvalidArgument("fundus: size_px must be in [64, 8192]");
  const EyeParameters& ep = eye.parameters;
  const double extent = eye.fundus_extent_mm;
  const int n = o.size_px;
  const double mm_per_px = 2.0 * extent / n;
  const auto to_mm = [&](int x, int y) {
    return Vec2((x + 0.5) * mm_per_px - extent, (y + 0.5) * mm_per_px - extent);
  };

  FundusTextures t;
  t.vessel_free_radius_mm = ep.fovea_radius_mm;
  Rng rng(o.seed);
  const std::uint64_t noise_seed = rng.next();

  // ---- Choroid -------------------------------------------------------------------------------
  t.choroid.width = t.choroid.height = n;
  t.choroid.rgba.assign(static_cast<std::size_t>(n) * n * 4, 255);
  const Vec2 disc = eye.optic_disc_fundus_mm;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const Vec2 p = to_mm(x, y);
      // Pigment mottling plus the choroidal vessel pattern ("tigroid" stripes) beneath.
      const double mottle = fractal(p.x() * 1.5, p.y() * 1.5, noise_seed);
      const double stripes = 0.5 + 0.5 * std::sin(3.0 * fractal(p.x() * 0.35, p.y() * 0.35, noise_seed + 1) * 2.0 * kPi);
      const double macular = std::exp(-p.squaredNorm() / (2.0 * ep.macula_radius_mm * ep.macula_radius_mm));
      const double shade = 0.75 + 0.2 * mottle + 0.1 * stripes - 0.25 * macular;
      std::uint8_t* px = t.choroid.pixel(x, y);
      px[0] = static_cast<std::uint8_t>(std::clamp(200.0 * shade, 0.0, 255.0));
      px[1] = static_cast<std::uint8_t>(std::clamp(75.0 * shade * (0.9 + 0.2 * stripes), 0.0, 255.0));
      px[2] = static_cast<std::uint8_t>(std::clamp(35.0 * shade, 0.0, 255.0));
      // The disc has no choroid behind it: pale scleral rim.
      if ((p - disc).norm() < ep.optic_disc_radius_mm * 1.08) {
        px[0] = 235;
        px[1] = 200;
        px[2] = 160;
      }
    }
  }

  // ---- Vessel tree ---------------------------------------------------------------------------
  const double exclusion = ep.fovea_radius_mm + 0.1;
  TreeBuilder tree{rng, exclusion, extent, disc, t.vessels};
  // The arcades pass above and below the fovea outside the macula, at a height that varies from
  // eye to eye, and run on to the temporal periphery slowly diverging from the horizontal raphe.
  const double height = std::max(ep.macula_radius_mm + 1.2, rng.uniform(4.3, 5.6));
  const double reach = extent * 1.8;  // long enough to run to the ora
  for (const bool artery : {false, true}) {  // veins first: arteries are drawn over them where they cross
    const double w = artery ? 0.11 : 0.155;
    for (double sign : {1.0, -1.0}) {
      // Temporal arcade: up (down) out of the disc, over the macula, on to the temporal periphery.
      const double offset = artery ? 0.18 : 0.42;  // the pair leaves the disc side by side
      const double h = height + (artery ? 0.0 : 0.4) + rng.uniform(-0.25, 0.25);
      const double spread = rng.uniform(1.0, 2.5);
      TreeBuilder::Steer arcade;
      arcade.waypoints = {Vec2(disc.x() - 0.4, sign * 0.45 * h), Vec2(0.5 * disc.x(), sign * 0.93 * h), Vec2(-2.0, sign * h),
                          Vec2(-7.0, sign * (h + 0.4 * spread)), Vec2(-13.0, sign * (h + spread)),
                          Vec2(-extent, sign * (h + 2.0 * spread))};
      arcade.count = 6;
      tree.grow(disc + Vec2(-0.1, sign * offset), sign * (kPi / 2 + rng.uniform(0.1, 0.4)), w, artery, 0, arcade, reach, 0.05);
      // Nasal vessel: out toward the nasal periphery, up (down).
      tree.grow(disc + Vec2(0.25, sign * offset), sign * rng.uniform(0.55, 0.95), 0.85 * w, artery, 0, TreeBuilder::Steer{},
                extent - disc.x(), 0.07);
    }
  }

  // ---- Retina map ----------------------------------------------------------------------------
  t.retina.width = t.retina.height = n;
  t.retina.rgba.assign(static_cast<std::size_t>(n) * n * 4, 0);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const Vec2 p = to_mm(x, y);
      std::uint8_t* px = t.retina.pixel(x, y);
      if (p.norm() > extent) continue;
      // Translucent neural retina: a faint grey-pink sheen with the nerve-fibre striation.
      const double sheen = 0.12 + 0.05 * fractal(p.x() * 4.0, p.y() * 4.0, noise_seed + 2);
      px[0] = 210;
      px[1] = 170;
      px[2] = 160;
      px[3] = static_cast<std::uint8_t>(std::lround(255.0 * sheen));
      // Macular pigment, darker toward the fovea, and the foveal reflex.
      const double r = p.norm();
      if (r < ep.macula_radius_mm) {
        const double m = 1.0 - r / ep.macula_radius_mm;
        blend(px, 0.45, 0.3, 0.12, 0.45 * m * m);
      }
      if (r < 0.12) blend(px, 1.0, 1.0, 0.9, 0.7);
      // Optic disc: pale pink-yellow rim with a whiter cup.
      const double dd = (p - disc).norm();
      if (dd < ep.optic_disc_radius_mm) {
        blend(px, 0.96, 0.78, 0.62, 1.0);
        if (dd < 0.4 * ep.optic_disc_radius_mm) blend(px, 1.0, 0.95, 0.85, 0.8);
      }
    }
  }
  // Veins (dark, wide) first, then arteries (bright red, narrower, with the light reflex along their
  // centre that tells an artery at a glance).
  for (const bool arteries : {false, true}) {
    for (const auto& s : t.vessels) {
      if (s.artery != arteries) continue;
      const double half = 0.5 * s.width_mm;
      const double lo_x = std::min(s.a_mm.x(), s.b_mm.x()) - half - mm_per_px, hi_x = std::max(s.a_mm.x(), s.b_mm.x()) + half + mm_per_px;
      const double lo_y = std::min(s.a_mm.y(), s.b_mm.y()) - half - mm_per_px, hi_y = std::max(s.a_mm.y(), s.b_mm.y()) + half + mm_per_px;
      const int x0 = std::max(0, static_cast<int>((lo_x + extent) / mm_per_px));
      const int x1 = std::min(n - 1, static_cast<int>((hi_x + extent) / mm_per_px));
      const int y0 = std::max(0, static_cast<int>((lo_y + extent) / mm_per_px));
      const int y1 = std::min(n - 1, static_cast<int>((hi_y + extent) / mm_per_px));
      const double rr = s.artery ? kArtery[0] : kVein[0], gg = s.artery ? kArtery[1] : kVein[1], bb = s.artery ? kArtery[2] : kVein[2];
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
          const double d = distance_to_segment(to_mm(x, y), s.a_mm, s.b_mm);
          // Coverage of a pixel by the vessel: 1 inside, fading over one pixel; thin vessels fade.
          const double cover = std::clamp((half + 0.5 * mm_per_px - d) / mm_per_px, 0.0, 1.0) *
                               std::min(1.0, s.width_mm / mm_per_px);
          if (cover <= 0.0) continue;
          std::uint8_t* px = t.retina.pixel(x, y);
          blend(px, rr, gg, bb, 0.95 * cover);
          // The arterial reflex: a lighter stripe a third of the vessel wide along its centre (only
          // where the vessel spans enough texels to carry it without aliasing into dots).
          if (s.artery && s.width_mm > 3.0 * mm_per_px) {
            const double reflex = std::clamp((0.17 * s.width_mm + 0.5 * mm_per_px - d) / mm_per_px, 0.0, 1.0);
            if (reflex > 0.0) blend(px, 0.92, 0.50, 0.40, 0.45 * reflex);
          }
        }
      }
    }
  }
  return t;
}

}  // namespace vitreo::core

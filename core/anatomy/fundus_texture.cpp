#include "core/anatomy/fundus_texture.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/common/status.hpp"

namespace vitreo::core {

namespace {

constexpr double kPi = std::numbers::pi;

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

struct TreeBuilder {
  Rng& rng;
  double exclusion_mm;   // no vessel point comes closer to the fovea than this
  double extent_mm;      // fundus radius
  Vec2 disc;
  std::vector<VesselSegment>& out;
  static constexpr double kStep = 0.15;
  static constexpr std::size_t kMaxSegments = 60000;

  // Grows one vessel from p with heading `heading` (rad). `arc_sign` != 0 makes it arch around the
  // fovea at `arc_radius` (+1 counter-clockwise), as the temporal arcades do.
  void grow(Vec2 p, double heading, double width, bool artery, int depth, double arc_sign, double arc_radius,
            double length_mm) {
    double travelled = 0.0;
    double next_branch = rng.uniform(1.2, 2.5);
    while (travelled < length_mm && out.size() < kMaxSegments) {
      Vec2 dir(std::cos(heading), std::sin(heading));
      const double r = p.norm();
      if (arc_sign != 0.0 && r > 1e-6) {
        const Vec2 radial = p / r;
        const Vec2 tangent = arc_sign * Vec2(-radial.y(), radial.x());
        const double ang = std::atan2(p.y(), p.x());
        // Past the temporal raphe (the far side from the disc) the arcade runs out to the periphery.
        const bool beyond = std::abs(ang) > 0.8 * kPi;
        Vec2 want = beyond ? Vec2(-1.0, 0.6 * radial.y()).normalized()
                           : (tangent + 0.8 * (arc_radius - r) / arc_radius * radial).normalized();
        if (!want.allFinite()) want = dir;
        const double target = std::atan2(want.y(), want.x());
        double d = std::remainder(target - heading, 2.0 * kPi);
        heading += 0.25 * d;
      }
      heading += rng.uniform(-0.12, 0.12);
      dir = Vec2(std::cos(heading), std::sin(heading));
      const Vec2 q = p + kStep * dir;
      // Never into the foveal avascular zone; never past the ora.
      if (q.norm() < exclusion_mm + 0.5 * width || q.norm() > extent_mm * 0.97) return;
      out.push_back({p, q, width, artery, depth});
      p = q;
      travelled += kStep;
      width = std::max(0.02, width * (1.0 - 0.003));
      if (travelled >= next_branch && depth < 5 && width > 0.03) {
        next_branch = travelled + rng.uniform(1.0, 2.5);
        const double side = rng.uniform() < 0.5 ? -1.0 : 1.0;
        const double child_heading = heading + side * rng.uniform(0.45, 1.0);
        const double child_width = width * rng.uniform(0.55, 0.75);
        width *= 0.92;
        grow(p, child_heading, child_width, artery, depth + 1, 0.0, 0.0, rng.uniform(2.0, 6.0) * (5 - depth) / 5.0 + 1.0);
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
  const double arc_r = std::max(ep.macula_radius_mm + 0.8, 0.9 * disc.x());
  // Temporal arcades (arching around the macula) and nasal branches, artery + vein each.
  for (int pair = 0; pair < 2; ++pair) {
    const bool artery = pair == 0;
    const double w = artery ? 0.10 : 0.13;
    const double jitter = artery ? 0.0 : 0.12;
    for (double sign : {1.0, -1.0}) {
      const Vec2 start = disc + Vec2(0.0, sign * (0.2 + jitter));
      tree.grow(start, sign * (kPi / 2 + 0.35 + jitter), w, artery, 0, sign, arc_r, extent * 1.6);
      tree.grow(start, sign * (0.6 + jitter), 0.8 * w, artery, 0, 0.0, 0.0, extent - disc.x());
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
  for (const auto& s : t.vessels) {
    const double half = 0.5 * s.width_mm;
    const double lo_x = std::min(s.a_mm.x(), s.b_mm.x()) - half - mm_per_px, hi_x = std::max(s.a_mm.x(), s.b_mm.x()) + half + mm_per_px;
    const double lo_y = std::min(s.a_mm.y(), s.b_mm.y()) - half - mm_per_px, hi_y = std::max(s.a_mm.y(), s.b_mm.y()) + half + mm_per_px;
    const int x0 = std::max(0, static_cast<int>((lo_x + extent) / mm_per_px));
    const int x1 = std::min(n - 1, static_cast<int>((hi_x + extent) / mm_per_px));
    const int y0 = std::max(0, static_cast<int>((lo_y + extent) / mm_per_px));
    const int y1 = std::min(n - 1, static_cast<int>((hi_y + extent) / mm_per_px));
    const double rr = s.artery ? 0.78 : 0.5, gg = s.artery ? 0.12 : 0.05, bb = s.artery ? 0.08 : 0.1;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double d = distance_to_segment(to_mm(x, y), s.a_mm, s.b_mm);
        // Coverage of a pixel by the vessel: 1 inside, fading over one pixel; thin vessels fade.
        const double cover = std::clamp((half + 0.5 * mm_per_px - d) / mm_per_px, 0.0, 1.0) *
                             std::min(1.0, s.width_mm / mm_per_px);
        if (cover > 0.0) blend(t.retina.pixel(x, y), rr, gg, bb, 0.95 * cover);
      }
    }
  }
  return t;
}

}  // namespace vitreo::core

#pragma once
// Exact closest-point queries between an instrument's axis segment and one tissue triangle, and
// ray–triangle intersection. Used inside the solver substeps (instrument contact), by grasping and by
// the endolaser; header-only so the substep loop can inline them. After Ericson, "Real-Time
// Collision Detection" (2005), ch. 5.1.5, 5.1.9, 5.3.6.
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/common/types.hpp"

namespace vitreo::core::contact {

// Closest point on triangle abc to p; bary receives its barycentric coordinates (a, b, c weights).
inline Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3& bary) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) { bary = {1, 0, 0}; return a; }
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) { bary = {0, 1, 0}; return b; }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    bary = {1 - v, v, 0};
    return a + v * ab;
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) { bary = {0, 0, 1}; return c; }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    bary = {1 - w, 0, w};
    return a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    bary = {0, 1 - w, w};
    return b + w * (c - b);
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  bary = {1 - v - w, v, w};
  return a + ab * v + ac * w;
}

// Closest points of segments p1q1 and p2q2: parameters s, t in [0, 1].
inline double closest_segment_segment(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, double& s, double& t) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  constexpr double eps = 1e-18;
  if (a <= eps && e <= eps) {
    s = t = 0.0;
  } else if (a <= eps) {
    s = 0.0;
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= eps) {
      t = 0.0;
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom != 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p1 + d1 * s) - (p2 + d2 * t)).squaredNorm();
}

// Ray (origin o, direction d, any length) against triangle abc (Möller–Trumbore, two-sided).
// Returns the ray parameter t ≥ 0 of the hit, or a negative value; bary receives the hit's
// barycentric coordinates.
inline double ray_triangle(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b, const Vec3& c, Vec3& bary) {
  const Vec3 e1 = b - a, e2 = c - a;
  const Vec3 p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-300) return -1.0;
  const double inv = 1.0 / det;
  const Vec3 s = o - a;
  const double u = s.dot(p) * inv;
  if (u < 0.0 || u > 1.0) return -1.0;
  const Vec3 q = s.cross(e1);
  const double v = d.dot(q) * inv;
  if (v < 0.0 || u + v > 1.0) return -1.0;
  const double t = e2.dot(q) * inv;
  if (t < 0.0) return -1.0;
  bary = {1.0 - u - v, u, v};
  return t;
}

struct SegmentTriangle {
  Vec3 on_segment;
  Vec3 on_triangle;
  Vec3 bary;           // of on_triangle
  double distance;     // 0 when the segment crosses the triangle
  bool crossing;
};

// Closest points between segment pq and triangle abc.
inline SegmentTriangle closest_segment_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  SegmentTriangle r{};
  Vec3 bary;
  const double t = ray_triangle(p, q - p, a, b, c, bary);
  if (t >= 0.0 && t <= 1.0) {
    r.on_segment = p + t * (q - p);
    r.on_triangle = r.on_segment;
    r.bary = bary;
    r.distance = 0.0;
    r.crossing = true;
    return r;
  }
  double best = std::numeric_limits<double>::infinity();
  auto consider_point = [&](const Vec3& s) {
    Vec3 bb;
    const Vec3 on = closest_on_triangle(s, a, b, c, bb);
    const double d2 = (on - s).squaredNorm();
    if (d2 < best) { best = d2; r.on_segment = s; r.on_triangle = on; r.bary = bb; }
  };
  consider_point(p);
  consider_point(q);
  const Vec3* v[3] = {&a, &b, &c};
  for (int i = 0; i < 3; ++i) {
    const Vec3& e0 = *v[i];
    const Vec3& e1 = *v[(i + 1) % 3];
    double s = 0, u = 0;
    const double d2 = closest_segment_segment(p, q, e0, e1, s, u);
    if (d2 < best) {
      best = d2;
      r.on_segment = p + s * (q - p);
      r.on_triangle = e0 + u * (e1 - e0);
      r.bary = Vec3::Zero();
      r.bary[i] = 1.0 - u;
      r.bary[(i + 1) % 3] = u;
    }
  }
  r.distance = std::sqrt(best);
  r.crossing = false;
  return r;
}

}  // namespace vitreo::core::contact

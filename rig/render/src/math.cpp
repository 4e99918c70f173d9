#include "vitreo/render/math.hpp"

namespace vitreo::render {

Mat4 operator*(const Mat4& a, const Mat4& b) {
  Mat4 r;
  for (int c = 0; c < 4; ++c) {
    for (int rr = 0; rr < 4; ++rr) {
      float s = 0;
      for (int k = 0; k < 4; ++k) s += a.at(rr, k) * b.at(k, c);
      r.at(rr, c) = s;
    }
  }
  return r;
}

Vec4 Mat4::operator*(Vec4 v) const {
  return {at(0, 0) * v.x + at(0, 1) * v.y + at(0, 2) * v.z + at(0, 3) * v.w,
          at(1, 0) * v.x + at(1, 1) * v.y + at(1, 2) * v.z + at(1, 3) * v.w,
          at(2, 0) * v.x + at(2, 1) * v.y + at(2, 2) * v.z + at(2, 3) * v.w,
          at(3, 0) * v.x + at(3, 1) * v.y + at(3, 2) * v.z + at(3, 3) * v.w};
}

Vec3 Mat4::transform_point(Vec3 p) const {
  const Vec4 r = (*this) * Vec4{p.x, p.y, p.z, 1.0f};
  return {r.x, r.y, r.z};
}

Vec3 Mat4::transform_dir(Vec3 d) const {
  const Vec4 r = (*this) * Vec4{d.x, d.y, d.z, 0.0f};
  return {r.x, r.y, r.z};
}

Mat4 translation(Vec3 t) {
  Mat4 r;
  r.at(0, 3) = t.x;
  r.at(1, 3) = t.y;
  r.at(2, 3) = t.z;
  return r;
}

Mat4 look_at(Vec3 eye, Vec3 center, Vec3 up) {
  const Vec3 f = normalize(center - eye);
  const Vec3 s = normalize(cross(f, up));
  const Vec3 u = cross(s, f);
  Mat4 r;
  r.at(0, 0) = s.x; r.at(0, 1) = s.y; r.at(0, 2) = s.z; r.at(0, 3) = -dot(s, eye);
  r.at(1, 0) = u.x; r.at(1, 1) = u.y; r.at(1, 2) = u.z; r.at(1, 3) = -dot(u, eye);
  r.at(2, 0) = -f.x; r.at(2, 1) = -f.y; r.at(2, 2) = -f.z; r.at(2, 3) = dot(f, eye);
  return r;
}

Mat4 frustum(float l, float r, float b, float t, float n, float f) {
  Mat4 m;
  m.m.fill(0.0f);
  m.at(0, 0) = 2 * n / (r - l);
  m.at(0, 2) = (r + l) / (r - l);
  m.at(1, 1) = 2 * n / (t - b);
  m.at(1, 2) = (t + b) / (t - b);
  m.at(2, 2) = -(f + n) / (f - n);
  m.at(2, 3) = -2 * f * n / (f - n);
  m.at(3, 2) = -1;
  return m;
}

Mat4 perspective(float fovy, float aspect, float n, float f) {
  const float t = n * std::tan(fovy * 0.5f);
  return frustum(-t * aspect, t * aspect, -t, t, n, f);
}

}  // namespace vitreo::render

#pragma once
// Small float vector/matrix types for the renderer. The renderer keeps its own (rather than Eigen)
// because everything here is 3-/4-component float data laid out exactly as OpenGL wants it
// (column-major 4×4), and the renderer must not depend on core/.
#include <array>
#include <cmath>

namespace vitreo::render {

struct Vec2 {
  float x = 0, y = 0;
};

struct Vec3 {
  float x = 0, y = 0, z = 0;
  friend Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
  friend Vec3 operator*(float s, Vec3 a) { return a * s; }
  friend Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
};

inline float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(Vec3 a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(Vec3 a) {
  const float l = length(a);
  return l > 0 ? a * (1.0f / l) : Vec3{0, 0, 0};
}

struct Vec4 {
  float x = 0, y = 0, z = 0, w = 0;
};

/// Column-major 4×4 matrix (m[col*4 + row]), as glUniformMatrix4fv(..., GL_FALSE, ...) expects.
struct Mat4 {
  std::array<float, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  float& at(int row, int col) { return m[static_cast<std::size_t>(col * 4 + row)]; }
  float at(int row, int col) const { return m[static_cast<std::size_t>(col * 4 + row)]; }
  static Mat4 identity() { return {}; }
  friend Mat4 operator*(const Mat4& a, const Mat4& b);
  Vec4 operator*(Vec4 v) const;
  Vec3 transform_point(Vec3 p) const;  // affine part only (w = 1, no divide)
  Vec3 transform_dir(Vec3 d) const;
};

Mat4 translation(Vec3 t);
/// Right-handed view matrix looking from `eye` at `center`.
Mat4 look_at(Vec3 eye, Vec3 center, Vec3 up);
/// OpenGL frustum (possibly asymmetric: off-axis stereo) with depth mapped to [-1, 1].
Mat4 frustum(float left, float right, float bottom, float top, float near_plane, float far_plane);
Mat4 perspective(float fovy_rad, float aspect, float near_plane, float far_plane);

}  // namespace vitreo::render

// Small fixed-size vector and matrix types for host and device code.
// Mat3 is row-major: m[r][c]. All operations are inline, allocation-free and branch-light.
#pragma once

#include <cmath>

#include "core/hd.hpp"

namespace qdemsph {

QDEMSPH_HD bool is_finite(double x) {
#if defined(__CUDA_ARCH__)
  return isfinite(x);
#else
  return std::isfinite(x);
#endif
}

struct Vec3 {
  double x = 0, y = 0, z = 0;
  QDEMSPH_HD double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  QDEMSPH_HD double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};

QDEMSPH_HD Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
QDEMSPH_HD Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
QDEMSPH_HD Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
QDEMSPH_HD Vec3 operator*(double s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
QDEMSPH_HD Vec3 operator*(Vec3 a, double s) { return {s * a.x, s * a.y, s * a.z}; }
QDEMSPH_HD Vec3 operator/(Vec3 a, double s) { return {a.x / s, a.y / s, a.z / s}; }
QDEMSPH_HD Vec3& operator+=(Vec3& a, Vec3 b) {
  a.x += b.x;
  a.y += b.y;
  a.z += b.z;
  return a;
}
QDEMSPH_HD Vec3& operator-=(Vec3& a, Vec3 b) {
  a.x -= b.x;
  a.y -= b.y;
  a.z -= b.z;
  return a;
}
QDEMSPH_HD double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
QDEMSPH_HD Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
QDEMSPH_HD double norm2(Vec3 a) { return dot(a, a); }
// v without the components named by bits 0..2 of `held` (x, y, z): those set to zero.
QDEMSPH_HD Vec3 unheld(Vec3 v, unsigned held) {
  return {held & 1u ? 0.0 : v.x, held & 2u ? 0.0 : v.y, held & 4u ? 0.0 : v.z};
}
QDEMSPH_HD double norm(Vec3 a) { return sqrt(dot(a, a)); }

struct Mat3 {
  double m[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  QDEMSPH_HD static Mat3 identity() {
    Mat3 r;
    r.m[0][0] = r.m[1][1] = r.m[2][2] = 1.0;
    return r;
  }
  // Matrix whose columns are a, b, c.
  QDEMSPH_HD static Mat3 from_columns(Vec3 a, Vec3 b, Vec3 c) {
    Mat3 r;
    r.m[0][0] = a.x;
    r.m[0][1] = b.x;
    r.m[0][2] = c.x;
    r.m[1][0] = a.y;
    r.m[1][1] = b.y;
    r.m[1][2] = c.y;
    r.m[2][0] = a.z;
    r.m[2][1] = b.z;
    r.m[2][2] = c.z;
    return r;
  }
  QDEMSPH_HD Vec3 col(int c) const { return {m[0][c], m[1][c], m[2][c]}; }
  QDEMSPH_HD Vec3 row(int r) const { return {m[r][0], m[r][1], m[r][2]}; }
};

QDEMSPH_HD Mat3 operator*(const Mat3& a, const Mat3& b) {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
  return r;
}
QDEMSPH_HD Vec3 operator*(const Mat3& a, Vec3 v) {
  return {dot(a.row(0), v), dot(a.row(1), v), dot(a.row(2), v)};
}
QDEMSPH_HD Mat3 operator+(const Mat3& a, const Mat3& b) {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][j] + b.m[i][j];
  return r;
}
QDEMSPH_HD Mat3 operator-(const Mat3& a, const Mat3& b) {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][j] - b.m[i][j];
  return r;
}
QDEMSPH_HD Mat3 operator*(double s, const Mat3& a) {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = s * a.m[i][j];
  return r;
}
QDEMSPH_HD Mat3 transpose(const Mat3& a) {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[j][i];
  return r;
}
QDEMSPH_HD double trace(const Mat3& a) { return a.m[0][0] + a.m[1][1] + a.m[2][2]; }
QDEMSPH_HD Mat3 sym(const Mat3& a) { return 0.5 * (a + transpose(a)); }
QDEMSPH_HD double ddot(const Mat3& a, const Mat3& b) {
  double s = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s += a.m[i][j] * b.m[i][j];
  return s;
}
QDEMSPH_HD double det(const Mat3& a) {
  return a.m[0][0] * (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) -
         a.m[0][1] * (a.m[1][0] * a.m[2][2] - a.m[1][2] * a.m[2][0]) +
         a.m[0][2] * (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]);
}
// Inverse by the adjugate; the caller guarantees det != 0.
QDEMSPH_HD Mat3 inverse(const Mat3& a) {
  const double d = 1.0 / det(a);
  Mat3 r;
  r.m[0][0] = (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) * d;
  r.m[0][1] = (a.m[0][2] * a.m[2][1] - a.m[0][1] * a.m[2][2]) * d;
  r.m[0][2] = (a.m[0][1] * a.m[1][2] - a.m[0][2] * a.m[1][1]) * d;
  r.m[1][0] = (a.m[1][2] * a.m[2][0] - a.m[1][0] * a.m[2][2]) * d;
  r.m[1][1] = (a.m[0][0] * a.m[2][2] - a.m[0][2] * a.m[2][0]) * d;
  r.m[1][2] = (a.m[0][2] * a.m[1][0] - a.m[0][0] * a.m[1][2]) * d;
  r.m[2][0] = (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]) * d;
  r.m[2][1] = (a.m[0][1] * a.m[2][0] - a.m[0][0] * a.m[2][1]) * d;
  r.m[2][2] = (a.m[0][0] * a.m[1][1] - a.m[0][1] * a.m[1][0]) * d;
  return r;
}

}  // namespace qdemsph

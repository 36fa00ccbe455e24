#include "internal/offset_roots.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace strata::internal {
namespace {

// Horner's rounding error on a cubic is below 6 ulps of the sum of its terms' magnitudes.
constexpr double kRounding = 8.0 * std::numeric_limits<double>::epsilon();

double det3(const Vec3& a, const Vec3& b, const Vec3& c) {
  return a.dot(b.cross(c));
}

double cubic_at(const double c[4], double t) {
  return c[0] + t * (c[1] + t * (c[2] + t * c[3]));
}

// The root in [lo, hi], where the cubic changes sign (flo = its value at lo): Newton's method from
// the middle, a step that would leave the bracket (or a zero derivative) replaced by the bracket's
// midpoint, until the cubic is zero to within its rounding or a step is below kFullRootWidth * T. On a
// monotone piece near a simple root it converges quadratically; a double root at a piece's end slows it to
// linear, and the bracket, halved or shrunk by every step, bounds it.
double solve_piece(const double c[4], double T, double lo, double hi, double flo, int& iterations) {
  double t = 0.5 * (lo + hi);
  for (iterations = 1; iterations <= 200; ++iterations) {
    const double f = cubic_at(c, t);
    // A root to within the evaluation's rounding: further steps would follow the rounding noise
    // (near a double root, as at the base's focal points, for many steps).
    const double at = std::abs(t);
    if (std::abs(f) <=
        kRounding * (std::abs(c[0]) + at * (std::abs(c[1]) + at * (std::abs(c[2]) + at * std::abs(c[3])))))
      return t;
    if ((f < 0) == (flo < 0))
      lo = t, flo = f;
    else
      hi = t;
    double next = t - f / (c[1] + t * (2.0 * c[2] + 3.0 * c[3] * t));
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - t) <= kFullRootWidth * T || hi - lo <= kFullRootWidth * T) return next;
    t = next;
  }
  return t;
}

Vec3 area_vector(const OffsetTriangle& tri, double t) {
  const Vec3 y0 = tri.x[0] + t * tri.n[0];
  return (tri.x[1] + t * tri.n[1] - y0).cross(tri.x[2] + t * tri.n[2] - y0);
}

}  // namespace

void offset_cubic(const OffsetTriangle& tri, const Vec3& p, double c[4]) {
  const Vec3 &x0 = tri.x[0], &n0 = tri.n[0];
  const Vec3 a1 = tri.x[1] - x0, b1 = tri.n[1] - n0;
  const Vec3 a2 = tri.x[2] - x0, b2 = tri.n[2] - n0;
  const Vec3 a3 = p - x0, b3 = -n0;
  c[0] = det3(a1, a2, a3);
  c[1] = det3(b1, a2, a3) + det3(a1, b2, a3) + det3(a1, a2, b3);
  c[2] = det3(b1, b2, a3) + det3(b1, a2, b3) + det3(a1, b2, b3);
  c[3] = det3(b1, b2, b3);
}

int cubic_root_brackets(const double c[4], double T, RootBracket out[3]) {
  double cuts[4];
  int nc = 0;
  cuts[nc++] = -T;
  // f'(t) = c1 + 2 c2 t + 3 c3 t^2.
  const double A = 3 * c[3], B = 2 * c[2], C = c[1];
  double crit[2];
  int ncrit = 0;
  if (std::abs(A) > 1e-300) {
    const double disc = B * B - 4 * A * C;
    if (disc > 0) {
      const double s = std::sqrt(disc);
      const double q = -0.5 * (B + (B >= 0 ? s : -s));
      crit[ncrit++] = q / A;
      if (q != 0) crit[ncrit++] = C / q;
    }
  } else if (std::abs(B) > 1e-300) {
    crit[ncrit++] = -C / B;
  }
  std::sort(crit, crit + ncrit);
  for (int i = 0; i < ncrit; ++i)
    if (crit[i] > -T && crit[i] < T) cuts[nc++] = crit[i];
  cuts[nc++] = T;
  int nr = 0;
  for (int i = 0; i + 1 < nc; ++i) {
    const double lo = cuts[i], hi = cuts[i + 1];
    const double flo = cubic_at(c, lo), fhi = cubic_at(c, hi);
    if (flo == 0.0) {
      // A cut that is a root starts this piece and may have ended the one before.
      if (nr == 0 || out[nr - 1].root != lo) out[nr++] = RootBracket{lo, lo, lo, 0};
      continue;
    }
    if (fhi == 0.0) {
      if (i + 2 == nc) out[nr++] = RootBracket{hi, hi, hi, 0};
      continue;
    }
    if ((flo < 0) == (fhi < 0)) continue;
    RootBracket& b = out[nr++];
    b.root = solve_piece(c, T, lo, hi, flo, b.iterations);
    const double half = 0.499 * kCoarseRootWidth * T;  // rounded, the width stays below it
    b.lo = std::max(lo, b.root - half);
    b.hi = std::min(hi, b.root + half);
  }
  return nr;
}

Vec3 offset_barycentric(const OffsetTriangle& tri, const Vec3& p, double t, bool* degenerate) {
  const Vec3 y0 = tri.x[0] + t * tri.n[0], y1 = tri.x[1] + t * tri.n[1], y2 = tri.x[2] + t * tri.n[2];
  const Vec3 v0 = y1 - y0, v1 = y2 - y0, v2 = p - y0;
  const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
  const double den = d00 * d11 - d01 * d01;
  const bool deg = !(std::abs(den) > 0.0);
  if (degenerate) *degenerate = deg;
  if (deg) return Vec3(-1, -1, -1);
  const double b1 = (d11 * d20 - d01 * d21) / den, b2 = (d00 * d21 - d01 * d20) / den;
  return Vec3(1.0 - b1 - b2, b1, b2);
}

bool offset_collapsed(const OffsetTriangle& tri, double t) {
  return !(area_vector(tri, t).norm() > 1e-8 * area_vector(tri, 0.0).norm());
}

bool root_outside(const OffsetTriangle& tri, const Vec3& p, const RootBracket& b, double tolerance) {
  if (!(b.lo < b.hi)) return false;
  const Vec3 a[3] = {area_vector(tri, b.lo), area_vector(tri, 0.5 * (b.lo + b.hi)), area_vector(tri, b.hi)};
  const double l[3] = {a[0].norm(), a[1].norm(), a[2].norm()};
  for (int k = 0; k < 2; ++k)
    if (!(a[k].dot(a[k + 1]) > 0.99 * l[k] * l[k + 1]) || !(l[k + 1] > 0.5 * l[k]) ||
        !(l[k] > 0.5 * l[k + 1]))
      return false;
  bool dlo = false, dhi = false;
  const Vec3 blo = offset_barycentric(tri, p, b.lo, &dlo), bhi = offset_barycentric(tri, p, b.hi, &dhi);
  if (dlo || dhi) return false;
  for (int i = 0; i < 3; ++i)
    if (std::max(blo[i], bhi[i]) + 2 * std::abs(bhi[i] - blo[i]) + 1e-12 < -tolerance) return true;
  return false;
}

}  // namespace strata::internal

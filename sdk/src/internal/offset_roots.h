// Internal: where a base triangle's normal offset passes through a point, for the encoding's
// projection (paper, section 3: p - q parallel to the interpolated normal at q). Not part of the
// API.
//
// The triangle offset along its vertex normals, y_k(t) = x_k + t n_k, contains p where
// det[y1 - y0, y2 - y0, p - y0] = 0, a cubic in t. Its roots in [-T, T] are found on the cubic's
// monotone pieces by Newton's method kept in a bracket, and each comes with a narrow bracket, so
// that the encoder can drop a root that the bracket's ends show to lie outside the triangle (most
// of the faces it searches) without evaluating the triangle at the root.
#pragma once

#include "strata/mesh.h"

namespace strata::internal {

//! A triangle (x0, x1, x2) with vertex normals (n0, n1, n2), offset by t: y_k = x_k + t n_k.
struct OffsetTriangle {
  Vec3 x[3];
  Vec3 n[3];
};

//! One root of a cubic and a bracket around it; lo == hi == root for a root at a piece's end.
struct RootBracket {
  double lo = 0.0, hi = 0.0;
  //! Within about kFullRootWidth * T of the exact root where the cubic is well conditioned; else a
  //! zero of the cubic to within its evaluation's rounding (near a double root).
  double root = 0.0;
  int iterations = 0;  //!< Newton or bisection steps taken
};

//! Width of the brackets, relative to T (root_outside()'s linearity argument needs them narrow).
constexpr double kCoarseRootWidth = 1e-4;
//! Accuracy of the roots, relative to T (a bisection of [-T, T] would take about 51 steps; Newton's
//! method takes 4 to 8 on the encoder's cubics).
constexpr double kFullRootWidth = 1e-15;

//! Coefficients c0..c3 of det[y1 - y0, y2 - y0, p - y0] as a cubic in t.
void offset_cubic(const OffsetTriangle& tri, const Vec3& p, double c[4]);

//! The real roots of c0 + c1 t + c2 t^2 + c3 t^3 in [-T, T], ascending: the interval is split at
//! the cubic's critical points (each piece monotone) and the root of every piece with a sign change
//! found by Newton's method from the piece's middle, a step that would leave the bracket of the
//! sign change replaced by a bisection, until the cubic is zero to within the rounding of its
//! evaluation or a step is below kFullRootWidth * T (or 200 steps). Each root's bracket is the
//! kCoarseRootWidth * T around it, within its piece. Robust against vanishing leading coefficients, which are
//! common (parallel normals make the cubic a line). Returns the count (at most 3).
int cubic_root_brackets(const double c[4], double T, RootBracket out[3]);

//! Barycentric coordinates of p's projection onto the plane of the triangle offset by t; (-1, -1,
//! -1) and *degenerate = true (if given) where that triangle is degenerate (never inside).
Vec3 offset_barycentric(const OffsetTriangle& tri, const Vec3& p, double t, bool* degenerate = nullptr);

//! Whether the triangle offset by t has collapsed: its area at most 1e-8 of the triangle's own (a
//! collinear or coincident offset, as at the focal points of the base's curvature, where every
//! point's cubic has a root). A root there is no projection: the barycentric coordinates of the
//! collapsed triangle are rounding noise.
bool offset_collapsed(const OffsetTriangle& tri, double t);

//! Whether the root in the bracket \p b is sure to lie outside the triangle, that is, to have a
//! barycentric coordinate below -tolerance at b.root, so that the encoder can skip that root.
//! The coordinates are rational in t with the offset triangle's squared area as denominator.
//! Where that triangle keeps its orientation and size across the bracket (its area vector is
//! quadratic in t, so its ends and middle fix it), they are smooth and, over so narrow a bracket,
//! linear to within far less than their change across it: a coordinate below -tolerance at both
//! ends by twice that change is below it at the root. Otherwise (the offset triangle degenerates
//! inside, as at a cylinder's axis, where every face's cubic has a root) the answer is false.
bool root_outside(const OffsetTriangle& tri, const Vec3& p, const RootBracket& b, double tolerance);

}  // namespace strata::internal

// The encoding's root finding (internal/offset_roots.h): the bracketed Newton roots against an
// independent bisection, and the brackets' "outside" verdicts against the roots.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "internal/offset_roots.h"

using namespace strata;
using namespace strata::internal;

namespace {

// The reference: the roots in [-T, T] by the same splitting at the critical points, each piece
// with a sign change bisected in one go to 1e-15 T (the encoder's root finding before the split).
int reference_roots(const double c[4], double T, double roots[3]) {
  auto f = [&](double t) { return c[0] + t * (c[1] + t * (c[2] + t * c[3])); };
  double cuts[4];
  int nc = 0;
  cuts[nc++] = -T;
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
    double lo = cuts[i], hi = cuts[i + 1];
    double flo = f(lo), fhi = f(hi);
    if (flo == 0.0) {
      if (nr == 0 || roots[nr - 1] != lo) roots[nr++] = lo;
      continue;
    }
    if (fhi == 0.0) {
      if (i + 2 == nc) roots[nr++] = hi;
      continue;
    }
    if ((flo < 0) == (fhi < 0)) continue;
    for (int it = 0; it < 200 && hi - lo > 1e-15 * T; ++it) {
      const double mid = 0.5 * (lo + hi);
      const double fm = f(mid);
      if (fm == 0.0)
        lo = hi = mid;
      else if ((fm < 0) == (flo < 0))
        lo = mid, flo = fm;
      else
        hi = mid;
    }
    roots[nr++] = 0.5 * (lo + hi);
  }
  return nr;
}

// A point on an offset triangle, of two kinds. Generic: a small triangle with normals near its
// face normal, offset by t in [-2, 2], and barycentric weights in [-1, 2] (summing to 1), so that
// the point is often outside. Focal: a triangle on the unit cylinder around the z axis with radial
// normals, whose offset collapses onto the axis at t = -1, offset by t = -1 + delta with |delta|
// from 1e-7 to 1e-3 and the point inside it: a coarse bracket of its root (1e-4 T wide) can then
// straddle the collapse, across which the coordinates are not smooth.
struct Sample {
  OffsetTriangle tri;
  Vec3 p;
  double t = 0.0;  // the root the point was placed at
};

enum class Kind { Generic, Focal, Pole };

Sample random_sample(std::mt19937& rng, Kind kind) {
  const bool focal = kind != Kind::Generic;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Sample s;
  Vec3 w;
  if (focal) {
    const double a = 3.14159 * u(rng), da = 0.2 + 0.1 * u(rng), z = u(rng);
    const double ang[3] = {a, a + da, a + 0.5 * da}, zz[3] = {z, z, z + 0.2};
    for (int k = 0; k < 3; ++k) {
      s.tri.x[k] = Vec3(std::cos(ang[k]), std::sin(ang[k]), zz[k]);
      s.tri.n[k] = Vec3(std::cos(ang[k]), std::sin(ang[k]), 0.0);
    }
    if (kind == Kind::Pole) {
      // A point outside the cylinder near the face: its cubic has a root at t = -1 exactly, where
      // the first two vertices' offsets meet on the axis.
      const double r = 1.1 + 0.4 * std::abs(u(rng)), b = a + 0.5 * da + 0.3 * u(rng);
      s.p = Vec3(r * std::cos(b), r * std::sin(b), z + 0.1 + 0.3 * u(rng));
      s.t = -1.0;
      return s;
    }
    const double delta = std::pow(10.0, -5.0 + 2.0 * u(rng));
    s.t = -1.0 + (u(rng) < 0 ? -delta : delta);
    w = Vec3(0.55 + 0.45 * u(rng), 0.55 + 0.45 * u(rng), 0.55 + 0.45 * u(rng));
  } else {
    const Vec3 c(u(rng), u(rng), u(rng));
    for (int k = 0; k < 3; ++k) s.tri.x[k] = c + 0.2 * Vec3(u(rng), u(rng), u(rng));
    const Vec3 nf = (s.tri.x[1] - s.tri.x[0]).cross(s.tri.x[2] - s.tri.x[0]).normalized();
    for (int k = 0; k < 3; ++k) s.tri.n[k] = (nf + 0.4 * Vec3(u(rng), u(rng), u(rng))).normalized();
    s.t = 2.0 * u(rng);
    w = Vec3(0.5 + 1.5 * u(rng), 0.5 + 1.5 * u(rng), 0.5 + 1.5 * u(rng));
  }
  w /= w.sum();
  s.p = Vec3::Zero();
  for (int k = 0; k < 3; ++k) s.p += w[k] * (s.tri.x[k] + s.t * s.tri.n[k]);
  return s;
}

}  // namespace

// The roots against an independent bisection of each monotone piece to kFullRootWidth * T: the
// same roots, as accurate, each inside its bracket, on offset cubics and on cubics with vanishing
// leading coefficients; and Newton's steps are few (a bisection takes about 51).
TEST(OffsetRoots, RootsAreThoseOfABisectionToFullWidth) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int compared = 0, agree = 0;
  long long steps = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    double c[4];
    const double T = 0.1 + 3.0 * std::abs(u(rng));
    if (trial % 4 < 2) {
      const Kind kind = trial % 4 == 0 ? Kind::Generic : trial % 4 == 1 ? Kind::Focal : Kind::Pole;
      const Sample s = random_sample(rng, kind);
      offset_cubic(s.tri, s.p, c);
    } else {
      for (double& x : c) x = u(rng);
      if (trial % 8 == 2) c[3] = 0.0;                 // a quadratic
      if (trial % 16 == 10) c[2] = c[3] = 0.0;        // a line
      if (trial % 32 == 26) c[0] = 0.0, c[1] = 1e-3;  // a root at 0
    }
    double ref[3];
    const int nref = reference_roots(c, T, ref);
    RootBracket b[3];
    const int n = cubic_root_brackets(c, T, b);
    ASSERT_EQ(n, nref) << "trial " << trial;
    for (int r = 0; r < n; ++r) {
      EXPECT_LE(b[r].hi - b[r].lo, kCoarseRootWidth * T);
      EXPECT_TRUE(b[r].lo <= b[r].root && b[r].root <= b[r].hi) << "trial " << trial << " root " << r;
      // Where the cubic is ill-conditioned (near a double root, as at the base's focal points) no
      // method pins the root below its evaluation's rounding: there both must be roots to within
      // that rounding (a backward error of a few ulps of the terms' sum).
      const double t = b[r].root;
      const double terms =
          std::abs(c[0]) +
          std::abs(t) * (std::abs(c[1]) + std::abs(t) * (std::abs(c[2]) + std::abs(t) * std::abs(c[3])));
      const double residual = std::abs(c[0] + t * (c[1] + t * (c[2] + t * c[3])));
      const bool same = std::abs(t - ref[r]) <= 2 * kFullRootWidth * T;
      EXPECT_TRUE(same || residual <= 16 * std::numeric_limits<double>::epsilon() * terms)
          << "trial " << trial << " root " << r << ": " << t << " against " << ref[r] << ", residual "
          << residual;
      agree += same;
      steps += b[r].iterations;
      ++compared;
    }
  }
  EXPECT_GT(compared, 10000);
  ::testing::Test::RecordProperty("roots", compared);
  ::testing::Test::RecordProperty("roots_within_2e-15_T_of_the_bisection", agree);
  ::testing::Test::RecordProperty("steps", static_cast<int>(steps));
  EXPECT_LT(static_cast<double>(steps) / compared, 12.0);
}

// A root that root_outside() drops is outside the triangle at the root, on generic triangles and on focal
// ones (see random_sample()), where the point's own root is inside and must not be dropped.
TEST(OffsetRoots, AnOutsideVerdictHoldsAtTheRefinedRoot) {
  const double tol = 1e-7, T = 3.0;
  std::mt19937 rng(11);
  int dropped = 0, refined = 0, focal_kept = 0;
  for (int trial = 0; trial < 40000; ++trial) {
    const bool focal = trial % 2 == 1;
    const Sample s = random_sample(rng, focal ? Kind::Focal : Kind::Generic);
    double c[4];
    offset_cubic(s.tri, s.p, c);
    RootBracket b[3];
    const int n = cubic_root_brackets(c, T, b);
    for (int r = 0; r < n; ++r) {
      const bool outside = root_outside(s.tri, s.p, b[r], tol);
      const double t = b[r].root;
      const Vec3 bary = offset_barycentric(s.tri, s.p, t);
      if (outside) {
        ++dropped;
        EXPECT_LT(bary.minCoeff(), -tol) << "trial " << trial << " t " << t << " placed at " << s.t;
      } else {
        ++refined;
        if (focal && std::abs(t - s.t) < 1e-9 && bary.minCoeff() >= -tol) ++focal_kept;
      }
    }
  }
  // Not vacuous: many roots are dropped, many refined, among them focal roots inside.
  EXPECT_GT(dropped, 5000);
  EXPECT_GT(refined, 5000);
  EXPECT_GT(focal_kept, 1000);
}

// Where the offset triangle collapses (every point's cubic has a root there), its coordinates are
// not smooth across the bracket, and refined they are rounding noise: such a root is never
// dropped on its coordinates (the encoder refines it and recognizes the collapse,
// offset_collapsed()). On the unit cylinder the first two
// vertices' offsets meet on the axis at t = -1; seen from a point outside, the first coordinate
// is about the same negative number at both ends of that root's bracket, which a test of the
// coordinates alone would take for "outside".
TEST(OffsetRoots, ARootWhereTheOffsetCollapsesIsNeverDropped) {
  std::mt19937 rng(5);
  int collapses = 0;
  for (int trial = 0; trial < 5000; ++trial) {
    const Sample s = random_sample(rng, Kind::Pole);
    double c[4];
    offset_cubic(s.tri, s.p, c);
    RootBracket b[3];
    const int n = cubic_root_brackets(c, 3.0, b);
    for (int r = 0; r < n; ++r) {
      if (!(b[r].lo <= -1.0 && -1.0 <= b[r].hi)) continue;
      ++collapses;
      EXPECT_FALSE(root_outside(s.tri, s.p, b[r], 1e-7)) << "trial " << trial;
    }
  }
  EXPECT_GT(collapses, 1000);
}

// The root where the cylinder's offset collapses onto its axis is reported as collapsed; the
// roots of points placed on a generic offset triangle are not.
TEST(OffsetRoots, ACollapsedOffsetIsRecognized) {
  std::mt19937 rng(13);
  for (int trial = 0; trial < 1000; ++trial) {
    const Sample pole = random_sample(rng, Kind::Pole);
    EXPECT_TRUE(offset_collapsed(pole.tri, -1.0)) << "trial " << trial;
    EXPECT_FALSE(offset_collapsed(pole.tri, 0.0)) << "trial " << trial;
    const Sample generic = random_sample(rng, Kind::Generic);
    EXPECT_FALSE(offset_collapsed(generic.tri, generic.t)) << "trial " << trial;
  }
}

// The barycentric coordinates of a point on the offset triangle reproduce it, and a degenerate
// offset (the focal one at t = -1) is reported as such.
TEST(OffsetRoots, BarycentricCoordinatesOfTheOffsetTriangle) {
  std::mt19937 rng(3);
  const Sample s = random_sample(rng, Kind::Generic);
  const double t = 0.3;
  const Vec3 w(0.2, 0.5, 0.3);
  Vec3 y[3];
  for (int k = 0; k < 3; ++k) y[k] = s.tri.x[k] + t * s.tri.n[k];
  const Vec3 p = w[0] * y[0] + w[1] * y[1] + w[2] * y[2];
  bool degenerate = true;
  EXPECT_LT((offset_barycentric(s.tri, p, t, &degenerate) - w).norm(), 1e-12);
  EXPECT_FALSE(degenerate);
  // Three points of one line: collinear at every t.
  OffsetTriangle line{{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)},
                      {Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1)}};
  EXPECT_EQ(offset_barycentric(line, Vec3(0.5, 1, 0), 0.0, &degenerate), Vec3(-1, -1, -1));
  EXPECT_TRUE(degenerate);
}

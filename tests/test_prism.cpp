#include <gtest/gtest.h>

#include <random>

#include "internal/prism_pair.h"
#include "strata/prism.h"

using strata::Vec3;

namespace {

struct Prism {
  Vec3 p[3], q[3];
};

double volume(const Prism& s) {
  return strata::prism_volume(s.p[0], s.p[1], s.p[2], s.q[0], s.q[1], s.q[2]);
}

Vec3 random_vec(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return Vec3(u(rng), u(rng), u(rng)) * scale;
}

// Random prisms of three families: general, thin (height << base size), sheared (top shifted
// tangentially by more than its size).
std::vector<Prism> random_prisms(int count) {
  std::mt19937 rng(1234);
  std::vector<Prism> out;
  for (int i = 0; i < count; ++i) {
    const int family = i % 3;
    Prism s;
    const Vec3 q0 = random_vec(rng, 10.0);
    s.q[0] = q0;
    s.q[1] = q0 + Vec3(1, 0, 0) + random_vec(rng, 0.3);
    s.q[2] = q0 + Vec3(0, 1, 0) + random_vec(rng, 0.3);
    const double height = family == 1 ? 1e-3 : 0.7;
    const Vec3 shear = family == 2 ? Vec3(1.5, -0.8, 0.0) : Vec3::Zero();
    for (int k = 0; k < 3; ++k)
      s.p[k] = s.q[k] + Vec3(0, 0, height) + shear + random_vec(rng, family == 1 ? 1e-4 : 0.4);
    out.push_back(s);
  }
  return out;
}

}  // namespace

TEST(Prism, UnitRightPrismHasExactVolume) {
  // Planar faces: the split quads are planar, so the volume is the polyhedron's exactly.
  Prism s{{Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(0, 1, 1)}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}};
  EXPECT_NEAR(volume(s), 0.5, 1e-15);
}

TEST(Prism, ObliquePlanarPrismMatchesPolyhedronVolume) {
  // A sheared prism with parallel top and bottom: volume = base area * height, whatever the shear.
  const Vec3 shift(0.7, -0.3, 2.5);
  Prism s{{Vec3(0, 0, 0) + shift, Vec3(2, 0, 0) + shift, Vec3(0, 3, 0) + shift},
          {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 3, 0)}};
  EXPECT_NEAR(volume(s), 3.0 * 2.5, 1e-13);
}

TEST(Prism, FrustumMatchesPolyhedronVolume) {
  // Top triangle scaled by 1/2 about the apex axis: a truncated pyramid with planar trapezoid
  // sides. Volume = h/3 (A1 + A2 + sqrt(A1 A2)).
  const double h = 1.5, a1 = 0.5 * 4.0 * 4.0, a2 = 0.5 * 2.0 * 2.0;
  Prism s{{Vec3(0, 0, h), Vec3(2, 0, h), Vec3(0, 2, h)}, {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)}};
  EXPECT_NEAR(volume(s), h / 3.0 * (a1 + a2 + std::sqrt(a1 * a2)), 1e-13);
}

TEST(Prism, GradientMatchesCentralDifferences) {
  for (const Prism& s : random_prisms(60)) {
    const auto g = strata::prism_volume_gradient(s.p[0], s.p[1], s.p[2], s.q[0], s.q[1], s.q[2]);
    EXPECT_NEAR(g.volume, volume(s), 1e-12 * (1.0 + std::abs(g.volume)));
    for (int k = 0; k < 3; ++k) {
      // The volume is affine in each single vertex, so central differences are exact up to
      // rounding; a moderate step keeps the rounding small.
      const double h = 1e-4;
      Vec3 fd;
      for (int d = 0; d < 3; ++d) {
        Prism a = s, b = s;
        a.p[k][d] += h;
        b.p[k][d] -= h;
        fd[d] = (volume(a) - volume(b)) / (2 * h);
      }
      EXPECT_LE((g.grad[k] - fd).norm(), 1e-6 * fd.norm() + 1e-12) << "corner " << k;
    }
  }
}

// The solver decides a cycle step on the volumes of the pass that also gives its gradients
// (reconstruction.cpp, project()), where the other steps use prism_volume(): the two must give
// the same numbers, bit for bit, or the presets' results would depend on which pass ran.
TEST(Prism, GradientPassGivesTheSameVolumeBits) {
  for (const Prism& s : random_prisms(3000)) {
    const double v = volume(s);
    EXPECT_EQ(v, strata::prism_volume_gradient(s.p[0], s.p[1], s.p[2], s.q[0], s.q[1], s.q[2]).volume);
  }
}

// The solver's passes take the prisms two at a time (internal/prism_pair.h); its results must not
// depend on that, so both lanes must give the scalar functions' bits. Pairs of unlike prisms
// (general with thin, thin with sheared, ...), far from the origin, flat (p = q), and one prism
// in both lanes, as an odd count's last pair.
TEST(Prism, PairKernelsGiveTheScalarBits) {
  std::vector<Prism> prisms = random_prisms(3001);
  for (int i = 0; i < 300; ++i) {
    Prism far = prisms[i];
    for (int a = 0; a < 3; ++a) {
      far.p[a] += Vec3(1e6, -3e5, 2e4);
      far.q[a] += Vec3(1e6, -3e5, 2e4);
    }
    prisms.push_back(far);
    Prism flat = prisms[i];
    for (int a = 0; a < 3; ++a) flat.p[a] = flat.q[a];
    prisms.push_back(flat);
  }
  int compared = 0;
  for (std::size_t i = 0; i < prisms.size(); ++i) {
    const Prism* s[2] = {&prisms[i], &prisms[i % 5 == 0 ? i : (i * 7919) % prisms.size()]};
    strata::internal::PrismPair c;
    for (int k = 0; k < 2; ++k)
      for (int a = 0; a < 3; ++a) {
        c.p[k][a] = &s[k]->p[a];
        c.q[k][a] = &s[k]->q[a];
      }
    strata::PrismVolumeGradient g[2];
    double v[2];
    strata::internal::prism_volume_gradient_pair(c, g);
    strata::internal::prism_volume_pair(c, v);
    for (int k = 0; k < 2; ++k) {
      const Prism& t = *s[k];
      const auto ref = strata::prism_volume_gradient(t.p[0], t.p[1], t.p[2], t.q[0], t.q[1], t.q[2]);
      ASSERT_EQ(g[k].volume, ref.volume) << "prism " << i << " lane " << k;
      ASSERT_EQ(v[k], volume(t)) << "prism " << i << " lane " << k;
      for (int a = 0; a < 3; ++a)
        for (int d = 0; d < 3; ++d)
          ASSERT_EQ(g[k].grad[a][d], ref.grad[a][d]) << "prism " << i << " corner " << a;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 2 * 3601);
}

TEST(Prism, VolumeIsAffineInOneVertex) {
  // The property the solver's incremental update relies on: V(p + d) = V(p) + grad . d exactly.
  for (const Prism& s : random_prisms(30)) {
    const auto g = strata::prism_volume_gradient(s.p[0], s.p[1], s.p[2], s.q[0], s.q[1], s.q[2]);
    Prism moved = s;
    const Vec3 d(0.3, -0.5, 0.9);
    moved.p[1] += d;
    EXPECT_NEAR(volume(moved), g.volume + g.grad[1].dot(d), 1e-11);
  }
}

TEST(Prism, TranslationInvariant) {
  for (const Prism& s : random_prisms(30)) {
    Prism t = s;
    const Vec3 shift(123.25, -77.5, 1000.125);
    for (int k = 0; k < 3; ++k) {
      t.p[k] += shift;
      t.q[k] += shift;
    }
    EXPECT_NEAR(volume(t), volume(s), 1e-10 * (1.0 + std::abs(volume(s))));
  }
}

TEST(Prism, SignFlipsBelowBase) {
  // Over a flat base, reflecting the detail through the base plane reverses the orientation of
  // the whole solid: the volume changes sign exactly, and it is positive above the base.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int i = 0; i < 30; ++i) {
    const Vec3 q[3] = {Vec3(u(rng), u(rng), 0), Vec3(1 + u(rng), u(rng), 0), Vec3(u(rng), 1 + u(rng), 0)};
    const double h = 0.05 + 0.1 * i;
    Vec3 p[3], m[3];
    for (int k = 0; k < 3; ++k) {
      p[k] = q[k] + Vec3(u(rng), u(rng), h * (1.0 + u(rng)));
      m[k] = Vec3(p[k][0], p[k][1], -p[k][2]);
    }
    const double v = strata::prism_volume(p[0], p[1], p[2], q[0], q[1], q[2]);
    const double w = strata::prism_volume(m[0], m[1], m[2], q[0], q[1], q[2]);
    EXPECT_GT(v, 0.0);
    EXPECT_NEAR(w, -v, 1e-14 * (1.0 + std::abs(v)));
  }
}

TEST(Prism, NeighbouringPrismsTileTheLayer) {
  // Two prisms sharing an edge use the same split of their common quad, so their volumes add up
  // to the volume of the union: a unit square slab split into two triangles, with a non-planar top.
  const Vec3 q[4] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
  const Vec3 p[4] = {Vec3(0, 0, 1), Vec3(1, 0, 1.3), Vec3(1, 1, 0.8), Vec3(0, 1, 1.1)};
  const double v1 = strata::prism_volume(p[0], p[1], p[2], q[0], q[1], q[2]);
  const double v2 = strata::prism_volume(p[0], p[2], p[3], q[0], q[2], q[3]);
  // The union is a box-like solid with a bilinear-free top made of the two triangles; its volume
  // over the unit square is the integral of the piecewise-linear height.
  const double h_tri1 = (1.0 + 1.3 + 0.8) / 3.0 * 0.5, h_tri2 = (1.0 + 0.8 + 1.1) / 3.0 * 0.5;
  EXPECT_NEAR(v1 + v2, h_tri1 + h_tri2, 1e-14);
}

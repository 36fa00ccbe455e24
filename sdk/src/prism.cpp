#include "strata/prism.h"

#include "internal/prism_pair.h"

namespace strata {
namespace {

// Contribution of the side quad over edge (a,b), split at its centroid c into the triangles
// (qa,qb,c), (qb,pb,c), (pb,pa,c), (pa,qa,c), each oriented outwards. Adds 6*volume to v6 and
// 6*gradient to ga, gb. The four determinants x.(y x c) sum to c.gc, with gc the sum of the
// edges' cross products: twice the quad's vector area, (pb - qa) x (pa - qb). Their gradients
// are c x (pb - qa) for pa and c x (qb - pa) for pb, plus gc through the centroid, which moves
// with weight 1/4.
inline void side_quad(const Vec3& pa, const Vec3& pb, const Vec3& qa, const Vec3& qb, double& v6, Vec3& ga,
                      Vec3& gb) {
  const Vec3 c = 0.25 * (pa + pb + qa + qb);
  const Vec3 gc = (pb - qa).cross(pa - qb);
  v6 += c.dot(gc);
  ga += c.cross(pb - qa) + 0.25 * gc;
  gb += c.cross(qb - pa) + 0.25 * gc;
}

// The same quad's 6*volume alone.
inline double side_quad_volume(const Vec3& pa, const Vec3& pb, const Vec3& qa, const Vec3& qb) {
  return (0.25 * (pa + pb + qa + qb)).dot((pb - qa).cross(pa - qb));
}

}  // namespace

PrismVolumeGradient prism_volume_gradient(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& q0,
                                          const Vec3& q1, const Vec3& q2) {
  // Work relative to a corner: the volume is translation invariant, and small coordinates keep
  // the determinants accurate far from the origin.
  const Vec3& o = q0;
  const Vec3 P[3] = {p0 - o, p1 - o, p2 - o};
  const Vec3 Q[3] = {Vec3::Zero(), q1 - o, q2 - o};
  PrismVolumeGradient r;
  double v6 = P[0].dot(P[1].cross(P[2])) + Q[0].dot(Q[2].cross(Q[1]));
  r.grad[0] = P[1].cross(P[2]);
  r.grad[1] = P[2].cross(P[0]);
  r.grad[2] = P[0].cross(P[1]);
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3;
    side_quad(P[a], P[b], Q[a], Q[b], v6, r.grad[a], r.grad[b]);
  }
  r.volume = v6 / 6.0;
  for (Vec3& g : r.grad) g /= 6.0;
  return r;
}

double prism_volume(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& q0, const Vec3& q1,
                    const Vec3& q2) {
  const Vec3& o = q0;
  const Vec3 P[3] = {p0 - o, p1 - o, p2 - o};
  const Vec3 Q[3] = {Vec3::Zero(), q1 - o, q2 - o};
  double v6 = P[0].dot(P[1].cross(P[2]));  // the base triangle's term vanishes with q0 at the origin
  for (int a = 0; a < 3; ++a) v6 += side_quad_volume(P[a], P[(a + 1) % 3], Q[a], Q[(a + 1) % 3]);
  return v6 / 6.0;
}

namespace internal {
namespace {

// Two doubles, one per prism of a pair; +, -, * and / act lane by lane, as the scalar operations.
typedef double Lanes __attribute__((vector_size(16)));

struct V2 {  // a Vec3 of each prism
  Lanes x, y, z;
};

inline Lanes lanes(double a) {
  return Lanes{a, a};
}

inline V2 load(const Vec3& a, const Vec3& b) {
  return {Lanes{a.x(), b.x()}, Lanes{a.y(), b.y()}, Lanes{a.z(), b.z()}};
}
inline V2 operator+(const V2& a, const V2& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline V2 operator-(const V2& a, const V2& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline V2 scaled(Lanes s, const V2& a) {
  return {s * a.x, s * a.y, s * a.z};
}
// Eigen's cross() and dot() of 3-vectors, term by term.
inline V2 cross(const V2& a, const V2& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline Lanes dot(const V2& a, const V2& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

// The corners relative to q0, as the scalar functions take them.
void relative_corners(const PrismPair& c, V2 P[3], V2 Q[3]) {
  const V2 o = load(*c.q[0][0], *c.q[1][0]);
  for (int a = 0; a < 3; ++a) P[a] = load(*c.p[0][a], *c.p[1][a]) - o;
  Q[0] = {lanes(0.0), lanes(0.0), lanes(0.0)};
  for (int a = 1; a < 3; ++a) Q[a] = load(*c.q[0][a], *c.q[1][a]) - o;
}

}  // namespace

void prism_volume_gradient_pair(const PrismPair& corners, PrismVolumeGradient out[2]) {
  V2 P[3], Q[3];
  relative_corners(corners, P, Q);
  Lanes v6 = dot(P[0], cross(P[1], P[2])) + dot(Q[0], cross(Q[2], Q[1]));
  V2 g[3] = {cross(P[1], P[2]), cross(P[2], P[0]), cross(P[0], P[1])};
  const Lanes quarter = lanes(0.25);
  for (int a = 0; a < 3; ++a) {  // side_quad()
    const int b = (a + 1) % 3;
    const V2 c = scaled(quarter, P[a] + P[b] + Q[a] + Q[b]);
    const V2 gc = cross(P[b] - Q[a], P[a] - Q[b]);
    v6 = v6 + dot(c, gc);
    g[a] = g[a] + (cross(c, P[b] - Q[a]) + scaled(quarter, gc));
    g[b] = g[b] + (cross(c, Q[b] - P[a]) + scaled(quarter, gc));
  }
  const Lanes six = lanes(6.0), volume = v6 / six;
  for (int k = 0; k < 2; ++k) {
    out[k].volume = volume[k];
    for (int a = 0; a < 3; ++a) out[k].grad[a] = Vec3(g[a].x[k], g[a].y[k], g[a].z[k]) / 6.0;
  }
}

void prism_volume_pair(const PrismPair& corners, double out[2]) {
  V2 P[3], Q[3];
  relative_corners(corners, P, Q);
  Lanes v6 = dot(P[0], cross(P[1], P[2]));
  const Lanes quarter = lanes(0.25);
  for (int a = 0; a < 3; ++a) {  // side_quad_volume()
    const int b = (a + 1) % 3;
    v6 = v6 + dot(scaled(quarter, P[a] + P[b] + Q[a] + Q[b]), cross(P[b] - Q[a], P[a] - Q[b]));
  }
  const Lanes v = v6 / lanes(6.0);
  out[0] = v[0];
  out[1] = v[1];
}

}  // namespace internal

}  // namespace strata

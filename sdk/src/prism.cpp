#include "strata/prism.h"

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

}  // namespace strata

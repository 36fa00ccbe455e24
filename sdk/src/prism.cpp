#include "strata/prism.h"

namespace strata {
namespace {

// Contribution of the side quad over edge (a,b), split at its centroid into the triangles
// (qa,qb,c), (qb,pb,c), (pb,pa,c), (pa,qa,c), each oriented outwards. Adds 6*volume to v6 and
// 6*gradient to ga, gb. For a triangle (x,y,z), det = x.(y x z) has d/dx = y x z, d/dy = z x x,
// d/dz = x x y; the centroid's gradient reaches pa and pb with weight 1/4.
inline void side_quad(const Vec3& pa, const Vec3& pb, const Vec3& qa, const Vec3& qb, double& v6, Vec3& ga,
                      Vec3& gb) {
  const Vec3 c = 0.25 * (pa + pb + qa + qb);
  v6 += qa.dot(qb.cross(c)) + qb.dot(pb.cross(c)) + pb.dot(pa.cross(c)) + pa.dot(qa.cross(c));
  // d/dc summed over the four triangles: twice the quad's vector area.
  const Vec3 gc = qa.cross(qb) + qb.cross(pb) + pb.cross(pa) + pa.cross(qa);
  ga += c.cross(pb) + qa.cross(c) + 0.25 * gc;
  gb += c.cross(qb) + pa.cross(c) + 0.25 * gc;
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
  return prism_volume_gradient(p0, p1, p2, q0, q1, q2).volume;
}

}  // namespace strata

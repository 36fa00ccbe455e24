//! \file prism.h
//! Signed volume of a displacement prism and its exact gradient (paper, section 3).
//!
//! A prism spans a detail triangle [p0,p1,p2] over its base points [q0,q1,q2]. Each of the three
//! non-planar side quads is split at its centroid c_ab = (p_a + p_b + q_a + q_b) / 4 into four
//! triangles, so the closed boundary has 14 triangles: top, bottom and 3 x 4 sides. The volume is
//! (1/6) sum det[u,v,w] over those triangles. It is positive when the detail triangle lies on the
//! side of the base its counter-clockwise orientation points to, negative below.
//!
//! With all other corners fixed, the volume is an affine function of any single top vertex p_a
//! (no boundary triangle holds p_a twice except through c_ab, whose determinant term stays linear),
//! so the gradient below is exact for finite moves of one vertex, not only infinitesimal ones.
#pragma once

#include "strata/mesh.h"

namespace strata {

//! Signed volume of the prism [p0,p1,p2,q0,q1,q2] with centroid-split side quads.
double prism_volume(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& q0, const Vec3& q1,
                    const Vec3& q2);

//! Volume and gradient of the prism volume with respect to each top vertex p0, p1, p2, including
//! the terms through the quad centroids c_ab.
struct PrismVolumeGradient {
  double volume = 0.0;
  Vec3 grad[3] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
};

//! Volume and exact gradient of the prism [p0,p1,p2,q0,q1,q2] with respect to p0, p1 and p2.
PrismVolumeGradient prism_volume_gradient(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& q0,
                                          const Vec3& q1, const Vec3& q2);

}  // namespace strata

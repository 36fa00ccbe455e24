// Internal: the parameter domains of ptex faces (triangles for Loop, unit squares for
// Catmull-Clark) and their edges, numbered from corner k to corner k+1.
#pragma once

#include <Eigen/Core>
#include <algorithm>

namespace strata::internal {

//! Clamps (u, v) into the domain of a ptex face with \p corners (3 or 4) corners.
inline void clamp_to_domain(int corners, double& u, double& v) {
  u = std::clamp(u, 0.0, 1.0);
  v = std::clamp(v, 0.0, 1.0);
  if (corners == 3 && u + v > 1.0) {
    const double s = u + v;
    u /= s;
    v /= s;
  }
}

//! The point at parameter t in [0,1] along edge e of a ptex face.
inline Eigen::Vector2d edge_point(int corners, int e, double t) {
  if (corners == 3) {
    switch (e) {
      case 0:
        return {t, 0.0};
      case 1:
        return {1.0 - t, t};
      default:
        return {0.0, 1.0 - t};
    }
  }
  switch (e) {
    case 0:
      return {t, 0.0};
    case 1:
      return {1.0, t};
    case 2:
      return {1.0 - t, 1.0};
    default:
      return {0.0, 1.0 - t};
  }
}

//! The parameter along edge e of a point (u, v) on that edge (inverse of edge_point).
inline double edge_param(int corners, int e, double u, double v) {
  if (corners == 3) return e == 0 ? u : e == 1 ? v : 1.0 - v;
  return e == 0 ? u : e == 1 ? v : e == 2 ? 1.0 - u : 1.0 - v;
}

//! Whether (u, v) lies on edge e of the domain, to within \p tol in the parameters.
inline bool on_edge(int corners, int e, double u, double v, double tol = 1e-12) {
  if (corners == 3) return e == 0 ? v <= tol : e == 1 ? u + v >= 1.0 - tol : u <= tol;
  return e == 0 ? v <= tol : e == 1 ? u >= 1.0 - tol : e == 2 ? v >= 1.0 - tol : u <= tol;
}

//! The unit normal of edge e pointing into the domain (edges run counter-clockwise, so it is the
//! edge direction turned left).
inline Eigen::Vector2d inward_normal(int corners, int e) {
  const Eigen::Vector2d d = edge_point(corners, e, 1.0) - edge_point(corners, e, 0.0);
  return Eigen::Vector2d(-d.y(), d.x()).normalized();
}

//! Where the segment from (u, v) (inside the domain) along (du, dv) first leaves the domain:
//! the fraction s in [0, 1) of the step and the edge it crosses, or s = 1 and edge -1 if the
//! whole step stays inside.
inline double exit_fraction(int corners, double u, double v, double du, double dv, int& edge) {
  double s = 1.0;
  edge = -1;
  auto limit = [&](double x, double dx, double bound, int e) {
    // x + s dx crosses bound
    if (dx == 0.0) return;
    const double t = (bound - x) / dx;
    if (t >= 0.0 && t < s) {
      s = t;
      edge = e;
    }
  };
  if (corners == 4) {
    if (v + dv < 0.0) limit(v, dv, 0.0, 0);
    if (u + du > 1.0) limit(u, du, 1.0, 1);
    if (v + dv > 1.0) limit(v, dv, 1.0, 2);
    if (u + du < 0.0) limit(u, du, 0.0, 3);
  } else {
    if (v + dv < 0.0) limit(v, dv, 0.0, 0);
    if (u + du + v + dv > 1.0) limit(u + v, du + dv, 1.0, 1);
    if (u + du < 0.0) limit(u, du, 0.0, 2);
  }
  return s;
}

}  // namespace strata::internal

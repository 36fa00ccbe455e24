// Foot points on a subdivision limit surface (project_to_limit): a closest-point seed on a
// tessellation, then damped Newton iterations on (u, v) that cross ptex-face edges.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <sstream>

#include "internal/closest_point.h"
#include "internal/parts.h"
#include "internal/ptex_domain.h"
#include "strata/exceptions.h"
#include "strata/subdiv.h"

namespace strata {
namespace {

// The working state of one projection run; project() is const and thread-safe.
class Projector {
 public:
  // With \p mesh, the points are its vertices, each projected within its part's surface parts.
  Projector(const SubdivSurface& s, const ProjectOptions& o, const TriMesh* mesh)
      : surface_(s),
        opt_(o),
        corners_(s.ptex_corners()),
        tess_(s.tessellate(o.seed_resolution)),
        tree_(tess_.mesh.vertices, tess_.mesh.faces),
        on_surface_(1e-12 * bbox_diagonal(s.control_points())),
        parts_(mesh ? internal::match_parts(*mesh, tess_.mesh.vertices, tess_.mesh.faces)
                    : internal::PartMatch{}),
        part_trees_(tess_.mesh.vertices, tess_.mesh.faces, parts_) {}

  struct Result {
    LimitPoint point;
    bool converged = false;
    bool on_boundary = false;
    int iterations = 0;
  };

  // The foot point of point i at p: seeded on its part's tessellation faces, and Newton's steps
  // cross ptex edges only, so it stays on the connected part of the seed.
  Result project(int i, const Vec3& p) const {
    const int group = parts_.group(i);
    const internal::TriangleTree::Hit hit = group < 0 ? tree_.closest(p) : part_trees_.closest(group, p);
    const auto& uv = tess_.face_uv[hit.face];
    const Eigen::Vector2d seed = hit.bary[0] * uv[0] + hit.bary[1] * uv[1] + hit.bary[2] * uv[2];
    Result r;
    r.point = {tess_.face_ptex[hit.face], seed.x(), seed.y()};
    internal::clamp_to_domain(corners_, r.point.u, r.point.v);
    LimitSample s = surface_.evaluate(r.point, true);
    Vec3 d = s.position - p;
    double phi = d.squaredNorm();
    double mu = 0.0;  // Levenberg-Marquardt damping, relative to the Hessian's diagonal
    // Newton where the distance's Hessian is positive definite, else Gauss-Newton (first
    // derivatives only); a failed step raises the Levenberg-Marquardt damping instead of giving up
    // on Newton for good. Near a focal point (the surface curved about as tightly as the point is
    // far) the distance is nearly flat and Gauss-Newton converges only linearly, too slowly for
    // the iteration budget, while damped Newton keeps its quadratic convergence.
    for (; r.iterations < opt_.max_iterations; ++r.iterations) {
      if (orthogonal(s, d)) {
        r.converged = true;
        return r;
      }
      if (boundary_foot(r.point, s, d, opt_.orthogonality_tolerance)) {
        r.converged = r.on_boundary = true;
        return r;
      }
      const Eigen::Vector2d g(s.du.dot(d), s.dv.dot(d));
      Eigen::Matrix2d full;  // the distance's Hessian
      full << s.du.dot(s.du) + s.duu.dot(d), s.du.dot(s.dv) + s.duv.dot(d), s.du.dot(s.dv) + s.duv.dot(d),
          s.dv.dot(s.dv) + s.dvv.dot(d);
      Eigen::Matrix2d H = full;
      if (!(H(0, 0) > 0 && H.determinant() > 0)) {
        // Not a local minimum's basin (the distance's Hessian is indefinite): Gauss-Newton.
        H << s.du.dot(s.du), s.du.dot(s.dv), s.du.dot(s.dv), s.dv.dot(s.dv);
      }
      H(0, 0) *= 1.0 + mu;
      H(1, 1) *= 1.0 + mu;
      Eigen::Vector2d step = -H.ldlt().solve(g);
      if (!step.allFinite()) break;
      {
        // On an open boundary with the step pointing out: the foot point is constrained to the
        // boundary curve, so take the 1D Newton step along the edge instead (the orthogonality
        // along the boundary can still be met, e.g. for detail on the boundary).
        // At a corner of the open boundary the step along one edge can point out through the
        // other (the foot point lies along that one): then the other edge is taken (stuck at
        // the corner, a point beyond a rounded corner ended there and counted a fallback).
        int edge = -1;
        double frac = internal::exit_fraction(corners_, r.point.u, r.point.v, step.x(), step.y(), edge);
        bool along_boundary = false;
        for (int tried = 0; tried < 2 && edge >= 0 && frac < 1e-12; ++tried) {
          const double t = internal::edge_param(corners_, edge, r.point.u, r.point.v);
          if (surface_.across_edge(r.point.face, edge, std::clamp(t, 0.0, 1.0)).face >= 0) break;
          const Eigen::Vector2d dir =
              internal::edge_point(corners_, edge, 1.0) - internal::edge_point(corners_, edge, 0.0);
          // The distance's own second derivative along the edge where it is positive: beyond a
          // boundary the full Hessian is mostly indefinite, and Gauss-Newton's |S_u|^2 there
          // was half the curve's (a point beyond a quad's edge zig-zagged for 355 iterations
          // where a few do; a review, thirty-eighth session).
          const double along_full = dir.dot(full * dir) * (1.0 + mu);
          const double ht = along_full > 0 ? along_full : dir.dot(H * dir);
          step = ht > 0 ? Eigen::Vector2d(-(g.dot(dir) / ht) * dir) : Eigen::Vector2d::Zero();
          along_boundary = true;
          if (step.norm() < 1e-14) break;
          const int along = edge;
          frac = internal::exit_fraction(corners_, r.point.u, r.point.v, step.x(), step.y(), edge);
          if (edge == along) break;  // out through its own edge's end: trial() stops it there
        }
        if (along_boundary && step.norm() < 1e-14) break;  // a fixed point on the boundary
      }
      LimitPoint y;
      LimitSample sy;
      bool stuck = false;
      if (!trial(r.point, s, step, y, sy, stuck)) {
        if (stuck) break;  // pushed against an open boundary: no foot point inside
        mu = mu == 0.0 ? 1e-3 : mu * 10.0;
        if (mu > 1e8) break;
        continue;
      }
      const Vec3 dy = sy.position - p;
      const double phiy = dy.squaredNorm();
      // Near the foot point phi changes by less than its round-off; such steps still count.
      if (phiy <= phi * (1.0 + 1e-12) + on_surface_ * on_surface_) {
        r.point = y;
        s = sy;
        d = dy;
        phi = phiy;
        mu *= 0.1;
        if (mu < 1e-9) mu = 0.0;
      } else {
        mu = mu == 0.0 ? 1e-3 : mu * 10.0;
        if (mu > 1e8) break;
      }
    }
    // Stalled: accepted if orthogonal to within the seams' tangent jumps.
    r.converged = orthogonal(s, d, opt_.seam_tolerance);
    if (!r.converged) r.converged = r.on_boundary = boundary_foot(r.point, s, d, opt_.seam_tolerance);
    return r;
  }

 private:
  bool orthogonal(const LimitSample& s, const Vec3& d) const {
    return orthogonal(s, d, opt_.orthogonality_tolerance);
  }
  bool orthogonal(const LimitSample& s, const Vec3& d, double cosine) const {
    const double dn = d.norm();
    if (dn <= on_surface_) return true;
    const double tol = cosine * dn, nu = s.du.norm(), nv = s.dv.norm();
    // A degenerate parameterization (a vanishing derivative) proves nothing.
    return nu > 0 && nv > 0 && std::abs(s.du.dot(d)) <= tol * nu && std::abs(s.dv.dot(d)) <= tol * nv;
  }

  // Whether x, on an open boundary edge of the surface, is the constrained closest point there
  // (the Karush-Kuhn-Tucker conditions): p - S is orthogonal to the boundary curve's tangent and
  // moving into the surface does not bring S closer. It is the foot point of a detail vertex
  // beyond the surface's open boundary, which has no orthogonal foot point inside.
  bool boundary_foot(const LimitPoint& x, const LimitSample& s, const Vec3& d, double cosine) const {
    for (int e = 0; e < corners_; ++e) {
      if (!internal::on_edge(corners_, e, x.u, x.v)) continue;
      const double t = std::clamp(internal::edge_param(corners_, e, x.u, x.v), 0.0, 1.0);
      if (surface_.across_edge(x.face, e, t).face >= 0) continue;
      const Eigen::Vector2d a =
          internal::edge_point(corners_, e, 1.0) - internal::edge_point(corners_, e, 0.0);
      const Eigen::Vector2d n = internal::inward_normal(corners_, e);
      const Vec3 along = a.x() * s.du + a.y() * s.dv, inward = n.x() * s.du + n.y() * s.dv;
      const double dn = d.norm(), na = along.norm();
      // d = S - p: moving inward changes |d|^2 at the rate 2 d . inward.
      if (na > 0 && std::abs(along.dot(d)) <= cosine * na * dn && inward.dot(d) >= 0.0) return true;
    }
    // At a corner of the open boundary (both of the domain's edges there open, so no other face
    // has the vertex): the closest point if moving along either boundary edge, away from the
    // corner, does not bring S closer; the domain's directions there lie between those two. A
    // point beyond the corner of a scan's open sheet projected there and was counted a fallback.
    for (int k = 0; k < corners_; ++k) {
      const int prev = (k + corners_ - 1) % corners_;
      if (!internal::on_edge(corners_, k, x.u, x.v) || !internal::on_edge(corners_, prev, x.u, x.v)) continue;
      if (surface_.across_edge(x.face, k, 0.0).face >= 0 || surface_.across_edge(x.face, prev, 1.0).face >= 0)
        continue;
      const Eigen::Vector2d a =
          internal::edge_point(corners_, k, 1.0) - internal::edge_point(corners_, k, 0.0);
      const Eigen::Vector2d b =
          internal::edge_point(corners_, prev, 0.0) - internal::edge_point(corners_, prev, 1.0);
      const Vec3 ta = a.x() * s.du + a.y() * s.dv, tb = b.x() * s.du + b.y() * s.dv;
      const double dn = d.norm();
      if (ta.norm() > 0 && tb.norm() > 0 && ta.dot(d) >= -cosine * ta.norm() * dn &&
          tb.dot(d) >= -cosine * tb.norm() * dn)
        return true;
    }
    return false;
  }

  // The point a Newton step leads to. A step that leaves the ptex face continues in the
  // neighbour across the crossed edge: the rest of the step is carried over as the same 3D
  // displacement, expressed in the neighbour's tangents (and stopped at its domain's border).
  // Returns false if the step cannot be taken (stuck: it pushes out through an open boundary
  // from the boundary itself).
  bool trial(const LimitPoint& x, const LimitSample& s, const Eigen::Vector2d& step, LimitPoint& y,
             LimitSample& sy, bool& stuck) const {
    int edge = -1;
    const double frac = internal::exit_fraction(corners_, x.u, x.v, step.x(), step.y(), edge);
    if (edge < 0) {
      y = {x.face, x.u + step.x(), x.v + step.y()};
      internal::clamp_to_domain(corners_, y.u, y.v);
      sy = surface_.evaluate(y, true);
      return true;
    }
    double eu = x.u + frac * step.x(), ev = x.v + frac * step.y();
    internal::clamp_to_domain(corners_, eu, ev);
    const double t = std::clamp(internal::edge_param(corners_, edge, eu, ev), 0.0, 1.0);
    const SubdivSurface::EdgeCrossing nb = surface_.across_edge(x.face, edge, t);
    if (nb.face < 0) {
      if (frac < 1e-12) {
        stuck = true;
        return false;
      }
      y = {x.face, eu, ev};
      sy = surface_.evaluate(y, true);
      return true;
    }
    const Eigen::Vector2d q = internal::edge_point(corners_, nb.edge, nb.t);
    y = {nb.face, q.x(), q.y()};
    sy = surface_.evaluate(y, true);
    // The remaining step as a 3D displacement, then in the neighbour's parameters.
    const Eigen::Vector2d rest = (1.0 - frac) * step;
    const Vec3 D = rest.x() * s.du + rest.y() * s.dv;
    Eigen::Matrix<double, 3, 2> T;
    T.col(0) = sy.du;
    T.col(1) = sy.dv;
    const Eigen::Vector2d r2 = (T.transpose() * T).ldlt().solve(T.transpose() * D);
    if (r2.allFinite()) {
      int e2 = -1;
      const double f2 = internal::exit_fraction(corners_, y.u, y.v, r2.x(), r2.y(), e2);
      LimitPoint z{y.face, y.u + f2 * r2.x(), y.v + f2 * r2.y()};
      internal::clamp_to_domain(corners_, z.u, z.v);
      y = z;
      sy = surface_.evaluate(y, true);
    }
    return true;
  }

  const SubdivSurface& surface_;
  const ProjectOptions& opt_;
  int corners_;
  LimitTessellation tess_;
  internal::TriangleTree tree_;
  double on_surface_;
  internal::PartMatch parts_;
  internal::GroupedTrees part_trees_;
};

Projection project_points(const SubdivSurface& surface, const std::vector<Vec3>& points,
                          const ProjectOptions& options, const TriMesh* mesh);

}  // namespace

Projection project_to_limit(const SubdivSurface& surface, const std::vector<Vec3>& points,
                            const ProjectOptions& options) {
  return project_points(surface, points, options, nullptr);
}

Projection project_mesh_to_limit(const SubdivSurface& surface, const TriMesh& mesh,
                                 const ProjectOptions& options) {
  check_face_indices(mesh.vertices.size(), mesh.faces, "project_mesh_to_limit");
  return project_points(surface, mesh.vertices, options, &mesh);
}

namespace {

// project_to_limit(), for the vertices of \p mesh if given (project_mesh_to_limit()).
Projection project_points(const SubdivSurface& surface, const std::vector<Vec3>& points,
                          const ProjectOptions& options, const TriMesh* mesh) {
  const auto t0 = std::chrono::steady_clock::now();
  if (options.seed_resolution < 1 || options.max_iterations < 1 || !(options.orthogonality_tolerance > 0) ||
      !(options.seam_tolerance >= options.orthogonality_tolerance))
    throw InvalidInput("projection options out of range");
  check_coordinates(points, "projected");
  // A cage below the engine's extent: its limit normals (du x dv, of the extent squared) underflow,
  // and a unit cube's cage scaled by 1e-160 had every point fall back to its closest point without
  // a word. (The cage itself may be anything: its stencils are its topology's.)
  if (const double extent = bbox_diagonal(surface.control_points()); !(extent >= kMinExtent)) {
    std::ostringstream s;
    s << "project_to_limit: the cage has an extent (bounding box diagonal) of " << extent
      << ", below the engine's range (" << kMinExtent << "): its limit normals would underflow";
    throw InvalidInput(s.str());
  }
  Projection out;
  const std::size_t n = points.size();
  out.points.resize(n);
  out.converged.assign(n, 0);
  std::vector<int> iterations(n, 0);
  std::vector<char> on_boundary(n, 0);
  const Projector proj(surface, options, mesh);
  auto body = [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Projector::Result r = proj.project(static_cast<int>(i), points[i]);
      out.points[i] = r.point;
      out.converged[i] = r.converged ? 1 : 0;
      iterations[i] = r.iterations;
      on_boundary[i] = r.on_boundary ? 1 : 0;
    }
  };
  if (options.parallel) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
  } else {
    body(0, n);
  }
  for (std::size_t i = 0; i < n; ++i) {
    out.num_converged += out.converged[i];
    out.num_on_boundary += on_boundary[i];
    out.max_iterations_used = std::max(out.max_iterations_used, iterations[i]);
  }
  out.num_fallback = static_cast<int>(n) - out.num_converged;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace

}  // namespace strata

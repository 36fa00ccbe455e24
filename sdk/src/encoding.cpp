#include "strata/encoding.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <sstream>
#include <string>

#include "internal/closest_point.h"
#include "internal/offset_roots.h"
#include "internal/option_error.h"
#include "internal/parts.h"
#include "internal/renumber.h"
#include "internal/topology.h"
#include "internal/vectors.h"
#include "strata/exceptions.h"
#include "strata/prism.h"

namespace strata {
namespace {

void check_mesh(const TriMesh& m, const char* what) {
  if (m.faces.empty()) throw InvalidInput(std::string(what) + " mesh has no faces");
  check_coordinates(m.vertices, std::string(what) + " mesh");
  for (const Face& f : m.faces)
    for (int v : f)
      if (v < 0 || v >= m.num_vertices())
        throw InvalidInput(std::string(what) + " mesh has an out-of-range index");
  check_extent(m.vertices, m.faces, std::string(what) + " mesh");
}

// Working state of one encode_detail() call.
class Encoder {
 public:
  Encoder(const TriMesh& detail, const TriMesh& base, const EncodeOptions& o)
      : base_(base),
        opt_(o),
        normals_(vertex_normals(base.vertices, base.faces)),
        adj_(internal::build_adjacency(base.num_vertices(), base.faces)),
        tree_(base.vertices, base.faces),
        parts_(internal::match_parts(detail, base.vertices, base.faces)),
        part_trees_(base.vertices, base.faces, parts_),
        unit_(std::min(1.0, bbox_diagonal(base.vertices))) {}

  // One thread's ring-search state: the faces of the rings, and each base face's last stamp.
  struct Scratch {
    std::vector<int> mark, ring;
  };
  Scratch scratch() const { return Scratch{std::vector<int>(base_.faces.size(), -1), {}}; }

  // Base point of detail vertex p (index i, for its part and the ring-search marks), on the base
  // parts under p's own part (internal::match_parts(): the rings grow within the closest face's
  // part). Depends on nothing but p and its part, so vertices may be projected in any order and
  // on any thread (each with its own scratch).
  BasePoint project(int i, const Vec3& p, EncodeReport& report, Scratch& sc) const {
    std::vector<int>& ring = sc.ring;
    std::vector<int>& mark = sc.mark;
    const int group = parts_.group(i);
    const auto hit = group < 0 ? tree_.closest(p) : part_trees_.closest(group, p);
    if (hit.face < 0) throw SolverError("no closest base face for detail vertex " + std::to_string(i));
    const double dc = std::sqrt(hit.distance_sq);
    const double T = opt_.max_distance_ratio * dc + 1e-12 * unit_;
    // Search outwards ring by ring and stop after the first ring (past the closest face's
    // neighbourhood) that yields a projection: nearer solutions lie in the inner rings.
    ring.clear();
    ring.push_back(hit.face);
    mark[hit.face] = i;
    int found = 0;
    double best = INFINITY;
    BasePoint bp;
    Vec3 best_q = Vec3::Zero();
    std::size_t begin = 0;  // first face of the ring being tested
    for (int r = 0; r <= opt_.search_rings; ++r) {
      const std::size_t end = ring.size();
      for (std::size_t k = begin; k < end; ++k) test_face(ring[k], p, T, found, best, best_q, bp);
      if (found > 0 && r >= 1) break;
      if (r < opt_.search_rings) grow_ring(i, begin, sc);
      begin = end;
    }
    if (found == 0) {
      ++report.num_fallback;
      bp.face = hit.face;
      bp.bary = hit.bary;
    } else {
      ++report.num_projected;
      if (found > 1) ++report.num_ambiguous;
    }
    return bp;
  }

 private:
  // Appends the faces sharing a vertex with ring[begin..) that are not yet marked.
  void grow_ring(int stamp, std::size_t begin, Scratch& sc) const {
    std::vector<int>& ring = sc.ring;
    std::vector<int>& mark = sc.mark;
    const std::size_t end = ring.size();
    for (std::size_t k = begin; k < end; ++k)
      for (int v : base_.faces[ring[k]])
        for (int s = adj_.face_offsets[v]; s < adj_.face_offsets[v + 1]; ++s) {
          const int g = adj_.faces[s];
          if (mark[g] != stamp) {
            mark[g] = stamp;
            ring.push_back(g);
          }
        }
  }

  // Solves for the points of face f whose interpolated normal passes through p (the roots t of
  // det[y1 - y0, y2 - y0, p - y0] = 0 with y_k = x_k + t n_k) and keeps the nearest one inside.
  void test_face(int f, const Vec3& p, double T, int& found, double& best, Vec3& best_q,
                 BasePoint& bp) const {
    const Face& F = base_.faces[f];
    const internal::OffsetTriangle tri{{base_.vertices[F[0]], base_.vertices[F[1]], base_.vertices[F[2]]},
                                       {normals_[F[0]], normals_[F[1]], normals_[F[2]]}};
    double c[4];
    internal::offset_cubic(tri, p, c);
    internal::RootBracket brackets[3];
    const int nr = internal::cubic_root_brackets(c, T, brackets);
    for (int r = 0; r < nr; ++r) {
      // Most faces of the rings are far from holding the projection: their roots are dropped on
      // their brackets' ends, before the triangle is evaluated at the root.
      if (internal::root_outside(tri, p, brackets[r], opt_.barycentric_tolerance)) continue;
      const double t = brackets[r].root;
      // A root where the offset triangle collapses (the base's focal points) is no projection;
      // counted as one, such roots made vertices ambiguous and at times won as the nearest.
      if (internal::offset_collapsed(tri, t)) continue;
      Vec3 b = internal::offset_barycentric(tri, p, t);
      // Not finite where the cubic overflows (a detail vertex 1e80 from a unit base): no root, so
      // the closest point is the fallback (such a vertex had no base face, and the frames crashed).
      if (!b.allFinite() || b.minCoeff() < -opt_.barycentric_tolerance) continue;
      b = b.cwiseMax(0.0);
      b /= b.sum();
      const Vec3 q = b[0] * tri.x[0] + b[1] * tri.x[1] + b[2] * tri.x[2];
      const double d = (p - q).norm();
      if (!(d <= T)) continue;
      // The same point found through two faces sharing an edge is not an ambiguity.
      if (found == 0 || (q - best_q).norm() > 1e-9 * (unit_ + d)) ++found;
      if (d < best) {
        best = d;
        best_q = q;
        bp.face = f;
        bp.bary = b;
      }
    }
  }

  const TriMesh& base_;
  const EncodeOptions& opt_;
  std::vector<Vec3> normals_;
  internal::Adjacency adj_;
  internal::TriangleTree tree_;
  internal::PartMatch parts_;
  internal::GroupedTrees part_trees_;
  // The absolute tolerances' unit: 1, or the base's diagonal if it is smaller, so that a mesh
  // scaled by 1e-9 encodes as at 1 (T bounds the root search: meshes of diagonal 1 or more keep
  // their encodings bit for bit).
  double unit_;
};

// The regularization weights of the detail at rest (section 4.2): normalized clamped cotangent
// weights of its own connectivity.
void set_regularization_weights(DetailEncoding& e) {
  const auto threads = internal::Threads::Caller;
  internal::Adjacency adj = internal::build_adjacency(e.num_detail_vertices(), e.detail_faces, threads);
  e.weights = internal::normalized_cotan_weights(e.detail_rest, e.detail_faces, adj, threads);
  e.weight_offsets = std::move(adj.neighbor_offsets);
  e.weight_neighbors = std::move(adj.neighbors);
}

// What every encoding stores once its base points are known (sections 3 and 4.2): the base
// points' rest positions, the displacement lengths and tangential offsets, the target volumes and
// the regularization weights of the original detail.
void finish_encoding(DetailEncoding& e, const TriMesh& detail, const BaseFrames& frames) {
  const int n = detail.num_vertices();
  e.base_rest_points = frames.points;
  e.base_rest_normals = frames.normals;
  e.base_rest_tangents = frames.tangents;
  e.normal_offsets.resize(n);
  e.tangential_offsets.resize(n);
  // Per vertex and per face on the caller's threads: every entry is independent (and a max is
  // the same in any order), so the encoding does not depend on them. Serial, these loops and the
  // weights were most of a scattered 1M-prism encoding's time.
  std::vector<double> max_tangential(n, 0.0);
  // The tolerance's unit, as Encoder::unit_ (of the detail here, whose offsets these are).
  const double unit = std::min(1.0, bbox_diagonal(detail.vertices));
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i != r.end(); ++i) {
      const Vec3 d = detail.vertices[i] - frames.points[i];
      const Vec3& nrm = frames.normals[i];
      const Vec3& t = frames.tangents[i];
      e.normal_offsets[i] = d.dot(nrm);
      const Vec3 tang = d - e.normal_offsets[i] * nrm;
      // Normal projections are parallel up to round-off: keep exact zeros for them, so the
      // regularizer's rest state is exactly the paper's.
      // At most relative to the detail's size (an absolute 1.0 here zeroed every offset of a
      // mesh scaled by 1e-9, whose vectors then no longer gave the detail back).
      const bool projected = tang.norm() <= 1e-9 * (unit + std::abs(e.normal_offsets[i]));
      e.tangential_offsets[i] =
          projected ? Eigen::Vector2d::Zero() : Eigen::Vector2d(tang.dot(t), tang.dot(nrm.cross(t)));
      if (!projected) max_tangential[i] = tang.norm();
    }
  });
  for (double t : max_tangential)
    e.report.max_tangential_offset = std::max(e.report.max_tangential_offset, t);
  const int m = static_cast<int>(detail.faces.size());
  e.target_volumes.resize(m);
  tbb::parallel_for(tbb::blocked_range<int>(0, m, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int j = r.begin(); j != r.end(); ++j) {
      const Face& f = detail.faces[j];
      e.target_volumes[j] = prism_volume(detail.vertices[f[0]], detail.vertices[f[1]], detail.vertices[f[2]],
                                         frames.points[f[0]], frames.points[f[1]], frames.points[f[2]]);
    }
  });
  set_regularization_weights(e);
}

}  // namespace

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The encoding over a triangle base with known base points (meshes and points checked by the
// caller). Every vertex counts as projected; encode_detail() overrides the counts.
DetailEncoding encoding_over_mesh(const TriMesh& detail, const TriMesh& base, std::vector<BasePoint> points) {
  DetailEncoding e;
  e.detail_faces = detail.faces;
  e.detail_rest = detail.vertices;
  e.base_num_vertices = base.num_vertices();
  e.base_faces = base.faces;
  e.base_points = std::move(points);
  e.report.num_vertices = e.report.num_projected = detail.num_vertices();
  finish_encoding(e, detail, evaluate_base_frames(e, base.vertices));
  return e;
}

// The same over a limit surface with known limit points.
DetailEncoding encoding_over_limit(const TriMesh& detail, const SubdivSurface& base,
                                   std::vector<LimitPoint> points) {
  DetailEncoding e;
  e.detail_faces = detail.faces;
  e.detail_rest = detail.vertices;
  e.base_num_vertices = base.num_control_points();
  e.cage_faces = base.cage().faces;
  e.cage_tags = base.tags();
  e.cage_options = base.options();
  e.cage_options.scheme = base.scheme();
  e.limit_points = std::move(points);
  e.report.num_vertices = e.report.num_projected = detail.num_vertices();
  finish_encoding(e, detail, evaluate_base_frames(e, base));
  return e;
}

}  // namespace

// NaN ratios and tolerances made every projection fail the comparisons and fall back to the
// closest point, silently.
void check_encode_options(const EncodeOptions& o) {
  auto fail = [](const char* name, double value, const char* range) {
    internal::option_out_of_range("encode", name, value, range);
  };
  // The ranges a .strata file's options are read with (layers/FORMAT.md).
  if (o.search_rings < 0 || o.search_rings > 100) fail("search_rings", o.search_rings, "0 to 100");
  if (!(o.barycentric_tolerance >= 0 && o.barycentric_tolerance <= 0.1))
    fail("barycentric_tolerance", o.barycentric_tolerance, "0 to 0.1");
  if (!(o.max_distance_ratio >= 1 && o.max_distance_ratio <= 1e6))
    fail("max_distance_ratio", o.max_distance_ratio, "1 to 1e6");
}

DetailEncoding encode_detail(const TriMesh& detail, const TriMesh& base, const EncodeOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  check_encode_options(options);
  check_mesh(detail, "detail");
  check_mesh(base, "base");
  const int n = detail.num_vertices();
  EncodeReport report;
  report.num_vertices = n;
  std::vector<BasePoint> points(n);
  {
    // The projections are independent: chunks run on TBB's threads, each with its own scratch
    // and counts (summed at the end, so the result does not depend on the threads). A scattered
    // numbering (a scan whose file hashes its vertices) is visited along a Morton curve of the
    // positions instead, so that consecutive queries share the base tree's paths in the caches
    // (the same points, projected in another order).
    const Encoder enc(detail, base, options);
    const std::vector<int> order = internal::locality_renumbering(detail.vertices, detail.faces).old_of_new;
    tbb::enumerable_thread_specific<Encoder::Scratch> scratch([&] { return enc.scratch(); });
    std::mutex counts;
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 1024), [&](const tbb::blocked_range<int>& r) {
      Encoder::Scratch& sc = scratch.local();
      EncodeReport part;
      for (int k = r.begin(); k != r.end(); ++k) {
        const int i = order.empty() ? k : order[static_cast<std::size_t>(k)];
        points[i] = enc.project(i, detail.vertices[i], part, sc);
      }
      const std::lock_guard<std::mutex> lock(counts);
      report.num_projected += part.num_projected;
      report.num_fallback += part.num_fallback;
      report.num_ambiguous += part.num_ambiguous;
    });
  }
  DetailEncoding e = encoding_over_mesh(detail, base, std::move(points));
  report.max_tangential_offset = e.report.max_tangential_offset;
  e.report = report;
  e.report.seconds = seconds_since(t0);
  return e;
}

DetailEncoding encode_detail(const TriMesh& detail, const SubdivSurface& base,
                             const ProjectOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  check_mesh(detail, "detail");
  Projection pr = project_mesh_to_limit(base, detail, options);
  DetailEncoding e = encoding_over_limit(detail, base, std::move(pr.points));
  e.report.num_projected = pr.num_converged;
  e.report.num_fallback = pr.num_fallback;
  e.report.seconds = seconds_since(t0);
  return e;
}

DetailEncoding encode_detail_at(const TriMesh& detail, const TriMesh& base,
                                std::vector<BasePoint> base_points) {
  const auto t0 = std::chrono::steady_clock::now();
  check_mesh(detail, "detail");
  check_mesh(base, "base");
  if (base_points.size() != detail.vertices.size())
    throw InvalidInput("encoding: " + std::to_string(base_points.size()) + " base points for " +
                       std::to_string(detail.vertices.size()) + " detail vertices");
  // Barycentric coordinates of a point on the face (the encoder's are clamped to it): 1e308 was
  // read from a file and silently changed the detail.
  for (std::size_t i = 0; i < base_points.size(); ++i) {
    const Vec3& b = base_points[i].bary;
    if (base_points[i].face < 0 || base_points[i].face >= base.num_faces() || !b.allFinite() ||
        b.minCoeff() < -1e-6 || std::abs(b.sum() - 1.0) > 1e-6)
      throw InvalidInput("encoding: base point " + std::to_string(i) + " is not on a base face");
  }
  DetailEncoding e = encoding_over_mesh(detail, base, std::move(base_points));
  e.report.seconds = seconds_since(t0);
  return e;
}

void check_limit_points(const std::vector<LimitPoint>& points, const SubdivSurface& surface) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    const LimitPoint& p = points[i];
    if (p.face < 0 || p.face >= surface.num_ptex_faces() || !(p.u >= -1e-6 && p.u <= 1 + 1e-6) ||
        !(p.v >= -1e-6 && p.v <= 1 + 1e-6))
      throw InvalidInput("limit point " + std::to_string(i) + " is not on a ptex face");
  }
}

DetailEncoding encode_detail_at(const TriMesh& detail, const SubdivSurface& base,
                                std::vector<LimitPoint> limit_points) {
  const auto t0 = std::chrono::steady_clock::now();
  check_mesh(detail, "detail");
  if (limit_points.size() != detail.vertices.size())
    throw InvalidInput("encoding: " + std::to_string(limit_points.size()) + " limit points for " +
                       std::to_string(detail.vertices.size()) + " detail vertices");
  try {
    check_limit_points(limit_points, base);
  } catch (const InvalidInput& x) {
    throw InvalidInput(std::string("encoding: ") + x.what());
  }
  DetailEncoding e = encoding_over_limit(detail, base, std::move(limit_points));
  e.report.seconds = seconds_since(t0);
  return e;
}

DetailEncoding restrict_encoding(const DetailEncoding& e, const std::vector<int>& faces,
                                 std::vector<int>& vertices) {
  if (faces.empty()) throw InvalidInput("restrict_encoding: no faces selected");
  check_encoding(e);
  const int n = e.num_detail_vertices();
  std::vector<int> id(n, -1);
  vertices.clear();
  DetailEncoding r;
  r.detail_faces.reserve(faces.size());
  r.target_volumes.reserve(faces.size());
  for (int j : faces) {
    if (j < 0 || j >= static_cast<int>(e.detail_faces.size()))
      throw InvalidInput("restrict_encoding: face " + std::to_string(j) + " out of range");
    Face g;
    for (int c = 0; c < 3; ++c) {
      int& v = id[e.detail_faces[j][c]];
      if (v < 0) {
        v = static_cast<int>(vertices.size());
        vertices.push_back(e.detail_faces[j][c]);
      }
      g[c] = v;
    }
    r.detail_faces.push_back(g);
    r.target_volumes.push_back(e.target_volumes[j]);
  }
  r.base_num_vertices = e.base_num_vertices;
  r.base_faces = e.base_faces;
  r.cage_faces = e.cage_faces;
  r.cage_tags = e.cage_tags;
  r.cage_options = e.cage_options;
  const bool limit = e.over_limit_surface();
  for (int v : vertices) {
    r.detail_rest.push_back(e.detail_rest[v]);
    r.base_rest_points.push_back(e.base_rest_points[v]);
    if (static_cast<int>(e.base_rest_normals.size()) == n &&
        static_cast<int>(e.base_rest_tangents.size()) == n) {
      r.base_rest_normals.push_back(e.base_rest_normals[v]);
      r.base_rest_tangents.push_back(e.base_rest_tangents[v]);
    }
    r.normal_offsets.push_back(e.normal_offsets[v]);
    r.tangential_offsets.push_back(e.tangential_offsets[v]);
    if (limit)
      r.limit_points.push_back(e.limit_points[v]);
    else
      r.base_points.push_back(e.base_points[v]);
    if (!e.pinned.empty()) r.pinned.push_back(e.pinned[v]);
  }
  set_regularization_weights(r);
  r.report.num_vertices = static_cast<int>(vertices.size());
  return r;
}

namespace {

// What evaluate_base_frames() reads (called by the encoders before the rest is filled in): the
// base points, one per detail vertex, on faces of the base whose indices are within it.
void check_base_part(const DetailEncoding& e) {
  const auto nv = static_cast<std::size_t>(e.num_detail_vertices());
  if (e.base_num_vertices < 0) throw InvalidInput("encoding has a negative base vertex count");
  const bool limit = e.over_limit_surface();
  if (limit && !e.base_points.empty())
    throw InvalidInput("encoding has both base points (a triangle base) and limit points (a limit surface)");
  const std::size_t points = limit ? e.limit_points.size() : e.base_points.size();
  if (points != nv)
    throw InvalidInput("encoding has " + std::to_string(points) + " base points for " + std::to_string(nv) +
                       " detail vertices");
  // Over a limit surface, the cage's faces and the limit points' patches: SubdivSurface and
  // LimitPointSet check them.
  if (limit) return;
  for (const Face& f : e.base_faces)
    for (int v : f)
      if (v < 0 || v >= e.base_num_vertices)
        throw InvalidInput("encoding has a base face index out of range (the base has " +
                           std::to_string(e.base_num_vertices) + " vertices)");
  for (std::size_t i = 0; i < e.base_points.size(); ++i) {
    const BasePoint& b = e.base_points[i];
    if (b.face < 0 || b.face >= static_cast<int>(e.base_faces.size()))
      throw InvalidInput("encoding has a base point on a missing base face");
    if (!b.bary.allFinite())  // the frames' point was NaN
      throw InvalidInput("base point " + std::to_string(i) + " has non-finite barycentric coordinates");
  }
}

}  // namespace

void check_encoding(const DetailEncoding& e) {
  // encode_detail() needs faces; an empty encoding is a caller's default-constructed one.
  if (e.detail_faces.empty()) throw InvalidInput("encoding is empty (no detail faces)");
  check_base_part(e);
  const int n = e.num_detail_vertices();
  const std::size_t nf = e.detail_faces.size();
  auto count = [](std::size_t size, std::size_t want, const char* what, const char* per) {
    if (size != want)
      throw InvalidInput("encoding has " + std::to_string(size) + " " + what + " for " +
                         std::to_string(want) + " " + per);
  };
  auto maybe = [&](std::size_t size, const char* what) {  // empty, or one per detail vertex
    if (size != 0) count(size, static_cast<std::size_t>(n), what, "detail vertices");
  };
  const auto nv = static_cast<std::size_t>(n);
  count(e.normal_offsets.size(), nv, "normal offsets", "detail vertices");
  count(e.tangential_offsets.size(), nv, "tangential offsets", "detail vertices");
  count(e.base_rest_points.size(), nv, "rest base points", "detail vertices");
  maybe(e.base_rest_normals.size(), "rest base normals");
  maybe(e.base_rest_tangents.size(), "rest base tangents");
  maybe(e.pinned.size(), "pinned flags");
  count(e.target_volumes.size(), nf, "target volumes", "detail faces");
  for (const Face& f : e.detail_faces)
    for (int v : f)
      if (v < 0 || v >= n) throw InvalidInput("encoding has an out-of-range detail face index");
  // The regularization graph in compressed rows: rows in order, neighbours within the detail.
  count(e.weight_offsets.size(), nv + 1, "weight offsets", "detail vertices plus one");
  const std::vector<int>& off = e.weight_offsets;
  if (off.front() != 0 || off.back() != static_cast<int>(e.weight_neighbors.size()) ||
      !std::is_sorted(off.begin(), off.end()))
    throw InvalidInput("encoding's weight_offsets are not the rows of weight_neighbors (" +
                       std::to_string(e.weight_neighbors.size()) + " entries)");
  count(e.weights.size(), e.weight_neighbors.size(), "weights", "weight_neighbors");
  for (int v : e.weight_neighbors)
    if (v < 0 || v >= n) throw InvalidInput("encoding has an out-of-range index in weight_neighbors");
}

BaseFrames evaluate_base_frames(const DetailEncoding& e, const std::vector<Vec3>& x) {
  if (e.over_limit_surface()) {
    SubdivSurface surface = limit_surface_for(e, x);
    return evaluate_base_frames(e, surface);
  }
  check_base_part(e);
  if (static_cast<int>(x.size()) != e.base_num_vertices)
    throw InvalidInput("edited base has " + std::to_string(x.size()) + " vertices, the encoding's base has " +
                       std::to_string(e.base_num_vertices));
  check_coordinates(x, "edited base");
  // Below the engine's range the normals underflow: a base scaled by 1e-150 was refused as "base
  // face 95 has no normal", one by 1e-21 solved unconverged.
  check_extent(x, e.base_faces, "edited base");
  const std::vector<Vec3> vn = vertex_normals(x, e.base_faces);
  const int n = e.num_detail_vertices();
  BaseFrames fr;
  fr.points.resize(n);
  fr.normals.resize(n);
  fr.tangents.resize(n);
  for (int i = 0; i < n; ++i) {
    const BasePoint& bp = e.base_points[i];
    const Face& F = e.base_faces[bp.face];
    const Vec3 &x0 = x[F[0]], &x1 = x[F[1]], &x2 = x[F[2]];
    fr.points[i] = bp.bary[0] * x0 + bp.bary[1] * x1 + bp.bary[2] * x2;
    Vec3 nrm = bp.bary[0] * vn[F[0]] + bp.bary[1] * vn[F[1]] + bp.bary[2] * vn[F[2]];
    if (!(nrm.norm() > 1e-12)) nrm = triangle_area_normal(x0, x1, x2);
    // A face whose corners coincide or lie on a line, among neighbours as degenerate, has no
    // normal: the frames would be NaN.
    if (!(nrm.norm() > 0))
      throw InvalidInput("base face " + std::to_string(bp.face) + " (under detail vertex " +
                         std::to_string(i) +
                         ") has no normal: its corners and its neighbours' coincide or are collinear");
    nrm.normalize();
    Vec3 t = (x1 - x0) - (x1 - x0).dot(nrm) * nrm;
    if (!(t.norm() > 0.0)) t = nrm.unitOrthogonal();
    fr.normals[i] = nrm;
    fr.tangents[i] = t.normalized();
  }
  return fr;
}

namespace {

// The encoding is over a limit surface whose cage has \p control_points points.
void check_limit_encoding(const DetailEncoding& e, int control_points) {
  if (!e.over_limit_surface())
    throw InvalidInput("the encoding's base is a triangle mesh, not a limit surface");
  check_base_part(e);
  if (control_points != e.base_num_vertices)
    throw InvalidInput("edited cage has " + std::to_string(control_points) +
                       " control points, the encoding's cage has " + std::to_string(e.base_num_vertices));
}

// Unit normals du x dv and tangents du (orthogonalized) from the base points' derivatives.
void limit_frames(const DetailEncoding& e, const SubdivSurface& surface, const std::vector<Vec3>& du,
                  const std::vector<Vec3>& dv, BaseFrames& fr);
// The unit normal du x dv and the tangent du (orthogonalized) of base point i.
void frame_at(const DetailEncoding& e, const SubdivSurface& surface, int i, const Vec3& du, const Vec3& dv,
              Vec3& normal, Vec3& tangent);

}  // namespace

SubdivSurface limit_surface_for(const DetailEncoding& e, const std::vector<Vec3>& control_points) {
  check_limit_encoding(e, static_cast<int>(control_points.size()));
  PolyMesh cage;
  cage.vertices = control_points;
  cage.faces = e.cage_faces;
  return SubdivSurface(cage, e.cage_tags, e.cage_options);
}

BaseFrames evaluate_base_frames(const DetailEncoding& e, const SubdivSurface& surface) {
  check_limit_encoding(e, surface.num_control_points());
  // Exact (double precision) evaluation per point: the encoding's rest frames come from here.
  const int n = e.num_detail_vertices();
  BaseFrames fr;
  fr.points.resize(n);
  std::vector<Vec3> du(n), dv(n);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 1024), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i < r.end(); ++i) {
      const LimitSample x = surface.evaluate(e.limit_points[i]);
      fr.points[i] = x.position;
      du[i] = x.du;
      dv[i] = x.dv;
    }
  });
  limit_frames(e, surface, du, dv, fr);
  return fr;
}

BaseFrames evaluate_base_frames(const DetailEncoding& e, const LimitPointSet& points,
                                const SubdivSurface& surface) {
  check_limit_encoding(e, surface.num_control_points());
  const int n = e.num_detail_vertices();
  if (points.size() != n)
    throw InvalidInput("limit point set has " + std::to_string(points.size()) + " points, the encoding " +
                       std::to_string(n));
  // One pass: each chunk's derivatives stay in small buffers while its frames are made.
  BaseFrames fr;
  fr.points.resize(n);
  fr.normals.resize(n);
  fr.tangents.resize(n);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 4096), [&](const tbb::blocked_range<int>& r) {
    constexpr int kChunk = 256;
    Vec3 du[kChunk], dv[kChunk];
    for (int b = r.begin(); b < r.end(); b += kChunk) {
      const int e_ = std::min(r.end(), b + kChunk);
      points.evaluate(surface, b, e_, fr.points.data() + b, du, dv);
      for (int i = b; i < e_; ++i)
        frame_at(e, surface, i, du[i - b], dv[i - b], fr.normals[i], fr.tangents[i]);
    }
  });
  return fr;
}

namespace {

void frame_at(const DetailEncoding& e, const SubdivSurface& surface, int i, const Vec3& du, const Vec3& dv,
              Vec3& normal, Vec3& tangent) {
  Vec3 nrm = du.cross(dv);
  Vec3 u = du;
  if (!(nrm.norm() > 1e-300)) {
    // A degenerate parameterization at this point (e.g. a valence-2 vertex): the frame of a
    // point nudged towards the ptex face's middle.
    LimitPoint lp = e.limit_points[i];
    const double c = surface.ptex_corners() == 3 ? 1.0 / 3.0 : 0.5;
    lp.u += 1e-7 * (c - lp.u);
    lp.v += 1e-7 * (c - lp.v);
    const LimitSample s2 = surface.evaluate(lp);
    nrm = s2.du.cross(s2.dv);
    u = s2.du;
  }
  // Still none: the surface itself is degenerate there (its cage collapsed to a point or a line
  // around it), as a triangle base's face without a normal. (An arbitrary normal was taken, and a
  // reconstruction over a collapsed cage returned positions without an error.)
  if (!(nrm.norm() > 1e-300))
    throw InvalidInput("base limit point " + std::to_string(i) + " (ptex face " +
                       std::to_string(e.limit_points[i].face) +
                       ") has no normal: the limit surface is degenerate there (its cage points coincide or "
                       "lie on a line around it)");
  nrm.normalize();
  Vec3 t = u - u.dot(nrm) * nrm;
  if (!(t.norm() > 0.0)) t = nrm.unitOrthogonal();
  normal = nrm;
  tangent = t.normalized();
}

void limit_frames(const DetailEncoding& e, const SubdivSurface& surface, const std::vector<Vec3>& du,
                  const std::vector<Vec3>& dv, BaseFrames& fr) {
  const int n = static_cast<int>(du.size());
  fr.normals.resize(n);
  fr.tangents.resize(n);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i < r.end(); ++i)
      frame_at(e, surface, i, du[i], dv[i], fr.normals[i], fr.tangents[i]);
  });
}

}  // namespace

std::vector<Vec3> internal::vectors_unchecked(const DetailEncoding& e, const BaseFrames& fr,
                                              double amplitude) {
  const int n = e.num_detail_vertices();
  std::vector<Vec3> p(n);
  for (int i = 0; i < n; ++i) p[i] = vector_position(e, fr, amplitude, i);
  return p;
}

void internal::check_frame_axes(const BaseFrames& fr, const std::string& what) {
  constexpr double kTol = 1e-6;  // above float frames' rounding (6e-8), far below a wrong frame
  for (std::size_t i = 0; i < fr.normals.size() && i < fr.tangents.size(); ++i) {
    const Vec3 &n = fr.normals[i], &t = fr.tangents[i];
    const char* problem = !(std::abs(n.norm() - 1.0) <= kTol)   ? "the normal is not of unit length"
                          : !(std::abs(t.norm() - 1.0) <= kTol) ? "the tangent is not of unit length"
                          : !(std::abs(n.dot(t)) <= kTol) ? "the normal and the tangent are not orthogonal"
                                                          : nullptr;
    if (problem) throw InvalidInput(what + "base frame " + std::to_string(i) + ": " + problem);
  }
}

std::vector<Vec3> reconstruct_vectors(const DetailEncoding& e, const BaseFrames& fr, double amplitude) {
  check_encoding(e);
  const auto nv = static_cast<std::size_t>(e.num_detail_vertices());
  if (fr.points.size() != nv || fr.normals.size() != nv || fr.tangents.size() != nv)
    throw InvalidInput("reconstruct_vectors: base frames with " + std::to_string(fr.points.size()) +
                       " points, " + std::to_string(fr.normals.size()) + " normals and " +
                       std::to_string(fr.tangents.size()) + " tangents for " + std::to_string(nv) +
                       " detail vertices");
  if (!(std::abs(amplitude) <= kMaxAmplitude)) {
    std::ostringstream m;
    m << "reconstruct_vectors: the amplitude " << amplitude << " is not within +-" << kMaxAmplitude;
    throw InvalidInput(m.str());
  }
  std::vector<Vec3> p = internal::vectors_unchecked(e, fr, amplitude);
  for (std::size_t i = 0; i < nv; ++i)
    if (!p[i].allFinite())
      throw InvalidInput("reconstruct_vectors: detail vertex " + std::to_string(i) +
                         ": its base frame or its offsets are not finite");
  internal::check_frame_axes(fr, "reconstruct_vectors: ");
  return p;
}

std::vector<Vec3> reconstruct_vectors(const DetailEncoding& e, const std::vector<Vec3>& base_vertices) {
  return reconstruct_vectors(e, evaluate_base_frames(e, base_vertices));
}

}  // namespace strata

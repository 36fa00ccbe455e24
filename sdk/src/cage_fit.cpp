#include "strata/cage_fit.h"

#include <tbb/parallel_for.h>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <string>

#include "internal/cage_graph.h"
#include "internal/topology.h"
#include "strata/exceptions.h"
#include "strata/mesh_io.h"
#include "strata/mesh_processing.h"

namespace strata {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

void check_options(const CageFitOptions& o) {
  if (o.faces < 0 || (o.faces > 0 && o.faces < 4))
    throw InvalidInput("cage fit: faces must be 0 (face_fraction chooses) or at least 4");
  if (!(o.face_fraction > 0.0 && o.face_fraction <= 1.0))
    throw InvalidInput("cage fit: face_fraction must lie in (0, 1]");
  if (o.min_faces < 4) throw InvalidInput("cage fit: min_faces must be >= 4");
  // Upper bounds too: 10^7 smoothing steps or 10^5 rounds ran for minutes (Taubin smoothing drifts
  // out of range after about 10^5 steps), and a smoothness of 1e308 failed the solve.
  if (o.smoothing_steps < 0 || o.smoothing_steps > 1000)
    throw InvalidInput("cage fit: smoothing_steps must be within 0-1000");
  if (!(o.smoothness >= 0.0 && o.smoothness <= 1e12))
    throw InvalidInput("cage fit: smoothness must be within 0-1e12");
  if (o.rounds < 1 || o.rounds > 100) throw InvalidInput("cage fit: rounds must be within 1-100");
  // The cage's subdivision options are the caller's: checked here, so that what the fitted cage
  // fails after the decimation is the fit's (a SolverError there), not these.
  if (o.subdiv.isolation_level < 1 || o.subdiv.isolation_level > 10)
    throw InvalidInput("cage fit: subdiv.isolation_level must be within 1-10, not " +
                       std::to_string(o.subdiv.isolation_level));
  if (o.subdiv.max_refined_faces < 0) throw InvalidInput("cage fit: subdiv.max_refined_faces must be >= 0");
  if (o.subdiv.boundary != BoundaryRule::EdgeOnly && o.subdiv.boundary != BoundaryRule::EdgeAndCorner)
    throw InvalidInput("cage fit: subdiv.boundary is not edge-only or edge-and-corner");
}

struct Distances {
  double rms = 0.0, max = 0.0;
};

Distances distances(const SubdivSurface& s, const std::vector<Vec3>& x, const std::vector<LimitPoint>& p) {
  std::vector<double> d(x.size());
  tbb::parallel_for(size_t(0), x.size(), [&](size_t i) { d[i] = (x[i] - s.evaluate(p[i]).position).norm(); });
  Distances r;
  for (double v : d) {
    r.rms += v * v;
    r.max = std::max(r.max, v);
  }
  r.rms = x.empty() ? 0.0 : std::sqrt(r.rms / x.size());
  return r;
}

// Working state of one fit_cage() call: the limit surface of the cage being fitted and the
// fitting targets.
class CageFitter {
 public:
  CageFitter(const PolyMesh& cage, const TriMesh& targets, const CageFitOptions& o)
      : o_(o),
        targets_(targets),
        surface_(cage, {}, loop_options(o.subdiv)),
        decimated_(cage.num_vertices(), 3) {
    // The boundary's smoothness is taken along the boundary, as in the scan's smoothing.
    const Eigen::SparseMatrix<double> L = internal::cage_laplacian(cage, true);
    LtL_ = L.transpose() * L;
    for (int j = 0; j < cage.num_vertices(); ++j) decimated_.row(j) = cage.vertices[j].transpose();
    LtL_decimated_ = LtL_ * decimated_;
  }

  // One round: foot points of the targets on the current limit (each on its own part's: scan
  // debris near the surface, with its own small part of the cage, pulled that part onto the
  // surface), then the cage that minimizes
  //   sum_i |S(p_i; C) - t_i|^2 + mu |L (C - C_0)|^2 + eps |C - C_prev|^2,
  // where S(p_i; C) = w_i^T C is linear in C through the limit stencil w_i and C_0 is the
  // decimated cage. The smoothness term asks for a smooth displacement of the decimated cage
  // rather than a flat cage (|L C|^2 would shrink curved parts). The small eps keeps cage
  // vertices that no target sees at their place.
  void round() {
    const Projection pr = project_mesh_to_limit(surface_, targets_, o_.projection);
    const int m = targets_.num_vertices(), n = surface_.num_control_points();
    std::vector<SubdivSurface::Stencil> st(m);
    tbb::parallel_for(0, m, [&](int i) { st[i] = surface_.stencil(pr.points[i]); });
    std::vector<Eigen::Triplet<double>> t;
    for (int i = 0; i < m; ++i)
      for (size_t k = 0; k < st[i].indices.size(); ++k)
        t.emplace_back(i, st[i].indices[k], st[i].position[k]);
    Eigen::SparseMatrix<double> A(m, n);
    A.setFromTriplets(t.begin(), t.end());
    const double mu = o_.smoothness * static_cast<double>(m) / n, eps = 1e-8 * static_cast<double>(m) / n;
    Eigen::SparseMatrix<double> I(n, n);
    I.setIdentity();
    const Eigen::SparseMatrix<double> At = A.transpose();
    const Eigen::SparseMatrix<double> N = At * A + mu * LtL_ + eps * I;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(N);
    if (ldlt.info() != Eigen::Success) throw SolverError("cage fit: the least-squares system is singular");
    Eigen::MatrixXd T(m, 3), C(n, 3);
    for (int i = 0; i < m; ++i) T.row(i) = targets_.vertices[i].transpose();
    const std::vector<Vec3>& prev = surface_.control_points();
    for (int j = 0; j < n; ++j) C.row(j) = prev[j].transpose();
    const Eigen::MatrixXd X = ldlt.solve(At * T + mu * LtL_decimated_ + eps * C);
    if (ldlt.info() != Eigen::Success || !X.allFinite())
      throw SolverError("cage fit: the least-squares solve failed");
    std::vector<Vec3> next(n);
    for (int j = 0; j < n; ++j) next[j] = X.row(j).transpose();
    surface_.set_control_points(next);
  }

  const SubdivSurface& surface() const { return surface_; }

 private:
  static SubdivOptions loop_options(SubdivOptions s) {
    s.scheme = SubdivScheme::Loop;
    return s;
  }

  const CageFitOptions& o_;
  const TriMesh& targets_;
  SubdivSurface surface_;
  Eigen::MatrixXd decimated_;        // C_0, n x 3
  Eigen::SparseMatrix<double> LtL_;  // L^T L of the cage's Laplacian, fixed over the rounds
  Eigen::MatrixXd LtL_decimated_;    // L^T L C_0
};

}  // namespace

namespace {
// fit_cage() on a scan centred at the origin.
CageFit fit_centred(const TriMesh& scan, const CageFitOptions& options);
}  // namespace

CageFit fit_cage(const TriMesh& scan, const CageFitOptions& options) {
  check_cage_fit_options(options, scan.num_faces());
  validate_mesh(scan, "scan");
  check_coordinates(scan.vertices, "scan");
  check_extent(scan.vertices, scan.faces, "scan");
  // Fitted relative to the centre of the scan's bounding box, then moved back: a scan far from the
  // origin (a georeferenced one, 1e6 away) lost precision in the decimation's quadrics and the
  // fit's solves, and its cage came out other than the one the scan at the origin gets.
  const Vec3 centre = bbox_centre(scan.vertices, scan.faces);
  TriMesh centred = scan;
  for (Vec3& p : centred.vertices) p -= centre;
  CageFit fit = fit_centred(centred, options);
  for (Vec3& p : fit.cage.vertices) p += centre;
  return fit;
}

void check_cage_fit_options(const CageFitOptions& options, int scan_faces) {
  check_options(options);
  // The caller's refinement budget against the cage's ceiling, before the work (the cage's
  // SubdivSurface would refuse it after the decimation, as the fit's failure). The decimation
  // ends within a collapse of the target, so the ceiling of 2 triangles fewer is the cage's or less.
  const int target = default_cage_faces(options, scan_faces);
  const long long ceiling = SubdivSurface::max_refined_faces_ceiling(3LL * std::max(target - 2, 1));
  if (options.subdiv.max_refined_faces > ceiling)
    throw InvalidInput("cage fit: subdiv.max_refined_faces " +
                       std::to_string(options.subdiv.max_refined_faces) +
                       " is above the ceiling of a cage of " + std::to_string(target) + " triangles, " +
                       std::to_string(ceiling) + " (SubdivSurface::max_refined_faces_ceiling())");
}

int default_cage_faces(const CageFitOptions& options, int scan_faces) {
  if (options.faces > 0) return options.faces;
  const int by_fraction =
      std::max(options.min_faces, static_cast<int>(std::lround(options.face_fraction * scan_faces)));
  return std::min(by_fraction, std::max(4, scan_faces / 4));
}

namespace {
CageFit fit_centred(const TriMesh& scan, const CageFitOptions& options) {
  const int target = default_cage_faces(options, scan.num_faces());
  if (target > scan.num_faces())
    throw InvalidInput("cage fit: the scan has " + std::to_string(scan.num_faces()) +
                       " faces, fewer than the cage's " + std::to_string(target));
  CageFit fit;
  auto t0 = Clock::now();
  const std::vector<Vec3> smooth = taubin_smooth(scan, options.smoothing_steps);
  fit.seconds_smooth = seconds_since(t0);
  t0 = Clock::now();
  const TriMesh decimated_mesh = decimate_mesh(TriMesh{smooth, scan.faces}, target);
  PolyMesh decimated;
  decimated.vertices = decimated_mesh.vertices;
  for (const Face& f : decimated_mesh.faces) decimated.faces.push_back({f[0], f[1], f[2]});
  fit.seconds_decimate = seconds_since(t0);

  // The fit's targets are the vertices in faces: a stray point (validate_mesh() allows them) would
  // pull the cage towards itself.
  // Their faces are kept (renumbered) for the projections' parts.
  std::vector<int> used(scan.vertices.size(), -1);
  for (const Face& f : scan.faces)
    for (int v : f) used[v] = 0;
  TriMesh smooth_used, scan_used;
  for (std::size_t i = 0; i < used.size(); ++i)
    if (used[i] == 0) {
      used[i] = smooth_used.num_vertices();
      smooth_used.vertices.push_back(smooth[i]);
      scan_used.vertices.push_back(scan.vertices[i]);
    }
  for (const Face& f : scan.faces) smooth_used.faces.push_back({used[f[0]], used[f[1]], used[f[2]]});
  scan_used.faces = smooth_used.faces;

  t0 = Clock::now();
  // The decimated cage is the fit's own: a cage it cannot subdivide (a vertex of the scan's in
  // over 64 faces survives the decimation) is the fit's failure, not the caller's input.
  std::optional<CageFitter> made;
  try {
    made.emplace(decimated, smooth_used, options);
  } catch (const InvalidInput& e) {
    throw SolverError(std::string("cage fit: the decimation did not reach a valid cage: ") + e.what());
  }
  CageFitter& fitter = *made;
  for (int r = 0; r < options.rounds; ++r) fitter.round();
  fit.rounds = options.rounds;
  const SubdivSurface& s = fitter.surface();
  fit.cage = s.cage();
  fit.cage.vertices = s.control_points();
  const double diag = std::max(bbox_diagonal(scan_used.vertices), 1e-300);
  const Distances target_d =
      distances(s, smooth_used.vertices, project_mesh_to_limit(s, smooth_used, options.projection).points);
  fit.rms_error = target_d.rms / diag;
  fit.max_error = target_d.max / diag;
  const Projection scan_p = project_mesh_to_limit(s, scan_used, options.projection);
  const Distances scan_d = distances(s, scan_used.vertices, scan_p.points);
  fit.scan_rms_distance = scan_d.rms / diag;
  fit.scan_max_distance = scan_d.max / diag;
  fit.scan_fallback = scan_p.num_fallback;
  fit.seconds_fit = seconds_since(t0);
  return fit;
}
}  // namespace

}  // namespace strata

#include "strata/cage_fit.h"

#include <tbb/parallel_for.h>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "internal/cage_graph.h"
#include "internal/topology.h"
#include "strata/exceptions.h"
#include "strata/mesh_io.h"

namespace strata {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct DoubleTraits : public OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
using OMesh = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;

void check_options(const CageFitOptions& o) {
  if (o.faces < 0) throw InvalidInput("cage fit: faces must be >= 0 (0 chooses face_fraction)");
  if (!(o.face_fraction > 0.0 && o.face_fraction <= 1.0))
    throw InvalidInput("cage fit: face_fraction must lie in (0, 1]");
  if (o.min_faces < 4) throw InvalidInput("cage fit: min_faces must be >= 4");
  if (o.smoothing_steps < 0) throw InvalidInput("cage fit: smoothing_steps must be >= 0");
  if (!(o.smoothness >= 0.0) || !std::isfinite(o.smoothness))
    throw InvalidInput("cage fit: smoothness must be finite and >= 0");
  if (o.rounds < 1) throw InvalidInput("cage fit: rounds must be >= 1");
}

// Taubin's lambda|mu smoothing with uniform weights: a low-pass filter that does not shrink the
// surface the way plain Laplacian smoothing does. A boundary vertex averages its boundary
// neighbours only, so open boundaries are smoothed along themselves instead of pulled inwards.
std::vector<Vec3> taubin_smooth(const TriMesh& m, int steps) {
  std::vector<Vec3> x = m.vertices;
  if (steps == 0) return x;
  const internal::Adjacency adj = internal::build_adjacency(m.num_vertices(), m.faces);
  const std::vector<char> boundary = internal::boundary_vertices(m.num_vertices(), m.faces);
  std::vector<Vec3> next(x.size());
  auto pass = [&](double factor) {
    tbb::parallel_for(0, m.num_vertices(), [&](int v) {
      Vec3 sum = Vec3::Zero();
      int n = 0;
      for (int k = adj.neighbor_offsets[v]; k < adj.neighbor_offsets[v + 1]; ++k) {
        const int w = adj.neighbors[k];
        if (boundary[v] && !boundary[w]) continue;
        sum += x[w];
        ++n;
      }
      next[v] = n > 0 ? Vec3(x[v] + factor * (sum / n - x[v])) : x[v];
    });
    x.swap(next);
  };
  for (int s = 0; s < steps; ++s) {
    pass(0.5);
    pass(-0.53);
  }
  return x;
}

// Quadric-error decimation (Garland and Heckbert) of the smoothed scan to about \p target faces,
// refusing collapses that flip a face normal or create slivers.
PolyMesh decimate(const std::vector<Vec3>& positions, const std::vector<Face>& faces, int target) {
  OMesh om;
  std::vector<OMesh::VertexHandle> vh(positions.size());
  for (size_t i = 0; i < positions.size(); ++i)
    vh[i] = om.add_vertex(OMesh::Point(positions[i].x(), positions[i].y(), positions[i].z()));
  // validate_mesh() guarantees manifold edges; a vertex where two fans touch (non-manifold vertex)
  // is rejected by OpenMesh's add_face. The cage only needs to approximate the scan, so such a
  // face is left out of the decimation input (every scan vertex is still a fitting target).
  for (const Face& f : faces) om.add_face(vh[f[0]], vh[f[1]], vh[f[2]]);
  // Unreferenced and isolated vertices would survive as stray cage points.
  for (auto v : om.vertices())
    if (om.is_isolated(v)) om.delete_vertex(v, false);
  // The normal-flipping module needs face normals (OpenMesh prints a warning and computes them).
  om.request_face_normals();
  om.update_face_normals();
  {
    using Decimater = OpenMesh::Decimater::DecimaterT<OMesh>;
    Decimater dec(om);
    OpenMesh::Decimater::ModQuadricT<OMesh>::Handle quadric;
    OpenMesh::Decimater::ModNormalFlippingT<OMesh>::Handle flipping;
    OpenMesh::Decimater::ModAspectRatioT<OMesh>::Handle aspect;
    dec.add(quadric);
    dec.module(quadric).unset_max_err();
    dec.add(flipping);
    dec.module(flipping).set_max_normal_deviation(45.0);
    dec.add(aspect);
    dec.module(aspect).set_aspect_ratio(8.0f);
    dec.module(aspect).set_binary(true);
    if (!dec.initialize()) throw SolverError("cage fit: the decimater could not be initialized");
    dec.decimate_to_faces(0, static_cast<size_t>(target));
    om.garbage_collection();  // while the decimater exists (OpenMesh's note)
  }
  PolyMesh cage;
  cage.vertices.reserve(om.n_vertices());
  for (auto v : om.vertices()) {
    const OMesh::Point& p = om.point(v);
    cage.vertices.emplace_back(p[0], p[1], p[2]);
  }
  cage.faces.reserve(om.n_faces());
  for (auto f : om.faces()) {
    std::vector<int> c;
    for (auto v : om.fv_range(f)) c.push_back(v.idx());
    cage.faces.push_back(std::move(c));
  }
  if (cage.num_faces() < 4) throw SolverError("cage fit: the decimation left fewer than 4 faces");
  return cage;
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
  CageFitter(const PolyMesh& cage, const std::vector<Vec3>& targets, const CageFitOptions& o)
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

  // One round: foot points of the targets on the current limit, then the cage that minimizes
  //   sum_i |S(p_i; C) - t_i|^2 + mu |L (C - C_0)|^2 + eps |C - C_prev|^2,
  // where S(p_i; C) = w_i^T C is linear in C through the limit stencil w_i and C_0 is the
  // decimated cage. The smoothness term asks for a smooth displacement of the decimated cage
  // rather than a flat cage (|L C|^2 would shrink curved parts). The small eps keeps cage
  // vertices that no target sees at their place.
  void round() {
    const Projection pr = project_to_limit(surface_, targets_, o_.projection);
    const int m = static_cast<int>(targets_.size()), n = surface_.num_control_points();
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
    for (int i = 0; i < m; ++i) T.row(i) = targets_[i].transpose();
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
  const std::vector<Vec3>& targets_;
  SubdivSurface surface_;
  Eigen::MatrixXd decimated_;        // C_0, n x 3
  Eigen::SparseMatrix<double> LtL_;  // L^T L of the cage's Laplacian, fixed over the rounds
  Eigen::MatrixXd LtL_decimated_;    // L^T L C_0
};

}  // namespace

CageFit fit_cage(const TriMesh& scan, const CageFitOptions& options) {
  check_options(options);
  validate_mesh(scan, "scan");
  const int target = options.faces > 0
                         ? options.faces
                         : std::max(options.min_faces,
                                    static_cast<int>(std::lround(options.face_fraction * scan.num_faces())));
  if (target > scan.num_faces())
    throw InvalidInput("cage fit: the scan has " + std::to_string(scan.num_faces()) +
                       " faces, fewer than the cage's " + std::to_string(target));
  CageFit fit;
  auto t0 = Clock::now();
  const std::vector<Vec3> smooth = taubin_smooth(scan, options.smoothing_steps);
  fit.seconds_smooth = seconds_since(t0);
  t0 = Clock::now();
  const PolyMesh decimated = decimate(smooth, scan.faces, target);
  fit.seconds_decimate = seconds_since(t0);

  t0 = Clock::now();
  CageFitter fitter(decimated, smooth, options);
  for (int r = 0; r < options.rounds; ++r) fitter.round();
  fit.rounds = options.rounds;
  const SubdivSurface& s = fitter.surface();
  fit.cage = s.cage();
  fit.cage.vertices = s.control_points();
  const double diag = std::max(bbox_diagonal(scan.vertices), 1e-300);
  const Distances target_d = distances(s, smooth, project_to_limit(s, smooth, options.projection).points);
  fit.rms_error = target_d.rms / diag;
  fit.max_error = target_d.max / diag;
  const Projection scan_p = project_to_limit(s, scan.vertices, options.projection);
  const Distances scan_d = distances(s, scan.vertices, scan_p.points);
  fit.scan_rms_distance = scan_d.rms / diag;
  fit.scan_max_distance = scan_d.max / diag;
  fit.scan_fallback = scan_p.num_fallback;
  fit.seconds_fit = seconds_since(t0);
  return fit;
}

}  // namespace strata

// The vertex-space multigrid of the Gauss-Newton volume step (internal/vertex_multigrid.h),
// against a direct (sparse LDL^T) reference solve, and the reconstruction built on it.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>

#include "internal/vertex_multigrid.h"
#include "paper_cases.h"
#include "strata/encoding.h"
#include "strata/intersections.h"
#include "strata/metrics.h"
#include "strata/prism.h"
#include "strata/reconstruction.h"
#include "test_meshes.h"

using namespace strata;

namespace {

// The paper's cylinder case of \p kind at about \p triangles prisms (jitter 0: the regular grid).
cases::CylinderCase cylinder_case(cases::DetailKind kind, int triangles, double jitter) {
  cases::CylinderCaseOptions o;
  o.detail = kind;
  o.target_detail_triangles = triangles;
  o.jitter = jitter;
  return cases::make_cylinder_case(o);
}

// One step's system over a paper case: the prism gradients and residuals of the detail placed by
// displacement vectors over the bent base (a configuration the solver meets), with the encoding's
// regularization neighbours and the vertex -> (face, corner) lists.
struct StepSystem {
  DetailEncoding enc;
  std::vector<std::array<Vec3, 3>> grad;
  std::vector<double> r;
  std::vector<int> vf_offsets, vf;
  std::vector<char> fixed;
  mutable std::vector<float> gf;   // grad in single precision, as the solver takes J
  std::vector<Vec3> base_normals;  // the base normals at the base points (edited base)
  // Optional: the tangential damping's weighted normals and weight (VertexStepSystem::normals).
  std::vector<Eigen::Vector3f> damped_normals;
  double eps_t = 0.0;

  internal::VertexStepSystem view(double eps, double eps_lap) const {
    gf.resize(9 * grad.size());
    for (std::size_t j = 0; j < grad.size(); ++j)
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) gf[9 * j + 3 * c + k] = static_cast<float>(grad[j][c][k]);
    internal::VertexStepSystem s;
    s.faces = &enc.detail_faces;
    s.gf = &gf;
    s.vf_offsets = &vf_offsets;
    s.vf = &vf;
    s.r = &r;
    s.fixed = fixed.empty() ? nullptr : &fixed;
    s.eps = eps;
    s.eps_lap = eps_lap;
    if (!damped_normals.empty()) {
      s.normals = &damped_normals;
      s.eps_tangential = eps_t;
    }
    return s;
  }
  internal::VertexMultigrid hierarchy() const {
    return internal::VertexMultigrid(enc.num_detail_vertices(), enc.detail_faces, enc.weight_offsets,
                                     enc.weight_neighbors, enc.weights);
  }
  // The mean diagonal of J^T J, the scale of eps.
  double diag() const {
    double d = 0.0;
    for (const auto& g : grad) d += g[0].squaredNorm() + g[1].squaredNorm() + g[2].squaredNorm();
    return d / (3.0 * enc.num_detail_vertices());
  }
};

// s's vertex -> (face * 3 + corner) lists, faces ascending.
void vertex_faces(StepSystem& s) {
  const std::vector<Face>& faces = s.enc.detail_faces;
  const int n = s.enc.num_detail_vertices();
  s.vf_offsets.assign(n + 1, 0);
  for (const Face& f : faces)
    for (int v : f) ++s.vf_offsets[v + 1];
  for (int v = 0; v < n; ++v) s.vf_offsets[v + 1] += s.vf_offsets[v];
  s.vf.resize(3 * faces.size());
  std::vector<int> fill(s.vf_offsets.begin(), s.vf_offsets.end() - 1);
  for (std::size_t j = 0; j < faces.size(); ++j)
    for (int k = 0; k < 3; ++k) s.vf[fill[faces[j][k]]++] = static_cast<int>(3 * j) + k;
}

StepSystem make_system(cases::DetailKind kind, int triangles, double jitter) {
  const cases::CylinderCase c = cylinder_case(kind, triangles, jitter);
  StepSystem s;
  s.enc = encode_detail(c.detail, c.base);
  const BaseFrames fr = evaluate_base_frames(s.enc, c.edited_base.vertices);
  const std::vector<Vec3> p = reconstruct_vectors(s.enc, fr);
  const std::vector<Face>& faces = s.enc.detail_faces;
  s.grad.resize(faces.size());
  s.r.resize(faces.size());
  for (std::size_t j = 0; j < faces.size(); ++j) {
    const Face& f = faces[j];
    const PrismVolumeGradient g =
        prism_volume_gradient(p[f[0]], p[f[1]], p[f[2]], fr.points[f[0]], fr.points[f[1]], fr.points[f[2]]);
    for (int k = 0; k < 3; ++k) s.grad[j][k] = g.grad[k];
    s.r[j] = s.enc.target_volumes[j] - g.volume;
  }
  vertex_faces(s);
  s.base_normals = fr.normals;
  return s;
}

// The direct reference: (J^T J + eps I + eps_lap L) delta = J^T r over the free vertices, with J
// rounded to single precision as the solver takes it and L the Laplacian of the symmetrized
// regularization weights, solved by a sparse LDL^T factorization (Eigen's own, not the SDK's
// solvers; a dense one took most of these tests' time under the sanitizers).
std::vector<Vec3> direct_solve(const StepSystem& s, double eps, double eps_lap) {
  const int n = s.enc.num_detail_vertices();
  // Each dof's column among the free ones (-1: fixed).
  std::vector<int> column(3 * n, -1);
  int m = 0;
  for (int v = 0; v < n; ++v)
    if (s.fixed.empty() || !s.fixed[v])
      for (int c = 0; c < 3; ++c) column[3 * v + c] = m++;
  std::vector<Eigen::Triplet<double>> entries;
  auto add = [&](int i, int k, double x) {
    if (column[i] >= 0 && column[k] >= 0) entries.emplace_back(column[i], column[k], x);
  };
  Eigen::VectorXd b = Eigen::VectorXd::Zero(m);
  for (std::size_t j = 0; j < s.grad.size(); ++j) {
    Eigen::Matrix<double, 9, 1> g;
    for (int c = 0; c < 3; ++c) g.segment<3>(3 * c) = s.grad[j][c].cast<float>().cast<double>();
    const Face& f = s.enc.detail_faces[j];
    for (int a = 0; a < 3; ++a) {
      for (int x = 0; x < 3; ++x)
        if (column[3 * f[a] + x] >= 0) b[column[3 * f[a] + x]] += s.r[j] * g[3 * a + x];
      for (int c = 0; c < 3; ++c)
        for (int x = 0; x < 3; ++x)
          for (int y = 0; y < 3; ++y) add(3 * f[a] + x, 3 * f[c] + y, g[3 * a + x] * g[3 * c + y]);
    }
  }
  for (int i = 0; i < 3 * n; ++i) add(i, i, eps);
  // The tangential damping: eps_t (|u|^2 I - u u^T) per vertex.
  if (!s.damped_normals.empty())
    for (int k = 0; k < n; ++k) {
      const Vec3 u = s.damped_normals[k].cast<double>();
      for (int x = 0; x < 3; ++x)
        for (int y = 0; y < 3; ++y)
          add(3 * k + x, 3 * k + y, s.eps_t * ((x == y ? u.squaredNorm() : 0.0) - u[x] * u[y]));
    }
  for (int k = 0; k < n; ++k)
    for (int t = s.enc.weight_offsets[k]; t < s.enc.weight_offsets[k + 1]; ++t) {
      const int l = s.enc.weight_neighbors[t];
      const double w = 0.5 * eps_lap * s.enc.weights[t];  // half of w(k,l); w(l,k) adds the other half
      for (int c = 0; c < 3; ++c) {
        add(3 * k + c, 3 * k + c, w);
        add(3 * l + c, 3 * l + c, w);
        add(3 * k + c, 3 * l + c, -w);
        add(3 * l + c, 3 * k + c, -w);
      }
    }
  Eigen::SparseMatrix<double> K(m, m);
  K.setFromTriplets(entries.begin(), entries.end());  // sums repeated entries
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(K);
  EXPECT_EQ(ldlt.info(), Eigen::Success);
  const Eigen::VectorXd x = ldlt.solve(b);
  std::vector<Vec3> delta(n, Vec3::Zero());
  for (int i = 0; i < 3 * n; ++i)
    if (column[i] >= 0) delta[i / 3][i % 3] = x[column[i]];
  return delta;
}

double relative_difference(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double d = 0.0, s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    d += (a[i] - b[i]).squaredNorm();
    s += b[i].squaredNorm();
  }
  return std::sqrt(d / s);
}

// ||r - J delta|| / ||r|| in double precision.
double linear_residual(const StepSystem& s, const std::vector<Vec3>& delta) {
  double rr = 0.0, r0 = 0.0;
  for (std::size_t j = 0; j < s.grad.size(); ++j) {
    const Face& f = s.enc.detail_faces[j];
    const double e = s.r[j] - (s.grad[j][0].dot(delta[f[0]]) + s.grad[j][1].dot(delta[f[1]]) +
                               s.grad[j][2].dot(delta[f[2]]));
    rr += e * e;
    r0 += s.r[j] * s.r[j];
  }
  return std::sqrt(rr / r0);
}

}  // namespace

// Run to convergence, the preconditioned CG lands on the direct solution of the same system, with
// and without the smoothness term: the hierarchy only preconditions, it does not change the step.
TEST(VertexMultigrid, ConvergesToTheDirectSolutionOfTheDampedStep) {
  const StepSystem s = make_system(cases::DetailKind::Bumps, 1200, 0.4);
  const internal::VertexMultigrid mg = s.hierarchy();
  ASSERT_GE(mg.level_sizes().size(), 2u);
  internal::VertexMultigrid::Workspace ws;
  for (const double lap : {0.0, 1e-2}) {
    const double d = s.diag();
    std::vector<Vec3> delta;
    // (The damped minimizer keeps a residual, so the stopping test never ends this solve early.)
    const internal::VertexStepResult res = mg.solve(s.view(1e-4 * d, lap * d), 0.0, 1000, delta, ws, nullptr);
    const std::vector<Vec3> ref = direct_solve(s, 1e-4 * d, lap * d);
    EXPECT_LT(relative_difference(delta, ref), 1e-6) << "eps_lap " << lap;
    // The reported residual is the true one (up to J's rounding to single precision).
    EXPECT_NEAR(res.relative_residual, linear_residual(s, delta), 1e-5);
  }
}

// The tangential damping (MultigridStepOptions::tangential_damping) is part of the system the
// hierarchy solves: with per-vertex weights (0 on a band of vertices, 1 and values between
// elsewhere) the solve lands on the direct solution of the system with the term, which moves the
// fully weighted vertices less along the base than without it, and the unweighted ones less so.
TEST(VertexMultigrid, TheTangentialDampingIsPartOfTheSolvedSystem) {
  StepSystem s = make_system(cases::DetailKind::Bumps, 1200, 0.4);
  const internal::VertexMultigrid mg = s.hierarchy();
  internal::VertexMultigrid::Workspace ws;
  const double d = s.diag();
  const int n = s.enc.num_detail_vertices();
  std::vector<Vec3> plain;
  mg.solve(s.view(1e-4 * d, 1e-2 * d), 0.0, 1000, plain, ws, nullptr);
  s.damped_normals.resize(n);
  std::vector<double> weight(n);
  for (int k = 0; k < n; ++k) {
    weight[k] = k % 5 == 0 ? 0.0 : (k % 5) / 4.0;  // 0, 0.25, 0.5, 0.75, 1
    s.damped_normals[k] = (std::sqrt(weight[k]) * s.base_normals[k]).cast<float>();
  }
  s.eps_t = 10.0 * d;
  std::vector<Vec3> damped;
  for (const double lap : {0.0, 1e-2}) {  // the products with and without the smoothness term
    mg.solve(s.view(1e-4 * d, lap * d), 0.0, 1000, damped, ws, nullptr);
    EXPECT_LT(relative_difference(damped, direct_solve(s, 1e-4 * d, lap * d)), 1e-6) << "eps_lap " << lap;
  }
  // The tangential motion of the fully weighted vertices shrinks; the normal motion stays.
  auto tangential = [&](const std::vector<Vec3>& delta, double w) {
    double sum = 0.0;
    for (int k = 0; k < n; ++k)
      if (weight[k] == w) sum += (delta[k] - delta[k].dot(s.base_normals[k]) * s.base_normals[k]).norm();
    return sum;
  };
  const double kept1 = tangential(damped, 1.0) / tangential(plain, 1.0);
  const double kept0 = tangential(damped, 0.0) / tangential(plain, 0.0);
  EXPECT_LT(kept1, 0.2);
  // The undamped vertices keep more of theirs (less than all: the smoothness term ties them to
  // their damped neighbours).
  EXPECT_GT(kept0, 2.0 * kept1);
}

namespace {
// Adds to \p s's regularization graph an edge from every 37th vertex to the vertex half the mesh
// away (no face has it: a hand-made encoding's neighbours need not be the 1-ring), weight 0.5.
void add_non_face_edges(StepSystem& s) {
  DetailEncoding& e = s.enc;
  const int n = e.num_detail_vertices();
  std::vector<int> off{0}, nb;
  std::vector<double> w;
  for (int v = 0; v < n; ++v) {
    for (int t = e.weight_offsets[v]; t < e.weight_offsets[v + 1]; ++t) {
      nb.push_back(e.weight_neighbors[t]);
      w.push_back(e.weights[t]);
    }
    if (v % 37 == 0) {
      nb.push_back((v + n / 2) % n);
      w.push_back(0.5);
    }
    off.push_back(static_cast<int>(nb.size()));
  }
  e.weight_offsets = off;
  e.weight_neighbors = nb;
  e.weights = w;
}

// A step on one thread and on three (the threaded product's two passes) is the same to the bit,
// with the V-cycle in double precision (the polish's) as in single (the cycle steps').
void expect_the_same_step_on_one_thread_and_three(const StepSystem& s) {
  const internal::VertexMultigrid mg = s.hierarchy();
  const double d = s.diag();
  tbb::task_arena arena(3);
  for (bool single : {false, true}) {
    SCOPED_TRACE(single ? "single precision" : "double precision");
    std::vector<Vec3> one, three;
    internal::VertexMultigrid::Workspace w1, w3;
    const internal::VertexStepResult r1 =
        mg.solve(s.view(1e-6 * d, 1e-2 * d), 0.0, 8, one, w1, nullptr, single);
    const internal::VertexStepResult r3 =
        mg.solve(s.view(1e-6 * d, 1e-2 * d), 0.0, 8, three, w3, &arena, single);
    EXPECT_EQ(r1.relative_residual, r3.relative_residual);
    ASSERT_EQ(one.size(), three.size());
    for (std::size_t v = 0; v < one.size(); ++v) ASSERT_EQ(one[v], three[v]) << v;
  }
}
}  // namespace

// The smoothness term over a graph with edges that no face has: the product applies the faces'
// edges in its face pass and the others per vertex; together they are the reference's Laplacian,
// and one thread or three give the same step.
TEST(VertexMultigrid, ARegularizationGraphBeyondTheFacesIsAppliedWhole) {
  StepSystem s = make_system(cases::DetailKind::Bumps, 1200, 0.4);
  const double d = s.diag();
  std::vector<Vec3> plain, extra;
  internal::VertexMultigrid::Workspace ws;
  s.hierarchy().solve(s.view(1e-4 * d, 1e-1 * d), 0.0, 1000, plain, ws, nullptr);
  add_non_face_edges(s);
  s.hierarchy().solve(s.view(1e-4 * d, 1e-1 * d), 0.0, 1000, extra, ws, nullptr);
  EXPECT_LT(relative_difference(extra, direct_solve(s, 1e-4 * d, 1e-1 * d)), 1e-6);
  EXPECT_GT(relative_difference(extra, plain), 1e-3);  // the extra edges do change the step

  StepSystem big = make_system(cases::DetailKind::Rings, 20000, 0.4);
  add_non_face_edges(big);
  expect_the_same_step_on_one_thread_and_three(big);
}

// Faces that share an edge with two others (a non-manifold edge) and a face with a repeated
// corner: each graph edge is applied once, on the first face that has it, and a repeated corner's
// "edge" not at all; the step is the reference's.
TEST(VertexMultigrid, AnEdgeOfThreeFacesAndARepeatedCornerKeepTheReferenceStep) {
  StepSystem s = make_system(cases::DetailKind::Bumps, 1200, 0.4);
  const Face f0 = s.enc.detail_faces[0];
  const int far = s.enc.num_detail_vertices() / 2;
  s.enc.detail_faces.push_back({f0[1], f0[0], far});  // a third face on edge (f0[0], f0[1])
  s.enc.detail_faces.push_back({f0[2], f0[2], far});  // a repeated corner
  for (int k = 0; k < 2; ++k) {
    s.grad.push_back({Vec3(0.3, -0.2, 0.1), Vec3(-0.1, 0.4, 0.2), Vec3(0.2, 0.1, -0.3)});
    s.r.push_back(0.01 * (k + 1));
  }
  vertex_faces(s);
  const double d = s.diag();
  std::vector<Vec3> delta;
  internal::VertexMultigrid::Workspace ws;
  s.hierarchy().solve(s.view(1e-4 * d, 1e-1 * d), 0.0, 1000, delta, ws, nullptr);
  EXPECT_LT(relative_difference(delta, direct_solve(s, 1e-4 * d, 1e-1 * d)), 1e-6);
}

// Fixed (pinned) vertices: delta is exactly 0 there, and the rest is the reference solution of
// the free vertices' system.
TEST(VertexMultigrid, FixedVerticesDoNotMove) {
  StepSystem s = make_system(cases::DetailKind::Cuboid, 1200, 0.3);
  const int n = s.enc.num_detail_vertices();
  s.fixed.assign(n, 0);
  for (int v = 0; v < n; v += 3) s.fixed[v] = 1;
  // The encoding zeroes the gradients of fixed corners, as the reconstruction does.
  for (std::size_t j = 0; j < s.grad.size(); ++j)
    for (int c = 0; c < 3; ++c)
      if (s.fixed[s.enc.detail_faces[j][c]]) s.grad[j][c].setZero();
  const internal::VertexMultigrid mg = s.hierarchy();
  internal::VertexMultigrid::Workspace ws;
  const double d = s.diag();
  std::vector<Vec3> delta;
  mg.solve(s.view(1e-4 * d, 1e-2 * d), 0.0, 300, delta, ws, nullptr);
  for (int v = 0; v < n; ++v)
    if (s.fixed[v]) {
      ASSERT_EQ(delta[v], Vec3::Zero()) << v;
    }
  EXPECT_LT(relative_difference(delta, direct_solve(s, 1e-4 * d, 1e-2 * d)), 1e-6);
}

// What the solver is for: on a scan-like (irregular) triangulation of a 20k-prism bend, ten
// iterations lower the linearized volume residual below a tenth (measured: 2-4%).
TEST(VertexMultigrid, TenIterationsLowerAnIrregularBendsResidualTenfold) {
  const StepSystem s = make_system(cases::DetailKind::Bumps, 20000, 0.4);
  const internal::VertexMultigrid mg = s.hierarchy();
  internal::VertexMultigrid::Workspace ws;
  const double d = s.diag();
  std::vector<Vec3> delta;
  const internal::VertexStepResult res = mg.solve(s.view(1e-6 * d, 1e-2 * d), 0.0, 10, delta, ws, nullptr);
  EXPECT_EQ(res.iterations, 10);
  EXPECT_LT(res.relative_residual, 0.1);
  EXPECT_NEAR(res.relative_residual, linear_residual(s, delta), 1e-4);
}

// The V-cycle in single precision (the cycle steps' preconditioner) does the double one's work:
// ten iterations lower the residual as far, up to a few percent, and the conjugate gradients'
// own bookkeeping stays exact (the tracked residual is the true one).
TEST(VertexMultigrid, ASinglePrecisionCycleLowersTheResidualAsFar) {
  const StepSystem s = make_system(cases::DetailKind::Bumps, 20000, 0.4);
  const internal::VertexMultigrid mg = s.hierarchy();
  internal::VertexMultigrid::Workspace w1, w2;
  const double d = s.diag();
  std::vector<Vec3> twice, single;
  const internal::VertexStepResult rd =
      mg.solve(s.view(1e-6 * d, 1e-2 * d), 0.0, 10, twice, w1, nullptr, false);
  const internal::VertexStepResult rs =
      mg.solve(s.view(1e-6 * d, 1e-2 * d), 0.0, 10, single, w2, nullptr, true);
  EXPECT_LT(rs.relative_residual, 0.1);
  EXPECT_NEAR(rs.relative_residual, rd.relative_residual, 0.05 * rd.relative_residual);
  EXPECT_NEAR(rs.relative_residual, linear_residual(s, single), 1e-4);
  EXPECT_NE(single, twice);  // the two preconditioners do differ
}

// The smoother's degree (MultigridStepOptions::smoothing_degree) changes the preconditioner, not
// the step: run to convergence every degree lands on the direct solution; 0 is the hierarchy's
// degree, 2; and in ten iterations degree 1 still lowers the residual of the 20k bend tenfold.
TEST(VertexMultigrid, EverySmoothingDegreeConvergesToTheDirectSolution) {
  const StepSystem s = make_system(cases::DetailKind::Bumps, 1200, 0.4);
  const internal::VertexMultigrid mg = s.hierarchy();
  const double d = s.diag();
  const std::vector<Vec3> ref = direct_solve(s, 1e-4 * d, 1e-2 * d);
  std::vector<std::vector<Vec3>> short_runs;
  for (const int degree : {0, 1, 2, 3}) {
    internal::VertexStepSystem sys = s.view(1e-4 * d, 1e-2 * d);
    sys.smoothing_degree = degree;
    internal::VertexMultigrid::Workspace ws;
    std::vector<Vec3> delta;
    mg.solve(sys, 0.0, 1000, delta, ws, nullptr);
    EXPECT_LT(relative_difference(delta, ref), 1e-6) << "degree " << degree;
    mg.solve(sys, 0.0, 4, delta, ws, nullptr);
    short_runs.push_back(delta);
  }
  EXPECT_EQ(short_runs[0], short_runs[2]);  // 0: the hierarchy's own degree, 2
  EXPECT_NE(short_runs[1], short_runs[2]);
  EXPECT_NE(short_runs[3], short_runs[2]);

  const StepSystem big = make_system(cases::DetailKind::Bumps, 20000, 0.4);
  const internal::VertexMultigrid bmg = big.hierarchy();
  internal::VertexStepSystem sys = big.view(1e-6 * big.diag(), 1e-2 * big.diag());
  sys.smoothing_degree = 1;
  internal::VertexMultigrid::Workspace ws;
  std::vector<Vec3> delta;
  const internal::VertexStepResult res = bmg.solve(sys, 0.0, 10, delta, ws, nullptr, true);
  EXPECT_LT(res.relative_residual, 0.1);
  EXPECT_NEAR(res.relative_residual, linear_residual(big, delta), 1e-4);
}

// Threads change nothing: every sum is taken in one order.
TEST(VertexMultigrid, TheSameStepOnOneThreadAndThree) {
  expect_the_same_step_on_one_thread_and_three(make_system(cases::DetailKind::Rings, 20000, 0.4));
}

namespace {
// The paper's bend of \p kind over a scan-like triangulation (12k prisms) rebuilt with \p ro on
// one thread, checked against the acceptance: converged, max / RMS error, total volume, no
// whole-level factorization (only the polish's local end factorizes, a neighbourhood each), and
// no new intersections where the displacement vectors fold. Returns the solve's statistics.
ReconstructStats expect_a_clean_bend(cases::DetailKind kind, ReconstructOptions ro) {
  const cases::CylinderCase c = cylinder_case(kind, 12000, 0.4);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  ro.threads = 1;
  const ReconstructResult r = VolumeReconstructor(e, ro).reconstruct(c.edited_base.vertices);
  const BaseFrames fr = evaluate_base_frames(e, c.edited_base.vertices);
  const VolumeMetrics m = volume_metrics(e, fr, r.positions);
  EXPECT_TRUE(r.stats.converged);
  EXPECT_LE(m.max_relative_error, 1e-3);
  EXPECT_LE(m.rms_relative_error, 1e-4);
  EXPECT_LT(std::abs(m.total_volume_change), 1e-3);
  EXPECT_EQ(r.stats.factorizations, r.stats.local_factorizations);
  EXPECT_EQ(find_self_intersections(c.detail.vertices, c.detail.faces).num_pairs, 0u);
  EXPECT_EQ(find_self_intersections(r.positions, c.detail.faces).num_pairs, 0u) << c.name;
  EXPECT_GT(find_self_intersections(reconstruct_vectors(e, fr), c.detail.faces).num_pairs, 0u);
  return r.stats;
}
}  // namespace

// The reconstruction on it (multigrid_reconstruct_options()): the paper's bend over a scan-like
// triangulation, to the accuracy of the acceptance, with no new intersections where displacement
// vectors fold, and without one factorization.
class MultigridBend : public ::testing::TestWithParam<cases::DetailKind> {};

TEST_P(MultigridBend, ConvergesWithoutFoldsOrFactorizations) {
  expect_a_clean_bend(GetParam(), multigrid_reconstruct_options());
}

// The paper's schedule (cycle_schedule_reconstruct_options()): every volume scale solves every
// level once, the finest included, and the bends end as the multigrid preset's do.
class CycleScheduleBend : public ::testing::TestWithParam<cases::DetailKind> {};

TEST_P(CycleScheduleBend, EveryScaleSolvesTheFinestLevelWithoutFolds) {
  const ReconstructOptions ro = cycle_schedule_reconstruct_options();
  EXPECT_NO_THROW(check_reconstruct_options(ro));
  EXPECT_EQ(ro.multigrid.smoothing_degree, 1);
  const ReconstructStats st = expect_a_clean_bend(GetParam(), ro);
  ASSERT_EQ(static_cast<int>(st.finest_cycles_per_scale.size()), ro.volume_scales);
  for (int sc = 0; sc + 1 < ro.volume_scales; ++sc) EXPECT_EQ(st.finest_cycles_per_scale[sc], 1) << sc;
  EXPECT_GE(st.finest_cycles_per_scale.back(), 1);
}

INSTANTIATE_TEST_SUITE_P(PaperCases, CycleScheduleBend,
                         ::testing::Values(cases::DetailKind::Bumps, cases::DetailKind::Rings,
                                           cases::DetailKind::Cuboid),
                         [](const auto& info) { return std::string(cases::to_string(info.param)); });

INSTANTIATE_TEST_SUITE_P(PaperCases, MultigridBend,
                         ::testing::Values(cases::DetailKind::Bumps, cases::DetailKind::Rings,
                                           cases::DetailKind::Cuboid),
                         [](const auto& info) { return std::string(cases::to_string(info.param)); });

namespace {
// A clean start over the unedited base returns the detail within 0.5% of its diagonal (the
// acceptance) on the regular cuboid and the scan-like bumps and rings at 20k prisms.
void expect_round_trips_within_half_a_percent(ReconstructOptions ro) {
  ro.threads = 1;
  for (auto [kind, jitter] :
       {std::pair{cases::DetailKind::Cuboid, 0.0}, std::pair{cases::DetailKind::Bumps, 0.4},
        std::pair{cases::DetailKind::Rings, 0.4}}) {
    const cases::CylinderCase c = cylinder_case(kind, 20000, jitter);
    const DetailEncoding e = encode_detail(c.detail, c.base);
    const ReconstructResult r = VolumeReconstructor(e, ro).reconstruct(c.base.vertices);
    EXPECT_TRUE(r.stats.converged) << c.name;
    EXPECT_EQ(static_cast<int>(r.stats.finest_cycles_per_scale.size()), ro.volume_scales);  // clean start
    EXPECT_LE(test::max_distance(r.positions, c.detail.vertices), 0.005 * bbox_diagonal(c.detail.vertices))
        << c.name;
  }
}
}  // namespace

// The preset's clean-start round trip over an unedited base, within the acceptance's 0.5% of the
// diagonal: `strata reconstruct` takes the preset from 80k prisms (--solver auto). Its coarsest
// level, smoothed to convergence with the rest Laplacian, is what brings the detail back.
// Measured at 20k prisms (regular cuboid, scan-like bumps and rings): 0.21 / 0.07 / 0.11%; the
// preset before (rest offsets, 8 sweeps and 2 cycles on the coarsest level, 3 final cycles) came
// back 3.86 / 0.40 / 0.57% off here, and 0.39-1.38% at 100k (sdk/docs/engine-log.md).
TEST(MultigridPreset, UneditedRoundTripWithinHalfAPercentOfTheDiagonal) {
  expect_round_trips_within_half_a_percent(multigrid_reconstruct_options());
}

// The paper's schedule: one cycle a scale and level regularizes no intermediate level, and the
// least-squares volume steps slid the detail over the base; the tangential damping of its
// intermediate scales (MultigridStepOptions::tangential_damping 1) keeps the steps along the base's
// normals. Measured (forty-fifth session): 0.087 / 0.121 / 0.069% here; without the damping
// 2.36 / 1.00 / 1.80%.
TEST(CycleSchedule, UneditedRoundTripWithinHalfAPercentOfTheDiagonal) {
  const ReconstructOptions ro = cycle_schedule_reconstruct_options();
  ASSERT_GT(ro.multigrid.tangential_damping, 0.0);
  expect_round_trips_within_half_a_percent(ro);
}

// The tangential damping spares the vertices where the edit bends the base: on the scan-like 20k
// bumps bend (no fold repair, no retry) the preset's first schedule leaves no intersecting pair,
// where damping every vertex (tangential_damping_bend 1e6) left 153 (measured).
TEST(CycleSchedule, TheTangentialDampingSparesTheBend) {
  const cases::CylinderCase c = cylinder_case(cases::DetailKind::Bumps, 20000, 0.4);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  ReconstructOptions ro = cycle_schedule_reconstruct_options();
  ro.threads = 1;
  ro.fold_repair_rounds = 0;
  ro.retry_on_new_intersections = false;
  auto pairs = [&](double bend) {
    ro.multigrid.tangential_damping_bend = bend;
    const ReconstructResult r = VolumeReconstructor(e, ro).reconstruct(c.edited_base.vertices);
    EXPECT_TRUE(r.stats.converged) << bend;
    return find_self_intersections(r.positions, c.detail.faces).num_pairs;
  };
  ASSERT_EQ(find_self_intersections(c.detail.vertices, c.detail.faces).num_pairs, 0u);
  EXPECT_EQ(pairs(0.1), 0u);
  EXPECT_GT(pairs(1e6), 0u);
}

// The default local_polish_max_motion (0.25% of the diagonal, half the round trip's acceptance)
// keeps the round trip's margin: on the scan-like 30k cuboid the polish ends locally over the
// unedited base, and that local end, allowed up to 0.5%, moved the detail 0.36% of the diagonal
// off (measured); with the default it is undone and the whole-level steps end 0.19% off.
TEST(MultigridPreset, UneditedRoundTripKeepsItsMarginOnTheScanLikeCuboid) {
  const cases::CylinderCase c = cylinder_case(cases::DetailKind::Cuboid, 30000, 0.4);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const double diag = bbox_diagonal(c.detail.vertices);
  ReconstructOptions ro = multigrid_reconstruct_options();
  ro.threads = 1;
  const ReconstructResult r = VolumeReconstructor(e, ro).reconstruct(c.base.vertices);
  ASSERT_TRUE(r.stats.converged);
  EXPECT_GE(r.stats.local_ends_undone, 1);
  EXPECT_LE(test::max_distance(r.positions, c.detail.vertices), 0.0025 * diag);
  ro.local_polish_max_motion = 5e-3;  // the bound before 2026-11-27, eleventh session
  const ReconstructResult wide = VolumeReconstructor(e, ro).reconstruct(c.base.vertices);
  ASSERT_TRUE(wide.stats.converged);
  EXPECT_EQ(wide.stats.local_ends_undone, 0);
  EXPECT_GT(test::max_distance(wide.positions, c.detail.vertices), 0.0025 * diag);
}

// The paper's bumps over a scan-like triangulation (jitter 0.4; 12k prisms unless given), encoded,
// and the base frames of its bend: the local-end tests' cases.
namespace {
struct ScanLikeBumps {
  explicit ScanLikeBumps(int triangles = 12000)
      : c(cylinder_case(cases::DetailKind::Bumps, triangles, 0.4)),
        e(encode_detail(c.detail, c.base)),
        fr(evaluate_base_frames(e, c.edited_base.vertices)) {}
  cases::CylinderCase c;
  DetailEncoding e;
  BaseFrames fr;
};

// ReconstructOptions::local_polish_max_motion: a local end whose rounds move a vertex farther than
// the bound, and farther than the polish's last whole-level step moved any vertex, is undone, and
// the whole-level steps finish the polish. The bound was made for a regular 60k cuboid whose local
// end rippled a patch over the unedited base (0.61% of the diagonal off); since the decimation's
// order changed (2026-11-27, tenth session) no regular cuboid of 20k-110k prisms ripples, so the
// contract is checked with a bound that any motion exceeds, on the 20k scan-like cuboid's round
// trip, where the polish ends locally before any whole-level step (measured: 1 local end, which
// moved 0.10% of the diagonal).
TEST(MultigridPreset, ALocalEndThatMovesTooFarIsUndone) {
  const cases::CylinderCase c = cylinder_case(cases::DetailKind::Cuboid, 20000, 0.4);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  ReconstructOptions ro = multigrid_reconstruct_options();
  ro.threads = 1;
  // Every coarse level solved at the intermediate scales, as the preset did when this case was
  // measured: with the second-finest level regularized only there (the preset since 2026-11-28,
  // twenty-first session) this round trip's local ends move farther and are undone by the default
  // bound too (0.278% of the diagonal off in the end, against 0.157%).
  ro.intermediate_regularized_levels = 0;
  const ReconstructResult kept = VolumeReconstructor(e, ro).reconstruct(c.base.vertices);
  ASSERT_TRUE(kept.stats.converged);
  EXPECT_GE(kept.stats.local_ends, 1);
  EXPECT_EQ(kept.stats.local_ends_undone, 0);
  ro.local_polish_max_motion = 1e-9;  // of the diagonal: any motion at all
  const ReconstructResult r = VolumeReconstructor(e, ro).reconstruct(c.base.vertices);
  ASSERT_TRUE(r.stats.converged);
  EXPECT_GE(r.stats.local_ends, 1);
  EXPECT_EQ(r.stats.local_ends_undone, r.stats.local_ends);
  const BaseFrames fr = evaluate_base_frames(e, c.base.vertices);
  const VolumeMetrics m = volume_metrics(e, fr, r.positions);
  EXPECT_LE(m.max_relative_error, ro.tolerance * (1 + 1e-9));
  EXPECT_NEAR(r.stats.max_relative_error, m.max_relative_error, 1e-9 * ro.tolerance);
  EXPECT_EQ(r.stats.new_intersecting_pairs, 0);
  EXPECT_LE(test::max_distance(r.positions, c.detail.vertices), 5e-3 * bbox_diagonal(c.detail.vertices));
}

// ... but a local end that moves no farther than the whole-level step before it is kept, whatever
// the bound: it stands in for more such steps. On the 12k scan-like bumps bend the second
// whole-level step moved a vertex 0.68% of the diagonal and the local end after it 0.35%
// (measured; with the bound alone, as before 2026-11-27, eleventh session, it was undone).
TEST(MultigridPreset, ALocalEndMovingLessThanTheWholeLevelStepIsKept) {
  const ScanLikeBumps b;
  ReconstructOptions ro = multigrid_reconstruct_options();
  ro.threads = 1;
  ro.local_polish_max_motion = 1e-9;
  const ReconstructResult r = VolumeReconstructor(b.e, ro).reconstruct(b.c.edited_base.vertices);
  ASSERT_TRUE(r.stats.converged);
  EXPECT_GE(r.stats.local_ends, 1);
  EXPECT_EQ(r.stats.local_ends_undone, 0);
  const VolumeMetrics m = volume_metrics(b.e, b.fr, r.positions);
  EXPECT_LE(m.max_relative_error, ro.tolerance * (1 + 1e-9));
  EXPECT_EQ(r.stats.new_intersecting_pairs, 0);
  EXPECT_EQ(find_self_intersections(r.positions, b.c.detail.faces).num_pairs, 0u);
}

// The paper's cuboid over its regular triangulation, at about \p triangles prisms, encoded: the
// cases where the preset's polish stalls or its first attempt folds.
struct RegularCuboid {
  explicit RegularCuboid(int triangles)
      : c(cylinder_case(cases::DetailKind::Cuboid, triangles, 0.0)), e(encode_detail(c.detail, c.base)) {}
  cases::CylinderCase c;
  DetailEncoding e;
};
}  // namespace

// ReconstructOptions::finest_intermediate_solves (the preset: false): the intermediate volume
// scales solve the coarse levels only, the finest level's volumes are solved at the full scale
// alone, with fewer volume constraints visited, and the bend still ends converged without new
// pairs. With true every scale solves the finest level.
TEST(MultigridBend, TheFinestLevelIsSolvedAtTheFullScaleOnly) {
  const ScanLikeBumps b;
  ReconstructOptions coarse = multigrid_reconstruct_options();
  ASSERT_FALSE(coarse.finest_intermediate_solves);
  ReconstructOptions every = coarse;
  every.finest_intermediate_solves = true;
  const ReconstructResult rc = VolumeReconstructor(b.e, coarse).reconstruct(b.c.edited_base.vertices);
  const ReconstructResult re = VolumeReconstructor(b.e, every).reconstruct(b.c.edited_base.vertices);
  ASSERT_EQ(static_cast<int>(rc.stats.finest_cycles_per_scale.size()), coarse.volume_scales);
  ASSERT_EQ(static_cast<int>(re.stats.finest_cycles_per_scale.size()), coarse.volume_scales);
  for (int sc = 0; sc < coarse.volume_scales; ++sc) {
    EXPECT_EQ(rc.stats.finest_cycles_per_scale[sc] > 0, sc + 1 == coarse.volume_scales) << sc;
    EXPECT_GT(re.stats.finest_cycles_per_scale[sc], 0) << sc;
  }
  EXPECT_LT(rc.stats.constraint_updates, re.stats.constraint_updates);
  for (const ReconstructResult* r : {&rc, &re}) {
    EXPECT_TRUE(r->stats.converged);
    EXPECT_LE(volume_metrics(b.e, b.fr, r->positions).max_relative_error, coarse.tolerance * (1 + 1e-9));
    EXPECT_EQ(find_self_intersections(r->positions, b.c.detail.faces).num_pairs, 0u);
  }
}

// The polish's local end (local_polish_max_fraction): once few prisms are off, only their
// neighbourhoods move, by small factorized steps, where whole-level steps each take a multigrid
// solve. Every prism still meets the tolerance, with fewer conjugate-gradient iterations than the
// whole-level polish, and no new intersecting pairs.
TEST(MultigridBend, ThePolishsLocalEndMeetsTheToleranceWithFewerIterations) {
  const ScanLikeBumps b;
  const cases::CylinderCase& c = b.c;
  const DetailEncoding& e = b.e;
  const BaseFrames& fr = b.fr;
  ReconstructOptions whole = multigrid_reconstruct_options();
  whole.threads = 1;
  whole.local_polish_max_fraction = 0.0;
  ReconstructOptions local = whole;
  local.local_polish_max_fraction = multigrid_reconstruct_options().local_polish_max_fraction;
  ASSERT_GT(local.local_polish_max_fraction, 0.0);
  const ReconstructResult rw = VolumeReconstructor(e, whole).reconstruct(c.edited_base.vertices);
  EXPECT_EQ(rw.stats.local_factorizations, 0);
  // A local end's result: only local factorizations, fewer iterations than \p than, every prism
  // within the tolerance, no new pairs.
  auto expect_local_end = [&](const ReconstructResult& r, const ReconstructResult& than) {
    EXPECT_GT(r.stats.local_factorizations, 0);
    EXPECT_EQ(r.stats.factorizations, r.stats.local_factorizations);
    EXPECT_LT(r.stats.cg_iterations, than.stats.cg_iterations);
    EXPECT_TRUE(r.stats.converged);
    EXPECT_LE(volume_metrics(e, fr, r.positions).max_relative_error, local.tolerance * (1 + 1e-9));
    EXPECT_EQ(find_self_intersections(r.positions, c.detail.faces).num_pairs, 0u);
  };
  const ReconstructResult rl = VolumeReconstructor(e, local).reconstruct(c.edited_base.vertices);
  expect_local_end(rl, rw);
  // With no limit the whole polish is local from its start: its first system spans most of the
  // level (measured: 11,646 prisms, above kSupernodalMinPrisms, so CHOLMOD's supernodal
  // factorization), the later rounds only the prisms still above the tolerance (7,415, 2,451, 818).
  ReconstructOptions all_local = whole;
  all_local.local_polish_max_fraction = 1.0;
  expect_local_end(VolumeReconstructor(e, all_local).reconstruct(c.edited_base.vertices), rl);
}

// The local end's contract under options that push it: every round's system within
// local_polish_max_fraction of the level (max_local_end_prisms counts them all, not only the
// first), and a local end that does not reach the tolerance in max_final_steps rounds is undone, the
// whole-level steps going on from the positions before it. Every run converges without new pairs,
// and the error the solver reports is the one of the positions it returns.
TEST(MultigridBend, LocalEndsStayWithinTheirLimitAndAreUndoneWhenTheyFail) {
  // The branches below depend on the case (and on the hierarchy's coarse levels): since the
  // decimation's order changed (2026-11-27, tenth session) the 12k bend reaches neither a local end
  // at the 0.02 limit nor an undone one-round end, the 11k bend reaches all but the latter, and the
  // 14k bend reaches that one.
  const ScanLikeBumps b(11000), b14(14000);
  auto run = [&](const ReconstructOptions& ro, const ScanLikeBumps& sb) {
    const ReconstructResult r = VolumeReconstructor(sb.e, ro).reconstruct(sb.c.edited_base.vertices);
    const VolumeMetrics m = volume_metrics(sb.e, sb.fr, r.positions);
    EXPECT_TRUE(r.stats.converged);
    EXPECT_LE(m.max_relative_error, ro.tolerance * (1 + 1e-9));
    EXPECT_NEAR(r.stats.max_relative_error, m.max_relative_error, 1e-9 * ro.tolerance);
    EXPECT_EQ(find_self_intersections(r.positions, sb.c.detail.faces).num_pairs, 0u);
    EXPECT_LE(r.stats.local_ends_undone, r.stats.local_ends);
    return r.stats;
  };
  const double prisms = static_cast<double>(b.c.detail.faces.size());
  // The preset before the rest Laplacian, whose polish the counts below were measured on: the
  // contract does not depend on it, but which branches a case reaches does (with the current
  // preset no local end happens at the 0.02 limit and none is undone).
  ReconstructOptions base = test::rest_offset_multigrid_preset();
  base.threads = 1;
  for (double fraction : {0.02, 0.2, 1.0}) {
    SCOPED_TRACE(fraction);
    ReconstructOptions ro = base;
    ro.local_polish_max_fraction = fraction;
    const ReconstructStats st = run(ro, b);
    EXPECT_GE(st.local_ends, 1);
    EXPECT_GT(st.max_local_end_prisms, 0);
    EXPECT_LE(static_cast<double>(st.max_local_end_prisms), fraction * prisms);
  }
  // One round a local end (measured on the 14k bend: 2 local ends, both undone, 2 local and 5
  // factorizations in all): undone, and the factorized whole-level steps finish.
  ReconstructOptions one_round = base;
  one_round.max_final_steps = 1;
  one_round.max_factorized_steps = 1;  // as measured, before the two were apart
  const ReconstructStats st1 = run(one_round, b14);
  EXPECT_GE(st1.local_ends_undone, 1);
  EXPECT_GE(st1.local_factorizations, 1);
  EXPECT_GT(st1.factorizations, st1.local_factorizations);
  // Without rings around the off prisms, the first local end fails and is undone, not after all
  // max_final_steps rounds (measured on the 11k bend: after one round, its second round's system
  // being over the limit; on the 12k bend before the decimation's order changed, after two rounds
  // without fewer prisms off); a later one, tried once the whole-level steps have halved the off
  // prisms, finishes (2 local ends, 2 local factorizations in all).
  ReconstructOptions no_rings = base;
  no_rings.local_polish_rings = 0;
  const ReconstructStats st0 = run(no_rings, b);
  EXPECT_GE(st0.local_ends_undone, 1);
  EXPECT_GT(st0.local_ends, st0.local_ends_undone);
  EXPECT_EQ(st0.factorizations, st0.local_factorizations);
  EXPECT_LT(st0.local_factorizations, no_rings.max_final_steps);
  // The stall rule alone: with no size limit (fraction 1), no motion bound and no rings, a local
  // end that leaves as many prisms off two rounds in a row is undone before max_final_steps rounds
  // (measured on the 11k bend: 4 local ends, 3 undone, 23 local factorizations in all). Each round
  // is one local factorization, so fewer of them than undone ends times max_final_steps means that
  // some undone end stopped early, which nothing but the stall rule does here.
  ReconstructOptions stall = no_rings;
  stall.local_polish_max_fraction = 1.0;
  stall.local_polish_max_motion = 0.0;
  const ReconstructStats sts = run(stall, b);
  ASSERT_GE(sts.local_ends_undone, 1);
  EXPECT_LT(sts.local_factorizations, sts.local_ends_undone * stall.max_final_steps);
}

// A multigrid polish that ends above the tolerance (its linear solves leave what the hierarchy does
// not represent, as a regular grid's checkerboard modes) is finished by whole-level factorized
// steps. Since the rest Laplacian and the local end, the preset's polish no longer stalls on the
// paper's regular bends at 2k-20k prisms (their factorizations are the fold repair's and the local
// end's), so the stall is made here: one conjugate-gradient iteration per polish step, no local
// end. Measured on the regular 2k cuboid: the 10 multigrid steps end above the tolerance, then 4
// factorized steps converge, without new pairs; with the preset's 25 iterations no factorization.
TEST(MultigridBend, AStalledPolishIsFinishedByFactorizedSteps) {
  const RegularCuboid b(2000);
  const cases::CylinderCase& c = b.c;
  const DetailEncoding& e = b.e;
  ReconstructOptions ro = multigrid_reconstruct_options();
  ro.threads = 1;
  ro.local_polish_max_fraction = 0.0;
  const ReconstructResult full = VolumeReconstructor(e, ro).reconstruct(c.edited_base.vertices);
  ASSERT_TRUE(full.stats.converged);
  ASSERT_EQ(full.stats.factorizations, 0);  // the control: this polish does not stall
  ro.multigrid.polish_iterations = 1;
  const ReconstructResult r = VolumeReconstructor(e, ro).reconstruct(c.edited_base.vertices);
  EXPECT_TRUE(r.stats.converged);
  EXPECT_GT(r.stats.factorizations, 0);
  EXPECT_EQ(r.stats.local_factorizations, 0);  // whole-level steps, not a local end or a repair
  EXPECT_EQ(r.stats.fold_repairs, 0);
  EXPECT_GT(r.stats.final_sweeps, ro.max_final_steps);  // the multigrid steps all ran first
  const VolumeMetrics m = volume_metrics(e, evaluate_base_frames(e, c.edited_base.vertices), r.positions);
  EXPECT_LE(m.max_relative_error, ro.tolerance * (1 + 1e-9));
  EXPECT_EQ(find_self_intersections(r.positions, c.detail.faces).num_pairs, 0u);
  // The factorized steps are at most max_factorized_steps: one fewer than this solve took, and
  // without the retries, it ends unconverged after exactly that many.
  const int taken = r.stats.factorizations;
  ASSERT_GE(taken, 2);
  ReconstructOptions capped = ro;
  capped.max_factorized_steps = taken - 1;
  capped.retry_volume_iterations = 0;
  capped.retry_other_regularization = false;
  capped.fallback_schedule = false;
  capped.multigrid.retry_iterations = 0;
  const ReconstructResult short_of = VolumeReconstructor(e, capped).reconstruct(c.edited_base.vertices);
  EXPECT_FALSE(short_of.stats.converged);
  EXPECT_EQ(short_of.stats.factorizations - short_of.stats.local_factorizations, taken - 1);
  EXPECT_EQ(short_of.stats.retries, 0);
  // And they are not capped by max_final_steps (as they were before 2026-11-29): with 1 polish
  // step and no retries, the factorized steps still finish the solve, taking more than 1.
  ReconstructOptions one_step = capped;
  one_step.max_factorized_steps = ReconstructOptions{}.max_factorized_steps;
  one_step.max_final_steps = 1;
  const ReconstructResult past = VolumeReconstructor(e, one_step).reconstruct(c.edited_base.vertices);
  EXPECT_TRUE(past.stats.converged);
  EXPECT_GT(past.stats.factorizations - past.stats.local_factorizations, one_step.max_final_steps);
  EXPECT_EQ(past.stats.retries, 0);
}

// ReconstructOptions::retry_other_regularization: a preset solve that folds is retried with the
// rest offsets on the same hierarchy, and that retry is exactly the rest offsets' own solve. The
// regular 3k cuboid, without repair rounds or the other retries (measured: the rest Laplacian
// leaves 10 new pairs, the rest offsets none), and without the polish's smoothness term, with
// which the rest Laplacian's solve does not fold here.
TEST(MultigridPreset, AFoldedSolveIsRetriedWithTheRestOffsets) {
  const RegularCuboid b(3000);
  const cases::CylinderCase& c = b.c;
  const DetailEncoding& e = b.e;
  ASSERT_EQ(find_self_intersections(c.detail.vertices, c.detail.faces).num_pairs, 0u);
  ReconstructOptions ro = test::without_polish_smoothness(multigrid_reconstruct_options());
  ro.threads = 1;
  ro.fold_repair_rounds = 0;
  ro.retry_volume_iterations = 0;
  ro.multigrid.retry_iterations = 0;
  ro.fallback_schedule = false;
  // The schedule this case folds with under the rest Laplacian alone (without the finest level's
  // intermediate solves both regularizations leave pairs here, for the repair rounds).
  ro.finest_intermediate_solves = true;
  ASSERT_TRUE(ro.retry_other_regularization);  // the default
  ReconstructOptions off = ro;
  off.retry_other_regularization = false;
  const ReconstructResult folded = VolumeReconstructor(e, off).reconstruct(c.edited_base.vertices);
  EXPECT_TRUE(folded.stats.converged);
  EXPECT_EQ(folded.stats.retries, 0);
  EXPECT_GT(folded.stats.new_intersecting_pairs, 0);  // the case: the rest Laplacian folds it
  const ReconstructResult r = VolumeReconstructor(e, ro).reconstruct(c.edited_base.vertices);
  EXPECT_EQ(r.stats.retries, 1);
  EXPECT_TRUE(r.stats.converged);
  EXPECT_EQ(r.stats.new_intersecting_pairs, 0);
  EXPECT_EQ(find_self_intersections(r.positions, c.detail.faces).num_pairs, 0u);
  ReconstructOptions offsets = ro;
  offsets.tangential_regularization = TangentialRegularization::RestOffset;
  const ReconstructResult theirs = VolumeReconstructor(e, offsets).reconstruct(c.edited_base.vertices);
  EXPECT_EQ(theirs.stats.retries, 0);
  EXPECT_EQ(r.positions, theirs.positions);
}

// The rest Laplacian under a band's amplitude a (ReconstructRequest::amplitude): its c_i is the
// blend (1 - a) Lap(q) + a Lap(p) of the base points' and the detail's rest Laplacians, the
// tangential Laplacian of the scaled detail q + a (p - q). Over the unedited base its clean start
// converges without new pairs, the detail's height scales with a, and it comes back near where the
// rest offsets' does (which scales the offsets), for damped and exaggerated detail. (Not to the
// scaled detail itself: over a curved base a prism's volume is not linear in its height.)
TEST(MultigridPreset, AnAmplitudeScalesTheRestLaplacianAsTheRestOffsets) {
  const ScanLikeBumps b;
  const cases::CylinderCase& c = b.c;
  const DetailEncoding& e = b.e;
  ReconstructOptions lap = multigrid_reconstruct_options();
  lap.threads = 1;
  ASSERT_EQ(lap.tangential_regularization, TangentialRegularization::RestLaplacian);
  ReconstructOptions off = test::rest_offset_multigrid_preset();
  off.threads = 1;
  const VolumeReconstructor rl(e, lap), ro(e, off);
  const double diag = bbox_diagonal(c.detail.vertices);
  for (double a : {0.5, 2.0}) {
    ReconstructRequest req;
    req.amplitude = a;
    const ReconstructResult r = rl.reconstruct(c.base.vertices, req);
    const ReconstructResult s = ro.reconstruct(c.base.vertices, req);
    EXPECT_TRUE(r.stats.converged) << "amplitude " << a;
    EXPECT_TRUE(s.stats.converged) << "amplitude " << a;
    EXPECT_EQ(r.stats.new_intersecting_pairs, 0) << "amplitude " << a;
    // The RMS displacement from the base points, relative to the rest detail's (measured 0.54 and
    // 1.78: on the cylinder a prism's volume grows faster than its height).
    double d2 = 0.0, r2 = 0.0;
    for (std::size_t i = 0; i < r.positions.size(); ++i) {
      d2 += (r.positions[i] - e.base_rest_points[i]).squaredNorm();
      r2 += (e.detail_rest[i] - e.base_rest_points[i]).squaredNorm();
    }
    EXPECT_NEAR(std::sqrt(d2 / r2), a, 0.15 * a) << "amplitude " << a;
    // Measured: 0.13% and 1.19% of the diagonal apart.
    EXPECT_LE(test::max_distance(r.positions, s.positions), 0.02 * diag) << "amplitude " << a;
  }
}

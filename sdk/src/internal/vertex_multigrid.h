// Internal: the Gauss-Newton volume step as a least-squares problem over the detail vertices,
// solved by conjugate gradients preconditioned with an aggregation multigrid. Not part of the API.
//
// Why vertex space: the prism-space system (J J^T) y = r of the minimum-norm step has near-null
// modes, volume patterns that no small vertex motion makes (on a regular triangulation, the
// checkerboard of up and down triangles times any smooth envelope, as the pressure modes of P1/P0
// Stokes elements), so Jacobi-preconditioned CG barely lowers its residual at 100k prisms. The
// vertex-space system (J^T J + eps I + eps_lap L) delta = J^T r solves the same linearized volume
// equations; its slow error is smooth vertex motion, which an aggregation hierarchy of the
// vertex graph represents. On irregular triangulations (scans) ten preconditioned iterations
// lower the linearized residual 15-50 times (the 100k and 1M bends); on regular ones the
// checkerboard modes stay slow.
// The smoothness term eps_lap L (L the graph Laplacian of the regularization weights) makes the
// part of delta that the volumes do not determine smooth, where eps I alone would let the
// preconditioner leave rough motion there.
#pragma once

#include <tbb/task_arena.h>

#include <Eigen/Dense>
#include <array>
#include <atomic>
#include <vector>

#include "strata/mesh.h"

namespace strata::internal {

//! Options of the hierarchy and its smoother (internal defaults, measured on the paper's bends).
struct VertexMultigridOptions {
  //! Aggregation stops when a level has at most this many vertices (solved densely).
  int max_coarse_vertices = 48;
  //! Levels at most, the fine level included.
  int max_levels = 12;
  //! Degree of the Chebyshev block-Jacobi smoother, before and after the coarse correction. On the
  //! 100k bends, degree 2 took 7.8 s of CPU for the three cases against 8.8 s for degree 1.
  int smoothing_degree = 2;
  //! The smoother damps the part of D^-1 K's spectrum in [bound / ratio, bound]; bound = 3 bounds
  //! it, since each prism adds a rank-one term over three vertex blocks (and L <= 2 diag(L)).
  double smoothing_ratio = 20.0;
};

//! One Gauss-Newton step's least-squares system over a mesh level.
struct VertexStepSystem {
  const std::vector<Face>* faces = nullptr;  //!< in the level's vertex ids
  //! J in single precision: per face, the volume gradient at each corner (9 floats, corner by
  //! corner; zero at the corners of fixed vertices).
  const std::vector<float>* gf = nullptr;
  //! Vertex -> its (face * 3 + corner) entries, faces ascending, in CSR form.
  const std::vector<int>* vf_offsets = nullptr;
  const std::vector<int>* vf = nullptr;
  const std::vector<double>* r = nullptr;    //!< per face, the volume residual target - volume
  const std::vector<char>* fixed = nullptr;  //!< optional: vertices whose delta is 0
  double eps = 0.0;                          //!< > 0: weight of ||delta||^2 (Levenberg-Marquardt)
  double eps_lap = 0.0;                      //!< >= 0: weight of the smoothness term delta^T L delta
  //! Optional, with eps_tangential > 0: per vertex a normal u = sqrt(w) n (n a unit normal, w >= 0
  //! the vertex's weight); the term eps_tangential delta_v^T (|u|^2 I - u u^T) delta_v =
  //! eps_tangential w ||(I - n n^T) delta_v||^2 penalizes the tangential part of each step
  //! (ReconstructOptions' MultigridStepOptions::tangential_damping).
  //! (Single precision: read in every product, where the damping needs a few digits.)
  const std::vector<Eigen::Vector3f>* normals = nullptr;
  double eps_tangential = 0.0;
  //! > 0: the Chebyshev smoother's degree in this solve's V-cycles (0: the hierarchy's
  //! VertexMultigridOptions::smoothing_degree).
  int smoothing_degree = 0;
  //! Optional: once it reads true the iterations stop (ReconstructOptions::cancel; the caller
  //! then throws without using the step).
  const std::atomic<bool>* stop = nullptr;
};

//! Outcome of one solve.
struct VertexStepResult {
  int iterations = 0;              //!< conjugate-gradient iterations
  double relative_residual = 1.0;  //!< ||r - J delta|| / ||r|| at the end (0 if r = 0)
};

//! The aggregation hierarchy of one mesh level's vertex graph, built once from its faces and
//! regularization neighbours, and the step solve over it. The coarse operators are Galerkin
//! products of the current J^T J + eps I + eps_lap L, formed in every solve from the prism
//! gradients; their patterns are fixed here.
class VertexMultigrid {
 public:
  //! \p faces in vertex ids [0, num_vertices). \p nb_offsets, \p nb, \p weights: each vertex's
  //! regularization neighbours and weights (not necessarily symmetric); the smoothness term uses
  //! the graph Laplacian of the symmetrized weights (w(k,l) + w(l,k)) / 2, per coordinate.
  VertexMultigrid(int num_vertices, const std::vector<Face>& faces, const std::vector<int>& nb_offsets,
                  const std::vector<int>& nb, const std::vector<double>& weights,
                  const VertexMultigridOptions& options = {});

  //! Per-solve working arrays; one per thread of control, reused across solves and levels.
  struct Workspace;

  //! Finds delta (one entry per vertex) approximately minimizing
  //! ||J delta - r||^2 + eps ||delta||^2 + eps_lap delta^T L delta, with delta = 0 on fixed
  //! vertices, by preconditioned CG from delta = 0, stopping once ||r - J delta|| <= tolerance ||r||
  //! or after max_iterations. J is taken in single precision (the step needs a few digits; the
  //! volumes it is judged by are double). \p arena: threads of the per-vertex and per-face loops
  //! (null: the calling thread); every sum is taken in one order, so the result does not depend on
  //! it. \p single_precision_cycle: the V-cycle's vectors and the conjugate gradients around it in
  //! single precision, their sums in double (faster; for the inexact steps, not for nearly
  //! singular systems, whose solves then stall).
  //! \pre the system's arrays match this hierarchy's vertex and face counts; eps > 0.
  VertexStepResult solve(const VertexStepSystem& system, double tolerance, int max_iterations,
                         std::vector<Vec3>& delta, Workspace& ws, tbb::task_arena* arena,
                         bool single_precision_cycle = false) const;

  //! Vertex counts per level, finest first.
  std::vector<int> level_sizes() const;

 private:
  struct Coarse {
    int n = 0;                        // block rows
    std::vector<int> row, col;        // block CSR pattern (symmetric, columns ascending)
    std::vector<int> diag;            // slot of each row's diagonal block
    std::vector<int> agg;             // rows -> next coarser level's rows (not on the coarsest)
    std::vector<int> to_coarse_slot;  // each block -> its block on the next coarser level
  };
  int n0_ = 0;
  // The smoothness term (the graph Laplacian of the symmetrized weights): its diagonal per fine
  // vertex, and per face the weights of its edges (f0,f1), (f1,f2), (f2,f0), each graph edge on
  // the first face that has it and 0 on the others, so that a fine product's face pass applies
  // it from the corners it reads anyway. A pass over neighbour lists was a third of the
  // product's memory traffic at 1M prisms. The graph's edges that no face has (a hand-made
  // encoding's) are kept per vertex (rest_*), with their level-1 blocks.
  std::vector<double> lap_diag_;
  std::vector<float> face_lap_w_;
  std::vector<int> rest_offsets_, rest_nb_, rest_slot_;
  std::vector<double> rest_w_;
  std::vector<int> agg0_;  // fine vertex -> level-1 row
  std::vector<std::array<int, 6>>
      face_slot_;               // corner pairs (0,1),(1,0),(0,2),(2,0),(1,2),(2,1) -> level-1 block
  std::vector<Coarse> coarse_;  // levels 1.., finest first; the last is solved densely
  VertexMultigridOptions opt_;
};

struct VertexMultigrid::Workspace {
  struct Level {
    // The operator and smoother of a preconditioner: single precision does (and lowers the
    // peak memory of the 100k bends by 56-68 bytes per prism).
    std::vector<Eigen::Matrix3f> val;   // one per block of the level's pattern (coarse levels)
    std::vector<Eigen::Matrix3f> dinv;  // one per row: its diagonal block's inverse
    // The V-cycle's vectors: in single precision for the inexact cycle steps (as its operators; a
    // preconditioner needs a few digits there, and the conjugate gradients around it run in
    // double), in double for the polish, whose nearly singular systems (eps ~ 1e-8) need them.
    template <class T>
    struct Vectors {
      std::vector<Eigen::Matrix<T, 3, 1>> x, b, r, d, t;
    };
    Vectors<float> f32;
    Vectors<double> f64;
    Vectors<float>& vectors(float) { return f32; }
    Vectors<double>& vectors(double) { return f64; }
  };
  Level fine;                 // level 0 (matrix-free: no val)
  std::vector<Level> levels;  // levels 1..
  Eigen::LDLT<Eigen::MatrixXd> coarsest;
  // The conjugate gradients' vectors, in the V-cycle's precision (their residual and
  // preconditioned residual are the fine level's b and x).
  template <class T>
  struct CgVectors {
    std::vector<Eigen::Matrix<T, 3, 1>> p, kp, delta;  // delta: single precision only
    std::vector<T> rho, jp;                            // per face: r - J delta, J p
  };
  CgVectors<float> cg32;
  CgVectors<double> cg64;
  CgVectors<float>& cg_vectors(float) { return cg32; }
  CgVectors<double>& cg_vectors(double) { return cg64; }
  // Per face: J x between the two passes of a threaded V-cycle product, per precision.
  std::vector<float> jx32;
  std::vector<double> jx64;
  std::vector<float>& jx_scratch(float) { return jx32; }
  std::vector<double>& jx_scratch(double) { return jx64; }
  // Per face: the smoothness term's three edge terms, between the two passes of a threaded
  // product, per precision.
  std::vector<Eigen::Vector3f> el32;
  std::vector<Vec3> el64;
  std::vector<Eigen::Vector3f>& edge_scratch(float) { return el32; }
  std::vector<Vec3>& edge_scratch(double) { return el64; }
};

}  // namespace strata::internal

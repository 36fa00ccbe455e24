#include "strata/reconstruction.h"

#include <tbb/task_arena.h>

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <optional>
#include <queue>
#include <sstream>
#include <type_traits>
#include <unordered_map>

#include "internal/cell_grid.h"
#include "internal/contact.h"
#include "internal/hierarchy.h"
#include "internal/intersection_update.h"
#include "internal/option_error.h"
#include "internal/parallel.h"
#include "internal/prism_pair.h"
#include "internal/renumber.h"
#include "internal/serial_openmp.h"
#include "internal/topology.h"
#include "internal/vectors.h"
#include "internal/vertex_multigrid.h"
#include "strata/exceptions.h"
#include "strata/intersections.h"
#include "strata/prism.h"

namespace strata {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// Adds the seconds of its scope to one of ReconstructStats' phase times.
class PhaseTimer {
 public:
  explicit PhaseTimer(double& total) : total_(total) {}
  PhaseTimer(const PhaseTimer&) = delete;
  PhaseTimer& operator=(const PhaseTimer&) = delete;
  ~PhaseTimer() { total_ += seconds_since(t0_); }

 private:
  double& total_;
  Clock::time_point t0_ = Clock::now();
};

// One multigrid level: its prisms (in the ids of the state it is solved in: original vertex ids
// on the finest level, compact ids on the coarser ones, so that they share the coarse state's
// arrays), per-level targets, adjacency and regularization weights (in level-local ids).
struct Level {
  std::vector<int> verts;
  std::vector<Face> faces;
  std::vector<Face> local_faces;  // faces in level-local ids; empty on the finest (ids are original)
  // Level-local vertex -> its (face * 3 + corner) entries, faces ascending: J^T x gathered per
  // vertex sums in the same order as a scatter over the faces would, so threads change nothing.
  std::vector<int> vf_offsets, vf;
  std::vector<double> targets;
  // Per prism, for ReconstructOptions::max_constraint_motion: its longest rest edge and its longest
  // guarded displacement length (scaled by the amplitude in each solve). Single precision: a
  // bound, not a measure.
  std::vector<float> edge_sizes, length_sizes;
  double mean_abs_target = 0.0;
  std::vector<int> nb_offsets, nb;  // level-local neighbour ids
  std::vector<double> weights;
  // TangentialRegularization::RestLaplacian: per level-local vertex, the tangential Laplacian
  // (with `weights`) of the rest detail and of the rest base points, in the original base's frame
  // at the vertex (first tangent, normal x tangent); zero on boundary vertices.
  std::vector<Eigen::Vector2d> rest_lap_detail, rest_lap_base;
  std::vector<char> boundary;  // level-local: the vertex lies on a boundary edge
  // The vertices this level adds to the coarser one, each with its removal ring (ring_vertices
  // from ring_offsets[k] to ring_offsets[k + 1]), in the order prolongate() visits them: by id,
  // each vertex after the inserted vertices of its ring (prolongation_orders()), so that its reads
  // and writes go through the arrays nearly in order rather than in the decimation's order, which
  // is by edge length.
  std::vector<int> inserted, ring_offsets, ring_vertices;
  // The direct solver of J J^T (prisms sharing a vertex): its lower triangle with the pattern
  // fixed, the diagonal's slots in its value array, and the Cholesky factorization whose symbolic
  // analysis is done once per level. The values are written straight into the matrix from the
  // gradients (assemble()); no per-entry index arrays are kept.
  // Mutable: refactorized in every step of a (logically const) reconstruction.
  // Built lazily (ensure_factorizable()) on a multigrid polish's finest level, only if it stalls.
  mutable Eigen::SparseMatrix<double> jj;
  mutable std::vector<int> jj_diag_slot;
  mutable std::unique_ptr<Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower>> llt;
  // The vertex-space multigrid of the step (VolumeStepSolver::Multigrid), if used on this level,
  // and the level-local vertices it must not move (the pinned ones; empty if none).
  std::unique_ptr<internal::VertexMultigrid> mg;
  std::vector<char> fixed;
  // J J^T is too dense to factorize (dense_pattern()): nothing is factorized on this level, its
  // exact steps go by the vertex multigrid and its cycle steps by conjugate gradients.
  bool dense = false;
};

// A level's J J^T has a dense block over the prisms around each vertex: a hub of valence k (a CAD
// cylinder's cap, a fan) makes k^2 / 2 entries and k^3 / 3 flops of factorization. A 10,000-face
// fan took 20.9 s and 2.0 GB with the default options (7.7 s of symbolic analysis, a 12.9 s
// factorization); the vertex-space multigrid, sparse there, solved it in 0.3 s and 29 MB.
// Vertices in more than kDenseValence prisms count, and the pattern is dense when their blocks
// hold more than kDenseEntries entries (a single hub of about 2,900 prisms).
constexpr int kDenseValence = 64;
constexpr double kDenseEntries = 4194304.0;

// Whether the lower triangle of J J^T's blocks around the vertices \p verts (ids into the CSR
// vertex -> prism-corner lists \p vf_offsets) is dense as above; all vertices if \p verts is null.
inline bool dense_pattern(const std::vector<int>& vf_offsets, const std::vector<int>* verts) {
  double entries = 0.0;
  auto add = [&](int v) {
    const double k = vf_offsets[v + 1] - vf_offsets[v];
    if (k > kDenseValence) entries += 0.5 * k * (k + 1.0);
  };
  if (verts)
    for (int v : *verts) add(v);
  else
    for (std::size_t v = 0; v + 1 < vf_offsets.size(); ++v) add(static_cast<int>(v));
  return entries > kDenseEntries;
}

// Relative diagonal shift of the exact steps' system J J^T + eps I (eps = damping * max diagonal):
// at least enough to factorize the singular clean start, at most a short gradient-like step.
constexpr double kMinDamping = 1e-10;
constexpr double kMaxDamping = 1e-2;

// The largest regularization weight a hand-made encoding may have: the multigrid holds the weights
// in single precision, and a normalized cotangent weight is at most a few units.
constexpr double kMaxWeight = 1e30;

// Local exact steps (local_polish()) over at least this many prisms factorize with CHOLMOD's
// supernodal Cholesky, smaller ones with Eigen's simplicial LDL^T. Measured on the 1M bend's local
// polish end over 129k prisms: 0.32 s a factorization and solve, where the simplicial one made
// that end cost more than the whole-level step it replaces.
constexpr int kSupernodalMinPrisms = 10000;

// How a Gauss-Newton step's linear system is solved.
enum class StepSolve {
  Cycle,      // during the cycles: ReconstructOptions::step_solver (inexact unless Direct)
  Exact,      // the polish: ReconstructOptions::polish_solver
  Factorized  // a Cholesky factorization, whatever the options
};

// Scratch of one Gauss-Newton step, reused across steps.
struct GnScratch {
  double damping = kMinDamping;  // of the exact steps, adapted step by step
  int cg_max_iterations = 0;     // 0: the options'; a drag step's own budget otherwise
  int mg_iterations = 0;         // multigrid cycle steps' iterations; 0: MultigridStepOptions::iterations
  double motion = 0.0;           // the last exact step's largest vertex move (0: undone, or inexact)
  int polish_steps = 0;          // the polish's multigrid steps so far (polish_smoothness_decay)
  std::vector<std::array<Vec3, 3>> grad;  // the steps solved without the multigrid
  std::vector<float> gf;                  // the multigrid's: J in single precision, 9 per face
  std::vector<Vec3> gv;                   // grad in the level's vertex order (Level::vf), for J^T x
  std::vector<double> r, y, z, p, Ap, diag;
  std::vector<Vec3> delta;
  std::vector<Vec3> jt;      // J^T x per level vertex, inside the matrix-free products
  std::vector<Vec3> ldelta;  // the multigrid step per level vertex
  internal::VertexMultigrid::Workspace mgw;
  // MultigridStepOptions::tangential_damping of the step being solved (relative; 0: none), and per
  // level vertex its base normal scaled by the square root of the vertex's weight.
  double tangential_damping = 0.0;
  std::vector<Eigen::Vector3f> damped_normals;
};

// Frees \p g's arrays (the small dense factor of the multigrid's coarsest level stays: Eigen's
// LDLT does not move cleanly), keeping its settings (the exact steps' damping and the iteration
// budgets).
void release_step_scratch(GnScratch& g) {
  auto release = [](auto&... v) { (std::decay_t<decltype(v)>().swap(v), ...); };
  release(g.grad, g.gf, g.gv, g.r, g.y, g.z, g.p, g.Ap, g.diag, g.delta, g.jt, g.ldelta, g.damped_normals);
  internal::VertexMultigrid::Workspace& w = g.mgw;
  release(w.levels, w.jx32, w.jx64, w.el32, w.el64);
  w.fine = {};
  w.cg32 = {};
  w.cg64 = {};
}

// The per-reconstruction working arrays, indexed by original vertex id (or, in the coarse
// levels' state, by compact id: see VolumeReconstructor::Impl::compact_to_orig_), and the
// scratch of the sweeps (one State per call, so calls share nothing but the levels'
// factorizations).
struct State {
  // The tangential regularization in use: the options', or RestOffset in the retry of
  // ReconstructOptions::retry_other_regularization.
  TangentialRegularization tangential = TangentialRegularization::RestOffset;

  std::vector<Vec3> P;                // current detail positions
  std::vector<Vec3> Q;                // base points on the edited base
  std::vector<Vec3> N;                // unit normals at the base points
  std::vector<Vec3> R;                // rest tangential offset, rotated into the edited base's frame
  std::vector<Vec3> T;                // first tangents at the base points (RestLaplacian only)
  std::vector<Vec3> P0;               // positions at the start of the current multigrid pass
  std::vector<double> dRho;           // prolongated change of d/f
  std::vector<Vec3> dT;               // prolongated change of the tangential displacement
  std::vector<double> rho;            // regularization scratch: d/f per level vertex
  std::vector<Vec3> pk;               // regularization scratch: positions per level vertex (RestLaplacian)
  std::vector<Vec3> tdev;             // regularization scratch: tangential deviation per level vertex
  std::vector<Vec3> before;           // the level's positions before a regularization round (level-local)
  std::vector<Vec3> pinned_at;        // where the pinned vertices stay (empty: none pinned)
  double amplitude = 1.0;             // scales every target and rest offset (ReconstructRequest)
  bool clean_start = false;           // inside clean_start() (the coarsest level's own options)
  int volume_iterations = 0;          // volume steps per cycle on the level being solved
  int cycle_volume_iterations = 0;    // the clean start's n (volume_iterations, or the retry's)
  const char* phase = "reconstruct";  // the progress reports' phase (ReconstructOptions::progress)
  double work_done = 0.0, work_total = 0.0;  // a clean start's progress, in weighted prisms
  GnScratch gn;
  // The guarded displacement lengths and the pinned flags (null: none pinned), indexed as the
  // arrays above: by original vertex id, or by compact id in the coarse levels' state.
  const std::vector<double>* f = nullptr;
  const std::vector<char>* pin = nullptr;
  bool pinned(int i) const { return pin && (*pin)[i]; }
  // The fold checks' contact test (ReconstructOptions::contact_ratio), made on first use: it
  // depends on the base points alone, which a reconstruction does not change, so its retries and
  // repair rounds share it.
  mutable std::unique_ptr<internal::ContactTest> contact;
  // The last fold check's search of the detail and the positions it searched: the next check
  // (after a fold-repair round, which moves a few thousand vertices) searches only around the
  // faces that moved since (search_detail()).
  mutable std::unique_ptr<IntersectionResult> searched;
  mutable std::vector<Vec3> searched_at;
  // Per vertex, the weight of MultigridStepOptions::tangential_damping: 0 where the edit bends the
  // base, 1 away from there (empty: none computed, 1 everywhere).
  std::vector<float> damping_weight;
};

// p carried along from the frame (from) of vertex i to its frame (to): the displacement keeps
// its tangent, bitangent and normal components.
Vec3 carry(const Vec3& p, const BaseFrames& from, const BaseFrames& to, int i) {
  const Vec3 d = p - from.points[i];
  const Vec3 &t0 = from.tangents[i], &n0 = from.normals[i];
  const Vec3 &t1 = to.tangents[i], &n1 = to.normals[i];
  return to.points[i] + d.dot(t0) * t1 + d.dot(n0.cross(t0)) * n1.cross(t1) + d.dot(n0) * n1;
}

}  // namespace

struct DragState::Impl {
  BaseFrames frames;                     // the frames the positions below are over
  std::vector<Vec3> start;               // reset()'s positions, until the first step
  std::vector<std::vector<Vec3>> level;  // per level, indexed by detail vertex (the level's own)
  bool started = false;
  // The reconstructor whose hierarchy `level` follows (its Impl's serial; 0: none yet). A state
  // carried to another reconstructor would index its levels by the first one's sizes.
  std::uint64_t owner = 0;
  // frames and start are in the owner's numbering (VolumeReconstructor's renumbering): converted
  // once, at the first step.
  bool in_solver_order = false;
};

DragState::DragState() : impl_(std::make_unique<Impl>()) {}
DragState::~DragState() = default;
DragState::DragState(DragState&&) noexcept = default;
DragState& DragState::operator=(DragState&&) noexcept = default;

void DragState::reset(const BaseFrames& frames, std::vector<Vec3> start) {
  const std::size_t n = start.size();
  if (frames.points.size() != n || frames.normals.size() != n || frames.tangents.size() != n)
    throw InvalidInput("drag start has " + std::to_string(n) + " positions but base frames with " +
                       std::to_string(frames.points.size()) + " points, " +
                       std::to_string(frames.normals.size()) + " normals and " +
                       std::to_string(frames.tangents.size()) + " tangents");
  for (std::size_t i = 0; i < n; ++i)
    if (!start[i].allFinite() || !frames.points[i].allFinite() || !frames.normals[i].allFinite() ||
        !frames.tangents[i].allFinite())
      throw InvalidInput("drag start: vertex " + std::to_string(i) + " or its base frame is not finite");
  check_coordinates(start, "drag start:");
  check_coordinates(frames.points, "drag start's base frames:");
  internal::check_frame_axes(frames, "drag start's ");
  if (!impl_) impl_ = std::make_unique<Impl>();  // a moved-from state starts anew
  impl_->frames = frames;
  impl_->start = std::move(start);
  impl_->level.clear();
  impl_->owner = 0;
  impl_->in_solver_order = false;
  impl_->started = true;
}

bool DragState::started() const {
  return impl_ && impl_->started;
}

// A NaN tolerance made a warm start end unconverged at once; negative counts passed unnoticed.
void check_warm_start_options(const WarmStartOptions& w) {
  auto fail = [](const char* name, double value, const char* range) {
    internal::option_out_of_range("warm-start", name, value, range);
  };
  if (!(w.tolerance > 0 && std::isfinite(w.tolerance))) fail("tolerance", w.tolerance, "above 0, finite");
  if (w.level_steps < 0 || w.level_steps > 100000) fail("level_steps", w.level_steps, "0-100000");
  if (w.cg_max_iterations < 0 || w.cg_max_iterations > 1000000)
    fail("cg_max_iterations", w.cg_max_iterations, "0-1000000");
  if (w.max_cycles < 0 || w.max_cycles > 100000) fail("max_cycles", w.max_cycles, "0-100000");
}

class VolumeReconstructor::Impl {
 public:
  Impl(DetailEncoding e, ReconstructOptions o) : enc_(std::move(e)), opt_(std::move(o)) {
    const auto t0 = Clock::now();
    validate();
    // A scattered numbering (a scan whose tool hashed or shuffled its vertices) costs the solve
    // its caches (renumber_for_locality).
    if (opt_.renumber_for_locality) {
      renum_ = internal::locality_renumbering(enc_.detail_rest, enc_.detail_faces);
      if (!renum_.empty()) enc_ = internal::renumber(enc_, renum_, &face_order_);
    }
    const int n = enc_.num_detail_vertices();
    // The mean displacement length over the vertices of faces: one stray vertex far from a scan
    // raised it (to 300 times the detail's height at 1e4 away), and with it the length filter's
    // floor and the fixed-point test's scale, which moved the detail 0.15 in a round trip.
    std::vector<char> in_face(n, 0);
    for (const Face& f : enc_.detail_faces)
      for (int v : f) in_face[v] = 1;
    double mean_f = 0.0;
    int counted = 0;
    for (int i = 0; i < n; ++i)
      if (in_face[i]) {
        mean_f += std::abs(enc_.normal_offsets[i]);
        ++counted;
      } else {
        isolated_.push_back(i);
      }
    mean_f = counted > 0 ? mean_f / counted : 0.0;
    mean_abs_f_ = mean_f;
    if (isolated_.empty()) {
      rest_diagonal_ = bbox_diagonal(enc_.detail_rest);
    } else {  // the faces' extent, as the mean above
      std::vector<Vec3> used;
      for (int i = 0; i < n; ++i)
        if (in_face[i]) used.push_back(enc_.detail_rest[i]);
      rest_diagonal_ = bbox_diagonal(used);
    }
    guarded_f_.resize(n);
    const double fmin = std::max(opt_.min_length_fraction * mean_f, 1e-300);
    for (int i = 0; i < n; ++i) {
      const double f = enc_.normal_offsets[i];
      guarded_f_[i] = std::abs(f) >= fmin ? f : (f < 0 ? -fmin : fmin);
    }
    const int threads = opt_.threads > 0 ? opt_.threads : tbb::this_task_arena::max_concurrency();
    if (threads > 1) arena_ = std::make_unique<tbb::task_arena>(threads);
    internal::HierarchyOptions ho;
    ho.max_levels = opt_.max_levels;
    ho.coarsest_vertices = opt_.coarsest_vertices;
    ho.ratio = opt_.coarsening_ratio;
    // Progress "setup": the decimation about 60% of it (the 1M bumps: 2 of 3.2 s), then the
    // levels by their prisms.
    constexpr double kDecimation = 0.6;
    ho.cancel = opt_.cancel;
    if (opt_.progress) ho.progress = [this](double f) { report("setup", kDecimation * f); };
    report("setup", 0.0);
    internal::Hierarchy h = internal::build_hierarchy(enc_.detail_rest, enc_.detail_faces, ho);
    const int nl = static_cast<int>(h.levels.size());
    double prisms = 0.0, done = 0.0;
    for (const auto& hl : h.levels) prisms += static_cast<double>(hl.faces.size());
    levels_.resize(nl);
    for (int l = 0; l < nl; ++l) {
      check_cancel();
      done += static_cast<double>(h.levels[l].faces.size());
      make_level(h.levels[l], l == nl - 1, levels_[l]);
      report("setup", kDecimation + (1.0 - kDecimation) * done / prisms);
    }
    // A dense finest level (dense_pattern()) is polished by the vertex multigrid, whatever the
    // options say.
    polish_by_multigrid_ = opt_.polish_solver == VolumeStepSolver::Multigrid || levels_.back().dense;
    compact_coarse_levels();
    prolongation_orders();
    if (enc_.over_limit_surface()) {
      std::vector<Vec3> rest(enc_.base_num_vertices, Vec3::Zero());
      limit_ = std::make_unique<SubdivSurface>(limit_surface_for(enc_, rest));
      limit_points_ = std::make_unique<LimitPointSet>(*limit_, enc_.limit_points);
    }
    setup_seconds_ = seconds_since(t0);
  }

  // The base frames on an edited base given by its vertices (or its cage's control points).
  BaseFrames frames_for(const std::vector<Vec3>& base) const {
    try {
      if (!limit_) return evaluate_base_frames(enc_, base);
      limit_->set_control_points(base);  // keeps the patch table: only the patch points change
      return evaluate_base_frames(enc_, *limit_points_, *limit_);
    } catch (const InvalidInput&) {
      // Its message names a detail vertex: evaluated again over the caller's encoding, which
      // fails at the caller's first such vertex (only on this error's path).
      if (!renum_.empty()) {
        const DetailEncoding& caller = encoding();
        if (!limit_)
          evaluate_base_frames(caller, base);
        else
          evaluate_base_frames(caller, LimitPointSet(*limit_, caller.limit_points), *limit_);
      }
      throw;
    }
  }

  ReconstructResult run(const std::vector<Vec3>& base, const std::vector<Vec3>* start,
                        const WarmStartOptions* warm, const ReconstructRequest& request = {}) const {
    const auto t0 = Clock::now();
    const BaseFrames fr = frames_for(base);
    const double seconds = seconds_since(t0);
    ReconstructResult res = run(fr, start, warm, request);
    res.stats.seconds_frames += seconds;  // evaluating the frames, then preparing the state
    return res;
  }

  ReconstructResult run(const BaseFrames& fr, const std::vector<Vec3>* start, const WarmStartOptions* warm,
                        const ReconstructRequest& request = {}) const {
    ReconstructResult res = solve_frames(fr, start, warm, request);
    place_isolated(fr, request.amplitude, res.positions);
    return res;
  }

  // Vertices in no face have no prism to solve: they are placed by their displacement vectors
  // (a review, thirty-eighth session: a scan's stray vertex stayed on its base point, its
  // displacement lost).
  void place_isolated(const BaseFrames& fr, double amplitude, std::vector<Vec3>& P) const {
    for (int i : isolated_) P[i] = internal::vector_position(enc_, fr, amplitude, i);
  }

  ReconstructResult solve_frames(const BaseFrames& fr, const std::vector<Vec3>* start,
                                 const WarmStartOptions* warm, const ReconstructRequest& request) const {
    if (warm) check_warm_start_options(*warm);
    ReconstructResult res;
    ReconstructStats& st = res.stats;
    auto t0 = Clock::now();
    State s;
    init_state(fr, request, s);
    s.phase = phase_;
    st.seconds_frames = seconds_since(t0);
    t0 = Clock::now();
    level_stats(st);
    std::vector<double> V;
    const double a = s.amplitude;
    check_cancel();
    if (a == 0.0) {
      // No detail: every prism is flat, which the clean configuration solves exactly.
      s.P = s.Q;
      place_pinned(s);
      st.converged = true;
      st.seconds_solve = seconds_since(t0);
      res.positions = std::move(s.P);
      return res;
    }
    if (!start) {
      clean_start(s, a, opt_.volume_iterations, st, V);
      Outcome first;
      {
        PhaseTimer timer(st.seconds_folds);
        first = outcome(s, a, V);
        repair_folds(s, a, st, V, first);
      }
      // Not converged, or still folded: once more from the clean start with another schedule, and
      // the better of the two is kept (converged first, then fewer new pairs).
      auto retry = [&](int volume_iterations, int mg_iterations) {
        std::vector<Vec3> kept = s.P;
        ++st.retries;
        s.phase = "retry";
        s.gn.damping = kMinDamping;
        s.gn.mg_iterations = mg_iterations;
        clean_start(s, a, volume_iterations, st, V);
        s.gn.mg_iterations = 0;
        PhaseTimer timer(st.seconds_folds);
        Outcome second = outcome(s, a, V);
        repair_folds(s, a, st, V, second);
        if (second.better_than(first))
          first = std::move(second);
        else
          s.P.swap(kept);
      };
      auto failed = [&] { return !first.converged || first.folds() > 0; };
      // First with the other tangential regularization (retry_other_regularization): the rest
      // offsets fold on other regular grids than the rest Laplacian.
      if (opt_.retry_other_regularization &&
          opt_.tangential_regularization == TangentialRegularization::RestLaplacian && failed()) {
        s.tangential = TangentialRegularization::RestOffset;
        retry(opt_.volume_iterations, 0);
        s.tangential = opt_.tangential_regularization;
      }
      if (opt_.retry_volume_iterations > 0 && opt_.retry_volume_iterations != opt_.volume_iterations &&
          failed())
        retry(opt_.retry_volume_iterations, 0);
      // Then with accurate multigrid steps (MultigridStepOptions::retry_iterations).
      if (opt_.multigrid.retry_iterations > 0 && opt_.step_solver == VolumeStepSolver::Multigrid && failed())
        retry(opt_.retry_volume_iterations > 0 ? opt_.retry_volume_iterations : opt_.volume_iterations,
              opt_.multigrid.retry_iterations);
      {
        PhaseTimer timer(st.seconds_folds);
        fold_checked(s, a, st, V, first);
      }
      if (opt_.fallback_schedule && first.counted && first.folds() > 0) fall_back(fr, request, s, st, first);
      report_pairs(first, st);
    } else {
      check_start(*start);
      s.P = *start;
      place_pinned(s);
      if (warm->coarse_levels_only) {
        multigrid_pass(s, a, true, warm->tolerance, true, st, V);
      } else {
        // The exact solve from a nearby start: the finest level only, so that a start which
        // already solves the problem stays put (coarse levels have their own targets).
        const Level& F = levels_.back();
        s.volume_iterations = opt_.volume_iterations;
        {
          PhaseTimer timer(st.seconds_levels.back());
          st.finest_cycles_per_scale.push_back(
              solve_level(F, s, a, warm->tolerance,
                          warm->max_cycles > 0 ? warm->max_cycles : opt_.final_max_cycles, st, V));
        }
        PhaseTimer timer(st.seconds_polish);
        polish(F, s, warm->tolerance, st, V);
      }
    }
    finish(s, start ? warm->tolerance : opt_.tolerance, t0, V, res);
    return res;
  }

  // One drag step (section 5) with per-level warm starts; see VolumeReconstructor::drag_step().
  ReconstructResult drag(const BaseFrames& fr, DragState::Impl& ds, const WarmStartOptions& warm,
                         const ReconstructRequest& request) const {
    ReconstructResult res = drag_frames(fr, ds, warm, request);
    place_isolated(fr, request.amplitude, res.positions);
    return res;
  }
  ReconstructResult drag_frames(const BaseFrames& fr, DragState::Impl& ds, const WarmStartOptions& warm,
                                const ReconstructRequest& request) const {
    const int n = enc_.num_detail_vertices();
    if (!ds.started) throw InvalidInput("drag_step() before DragState::reset()");
    check_warm_start_options(warm);
    if (static_cast<int>(ds.frames.points.size()) != n)
      throw InvalidInput("drag state has " + std::to_string(ds.frames.points.size()) +
                         " vertices, the detail has " + std::to_string(n));
    if (ds.owner != 0 && ds.owner != serial_)
      throw InvalidInput(
          "drag state belongs to another VolumeReconstructor (reset() it to start a drag here)");
    ReconstructResult res;
    ReconstructStats& st = res.stats;
    auto t0 = Clock::now();
    State s;
    init_state(fr, request, s);  // its checks first: a refused step leaves the state as it was
    if (!ds.in_solver_order) {   // reset()'s frames and positions, in the caller's numbering
      if (!renum_.empty()) {
        ds.frames = internal::to_new(renum_, ds.frames);
        ds.start = internal::to_new(renum_, ds.start);
      }
      ds.in_solver_order = true;
      // In this solver's numbering from now on, renumbered or not: a state converted here and
      // then stepped by a renumbering reconstructor was read in the wrong numbering.
      ds.owner = serial_;
    }
    const int nl = static_cast<int>(levels_.size());
    level_stats(st);
    // Level l's state ids -> original ids (the coarse levels' are compact: gather_coarse()).
    auto orig = [&](int l, int i) { return l + 1 < nl ? compact_to_orig_[i] : i; };
    const int nc = static_cast<int>(compact_to_orig_.size());
    if (ds.level.empty()) {
      // The first step: every level starts from the drag's start positions.
      ds.level.assign(nl, {});
      for (int l = 0; l < nl; ++l) {
        ds.level[l].assign(l + 1 < nl ? nc : n, Vec3::Zero());
        for (int i : levels_[l].verts) ds.level[l][i] = ds.start[orig(l, i)];
      }
      ds.start = {};
      ds.owner = serial_;
    }
    // Every level's last solution, carried along with the base frames.
    for (int l = 0; l < nl; ++l)
      for (int i : levels_[l].verts) {
        const int o = orig(l, i);
        ds.level[l][i] = pinned(o) ? s.pinned_at[o] : carry(ds.level[l][i], ds.frames, fr, o);
      }
    ds.frames = fr;
    st.seconds_frames = seconds_since(t0);
    t0 = Clock::now();
    const double a = s.amplitude;
    std::vector<double> V;
    s.P.assign(n, Vec3::Zero());
    s.P0.assign(n, Vec3::Zero());
    s.gn.cg_max_iterations = warm.cg_max_iterations;
    // The coarse levels in their own compact state (as a clean start's multigrid_pass()).
    State c;
    if (nl > 1) gather_coarse(s, c);
    for (int l = 0; l < nl; ++l) {
      check_cancel();
      const Level& L = levels_[l];
      const bool finest = l + 1 == nl;
      State& ls = finest ? s : c;
      const std::vector<Vec3>& start = ds.level[l];
      std::optional<PhaseTimer> level_timer(std::in_place, st.seconds_levels[l]);
      if (l == 0) {
        for (int i : L.verts) ls.P[i] = ls.P0[i] = start[i];
      } else {
        // The coarser level's correction (its solution minus its start) carried to this level's
        // own start: added as is on the shared vertices, prolongated to the inserted ones.
        const std::vector<int>* coarse_verts = &levels_[l - 1].verts;
        if (finest) {
          scatter_coarse(c, s);
          for (int k = 0; k < nc; ++k) s.P0[compact_to_orig_[k]] = c.P0[k];
          c = State{};
          coarse_verts = &compact_to_orig_;
        }
        for (int i : L.inserted) ls.P[i] = ls.P0[i] = start[i];
        prolongate(L, *coarse_verts, ls);
        for (int i : *coarse_verts) {
          ls.P[i] = ls.pinned(i) ? start[i] : Vec3(start[i] + (ls.P[i] - ls.P0[i]));
          ls.P0[i] = start[i];
        }
      }
      if (a == 0.0) {
        for (int i : L.verts) ls.P[i] = ls.pinned(i) ? ls.pinned_at[i] : ls.Q[i];
      } else if (!finest && !warm.coarse_levels_only) {
        // The exact solve: the coarse levels only serve the previews; carried along, unsolved.
      } else if (finest && warm.coarse_levels_only && nl > 1) {
        regularize_sweeps(L, s, st);
      } else if (!finest && warm.level_steps > 0) {
        regularize_sweeps(L, ls, st);
        project(L, ls, a, opt_.level_tolerance, warm.level_steps, cycle_solve(L), st, V);
        ++st.cycles;
      } else {
        ls.volume_iterations = opt_.volume_iterations;
        const int final_cycles = warm.max_cycles > 0 ? warm.max_cycles : opt_.final_max_cycles;
        const int cycles = solve_level(L, ls, a, finest ? warm.tolerance : opt_.level_tolerance,
                                       finest ? final_cycles : opt_.max_cycles, st, V);
        if (finest) {
          st.finest_cycles_per_scale.push_back(cycles);
          level_timer.reset();
          {
            PhaseTimer timer(st.seconds_polish);
            polish(L, s, warm.tolerance, st, V);
          }
          // The exact solve: its folds are counted and repaired as a clean start's.
          PhaseTimer timer(st.seconds_folds);
          Outcome o = outcome(s, a, V);
          repair_folds(s, a, st, V, o);
          fold_checked(s, a, st, V, o);
          report_pairs(o, st);
        }
      }
      for (int i : L.verts) ds.level[l][i] = ls.P[i];
    }
    finish(s, warm.tolerance, t0, V, res);
    return res;
  }

  // VolumeReconstructor::set_intersection_context(): checked, into the solver's numbering, and
  // cut to the faces near the detail at rest.
  void set_intersection_context(IntersectionContext c) {
    const auto n = static_cast<long long>(enc_.num_detail_vertices());
    const long long total = n + static_cast<long long>(c.points.size());
    if (!c.rest_points.empty() && c.rest_points.size() != c.points.size())
      throw InvalidInput("intersection context: " + std::to_string(c.rest_points.size()) +
                         " rest points for " + std::to_string(c.points.size()) + " points");
    for (const std::vector<Vec3>* pts : {&c.points, &c.rest_points})
      for (std::size_t k = 0; k < pts->size(); ++k)
        if (!(*pts)[k].allFinite() || (*pts)[k].cwiseAbs().maxCoeff() > kMaxCoordinate)
          throw InvalidInput(
              "intersection context: " + std::string(pts == &c.points ? "point " : "rest point ") +
              std::to_string(k) + " is not finite or beyond the engine's range");
    for (std::size_t j = 0; j < c.faces.size(); ++j)
      for (int k = 0; k < 3; ++k)
        if (c.faces[j][k] < 0 || c.faces[j][k] >= total)
          throw InvalidInput("intersection context: face " + std::to_string(j) + " has vertex index " +
                             std::to_string(c.faces[j][k]) + ", not in [0, " + std::to_string(total) + ")");
    // Into the solver's numbering of the detail's vertices.
    if (!renum_.empty())
      for (Face& f : c.faces)
        for (int& i : f)
          if (i < n) i = renum_.new_of_old[i];
    // Only the faces that can make a pair that is no contact are kept (near_context(), at rest),
    // with the points they use.
    const std::vector<Vec3>& rest = c.rest_points.empty() ? c.points : c.rest_points;
    const std::vector<int> near = near_context(rest, c.faces);
    std::vector<int> point_id(c.points.size(), -1);
    IntersectionContext kept;
    kept.faces.reserve(near.size());
    for (int k : near) {
      Face g = c.faces[k];
      for (int& i : g) {
        if (i < n) continue;
        int& id = point_id[i - n];
        if (id < 0) {
          id = static_cast<int>(n + static_cast<long long>(kept.points.size()));
          kept.points.push_back(c.points[i - n]);
          if (!c.rest_points.empty()) kept.rest_points.push_back(c.rest_points[i - n]);
        }
        i = id;
      }
      kept.faces.push_back(g);
    }
    context_ = std::move(kept);
    rest_context_.reset();
    // The fallback schedule's solver is built from this one's encoding, without renumbering.
    if (fallback_) fallback_->set_intersection_context(context_);
  }
  // The context's points at rest (IntersectionContext::rest_points).
  const std::vector<Vec3>& context_rest_points() const {
    return context_.rest_points.empty() ? context_.points : context_.rest_points;
  }
  // The caller's encoding (the solver's own is renumbered if renum_ is not empty): restored on
  // first use rather than kept, which would cost its memory through every solve.
  const DetailEncoding& encoding() const {
    if (renum_.empty()) return enc_;
    // Once, even from two threads (a getter that looks read-only).
    std::call_once(original_once_, [&] {
      original_ = std::make_unique<DetailEncoding>(internal::restore(enc_, renum_, face_order_));
    });
    return *original_;
  }

  // The public calls' per-vertex arrays are in the caller's numbering; the solver's in its own.
  // solve(start, request) runs with both in the solver's, and the result comes back in the
  // caller's.
  template <class Solve>
  ReconstructResult in_solver_order(const std::vector<Vec3>* start, const ReconstructRequest& request,
                                    Solve&& solve) const {
    if (renum_.empty()) return solve(start, request);
    std::vector<Vec3> s, pinned;
    if (start) {
      check_start(*start);
      s = internal::to_new(renum_, *start);
    }
    ReconstructRequest q = request;
    if (request.pinned_positions && !enc_.pinned.empty()) {
      check_pinned_positions(*request.pinned_positions,
                             [&](int v) { return enc_.pinned[renum_.new_of_old[v]] != 0; });
      pinned = internal::to_new(renum_, *request.pinned_positions);
      q.pinned_positions = &pinned;
    }
    ReconstructResult r = solve(start ? &s : nullptr, q);
    r.positions = internal::to_old(renum_, r.positions);
    return r;
  }
  // The caller's frames in the solver's numbering (held by \p copy if renumbered).
  // The caller's frames in the solver's numbering, checked (their axes here only: the frames the
  // reconstructor evaluates itself are orthonormal, and a drag step need not check them again).
  const BaseFrames& solver_frames(const BaseFrames& f, BaseFrames& copy) const {
    check_frames(f);
    internal::check_frame_axes(f, "");
    if (renum_.empty()) return f;
    copy = internal::to_new(renum_, f);
    return copy;
  }
  BaseFrames caller_frames(BaseFrames f) const { return renum_.empty() ? f : internal::to_old(renum_, f); }
  const ReconstructOptions& options() const { return opt_; }
  double setup_seconds() const { return setup_seconds_; }
  std::vector<int> level_vertex_counts() const {
    std::vector<int> out;
    for (const Level& L : levels_) out.push_back(static_cast<int>(L.verts.size()));
    return out;
  }

 private:
  void validate() const {
    check_encoding(enc_);  // not empty; sizes and indices
    const int n = enc_.num_detail_vertices();
    // The hierarchy's decimation orders edges by length: a non-finite one has no place there.
    check_coordinates(enc_.detail_rest, "encoding's detail at rest:");
    for (const BasePoint& b : enc_.base_points)
      if (!b.bary.allFinite()) throw InvalidInput("encoding has a base point with non-finite barycentrics");
    // Every number the solve reads.
    auto finite = [](const auto& values, const char* name) {
      for (const auto& x : values) {
        bool ok;
        if constexpr (std::is_arithmetic_v<std::decay_t<decltype(x)>>)
          ok = std::isfinite(x);
        else
          ok = x.allFinite();
        if (!ok) throw InvalidInput(std::string("encoding has a non-finite value in ") + name);
      }
    };
    for (double w : enc_.weights)
      if (!(std::abs(w) <= kMaxWeight))
        throw InvalidInput("encoding has weights that are not finite or beyond +-1e30 (kMaxWeight)");
    finite(enc_.normal_offsets, "normal_offsets");
    finite(enc_.tangential_offsets, "tangential_offsets");
    finite(enc_.target_volumes, "target_volumes");
    finite(enc_.base_rest_points, "base_rest_points");
    finite(enc_.base_rest_normals, "base_rest_normals");
    finite(enc_.base_rest_tangents, "base_rest_tangents");
    if (opt_.tangential_regularization == TangentialRegularization::RestLaplacian &&
        (static_cast<int>(enc_.base_rest_normals.size()) != n ||
         static_cast<int>(enc_.base_rest_tangents.size()) != n))
      throw InvalidInput(
          "encoding has no base rest frames (base_rest_normals, base_rest_tangents), which the "
          "reconstruction option tangential_regularization = rest_laplacian needs");
    check_reconstruct_options(opt_);
  }

  // The coarse levels' vertex ids from original to compact (gather_coarse()): each coarse
  // level's vertices are among the second-finest level's.
  void compact_coarse_levels() {
    const int nl = static_cast<int>(levels_.size());
    if (nl < 2) return;
    compact_to_orig_ = levels_[nl - 2].verts;
    std::vector<int> compact(enc_.num_detail_vertices(), -1);
    for (std::size_t k = 0; k < compact_to_orig_.size(); ++k)
      compact[compact_to_orig_[k]] = static_cast<int>(k);
    auto remap = [&compact](int& i) {
      i = compact[i];
      assert(i >= 0);
    };
    for (int l = 0; l + 1 < nl; ++l) {
      Level& L = levels_[l];
      for (int& i : L.verts) remap(i);
      for (Face& f : L.faces)
        for (int& i : f) remap(i);
      for (int& i : L.inserted) remap(i);
      for (int& i : L.ring_vertices) remap(i);
    }
    compact_f_.resize(compact_to_orig_.size());
    for (std::size_t k = 0; k < compact_to_orig_.size(); ++k) compact_f_[k] = guarded_f_[compact_to_orig_[k]];
    if (!enc_.pinned.empty()) {
      compact_pinned_.resize(compact_to_orig_.size());
      for (std::size_t k = 0; k < compact_to_orig_.size(); ++k)
        compact_pinned_[k] = enc_.pinned[compact_to_orig_[k]];
    }
  }

  // Every level's inserted vertices and rings put in prolongate()'s order (Level::inserted). Each
  // inserted vertex takes the mean of its ring, whose inserted vertices come earlier in the removal
  // order: any order that keeps those before it computes the same numbers. This one goes up the vertex ids,
  // each vertex after its ring's inserted ones (depth first), so that the pass reads the arrays nearly in
  // order: at 1M prisms the finest level's pass took 45 ms in waves of ascending ids (28 of them), 25 ms in
  // this order. A ring that reads a vertex inserted later (none in the hierarchies build_hierarchy() makes)
  // keeps the removal order, so that nothing changes there either.
  void prolongation_orders() {
    std::vector<int> pos(enc_.num_detail_vertices(), -1);
    for (Level& L : levels_) {
      const int k_count = static_cast<int>(L.inserted.size());
      bool in_order = true;
      for (int k = 0; k < k_count; ++k) pos[L.inserted[k]] = k;
      for (int k = 0; k < k_count && in_order; ++k)
        for (int r = L.ring_offsets[k]; r < L.ring_offsets[k + 1]; ++r)
          if (pos[L.ring_vertices[r]] >= k) in_order = false;  // itself, or not yet inserted: a stale read
      std::vector<int> order(k_count);
      std::iota(order.begin(), order.end(), 0);
      if (in_order) {
        std::vector<int> by_id = order;
        std::sort(by_id.begin(), by_id.end(), [&](int a, int b) { return L.inserted[a] < L.inserted[b]; });
        // Depth first over "reads": a ring's inserted vertices come earlier in the removal order,
        // so the graph has no cycle and the stack is one path of it.
        std::vector<char> done(k_count, 0);
        std::vector<std::pair<int, int>> stack;  // (vertex, its next ring entry)
        order.clear();
        for (int k0 : by_id) {
          if (done[k0]) continue;
          stack.emplace_back(k0, L.ring_offsets[k0]);
          while (!stack.empty()) {
            auto& [k, r] = stack.back();
            if (r < L.ring_offsets[k + 1]) {
              const int q = pos[L.ring_vertices[r++]];
              if (q >= 0 && !done[q]) stack.emplace_back(q, L.ring_offsets[q]);
            } else {
              done[k] = 1;
              order.push_back(k);
              stack.pop_back();
            }
          }
        }
        assert(static_cast<int>(order.size()) == k_count);
      }
      for (int i : L.inserted) pos[i] = -1;
      // The inserted vertices and their rings stored in that order: the pass then reads them
      // sequentially, where through an index array it read each ring at its place in the removal
      // order (a cache miss per vertex at 1M prisms).
      std::vector<int> inserted(k_count), offsets(k_count + 1, 0), ring;
      ring.reserve(L.ring_vertices.size());
      for (int n = 0; n < k_count; ++n) {
        const int k = order[n];
        inserted[n] = L.inserted[k];
        ring.insert(ring.end(), L.ring_vertices.begin() + L.ring_offsets[k],
                    L.ring_vertices.begin() + L.ring_offsets[k + 1]);
        offsets[n + 1] = static_cast<int>(ring.size());
      }
      L.inserted = std::move(inserted);
      L.ring_offsets = std::move(offsets);
      L.ring_vertices = std::move(ring);
    }
  }

  void make_level(internal::Hierarchy::Level& hl, bool finest, Level& L) {
    L.verts = std::move(hl.vertices);
    L.faces = std::move(hl.faces);
    L.inserted = std::move(hl.inserted);
    L.ring_offsets = std::move(hl.ring_offsets);
    L.ring_vertices = std::move(hl.ring_vertices);
    const int n = enc_.num_detail_vertices();
    const int nv = static_cast<int>(L.verts.size());
    std::vector<int> local(n, -1);
    for (int k = 0; k < nv; ++k) local[L.verts[k]] = k;
    std::vector<Face> lf(L.faces.size());
    std::vector<Vec3> lx(nv);
    for (int k = 0; k < nv; ++k) lx[k] = enc_.detail_rest[L.verts[k]];
    for (std::size_t j = 0; j < L.faces.size(); ++j)
      for (int c = 0; c < 3; ++c) lf[j][c] = local[L.faces[j][c]];
    if (!finest) L.local_faces = lf;
    const internal::Adjacency adj = internal::build_adjacency(nv, lf);
    L.vf_offsets.assign(nv + 1, 0);
    for (std::size_t j = 0; j < lf.size(); ++j)
      for (int c = 0; c < 3; ++c) ++L.vf_offsets[lf[j][c] + 1];
    for (int k = 0; k < nv; ++k) L.vf_offsets[k + 1] += L.vf_offsets[k];
    L.vf.resize(3 * lf.size());
    {
      std::vector<int> fill(L.vf_offsets.begin(), L.vf_offsets.end() - 1);
      for (std::size_t j = 0; j < lf.size(); ++j)
        for (int c = 0; c < 3; ++c) L.vf[fill[lf[j][c]]++] = static_cast<int>(3 * j) + c;
    }
    L.boundary = internal::boundary_vertices(nv, lf);
    if (opt_.max_constraint_motion > 0) {
      L.edge_sizes.resize(L.faces.size());
      L.length_sizes.resize(L.faces.size());
      for (std::size_t j = 0; j < L.faces.size(); ++j) {
        const Face& f = L.faces[j];
        double edge = 0.0, length = 0.0;
        for (int c = 0; c < 3; ++c) {
          edge = std::max(edge, (enc_.detail_rest[f[c]] - enc_.detail_rest[f[(c + 1) % 3]]).norm());
          length = std::max(length, std::abs(guarded_f_[f[c]]));
        }
        L.edge_sizes[j] = static_cast<float>(edge);
        L.length_sizes[j] = static_cast<float>(length);
      }
    }
    // J J^T's pattern and symbolic factorization only where exact steps are taken: the finest
    // level (the polish), and the levels the options solve directly; not where it is dense.
    L.dense = dense_pattern(L.vf_offsets, nullptr);
    if (!L.dense && ((finest && opt_.polish_solver == VolumeStepSolver::Direct) ||
                     opt_.step_solver == VolumeStepSolver::Direct ||
                     static_cast<int>(L.faces.size()) <= opt_.direct_max_prisms))
      build_jj_pattern(lf, adj, L);
    if (finest) {
      // The encoding's own weights (the finest level's vertex ids are the original ones).
      L.nb_offsets = enc_.weight_offsets;
      L.nb = enc_.weight_neighbors;
      L.weights = enc_.weights;
      L.targets = enc_.target_volumes;
    } else {
      L.nb_offsets = adj.neighbor_offsets;
      L.nb = adj.neighbors;
      L.weights = internal::normalized_cotan_weights(lx, lf, adj);
      // Coarse prisms get their own targets from the original detail over the original base.
      const std::vector<Vec3>& p = enc_.detail_rest;
      const std::vector<Vec3>& q = enc_.base_rest_points;
      L.targets.resize(L.faces.size());
      for (std::size_t j = 0; j < L.faces.size(); ++j) {
        const Face& f = L.faces[j];
        L.targets[j] = prism_volume(p[f[0]], p[f[1]], p[f[2]], q[f[0]], q[f[1]], q[f[2]]);
      }
    }
    if (opt_.tangential_regularization == TangentialRegularization::RestLaplacian) rest_laplacians(L);
    if (opt_.step_solver == VolumeStepSolver::Multigrid ||
        (finest && (opt_.polish_solver == VolumeStepSolver::Multigrid || L.dense))) {
      L.mg = std::make_unique<internal::VertexMultigrid>(nv, lf, L.nb_offsets, L.nb, L.weights);
      if (!enc_.pinned.empty()) {
        L.fixed.assign(nv, 0);
        for (int k = 0; k < nv; ++k) L.fixed[k] = enc_.pinned[L.verts[k]];
      }
    }
    double sum = 0.0;
    for (double v : L.targets) sum += std::abs(v);
    L.mean_abs_target = L.targets.empty() ? 0.0 : sum / L.targets.size();
  }

  // TangentialRegularization::RestLaplacian's c_i before the amplitude: the level's tangential
  // Laplacians of the rest detail and of the rest base points, in the original base's frames.
  void rest_laplacians(Level& L) const {
    const int nv = static_cast<int>(L.verts.size());
    L.rest_lap_detail.assign(nv, Eigen::Vector2d::Zero());
    L.rest_lap_base.assign(nv, Eigen::Vector2d::Zero());
    const std::vector<Vec3>& p = enc_.detail_rest;
    const std::vector<Vec3>& q = enc_.base_rest_points;
    for (int k = 0; k < nv; ++k) {
      if (L.boundary[k]) continue;  // held at the rest offset
      const int i = L.verts[k];
      Vec3 lp = Vec3::Zero(), lq = Vec3::Zero();
      for (int t = L.nb_offsets[k]; t < L.nb_offsets[k + 1]; ++t) {
        const int j = L.verts[L.nb[t]];
        lp += L.weights[t] * (p[j] - p[i]);
        lq += L.weights[t] * (q[j] - q[i]);
      }
      const Vec3& t1 = enc_.base_rest_tangents[i];
      const Vec3 t2 = enc_.base_rest_normals[i].cross(t1);
      L.rest_lap_detail[k] = Eigen::Vector2d(lp.dot(t1), lp.dot(t2));
      L.rest_lap_base[k] = Eigen::Vector2d(lq.dot(t1), lq.dot(t2));
    }
  }

  // The lower triangle of J J^T's pattern: prism j and every prism k <= j that shares a vertex
  // with it.
  static void build_jj_pattern(const std::vector<Face>& lf, const internal::Adjacency& adj, const Level& L) {
    const int m = static_cast<int>(lf.size());
    std::vector<Eigen::Triplet<double>> trip;
    trip.reserve(8 * static_cast<std::size_t>(m));
    std::vector<int> row;
    for (int j = 0; j < m; ++j) {
      row.clear();
      for (int v : lf[j])
        for (int t = adj.face_offsets[v]; t < adj.face_offsets[v + 1]; ++t)
          if (adj.faces[t] <= j) row.push_back(adj.faces[t]);
      std::sort(row.begin(), row.end());
      row.erase(std::unique(row.begin(), row.end()), row.end());
      for (int k : row) trip.emplace_back(j, k, 1.0);
    }
    L.jj.resize(m, m);
    L.jj.setFromTriplets(trip.begin(), trip.end());
    L.jj.makeCompressed();
    L.jj_diag_slot.resize(m);
    for (int j = 0; j < m; ++j) L.jj_diag_slot[j] = jj_slot(L, j, j);
    L.llt = std::make_unique<Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower>>();
    L.llt->cholmod().print = 0;  // a failed factorization is handled; CHOLMOD printed it on stdout too
    const internal::SerialOpenMp serial;
    L.llt->analyzePattern(L.jj);
  }

  // Where entry (row, col), row >= col, of J J^T's lower triangle lives in L.jj's value array.
  static int jj_slot(const Level& L, int row, int col) {
    const int* inner = L.jj.innerIndexPtr();
    const int b = L.jj.outerIndexPtr()[col], e = L.jj.outerIndexPtr()[col + 1];
    return static_cast<int>(std::lower_bound(inner + b, inner + e, row) - inner);
  }

  // Writes the lower triangle of J J^T for gradients g (each entry the dot products of the two
  // prisms' gradients at their shared vertices, summed vertex by vertex) into L.jj's fixed
  // pattern, plus the damping's diagonal shift eps = damping * max diagonal.
  static void assemble(const Level& L, const std::vector<std::array<Vec3, 3>>& g, double damping) {
    const std::size_t m = L.faces.size();
    double* val = L.jj.valuePtr();
    std::fill(val, val + L.jj.nonZeros(), 0.0);
    const int nv = static_cast<int>(L.vf_offsets.size()) - 1;
    for (int k = 0; k < nv; ++k) {
      // The vertex's (face * 3 + corner) entries, faces ascending: each pair a <= b is the lower
      // entry (row b, column a).
      const int b0 = L.vf_offsets[k], b1 = L.vf_offsets[k + 1];
      for (int ta = b0; ta < b1; ++ta) {
        const int fa = L.vf[ta] / 3;
        const Vec3& ga = g[fa][L.vf[ta] % 3];
        val[L.jj_diag_slot[fa]] += ga.squaredNorm();
        for (int tb = ta + 1; tb < b1; ++tb) {
          const int fb = L.vf[tb] / 3;
          val[jj_slot(L, fb, fa)] += ga.dot(g[fb][L.vf[tb] % 3]);
        }
      }
    }
    double max_diag = 0.0;
    for (std::size_t j = 0; j < m; ++j) max_diag = std::max(max_diag, val[L.jj_diag_slot[j]]);
    const double eps = damping * max_diag + 1e-300;
    for (std::size_t j = 0; j < m; ++j) val[L.jj_diag_slot[j]] += eps;
  }

  void init_state(const BaseFrames& fr, const ReconstructRequest& request, State& s) const {
    if (!(std::abs(request.amplitude) <= kMaxAmplitude)) {
      std::ostringstream m;  // 1e300 overflowed the solve, reported as its options' fault
      m << "reconstruction: the amplitude " << request.amplitude << " is not within +-" << kMaxAmplitude;
      throw InvalidInput(m.str());
    }
    s.amplitude = request.amplitude;
    s.cycle_volume_iterations = opt_.volume_iterations;
    s.f = &guarded_f_;
    s.pin = enc_.pinned.empty() ? nullptr : &enc_.pinned;
    const int n = enc_.num_detail_vertices();
    check_frames(fr);
    s.Q = fr.points;
    s.N = fr.normals;
    s.tangential = opt_.tangential_regularization;
    if (opt_.tangential_regularization == TangentialRegularization::RestLaplacian) s.T = fr.tangents;
    s.R.resize(n);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d& o = enc_.tangential_offsets[i];
      s.R[i] = s.amplitude * (o[0] * fr.tangents[i] + o[1] * fr.normals[i].cross(fr.tangents[i]));
    }
    s.dRho.assign(n, 0.0);
    s.dT.assign(n, Vec3::Zero());
    // Checked with no pinned vertex too (the header's contract): a short array was taken silently.
    if (request.pinned_positions && static_cast<int>(request.pinned_positions->size()) != n)
      check_pinned_positions(*request.pinned_positions, [](int) { return false; });
    if (enc_.pinned.empty()) return;
    if (!request.pinned_positions) {
      s.pinned_at = internal::vectors_unchecked(enc_, fr, s.amplitude);  // both checked already
      return;
    }
    check_pinned_positions(*request.pinned_positions, [&](int i) { return enc_.pinned[i] != 0; });
    s.pinned_at = *request.pinned_positions;
  }

  // The checks of the callers' arrays, whose messages name vertices by index: run on the caller's
  // arrays before they are renumbered (in_solver_order(), solver_frames()), so that the index named
  // is the caller's.
  void check_frames(const BaseFrames& fr) const {
    const int n = enc_.num_detail_vertices();
    if (static_cast<int>(fr.points.size()) != n || static_cast<int>(fr.normals.size()) != n ||
        static_cast<int>(fr.tangents.size()) != n)
      throw InvalidInput("base frames have " + std::to_string(fr.points.size()) + " points, " +
                         std::to_string(fr.normals.size()) + " normals and " +
                         std::to_string(fr.tangents.size()) + " tangents; the detail has " +
                         std::to_string(n) + " vertices");
    for (int i = 0; i < n; ++i)
      if (!fr.points[i].allFinite() || !fr.normals[i].allFinite() || !fr.tangents[i].allFinite())
        throw InvalidInput("base frame " + std::to_string(i) + " is not finite");
    check_coordinates(fr.points, "base frames:");
  }
  template <class Pinned>
  void check_pinned_positions(const std::vector<Vec3>& pp, Pinned&& is_pinned) const {
    const int n = enc_.num_detail_vertices();
    if (static_cast<int>(pp.size()) != n)
      throw InvalidInput("reconstruction: " + std::to_string(pp.size()) + " pinned positions for " +
                         std::to_string(n) + " detail vertices");
    for (int i = 0; i < n; ++i)
      if (is_pinned(i) && !(pp[i].allFinite() && pp[i].cwiseAbs().maxCoeff() <= kMaxCoordinate))
        throw InvalidInput("reconstruction: pinned position " + std::to_string(i) +
                           " is not finite or beyond the engine's range");
  }
  void check_start(const std::vector<Vec3>& start) const {
    if (static_cast<int>(start.size()) != enc_.num_detail_vertices())
      throw InvalidInput("warm start has " + std::to_string(start.size()) + " positions, the detail has " +
                         std::to_string(enc_.num_detail_vertices()) + " vertices");
    check_coordinates(start, "warm start:");
  }

  bool pinned(int i) const { return !enc_.pinned.empty() && enc_.pinned[i]; }

  // Pinned vertices sit where displacement vectors (or the caller) put them, whatever the start;
  // at a volume scale t < 1 their displacement from the base point is scaled by t.
  void place_pinned(State& s, double t = 1.0) const {
    if (enc_.pinned.empty()) return;
    for (std::size_t i = 0; i < s.P.size(); ++i)
      if (enc_.pinned[i]) s.P[i] = t == 1.0 ? s.pinned_at[i] : Vec3(s.Q[i] + t * (s.pinned_at[i] - s.Q[i]));
  }

  void report(const char* phase, double f) const {
    if (opt_.progress) opt_.progress(phase, f);
  }

  // ReconstructOptions::cancel, read between steps.
  void check_cancel() const {
    if (opt_.cancel && opt_.cancel->load(std::memory_order_relaxed))
      throw Cancelled("reconstruction cancelled (ReconstructOptions::cancel)");
  }

  // Whether coarse level l only follows by prolongation and regularization in a clean start's
  // intermediate pass (ReconstructOptions::intermediate_regularized_levels); never the coarsest.
  bool regularized_only(int l, bool full_scale, bool coarse_only) const {
    const int nl = static_cast<int>(levels_.size());
    return coarse_only && !full_scale && l > 0 && l + 1 < nl &&
           nl - 1 - l <= opt_.intermediate_regularized_levels;
  }

  // A level's share of a clean start's work (ReconstructOptions::progress): its prisms, three
  // times the finest level's at the full scale (the cycles and the polish), a tenth where it is
  // only regularized.
  double level_work(int l, bool full_scale, bool coarse_only) const {
    const bool finest = l + 1 == static_cast<int>(levels_.size());
    const double prisms = static_cast<double>(levels_[l].faces.size());
    if ((finest && coarse_only && levels_.size() > 1) || regularized_only(l, full_scale, coarse_only))
      return 0.1 * prisms;
    return finest && full_scale ? 3.0 * prisms : prisms;
  }

  // Relative volume errors this small are rounding: solves driven to a tolerance below reach (the
  // tests' folding rings at 1e-15) end at 4e-14 to 6e-14 of the mean volume.
  static constexpr double kRoundingError = 1e-12;

  // How a clean-start solve ended: converged to the tolerance, and (if counted) the intersecting
  // pairs of detail triangles that the rest detail does not have.
  struct Outcome {
    bool converged = false;
    double max_error = 0.0;
    std::size_t new_pairs = 0;
    // Of new_pairs, those that are a contact made by the edit (ReconstructOptions::contact_ratio):
    // no schedule or repair undoes them, so they start no retry, repair or fallback.
    std::size_t contact_pairs = 0;
    // Of new_pairs, the others near the edited base's own new crossings (base_crossing_rings).
    std::size_t crossing_pairs = 0;
    bool counted = false;    // new_pairs was counted
    bool listed = false;     // and its pairs listed (the search was not cut short)
    double tolerance = 0.0;  // the tolerance converged was judged by
    // The faces of the new pairs that are not contacts (those the fold repair works on), sorted,
    // distinct.
    std::vector<int> new_pair_faces;
    // The new pairs that decide the retries and the fallback schedule: neither contacts nor next
    // to the base's crossings, which a clean-start solve with another schedule would meet again.
    std::size_t folds() const { return new_pairs - contact_pairs - crossing_pairs; }
    // Those the fold repair takes on: all but the contacts (local smoothing may still undo a pair
    // next to a crossing of the base: the camel's neck bend, 2 such pairs).
    std::size_t repairable() const { return new_pairs - contact_pairs; }
    bool better_than(const Outcome& o) const {
      if (converged != o.converged) return converged;
      // By all the new pairs, as before the base's pairs were told apart: they only decide
      // whether another schedule runs. (Choosing by the other pairs first kept 1,101 new pairs,
      // none of them a fold, over 567 with 6 on the camel's band 2 when its top bends into the
      // body.)
      if (converged) return new_pairs < o.new_pairs;
      // Two unconverged results whose pairs were counted (a fold repair after a solve that ends
      // above the tolerance): better only if worse in neither, so that a repair never trades
      // volume accuracy for folds or back. Errors within 1% of the tolerance, or within
      // kRoundingError, count as equal: a repair that unfolds moves the prisms next to the worst
      // one, whose error then changes in its tenth digit (the armadillo's arm: 2.34615961839e-4
      // against 2.34615961794e-4), and a solve that ends at rounding (tolerance below it) ends
      // where the BLAS kernels' rounding puts it (the folding rings of the tests at 1e-15: 4.1e-14
      // to 6.3e-14 with 56 new pairs, repaired 4.2e-14 to 5.2e-14 with none, by OpenBLAS's kernel
      // set; with 1% of the tolerance alone the Zen and Haswell kernels' repairs were refused).
      if (counted && o.counted)
        return (new_pairs < o.new_pairs &&
                max_error <= o.max_error + std::max(1e-2 * tolerance, kRoundingError)) ||
               (new_pairs <= o.new_pairs && max_error < o.max_error);
      return max_error < o.max_error;
    }
  };

  // A solve driven out of range (e.g. a regularization weight of 1e308) is named as such, not as
  // the non-finite coordinates that a count or a writer would meet next.
  // The vertex named is the caller's: the smallest caller index among the non-finite ones.
  // Positions beyond ten times the range the inputs are checked to lie in count too (over a cage
  // flattened to a plane a solve returned coordinates of 8e21).
  void check_finite(const State& s) const {
    int bad = -1;
    for (std::size_t i = 0; i < s.P.size(); ++i)
      if (!s.P[i].allFinite() || s.P[i].cwiseAbs().maxCoeff() > 10 * kMaxCoordinate) {
        const int v = renum_.empty() ? static_cast<int>(i) : renum_.old_of_new[i];
        if (bad < 0 || v < bad) bad = v;
        if (renum_.empty()) break;
      }
    if (bad >= 0)
      throw SolverError(
          "reconstruction produced non-finite positions or positions beyond the engine's range (detail "
          "vertex " +
          std::to_string(bad) +
          "): the solve diverged (a base edited beyond what the detail can follow, or options out of a "
          "workable range)");
  }

  // The intersection searches of the fold checks: within bounded_intersection_options(), since a
  // detail whose triangles mostly cross (or whose long thin triangles' boxes mostly overlap) would
  // cost O(n^2), listing the pairs, on the solver's threads (ReconstructOptions::threads; the
  // pairs are sorted, so the count is the same on any number of them).
  IntersectionOptions search_options() const {
    IntersectionOptions io = bounded_intersection_options(enc_.detail_faces.size());
    io.collect_pairs = true;
    io.cancel = opt_.cancel;
    io.parallel = arena_ != nullptr;
    return io;
  }
  IntersectionResult search(const std::vector<Vec3>& p) const {
    const IntersectionOptions io = search_options();
    if (!arena_) return find_self_intersections(p, enc_.detail_faces, io);
    return arena_->execute([&] { return find_self_intersections(p, enc_.detail_faces, io); });
  }

  // search(s.P), around the faces moved since the state's last search when it has one (at 1M
  // prisms a whole search took 0.8 s, one thread: four fold-repair rounds cost more in searches
  // than in repairs).
  const IntersectionResult& search_detail(const State& s) const {
    if (s.searched && s.searched_at.size() == s.P.size()) {
      std::vector<char> moved(s.P.size(), 0);
      for (std::size_t v = 0; v < s.P.size(); ++v) moved[v] = s.P[v] != s.searched_at[v];
      std::vector<int> changed;
      const std::vector<Face>& faces = enc_.detail_faces;
      for (std::size_t j = 0; j < faces.size(); ++j)
        if (moved[faces[j][0]] || moved[faces[j][1]] || moved[faces[j][2]])
          changed.push_back(static_cast<int>(j));
      const IntersectionOptions io = search_options();
      auto update = [&] { return internal::update_self_intersections(s.P, faces, *s.searched, changed, io); };
      *s.searched = arena_ ? arena_->execute(update) : update();
    } else {
      s.searched = std::make_unique<IntersectionResult>(search(s.P));
    }
    s.searched_at = s.P;
    return *s.searched;
  }

  // ReconstructOptions::base_crossing_rings: per finest vertex, whether it lies within that many
  // rings of a new crossing of the edited base, as the detail's triangles over their base points
  // show it (pairs of them that cross where the rest base points' do not); exact for the vertices
  // of the faces \p seeds (the folds to tell), which is all a fold check asks. Empty if there is
  // none, or if the rest base's search or the edited one's was cut short, or the option is off.
  // Only the crossings that can reach a seed are searched: those with a face within the rings of
  // one (at 1M prisms the whole search took 0.5 s of a reconstruction, one thread).
  std::vector<char> near_base_crossings(const State& s, const std::vector<int>& seeds) const {
    if (opt_.base_crossing_rings < 0 || enc_.base_rest_points.size() != s.Q.size() || seeds.empty())
      return {};
    if (!rest_base_pairs_)
      rest_base_pairs_ = std::make_unique<IntersectionResult>(search(enc_.base_rest_points));
    if (rest_base_pairs_->truncated) return {};
    // The faces with a vertex within the rings of a seed: a crossing reaches a seed's vertex iff
    // one of its faces is one of them (the rings are symmetric). The other faces' pairs are the
    // rest base's in the search below, so they are not fresh.
    std::vector<int> subset, next, region;
    std::vector<char> in;
    grow_rings(seeds, opt_.base_crossing_rings, in, subset, next);
    const Level& F = levels_.back();
    std::vector<char> taken(F.faces.size(), 0);
    for (int v : subset)
      for (int t = F.vf_offsets[v]; t < F.vf_offsets[v + 1]; ++t)
        if (!taken[F.vf[t] / 3]) taken[F.vf[t] / 3] = 1, region.push_back(F.vf[t] / 3);
    const IntersectionOptions io = search_options();
    auto update = [&] {
      return internal::update_self_intersections(s.Q, enc_.detail_faces, *rest_base_pairs_, region, io);
    };
    const IntersectionResult now = arena_ ? arena_->execute(update) : update();
    if (now.truncated) return {};
    std::vector<std::pair<int, int>> fresh;
    std::set_difference(now.pairs.begin(), now.pairs.end(), rest_base_pairs_->pairs.begin(),
                        rest_base_pairs_->pairs.end(), std::back_inserter(fresh));
    if (fresh.empty()) return {};
    std::vector<int> crossing;
    for (const auto& [i, j] : fresh) crossing.insert(crossing.end(), {i, j});
    grow_rings(crossing, opt_.base_crossing_rings, in, subset, next);
    return in;
  }

  // ReconstructStats' pair counts of the result kept.
  static void report_pairs(const Outcome& o, ReconstructStats& st) {
    st.new_intersecting_pairs = o.counted ? static_cast<long long>(o.new_pairs) : -1;
    st.contact_pairs = o.listed ? static_cast<long long>(o.contact_pairs) : -1;
    st.base_crossing_pairs = o.listed ? static_cast<long long>(o.crossing_pairs) : -1;
  }

  // The new pairs are counted (retry_on_new_intersections) for a converged result, and for an
  // unconverged one only if \p count_unconverged: during the solve an unconverged result is
  // retried, or compared by its error, regardless; the result kept in the end is checked either
  // way (fold_checked()).
  Outcome outcome(const State& s, double a, std::vector<double>& V, bool count_unconverged = false) const {
    check_finite(s);
    Outcome o;
    const Level& F = levels_.back();
    compute_volumes(F, s, V);
    o.max_error = relative_error(F, a, V, nullptr);
    o.tolerance = opt_.tolerance;
    o.converged = o.max_error <= opt_.tolerance;
    if ((o.converged || count_unconverged) && opt_.retry_on_new_intersections) {
      // Within bounded_intersection_options(): a detail whose triangles mostly cross (or whose
      // long thin triangles' boxes mostly overlap) would cost O(n^2). Whether a search is cut
      // short does not depend on the threads (find_self_intersections()), and neither does what
      // follows: a result cut short counts as max_pairs new pairs, none listed (far above what
      // the repair takes on), unless the rest detail's search is cut short too, which leaves the
      // check undone (no pair is known to be new).
      if (rest_pairs_ && rest_pairs_->truncated) return o;  // not counted, as below
      const IntersectionResult& now = search_detail(s);
      if (now.truncated) {
        if (!rest_pairs_) rest_pairs_ = std::make_unique<IntersectionResult>(search(enc_.detail_rest));
        if (rest_pairs_->truncated) return o;  // not counted
        o.counted = true;
        o.new_pairs = search_options().max_pairs;
        return o;
      }
      o.counted = true;
      // The result's pairs that do not cross at rest. Each is tested at the rest positions with
      // the search's own predicate (triangles_intersect(): the same exact test, degenerate
      // triangles apart), so the count is the one a whole search of the rest detail gives; that
      // search took 0.82 s of a 1M-prism first reconstruction (0.076 s at 100k), one thread.
      std::vector<std::pair<int, int>> fresh;
      if (rest_pairs_) {
        std::set_difference(now.pairs.begin(), now.pairs.end(), rest_pairs_->pairs.begin(),
                            rest_pairs_->pairs.end(), std::back_inserter(fresh));
      } else {
        const std::vector<Vec3>& R = enc_.detail_rest;
        auto corners = [&](int j) {
          const Face& f = enc_.detail_faces[j];
          return std::array<Vec3, 3>{R[f[0]], R[f[1]], R[f[2]]};
        };
        for (const auto& pr : now.pairs)
          if (!triangles_intersect(corners(pr.first), corners(pr.second))) fresh.push_back(pr);
      }
      o.new_pairs = fresh.size();
      o.listed = true;
      // The pairs that the edited base explains are not the solver's folds: contacts
      // (contact_ratio), and pairs next to the base's own new crossings (base_crossing_rings).
      std::vector<char> contact(fresh.size(), 0);
      if (opt_.contact_ratio > 0 && !fresh.empty()) {
        if (!s.contact)
          s.contact = std::make_unique<internal::ContactTest>(
              internal::BaseGraph{&F.faces, &F.vf_offsets, &F.vf, &s.Q}, opt_.contact_ratio);
        for (std::size_t k = 0; k < fresh.size(); ++k)
          contact[k] = (*s.contact)(fresh[k].first, fresh[k].second);
      }
      const bool folds_left = std::find(contact.begin(), contact.end(), 0) != contact.end();
      std::vector<char> near;
      if (folds_left) {
        std::vector<int> folds;
        for (std::size_t k = 0; k < fresh.size(); ++k)
          if (!contact[k]) folds.insert(folds.end(), {fresh[k].first, fresh[k].second});
        near = near_base_crossings(s, folds);
      }
      auto near_crossing = [&](int j) {
        const Face& f = F.faces[j];
        return near[f[0]] || near[f[1]] || near[f[2]];
      };
      for (std::size_t k = 0; k < fresh.size(); ++k) {
        if (contact[k]) {
          ++o.contact_pairs;
          continue;
        }
        if (!near.empty() && (near_crossing(fresh[k].first) || near_crossing(fresh[k].second)))
          ++o.crossing_pairs;
        o.new_pair_faces.push_back(fresh[k].first);
        o.new_pair_faces.push_back(fresh[k].second);
      }
      if (!context_.faces.empty()) add_context_pairs(s, o);
      std::sort(o.new_pair_faces.begin(), o.new_pair_faces.end());
      o.new_pair_faces.erase(std::unique(o.new_pair_faces.begin(), o.new_pair_faces.end()),
                             o.new_pair_faces.end());
    }
    return o;
  }

  // A uniform grid of points: each cell lists the points in it.
  struct PointGrid : internal::CellGrid {
    static constexpr double kMaxCells = 4096;
    std::unordered_map<std::uint64_t, std::vector<int>> cells;
    void insert(const Vec3& p, int id) { cells[key(p)].push_back(id); }
    // f(ids) for the lists of the cells \p b covers (which may hold points outside \p b: cell
    // coordinates wrap). \pre span(b) is small (the cells are enumerated).
    template <class F>
    void visit(const Eigen::AlignedBox3d& b, F&& f) const {
      for_each_cell(b, [&](std::uint64_t k) {
        const auto it = cells.find(k);
        if (it != cells.end()) f(it->second);
      });
    }
  };

  // The context faces (indices into \p faces, whose points past the detail's are \p points) that
  // can make a pair that is no contact (contact_ratio): those whose rest centroid lies within
  // contact_ratio times their and a detail face's longest edges of that detail face's rest
  // centroid. A farther one can only make contacts, which decide nothing. All of them without
  // contact_ratio. The detail faces in classes of longest edge (within a factor of 2), each a grid
  // of its centroids (cell: twice contact_ratio times its longest edge), so that a class's lookup
  // covers a few cells around a context face of that size and each detail face is listed once; a
  // lookup that would cover more cells than the class has faces checks them all.
  std::vector<int> near_context(const std::vector<Vec3>& points, const std::vector<Face>& faces) const {
    std::vector<int> near;
    const auto n = static_cast<int>(enc_.detail_rest.size());
    const double r = opt_.contact_ratio;
    if (!(r > 0)) {
      near.resize(faces.size());
      std::iota(near.begin(), near.end(), 0);
      return near;
    }
    auto at = [&](int i) -> const Vec3& { return i < n ? enc_.detail_rest[i] : points[i - n]; };
    auto longest = [&](const Face& f) {
      double e = 0.0;
      for (int k = 0; k < 3; ++k) e = std::max(e, (at(f[k]) - at(f[(k + 1) % 3])).norm());
      return e;
    };
    auto centroid = [&](const Face& f) -> Vec3 { return (at(f[0]) + at(f[1]) + at(f[2])) / 3.0; };
    const std::size_t nd = enc_.detail_faces.size();
    std::vector<Vec3> dc(nd);
    std::vector<double> de(nd);
    struct Class {
      double longest = 0.0;
      Eigen::AlignedBox3d box;  // of its centroids
      std::vector<int> faces;
      PointGrid grid;
    };
    std::map<int, Class> classes;  // by the binary exponent of the longest edge
    for (std::size_t j = 0; j < nd; ++j) {
      dc[j] = centroid(enc_.detail_faces[j]);
      de[j] = longest(enc_.detail_faces[j]);
      int exponent = 0;
      std::frexp(de[j], &exponent);
      Class& c = classes[exponent];
      c.longest = std::max(c.longest, de[j]);
      c.box.extend(dc[j]);
      c.faces.push_back(static_cast<int>(j));
    }
    for (auto& [exponent, c] : classes) {
      c.grid.cell = std::max(2.0 * r * c.longest, 1e-300);
      c.grid.cells.reserve(c.faces.size());
      for (int j : c.faces) c.grid.insert(dc[j], j);
    }
    for (std::size_t k = 0; k < faces.size(); ++k) {
      const Vec3 cg = centroid(faces[k]);
      const double eg = longest(faces[k]);
      auto within = [&](int j) { return (cg - dc[j]).norm() <= r * (eg + de[j]); };
      bool found = false;
      for (auto it = classes.begin(); it != classes.end() && !found; ++it) {
        const Class& c = it->second;
        // A little more than the reach, so that rounding cannot drop a face at exactly that distance.
        double reach = r * (eg + c.longest);
        reach += 1e-9 * (reach + cg.cwiseAbs().maxCoeff());
        if (c.box.exteriorDistance(cg) > reach) continue;  // most of a large mesh's rest
        const Eigen::AlignedBox3d box(cg - Vec3::Constant(reach), cg + Vec3::Constant(reach));
        if (c.grid.span(box) > std::min(PointGrid::kMaxCells, static_cast<double>(c.faces.size()))) {
          for (std::size_t t = 0; t < c.faces.size() && !found; ++t) found = within(c.faces[t]);
        } else {
          c.grid.visit(box, [&](const std::vector<int>& ids) {
            for (std::size_t t = 0; t < ids.size() && !found; ++t) found = within(ids[t]);
          });
        }
      }
      if (found) near.push_back(static_cast<int>(k));
    }
    return near;
  }

  // The pairs (detail face, context face) whose triangles share no vertex and intersect with the
  // detail at \p p and the context at \p points, sorted (find_intersections_between(), within the
  // fold checks' limits). *cut: more pairs or tests than those limits.
  std::vector<std::pair<int, int>> context_pairs(const std::vector<Vec3>& p, const std::vector<Vec3>& points,
                                                 bool& cut) const {
    std::vector<Vec3> all;
    all.reserve(p.size() + points.size());
    all.insert(all.end(), p.begin(), p.end());
    all.insert(all.end(), points.begin(), points.end());
    const IntersectionOptions io = search_options();
    auto run = [&] { return find_intersections_between(all, enc_.detail_faces, context_.faces, io); };
    IntersectionResult r = arena_ ? arena_->execute(run) : run();
    cut = r.truncated;
    return std::move(r.pairs);
  }

  // set_intersection_context(): the new pairs of a detail triangle and a context triangle, added to
  // \p o as the detail's own. Not by the detail pairs' contact test (a path along the base, which
  // a context triangle has no place in) but by the distance at rest: a pair whose triangles' rest
  // centroids lay farther apart than contact_ratio times their longest edges together is a
  // contact the edit made (a limb bent into the body); one that the displacement vectors'
  // placement of the detail triangle makes too is the base's (crossing_pairs; none with
  // base_crossing_rings < 0); the others are folds. The detail faces of all but the contacts go
  // to the repair, as the detail's own pairs next to a crossing do. A search cut short counts as
  // max_pairs new pairs, none listed; a rest search cut short leaves the context unchecked, as the
  // detail's own pairs are then.
  void add_context_pairs(const State& s, Outcome& o) const {
    if (!rest_context_) {
      // Filled before it is kept: a cancel during the search leaves no half-made cache behind.
      auto rest = std::make_unique<ContextPairs>();
      rest->pairs = context_pairs(enc_.detail_rest, context_rest_points(), rest->cut);
      rest_context_ = std::move(rest);
    }
    if (rest_context_->cut) return;
    bool cut = false;
    const std::vector<std::pair<int, int>> now = context_pairs(s.P, context_.points, cut);
    if (cut) {
      o.new_pairs += search_options().max_pairs;
      o.listed = false;
      return;
    }
    std::vector<std::pair<int, int>> fresh;
    std::set_difference(now.begin(), now.end(), rest_context_->pairs.begin(), rest_context_->pairs.end(),
                        std::back_inserter(fresh));
    const auto n = static_cast<int>(s.P.size());
    const std::vector<Vec3>& rest = context_rest_points();
    auto at = [&](int i) -> const Vec3& { return i < n ? s.P[i] : context_.points[i - n]; };
    auto at_rest = [&](int i) -> const Vec3& { return i < n ? enc_.detail_rest[i] : rest[i - n]; };
    auto longest_edge = [&](const Face& f) {
      double e = 0.0;
      for (int k = 0; k < 3; ++k) e = std::max(e, (at_rest(f[k]) - at_rest(f[(k + 1) % 3])).norm());
      return e;
    };
    auto centroid = [&](const Face& f) { return (at_rest(f[0]) + at_rest(f[1]) + at_rest(f[2])) / 3.0; };
    for (const auto& [d, c] : fresh) {
      ++o.new_pairs;
      const Face& f = enc_.detail_faces[d];
      const Face& g = context_.faces[c];
      if (opt_.contact_ratio > 0 &&
          (centroid(f) - centroid(g)).norm() > opt_.contact_ratio * (longest_edge(f) + longest_edge(g))) {
        ++o.contact_pairs;
        continue;
      }
      o.new_pair_faces.push_back(d);
      std::array<Vec3, 3> vectors, ctx;
      for (int k = 0; k < 3; ++k) {
        const int i = f[k];
        vectors[k] = s.Q[i] + s.amplitude * enc_.normal_offsets[i] * s.N[i] + s.R[i];
        ctx[k] = at(g[k]);
      }
      if (opt_.base_crossing_rings >= 0 && triangles_intersect(vectors, ctx)) ++o.crossing_pairs;
    }
  }

  // The result kept in the end, if it ended above the tolerance (both schedules did, or a drag's
  // exact end did): its new pairs are counted and repaired too (retry_on_new_intersections), so
  // that a result short of the tolerance is not left folded unchecked. Measured: the armadillo's
  // arm bend (tests/data/edits/armadillo_arm.json, smoothing 0.7) ends both schedules near 2.4e-4
  // of the mean volume, and with OpenBLAS's generic kernels (as the test binary got them on an
  // Intel VM) with 1 new pair, where the Haswell, SkylakeX, Cooperlake and Zen kernels' rounding
  // left none. The repair rounds keep a result only if it is worse in neither pairs nor error
  // (Outcome::better_than).
  void fold_checked(State& s, double a, ReconstructStats& st, std::vector<double>& V, Outcome& o) const {
    if (o.converged || o.counted || !opt_.retry_on_new_intersections) return;
    o = outcome(s, a, V, /*count_unconverged=*/true);
    repair_folds(s, a, st, V, o);
  }

  // ReconstructOptions::fallback_schedule: the clean-start solve once more with the other
  // preset, from its own Impl (built on first use: its hierarchy and solver structures differ), and
  // its result kept in s.P and \p first if better.
  void fall_back(const BaseFrames& fr, const ReconstructRequest& request, State& s, ReconstructStats& st,
                 Outcome& first) const {
    if (!fallback_) {
      ReconstructOptions o = opt_.step_solver == VolumeStepSolver::Multigrid
                                 ? ReconstructOptions{}
                                 : multigrid_reconstruct_options();
      o.tolerance = opt_.tolerance;
      o.threads = opt_.threads;
      o.fold_repair_local_first = opt_.fold_repair_local_first;  // a .strata file's, as it repaired
      o.fold_repair_local_rings = opt_.fold_repair_local_rings;
      o.fold_repair_local_rounds = opt_.fold_repair_local_rounds;
      o.renumber_for_locality = false;                       // enc_ is in the solver's numbering already
      o.max_constraint_motion = opt_.max_constraint_motion;  // the caller's bound (0: none)
      // The caller's, as the fold repair's: a .strata file written before solves as then, and the
      // default options (0) fall back to the preset with every coarse level solved, as before the
      // preset took 1 (with 1 the camel's top bend kept 781 new pairs on band 2 against 567).
      o.intermediate_regularized_levels = opt_.intermediate_regularized_levels;
      o.contact_ratio = opt_.contact_ratio;
      o.base_crossing_rings = opt_.base_crossing_rings;
      o.progress = opt_.progress;
      o.cancel = opt_.cancel;
      o.fallback_schedule = false;
      // An encoding built by hand may lack the base's rest frames, which the preset's rest
      // Laplacian needs: it then falls back to the preset with rest offsets, not to an error.
      if (enc_.base_rest_normals.size() != enc_.detail_rest.size() ||
          enc_.base_rest_tangents.size() != enc_.detail_rest.size()) {
        // The preset as it was before the rest Laplacian: rest offsets with a converged coarsest
        // level fold the bends.
        o.tangential_regularization = TangentialRegularization::RestOffset;
        o.coarsest_regularization_iterations = 0;
        o.coarsest_max_cycles = 0;
        o.final_max_cycles = 3;
      }
      fallback_ = std::make_unique<Impl>(enc_, std::move(o));
      fallback_->phase_ = "fallback";
      // Already in the solver's numbering; set_intersection_context() keeps it up to date after.
      if (!context_.faces.empty()) fallback_->set_intersection_context(context_);
    }
    // The rest detail's pairs, counted already (first.counted), are the same for it.
    if (!fallback_->rest_pairs_ && rest_pairs_)
      fallback_->rest_pairs_ = std::make_unique<IntersectionResult>(*rest_pairs_);
    if (!fallback_->rest_base_pairs_ && rest_base_pairs_)
      fallback_->rest_base_pairs_ = std::make_unique<IntersectionResult>(*rest_base_pairs_);
    ++st.fallbacks;
    ReconstructResult r = fallback_->run(fr, nullptr, nullptr, request);
    Outcome other;
    other.converged = r.stats.converged;
    other.max_error = r.stats.max_relative_error;
    other.tolerance = opt_.tolerance;
    other.counted = r.stats.new_intersecting_pairs >= 0;
    other.new_pairs = other.counted ? static_cast<std::size_t>(r.stats.new_intersecting_pairs) : 0;
    other.listed = r.stats.contact_pairs >= 0 && r.stats.base_crossing_pairs >= 0;
    other.contact_pairs = other.listed ? static_cast<std::size_t>(r.stats.contact_pairs) : 0;
    other.crossing_pairs = other.listed ? static_cast<std::size_t>(r.stats.base_crossing_pairs) : 0;
    if (other.counted && other.better_than(first)) {
      s.P = std::move(r.positions);
      first = std::move(other);
      st.fallback_kept = true;
    }
  }

  // Local fold repair (ReconstructOptions::fold_repair_rounds): rounds of regularization around
  // the new pairs' triangles at full weight, each followed by exact steps that restore the
  // volumes. \p best is the outcome of s.P on entry; on return s.P is the best result and \p best
  // its outcome. Two passes of rounds from the entry positions: first the volumes are restored by
  // moving the smoothed vertices and fold_repair_local_rings rings around them (a small system per
  // round); unless that ends converged without new pairs, the rounds again with the whole finest
  // level polished too, whose minimum-norm correction spreads wider and unfolds more (the rings),
  // at a whole-level solve a round (0.9 s on the scan-like 100k cuboid, where the local pass alone
  // leaves no new pairs). The second pass is the repair as it was before the first existed, so
  // the outcome is never worse by Outcome::better_than's order.
  void repair_folds(State& s, double a, ReconstructStats& st, std::vector<double>& V, Outcome& best) const {
    if (!best.counted || best.repairable() == 0 || opt_.fold_repair_rounds <= 0) return;
    // Many pairs are a global self-contact (a limb bent into the body: the armadillo's top in a
    // layered model had 10-12% of its prisms' triangles in new pairs), which local smoothing
    // cannot undo; local folds touch far fewer (the 100k rings: 246 pairs, 0.25%).
    if (static_cast<double>(best.repairable()) > opt_.fold_repair_max_fraction * levels_.back().faces.size())
      return;
    if (!opt_.fold_repair_local_first) {
      repair_rounds(s, a, st, V, best, /*whole_level=*/true, opt_.fold_repair_rounds);
      return;
    }
    const std::vector<Vec3> entry = s.P;
    Outcome local = best;
    const int local_rounds =
        opt_.fold_repair_local_rounds < 0 ? opt_.fold_repair_rounds : opt_.fold_repair_local_rounds;
    repair_rounds(s, a, st, V, local, /*whole_level=*/false, local_rounds);
    if (local.converged && local.repairable() == 0) {
      best = std::move(local);
      return;
    }
    std::vector<Vec3> local_positions;
    local_positions.swap(s.P);
    s.P = entry;
    repair_rounds(s, a, st, V, best, /*whole_level=*/true, opt_.fold_repair_rounds);
    if (local.better_than(best)) {
      s.P.swap(local_positions);
      best = std::move(local);
    }
  }

  // The rounds of repair_folds(), from s.P with outcome \p best; on return s.P is the best result
  // and \p best its outcome. \p whole_level: a round whose local restoration leaves folds (or
  // does not converge) also polishes the whole finest level from the smoothed positions, and keeps
  // the better of the two. At most \p rounds rounds.
  void repair_rounds(State& s, double a, ReconstructStats& st, std::vector<double>& V, Outcome& best,
                     bool whole_level, int rounds) const {
    // An unconverged result (checked by fold_checked()) has its rounds' results counted too.
    const bool count = !best.converged;
    const Level& F = levels_.back();
    std::vector<Vec3> kept = s.P;
    std::vector<int> seeds = best.new_pair_faces;
    std::vector<char> in;
    std::vector<int> subset, moving, next;
    std::vector<Vec3> smoothed, local_result;
    int stalled = 0;  // rounds since the best result last improved
    for (int round = 0; round < rounds; ++round) {
      check_cancel();
      grow_rings(seeds, opt_.fold_repair_rings + round, in, subset, next);
      for (int it = 0; it < opt_.fold_repair_sweeps; ++it) regularize(F, s, 1.0, &subset);
      st.regularization_sweeps += opt_.fold_repair_sweeps;
      // Only the prisms around the smoothed vertices lost their volumes: first restore them by
      // moving those vertices alone (a small system, nearly free), and in the local pass
      // fold_repair_local_rings rings more, so that the correction spreads beyond the smoothed
      // patch as a whole-level polish's does.
      smoothed = s.P;
      const int more_rings = whole_level ? 0 : opt_.fold_repair_local_rings;
      if (more_rings > 0) grow_rings(seeds, opt_.fold_repair_rings + round + more_rings, in, moving, next);
      Outcome o;
      double damping = kMinDamping;
      const bool local_done = local_polish(local_set(more_rings > 0 ? moving : subset), s, a, opt_.tolerance,
                                           st, opt_.max_final_steps, damping);
      if (local_done || count) o = outcome(s, a, V, count);
      if (whole_level && (!o.converged || o.repairable() > 0)) {
        local_result.swap(s.P);
        s.P = smoothed;
        s.gn.damping = kMinDamping;
        polish(F, s, opt_.tolerance, st, V, /*local_end=*/false);
        ++st.fold_repair_polishes;
        Outcome global = outcome(s, a, V, count);
        if (global.better_than(o))
          o = std::move(global);
        else
          s.P.swap(local_result);
      }
      ++st.fold_repairs;
      if (o.better_than(best)) {
        kept = s.P;
        best = std::move(o);
        stalled = 0;
        if (best.repairable() == 0) break;
      } else if (++stalled == 2) {
        break;  // two rounds without progress: the rest would not do better
      }
      // The next round grows around the new pairs of this round's result (or of the best one).
      seeds = o.new_pair_faces.empty() ? best.new_pair_faces : o.new_pair_faces;
      if (seeds.empty()) break;
    }
    s.P.swap(kept);
  }

  // \p subset = the vertices of the finest level's faces \p seeds, grown by \p rings rings over
  // the regularization neighbours. \p in (one flag per vertex) and \p next are scratch.
  void grow_rings(const std::vector<int>& seeds, int rings, std::vector<char>& in, std::vector<int>& subset,
                  std::vector<int>& next) const {
    const Level& F = levels_.back();
    in.assign(F.verts.size(), 0);
    subset.clear();
    for (int j : seeds)
      for (int v : F.faces[j])
        if (!in[v]) in[v] = 1, subset.push_back(v);
    for (int ring = 0; ring < rings; ++ring) {
      next.clear();
      for (int k : subset)
        for (int t = F.nb_offsets[k]; t < F.nb_offsets[k + 1]; ++t)
          if (!in[F.nb[t]]) in[F.nb[t]] = 1, next.push_back(F.nb[t]);
      subset.insert(subset.end(), next.begin(), next.end());
    }
  }

  // What a local step over the finest vertices \p free changes: the vertices that move (those of
  // \p free that are not pinned) and the prisms with a moving vertex.
  struct LocalSet {
    const std::vector<int>* free = nullptr;
    std::vector<char> moves;  // per finest vertex: whether it moves
    std::vector<int> faces;   // the prisms with a moving vertex, ascending
    std::vector<int> local;   // per finest prism: its index in faces (-1: not in it)
  };
  LocalSet local_set(const std::vector<int>& free) const {
    const Level& F = levels_.back();
    LocalSet ls;
    ls.free = &free;
    ls.moves.assign(F.verts.size(), 0);
    for (int v : free)
      if (!pinned(v)) ls.moves[v] = 1;
    ls.local.assign(F.faces.size(), -1);
    for (int v : free)
      if (ls.moves[v])
        for (int t = F.vf_offsets[v]; t < F.vf_offsets[v + 1]; ++t)
          if (ls.local[F.vf[t] / 3] < 0) ls.local[F.vf[t] / 3] = 0, ls.faces.push_back(F.vf[t] / 3);
    std::sort(ls.faces.begin(), ls.faces.end());
    for (std::size_t j = 0; j < ls.faces.size(); ++j) ls.local[ls.faces[j]] = static_cast<int>(j);
    return ls;
  }

  // Exact Gauss-Newton steps on the prisms of \p set (local_set()), only its moving vertices
  // moving, until these prisms meet the tolerance, at most \p max_steps of them. Other prisms do
  // not change. Returns whether the tolerance was reached; if not, the positions are as the last
  // step left them (as on entry if the system is dense, dense_pattern(): none is taken). \p damping: the
  // Levenberg-Marquardt shift to start from, and on return the one the next step would take.
  bool local_polish(const LocalSet& set, State& s, double a, double tol, ReconstructStats& st, int max_steps,
                    double& damping) const {
    const Level& F = levels_.back();
    const std::vector<int>& free = *set.free;
    const std::vector<char>& moves = set.moves;
    const std::vector<int>& faces = set.faces;
    const std::vector<int>& local = set.local;
    const int k = static_cast<int>(faces.size());
    if (dense_pattern(F.vf_offsets, &free)) return false;  // a hub: not factorized, nothing moved
    const double scale = std::abs(a) * F.mean_abs_target;
    std::vector<std::array<Vec3, 3>> g(k);
    Eigen::VectorXd r(k);
    auto residual = [&](bool with_gradients) {
      double rr = 0.0, mx = 0.0;
      for (int j = 0; j < k; ++j) {
        const Face& f = F.faces[faces[j]];
        const PrismVolumeGradient pg =
            prism_volume_gradient(s.P[f[0]], s.P[f[1]], s.P[f[2]], s.Q[f[0]], s.Q[f[1]], s.Q[f[2]]);
        if (with_gradients)
          for (int c = 0; c < 3; ++c) g[j][c] = moves[f[c]] ? pg.grad[c] : Vec3(Vec3::Zero());
        r[j] = a * F.targets[faces[j]] - pg.volume;
        rr += r[j] * r[j];
        mx = std::max(mx, std::abs(r[j]));
      }
      return std::make_pair(rr, scale > 0 ? mx / scale : 0.0);
    };
    // J J^T's pattern over the local prisms is the same at every step: its ordering and symbolic
    // factorization are made once (at 1M prisms a local end's three steps over 191k prisms each
    // redid CHOLMOD's ordering).
    std::unique_ptr<Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower>> llt;
    std::unique_ptr<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower>> ldlt;
    for (int step = 0; step <= max_steps; ++step) {
      check_cancel();
      const auto [rr0, err] = residual(true);
      if (err <= tol) return true;
      if (step == max_steps) break;
      // (J J^T + eps I) y = r over the local prisms: J J^T couples prisms sharing a moving vertex.
      std::vector<Eigen::Triplet<double>> trip;
      double max_diag = 0.0;
      for (int v : free) {
        if (!moves[v]) continue;
        for (int t1 = F.vf_offsets[v]; t1 < F.vf_offsets[v + 1]; ++t1)
          for (int t2 = F.vf_offsets[v]; t2 < F.vf_offsets[v + 1]; ++t2) {
            const int j1 = local[F.vf[t1] / 3], j2 = local[F.vf[t2] / 3];
            if (j2 > j1) continue;  // lower triangle
            trip.emplace_back(j1, j2, g[j1][F.vf[t1] % 3].dot(g[j2][F.vf[t2] % 3]));
          }
      }
      Eigen::SparseMatrix<double> A(k, k);
      A.setFromTriplets(trip.begin(), trip.end());
      for (int j = 0; j < k; ++j) max_diag = std::max(max_diag, A.coeff(j, j));
      for (int j = 0; j < k; ++j) A.coeffRef(j, j) += damping * max_diag + 1e-300;
      Eigen::VectorXd y;
      if (k >= kSupernodalMinPrisms) {
        const internal::SerialOpenMp serial;
        if (!llt) {
          llt = std::make_unique<Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower>>();
          llt->cholmod().print = 0;
          llt->analyzePattern(A);
          check_cancel();  // the ordering took 0.4 s of a 191k-prism local end at 1M prisms
        }
        llt->factorize(A);
        check_cancel();  // the factorization is not interrupted; what follows it is not run
        if (llt->info() != Eigen::Success) return factorization_failed(damping);
        y = llt->solve(r);
      } else {
        if (!ldlt) {
          ldlt = std::make_unique<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower>>();
          ldlt->analyzePattern(A);
        }
        ldlt->factorize(A);
        check_cancel();
        if (ldlt->info() != Eigen::Success) return factorization_failed(damping);
        y = ldlt->solve(r);
      }
      ++st.factorizations;
      ++st.local_factorizations;
      ++st.final_sweeps;
      std::vector<Vec3> delta(free.size(), Vec3::Zero());
      for (std::size_t q = 0; q < free.size(); ++q) {
        const int v = free[q];
        if (!moves[v]) continue;
        for (int t = F.vf_offsets[v]; t < F.vf_offsets[v + 1]; ++t)
          delta[q] += y[local[F.vf[t] / 3]] * g[local[F.vf[t] / 3]][F.vf[t] % 3];
        s.P[v] += delta[q];
      }
      // Halve while the residual grows; undo and damp more if 4 halvings do not help.
      double alpha = 1.0;
      int halvings = 0;
      while (residual(false).first > rr0) {
        if (++halvings > 4) {
          for (std::size_t q = 0; q < free.size(); ++q) s.P[free[q]] -= alpha * delta[q];
          damping = std::min(100 * damping, kMaxDamping);
          break;
        }
        alpha *= 0.5;
        for (std::size_t q = 0; q < free.size(); ++q) s.P[free[q]] -= alpha * delta[q];
      }
      if (halvings == 0) damping = std::max(0.1 * damping, kMinDamping);
    }
    return false;
  }

  // A local step whose factorization failed: the next one (the caller's next round) is damped
  // more, rather than the same system failing again.
  static bool factorization_failed(double& damping) {
    damping = std::min(100 * damping, kMaxDamping);
    return false;
  }

  // The hierarchy's sizes, coarsest first.
  void level_stats(ReconstructStats& st) const {
    st.levels = static_cast<int>(levels_.size());
    st.renumbered = !renum_.empty();
    st.seconds_levels.assign(levels_.size(), 0.0);
    for (const Level& L : levels_) {
      st.level_vertices.push_back(static_cast<int>(L.verts.size()));
      st.level_faces.push_back(static_cast<int>(L.faces.size()));
      st.dense_levels += L.dense;
    }
  }

  // The final accuracy on the finest level against \p tol, the solve's time since \p t0, and the
  // positions moved into \p res.
  void finish(State& s, double tol, Clock::time_point t0, std::vector<double>& V,
              ReconstructResult& res) const {
    ReconstructStats& st = res.stats;
    const Level& F = levels_.back();
    compute_volumes(F, s, V);
    st.max_relative_error = relative_error(F, s.amplitude, V, &st.rms_relative_error);
    st.converged = st.max_relative_error <= tol;
    check_finite(s);
    st.seconds_solve = seconds_since(t0);
    res.positions = std::move(s.P);
  }

  // MultigridStepOptions::tangential_damping's weight per vertex into s.damping_weight: 0 at the
  // vertices where the edited base bends differently from the rest base (the change of the angle
  // between a vertex's base normal and a neighbour's, over their rest distance, times the larger
  // displacement length, above tangential_damping_bend), rising to 1 over tangential_damping_margin
  // mean displacement lengths along the rest detail's edges (smoothstep). Over an unedited base
  // every weight is 1.
  void tangential_damping_weights(State& s) const {
    const MultigridStepOptions& mo = opt_.multigrid;
    const Level& F = levels_.back();
    const int n = static_cast<int>(s.N.size());
    const std::vector<Vec3>& p = enc_.detail_rest;
    const std::vector<Vec3>& n0 = enc_.base_rest_normals;
    auto angle = [](const Vec3& a, const Vec3& b) { return std::acos(std::clamp(a.dot(b), -1.0, 1.0)); };
    std::vector<char> bent(F.verts.size(), 0);
    for_each(F.verts.size(), [&](std::size_t k) {
      const int i = F.verts[k];
      for (int t = F.nb_offsets[k]; t < F.nb_offsets[k + 1]; ++t) {
        const int j = F.verts[F.nb[t]];
        const double change = std::abs(angle(s.N[i], s.N[j]) - angle(n0[i], n0[j]));
        const double len = (p[i] - p[j]).norm();
        if (change * std::max(std::abs(guarded_f_[i]), std::abs(guarded_f_[j])) >
            mo.tangential_damping_bend * len) {
          bent[k] = 1;
          return;
        }
      }
    });
    s.damping_weight.assign(n, 1.0f);
    // Multi-source shortest paths from the bent vertices along the rest detail's edges.
    std::vector<double> dist(F.verts.size(), std::numeric_limits<double>::infinity());
    using Item = std::pair<double, int>;  // (distance, level-local vertex)
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
    for (std::size_t k = 0; k < F.verts.size(); ++k)
      if (bent[k]) {
        dist[k] = 0.0;
        queue.push({0.0, static_cast<int>(k)});
      }
    if (queue.empty()) return;
    const double margin = mo.tangential_damping_margin * mean_abs_f_;
    while (!queue.empty()) {
      const auto [d, k] = queue.top();
      queue.pop();
      if (d > dist[k] || d >= margin) continue;
      for (int t = F.nb_offsets[k]; t < F.nb_offsets[k + 1]; ++t) {
        const int l = F.nb[t];
        const double nd = d + (p[F.verts[k]] - p[F.verts[l]]).norm();
        if (nd < dist[l]) {
          dist[l] = nd;
          queue.push({nd, l});
        }
      }
    }
    for (std::size_t k = 0; k < F.verts.size(); ++k) {
      const double x = margin > 0 ? std::min(1.0, dist[k] / margin) : (bent[k] ? 0.0 : 1.0);
      s.damping_weight[F.verts[k]] = static_cast<float>(x * x * (3 - 2 * x));
    }
  }

  // m regularization sweeps at full weight (the drags' and the coarse-only passes' finest level).
  void regularize_sweeps(const Level& L, State& s, ReconstructStats& st) const {
    for (int it = 0; it < opt_.regularization_iterations; ++it) regularize(L, s, 1.0);
    st.regularization_sweeps += opt_.regularization_iterations;
  }

  // Section 4.1: from the clean configuration p' = q', the volume scales h = a/k, 2a/k, .., a,
  // each a multigrid pass with n = volume_iterations steps per cycle.
  void clean_start(State& s, double a, int volume_iterations, ReconstructStats& st,
                   std::vector<double>& V) const {
    s.P = s.Q;
    s.cycle_volume_iterations = volume_iterations;
    s.clean_start = true;
    if (opt_.multigrid.tangential_damping > 0 && opt_.step_solver == VolumeStepSolver::Multigrid &&
        s.damping_weight.empty())
      tangential_damping_weights(s);
    const int k = std::max(1, opt_.volume_scales);
    s.work_done = s.work_total = 0.0;
    for (int sc = 0; sc < k; ++sc)
      for (int l = 0; l < static_cast<int>(levels_.size()); ++l)
        s.work_total += level_work(l, sc + 1 == k, !opt_.finest_intermediate_solves && sc + 1 < k);
    for (int sc = 0; sc < k; ++sc) {
      const double t = static_cast<double>(sc + 1) / k, h = a * t;
      // The pinned vertices' displacements follow the volume scale, so that the layer is scaled
      // down as a whole: pinned at full height next to free vertices at the clean start would
      // make steep walls at the border of the solved part, which fold.
      place_pinned(s, t);
      // finest_intermediate_solves: the finest level's volumes at the full scale only.
      const bool coarse_only = !opt_.finest_intermediate_solves && sc + 1 < k;
      multigrid_pass(s, h, sc + 1 == k, sc + 1 == k ? opt_.tolerance : opt_.level_tolerance, coarse_only, st,
                     V);
      // (A one-level hierarchy solves its only level in a coarse-only pass: multigrid_pass() counts
      // its cycles; a 0 as well made 5 entries for 3 scales.)
      if (coarse_only && levels_.size() > 1) st.finest_cycles_per_scale.push_back(0);
    }
    s.clean_start = false;
    s.work_total = 0.0;
  }

  // Listing 1 for one volume scale h: every level from the coarsest to the finest, each solved by
  // cycles of (at most) n volume steps and m regularization sweeps, then prolongated to the next
  // level.
  // h: the volume scale times the amplitude; full_scale: the last scale (h = amplitude).
  void multigrid_pass(State& s, double h, bool full_scale, double final_tol, bool coarse_only,
                      ReconstructStats& st, std::vector<double>& V) const {
    s.P0 = s.P;
    const int nl = static_cast<int>(levels_.size());
    // The coarse levels are solved in their own compact state, released after the pass.
    State c;
    if (nl > 1) gather_coarse(s, c);
    for (int l = 0; l < nl; ++l) {
      check_cancel();
      const Level& L = levels_[l];
      const bool finest = l + 1 == nl;
      State& ls = finest ? s : c;  // the level's state
      std::optional<PhaseTimer> level_timer(std::in_place, st.seconds_levels[l]);
      if (finest && l > 0) {
        scatter_coarse(c, s);
        c = State{};
        prolongate(L, compact_to_orig_, s);
      } else if (l > 0) {
        prolongate(L, levels_[l - 1].verts, ls);
      }
      // After the level (solved, or regularized only), a clean start reports its progress.
      auto level_done = [&] {
        if (s.work_total <= 0) return;
        s.work_done += level_work(l, full_scale, coarse_only);
        report(s.phase, std::min(1.0, s.work_done / s.work_total));
      };
      // Section 5: the finest level follows by regularization only, and so do the coarse levels
      // next to it at the intermediate scales (ReconstructOptions::intermediate_regularized_levels).
      if ((finest && coarse_only && nl > 1) || regularized_only(l, full_scale, coarse_only)) {
        regularize_sweeps(L, ls, st);
        level_done();
        continue;
      }
      const int max_cycles = finest && full_scale ? opt_.final_max_cycles : opt_.max_cycles;
      ls.volume_iterations =
          finest && !full_scale ? opt_.finest_volume_iterations : s.cycle_volume_iterations;
      const int cycles = solve_level(L, ls, h, finest ? final_tol : opt_.level_tolerance, max_cycles, st, V);
      level_timer.reset();
      if (finest) {
        st.finest_cycles_per_scale.push_back(cycles);
        if (full_scale) {
          PhaseTimer timer(st.seconds_polish);
          polish(L, s, final_tol, st, V);
        }
      }
      level_done();
    }
  }

  // "Do until convergence" of Listing 1: volume steps until the prisms hold their (scaled)
  // volumes, then regularization; repeated until the regularization stops moving the solution
  // (a fixed point of smoothing and projection) or max_cycles. Ends on volume steps.
  int solve_level(const Level& L, State& s, double h, double tol, int max_cycles, ReconstructStats& st,
                  std::vector<double>& V) const {
    double lambda = 1.0;
    int sweeps =
        &L == &levels_.back() ? opt_.regularization_iterations : opt_.coarse_regularization_iterations;
    // The coarsest level's own sweeps and cycles at the clean start's last volume scale
    // (h = a * 1.0 = a exactly), whose large-scale shape is the one kept: at the earlier scales as
    // well they cost 0.06 s more of a 1.4 s 100k solve, for round trips within 0.04 points.
    // Not in drag or warm steps, which must stay cheap.
    if (&L == &levels_.front() && levels_.size() > 1 && s.clean_start && h == s.amplitude) {
      if (opt_.coarsest_regularization_iterations > 0) sweeps = opt_.coarsest_regularization_iterations;
      if (opt_.coarsest_max_cycles > 0) max_cycles = opt_.coarsest_max_cycles;
    }
    int c = 0;
    for (;; ++c) {
      check_cancel();
      project(L, s, h, tol, st, V);
      ++st.cycles;
      if (c + 1 >= max_cycles || sweeps == 0) break;
      // The level's vertices only: a coarse level of a 1M-prism detail has a few thousand.
      s.before.resize(L.verts.size());
      for (std::size_t k = 0; k < L.verts.size(); ++k) s.before[k] = s.P[L.verts[k]];
      for (int it = 0; it < sweeps; ++it) regularize(L, s, lambda);
      st.regularization_sweeps += sweeps;
      lambda *= opt_.regularization_decay;
      double moved = 0.0;
      for (std::size_t k = 0; k < L.verts.size(); ++k)
        moved = std::max(moved, (s.P[L.verts[k]] - s.before[k]).norm());
      if (moved <= opt_.fixed_point_tolerance * mean_abs_f_) {
        project(L, s, h, tol, st, V);
        break;
      }
    }
    return c + 1;
  }

  // Volume steps until the max relative error is at most tol, at most max_steps of them; exact
  // (factorized) steps when `direct`. Returns the steps taken; V holds the final volumes.
  int project(const Level& L, State& s, double h, double tol, int max_steps, StepSolve how,
              ReconstructStats& st, std::vector<double>& V) const {
    // A cycle's first step takes its gradients from the pass that gives the volumes deciding
    // whether it runs (the same numbers compute_volumes() gives): the cycles' steps run at nearly
    // every call, and this spares them a pass over the prisms.
    const bool fused = how == StepSolve::Cycle && max_steps > 0;
    if (fused)
      gradient_pass(L, s, h, multigrid_step(how), &V);
    else
      compute_volumes(L, s, V);
    double err = relative_error(L, h, V, nullptr);
    int steps = 0;
    for (; steps < max_steps && err > tol; ++steps) {
      gauss_newton_step(L, s, h, how, st, V, /*fresh=*/fused && steps == 0);
      err = relative_error(L, h, V, nullptr);
    }
    st.volume_sweeps += steps;
    return steps;
  }

  // During the cycles: inexact steps, unless the level is small or the options ask for exact ones.
  int project(const Level& L, State& s, double h, double tol, ReconstructStats& st,
              std::vector<double>& V) const {
    return project(L, s, h, tol, s.volume_iterations, cycle_solve(L), st, V);
  }

  // Exact Gauss-Newton steps (one factorization each, symbolic analysis kept) until the
  // tolerance holds: the volume terms get all the weight at the end (section 4.2).
  // \p local_end: whether the polish may end locally (local_polish_max_fraction); the fold
  // repair's whole-level polish may not, since its wide correction is what unfolds.
  void polish(const Level& L, State& s, double tol, ReconstructStats& st, std::vector<double>& V,
              bool local_end = true) const {
    s.gn.polish_steps = 0;  // MultigridStepOptions::polish_smoothness_decay counts from here
    if (local_end && opt_.local_polish_max_fraction > 0 && &L == &levels_.back()) {
      // Whole-level steps until few prisms are off, then only their neighbourhoods move. A local
      // system has at least the off prisms, so more of them than the limit go on whole-level.
      compute_volumes(L, s, V);
      const double limit = opt_.local_polish_max_fraction * static_cast<double>(L.faces.size());
      const double scale = std::abs(s.amplitude) * L.mean_abs_target;
      int steps = 0;
      // After a local end that failed (its rounds undone), the next is tried only once the off
      // prisms are at most half as many: each attempt costs up to max_final_steps factorizations.
      double retry_below = limit;
      double whole_motion = 0.0;  // the last whole-level step's largest vertex move
      for (std::vector<int> off;; ++steps) {
        above_tolerance(L, s.amplitude, V, tol, off);
        if (off.empty() || !(scale > 0)) break;
        if (static_cast<double>(off.size()) <= retry_below) {
          if (finish_locally(off, s, tol, whole_motion, st, V)) break;
          retry_below = 0.5 * static_cast<double>(off.size());
        }
        if (steps == opt_.max_final_steps) break;
        gauss_newton_step(L, s, s.amplitude, StepSolve::Exact, st, V);
        whole_motion = s.gn.motion;
      }
      st.volume_sweeps += steps;
      st.final_sweeps += steps;
    } else {
      st.final_sweeps += project(L, s, s.amplitude, tol, opt_.max_final_steps, StepSolve::Exact, st, V);
    }
    if (opt_.polish_solver != VolumeStepSolver::Multigrid || L.dense ||  // a dense level: no factorization
        relative_error(L, s.amplitude, V, nullptr) <= tol)
      return;
    // A multigrid polish that stalls (its linear solves leave what the hierarchy does not
    // represent, as a regular grid's checkerboard modes) is finished by factorized steps. The
    // multigrid's arrays go first, as before a local end: the factorization sets the peak.
    release_step_scratch(s.gn);
    ensure_factorizable(L);
    s.gn.damping = kMinDamping;
    st.final_sweeps +=
        project(L, s, s.amplitude, tol, opt_.max_factorized_steps, StepSolve::Factorized, st, V);
  }

  // The finest level's prisms whose volume is more than \p tol (relative to the mean target
  // volume) off the scaled target a * V*, ascending, into \p off.
  void above_tolerance(const Level& L, double a, const std::vector<double>& V, double tol,
                       std::vector<int>& off) const {
    const double limit = tol * std::abs(a) * L.mean_abs_target;
    off.clear();
    for (std::size_t j = 0; j < V.size(); ++j)
      if (std::abs(a * L.targets[j] - V[j]) > limit) off.push_back(static_cast<int>(j));
  }

  // The polish's end (ReconstructOptions::local_polish_max_fraction): rounds of one exact step
  // that moves only the vertices of the finest level's prisms above the tolerance (\p off first)
  // and local_polish_rings rings around them, each round grown again from the prisms still above
  // it, so that the later rounds' systems are small. A factorized system over a neighbourhood
  // where a whole-level step costs a multigrid solve of the whole level. Returns whether the
  // tolerance holds on every prism that has a free vertex (prisms whose three vertices are pinned
  // cannot move, here or in a whole-level step); if not, or if a round's system would have more
  // than local_polish_max_fraction of the level's prisms, the positions are as on entry. V: the
  // volumes of the positions left. \p whole_motion: the largest vertex move of the polish's last
  // whole-level step (0 if none), which raises the local_polish_max_motion bound to itself.
  bool finish_locally(std::vector<int> off, State& s, double tol, double whole_motion, ReconstructStats& st,
                      std::vector<double>& V) const {
    const Level& F = levels_.back();
    const auto max_prisms = static_cast<std::size_t>(opt_.local_polish_max_fraction * F.faces.size());
    std::vector<char> in, saved(F.verts.size(), 0);
    std::vector<int> subset, next;
    std::vector<std::pair<int, Vec3>> kept;  // each moved vertex's position on entry
    double damping = kMinDamping;            // carried over the rounds, as over a fixed set's steps
    int stalled = 0;                         // rounds in a row that left as many prisms off
    for (int round = 0; round < opt_.max_final_steps; ++round) {
      grow_rings(off, opt_.local_polish_rings, in, subset, next);
      const LocalSet set = local_set(subset);
      // Every round's system is bounded, not only the first: the off prisms need not shrink. A
      // hub among its vertices makes it dense (dense_pattern()) as a level's.
      if (set.faces.size() > max_prisms || dense_pattern(F.vf_offsets, &subset)) {
        if (round == 0) return false;  // not tried: nothing moved
        break;
      }
      st.max_local_end_prisms = std::max<long long>(st.max_local_end_prisms, set.faces.size());
      if (round == 0) {
        ++st.local_ends;
        // The whole-level steps' arrays (a few hundred bytes per prism, the multigrid's included)
        // go before the local factorization, which would otherwise raise the solve's peak memory
        // (measured at 1M prisms: 952 bytes per prism without this, 829 with it). A fallback to
        // whole-level steps allocates them again.
        release_step_scratch(s.gn);
      }
      for (int v : subset)
        if (!saved[v]) saved[v] = 1, kept.emplace_back(v, s.P[v]);
      const bool converged = local_polish(set, s, s.amplitude, tol, st, 1, damping);
      update_volumes(F, s, set.faces, V);
      if (opt_.local_polish_max_motion > 0) {
        // local_polish_max_motion: a patch fixing a checkerboard by ripples is undone, unless the
        // last whole-level step moved a vertex as far (the step the local end stands in for).
        const double bound = std::max(opt_.local_polish_max_motion * rest_diagonal_, whole_motion);
        double moved = 0.0;
        for (const auto& [v, p] : kept) moved = std::max(moved, (s.P[v] - p).squaredNorm());
        if (!(moved <= bound * bound)) break;
      }
      if (converged) return true;
      const std::size_t before = off.size();
      above_tolerance(F, s.amplitude, V, tol, off);
      if (off.empty()) return true;
      // Two rounds in a row without fewer prisms off: the rest would not do better (measured
      // without rings, local_polish_rings = 0, on the 12k bumps with the hierarchy before
      // 2026-11-27, tenth session: eight more rounds at 19 off).
      stalled = off.size() < before ? 0 : stalled + 1;
      if (stalled == 2) break;
    }
    for (const auto& [v, p] : kept) s.P[v] = p;
    compute_volumes(F, s, V);
    ++st.local_ends_undone;
    return false;
  }

  // Cycle steps: factorized on levels the options solve directly, else as step_solver says.
  StepSolve cycle_solve(const Level& L) const {
    return !L.dense && (opt_.step_solver == VolumeStepSolver::Direct ||
                        static_cast<int>(L.faces.size()) <= opt_.direct_max_prisms)
               ? StepSolve::Factorized
               : StepSolve::Cycle;
  }

  // J J^T's pattern and symbolic analysis for a level built without them (make_level()).
  void ensure_factorizable(const Level& L) const {
    if (L.llt) return;
    const std::vector<Face>& lf = L.local_faces.empty() ? L.faces : L.local_faces;
    build_jj_pattern(lf, internal::build_adjacency(static_cast<int>(L.verts.size()), lf), L);
    check_cancel();  // the pattern and its analysis are kept for the next call
  }

  // V's entries of \p faces recomputed, after a step that moved only vertices of these prisms.
  void update_volumes(const Level& L, const State& s, const std::vector<int>& faces,
                      std::vector<double>& V) const {
    for_each(faces.size(), [&](std::size_t k) {
      const Face& f = L.faces[faces[k]];
      V[faces[k]] = prism_volume(s.P[f[0]], s.P[f[1]], s.P[f[2]], s.Q[f[0]], s.Q[f[1]], s.Q[f[2]]);
    });
  }

  void compute_volumes(const Level& L, const State& s, std::vector<double>& V) const {
    const std::size_t m = L.faces.size();
    V.resize(m);
    for_each((m + 1) / 2, [&](std::size_t k) {  // in pairs, as gradient_pass()
      const std::size_t j0 = 2 * k, j1 = std::min(j0 + 1, m - 1);
      double v[2];
      internal::prism_volume_pair(prism_pair(L, s, j0, j1), v);
      V[j0] = v[0];
      V[j1] = v[1];
    });
  }

  // The corners of prisms \p j0 and \p j1 at the current positions.
  static internal::PrismPair prism_pair(const Level& L, const State& s, std::size_t j0, std::size_t j1) {
    internal::PrismPair c;
    const std::size_t j[2] = {j0, j1};
    for (int k = 0; k < 2; ++k)
      for (int a = 0; a < 3; ++a) {
        c.p[k][a] = &s.P[L.faces[j[k]][a]];
        c.q[k][a] = &s.Q[L.faces[j[k]][a]];
      }
    return c;
  }

  // (J^T x) at level-local vertex k: its faces' gradients at its corners weighted by x, summed in
  // face order (a scatter over the faces would sum the same terms in the same order).
  // Reads the step's gradients in vertex order (w.gv, see vertex_gradients()): contiguous, where
  // w.grad[face][corner] would be a scattered load per entry.
  static Vec3 gather_jt(const Level& L, const GnScratch& w, const std::vector<double>& x, int k) {
    Vec3 acc = Vec3::Zero();
    for (int t = L.vf_offsets[k]; t < L.vf_offsets[k + 1]; ++t) acc += x[L.vf[t] / 3] * w.gv[t];
    return acc;
  }

  // w.gv[t] = the gradient of entry L.vf[t] (face * 3 + corner): the step's gradients in the
  // order gather_jt() reads them.
  void vertex_gradients(const Level& L, GnScratch& w) const {
    w.gv.resize(L.vf.size());
    for_each(L.verts.size(), [&](std::size_t k) {
      for (int t = L.vf_offsets[k]; t < L.vf_offsets[k + 1]; ++t) w.gv[t] = w.grad[L.vf[t] / 3][L.vf[t] % 3];
    });
  }

  // f(i) for i in [0, n): on the solver's threads when n is large enough to pay for them. Every
  // index is independent, so the result does not depend on the threads (reductions stay serial).
  template <class F>
  void for_each(std::size_t n, F&& f) const {
    internal::parallel_for_each(arena_.get(), n, std::forward<F>(f));
  }

  // max_j |h V*_j - V_j| / mean_j |h V*_j|, and optionally the RMS of the same ratio.
  static double relative_error(const Level& L, double h, const std::vector<double>& V, double* rms) {
    const double scale = std::abs(h) * L.mean_abs_target;
    if (!(scale > 0)) return 0.0;
    double mx = 0.0, sq = 0.0;
    for (std::size_t j = 0; j < V.size(); ++j) {
      const double e = std::abs(h * L.targets[j] - V[j]);
      mx = std::max(mx, e);
      sq += e * e;
    }
    if (rms) *rms = std::sqrt(sq / V.size()) / scale;
    return mx / scale;
  }

  // Whether a step of kind \p how solves by the vertex multigrid. (Exact steps are the finest
  // level's: polish_by_multigrid_.)
  bool multigrid_step(StepSolve how) const {
    return how == StepSolve::Exact
               ? polish_by_multigrid_
               : how == StepSolve::Cycle && opt_.step_solver == VolumeStepSolver::Multigrid;
  }

  // A step's pass over the prisms at the current positions: the residual s.gn.r = h V* - V and J,
  // for the multigrid in single precision (s.gn.gf, its rows' squared norms in s.gn.diag: no
  // array of the gradients in double, whose writing and two reads were 216 bytes of memory
  // traffic a prism a step), else in s.gn.grad; zero at pinned corners. \p V: if given, the
  // volumes too.
  void gradient_pass(const Level& L, State& s, double h, bool use_mg, std::vector<double>* V) const {
    GnScratch& w = s.gn;
    const std::size_t m = L.faces.size();
    if (use_mg)
      w.gf.resize(9 * m);
    else
      w.grad.resize(m);
    w.r.resize(m);
    w.diag.resize(m);
    if (V) V->resize(m);
    const auto store = [&](std::size_t j, const PrismVolumeGradient& g) {
      const Face& f = L.faces[j];
      if (V) (*V)[j] = g.volume;
      w.r[j] = h * L.targets[j] - g.volume;
      if (!use_mg) {
        for (int c = 0; c < 3; ++c) w.grad[j][c] = s.pinned(f[c]) ? Vec3(Vec3::Zero()) : g.grad[c];
        return;
      }
      double norm2 = 0.0;
      for (int c = 0; c < 3; ++c) {
        const Vec3 gc = s.pinned(f[c]) ? Vec3(Vec3::Zero()) : g.grad[c];
        norm2 += gc.squaredNorm();
        for (int k = 0; k < 3; ++k) w.gf[9 * j + 3 * c + k] = static_cast<float>(gc[k]);
      }
      w.diag[j] = norm2;
    };
    // Prisms in pairs, bit-identical to one at a time (internal/prism_pair.h); an odd count's
    // last pair is the last prism twice.
    for_each((m + 1) / 2, [&](std::size_t k) {
      const std::size_t j0 = 2 * k, j1 = std::min(j0 + 1, m - 1);
      PrismVolumeGradient g[2];
      internal::prism_volume_gradient_pair(prism_pair(L, s, j0, j1), g);
      store(j0, g[0]);
      if (j1 != j0) store(j1, g[1]);
    });
  }

  // One Gauss-Newton step towards the volume constraints: the minimum-norm correction
  // delta = J^T (J J^T)^{-1} r, with (J J^T) y = r solved by Jacobi-preconditioned conjugate
  // gradients. Each prism's row of J holds its exact volume gradients (section 3), so this is
  // the projection of the current positions onto the linearized constraint set.
  // \p fresh: gradient_pass() has run at the current positions with this h and kind of step.
  void gauss_newton_step(const Level& L, State& s, double h, StepSolve how, ReconstructStats& st,
                         std::vector<double>& V, bool fresh = false) const {
    // Exact steps (the polish, or factorized ones) are undone when they do not help, and adapt
    // the Levenberg-Marquardt damping; inexact ones are kept, as the cycles' regularization expects.
    check_cancel();
    const bool direct = how != StepSolve::Cycle;
    const bool use_mg = multigrid_step(how);
    GnScratch& w = s.gn;
    const std::size_t m = L.faces.size();
    if (!fresh) gradient_pass(L, s, h, use_mg, nullptr);
    if (!use_mg) vertex_gradients(L, w);
    double rr = 0.0;
    for (std::size_t j = 0; j < m; ++j) rr += w.r[j] * w.r[j];
    const double rr0 = rr;  // the line search's; rr becomes the right-hand side's if it changes
    if (!L.edge_sizes.empty() && defer_ill_posed(L, s, h, w, use_mg, st) > 0) {
      rr = 0.0;
      for (std::size_t j = 0; j < m; ++j) rr += w.r[j] * w.r[j];
    }
    if (use_mg) {
      // MultigridStepOptions::tangential_damping: a clean start's intermediate scales, 1 - t of it.
      w.tangential_damping = 0.0;
      if (how == StepSolve::Cycle && opt_.multigrid.tangential_damping > 0 && s.clean_start &&
          std::abs(h) < std::abs(s.amplitude)) {
        w.tangential_damping = opt_.multigrid.tangential_damping * (1.0 - h / s.amplitude);
        w.damped_normals.resize(L.verts.size());
        for_each(L.verts.size(), [&](std::size_t k) {
          const int i = L.verts[k];
          const double weight = s.damping_weight.empty() ? 1.0 : s.damping_weight[i];
          w.damped_normals[k] = (std::sqrt(weight) * s.N[i]).cast<float>();
        });
      }
      solve_multigrid(L, w, how == StepSolve::Exact, st);
      check_cancel();  // the solve stops early on a cancel; its step is not taken
    } else if (direct) {
      solve_direct(L, w, rr, st);
    } else {
      // Matrix-free: J J^T x = J (J^T x), J^T x gathered per vertex. Half the memory traffic of a
      // sweep over J J^T's ~13 entries a row, and no matrix to build per step.
      const std::vector<Face>& lf = L.local_faces.empty() ? L.faces : L.local_faces;
      const std::size_t nv = L.verts.size();
      for_each(m, [&](std::size_t j) {
        const double d = w.grad[j][0].squaredNorm() + w.grad[j][1].squaredNorm() + w.grad[j][2].squaredNorm();
        w.diag[j] = d > 0 ? 1.0 / d : 0.0;
      });
      w.jt.resize(nv);
      auto apply = [&](const std::vector<double>& x, std::vector<double>& out) {
        for_each(nv, [&](std::size_t k) { w.jt[k] = gather_jt(L, w, x, static_cast<int>(k)); });
        out.resize(m);
        for_each(m, [&](std::size_t j) {
          const Face& f = lf[j];
          out[j] = w.grad[j][0].dot(w.jt[f[0]]) + w.grad[j][1].dot(w.jt[f[1]]) + w.grad[j][2].dot(w.jt[f[2]]);
        });
      };
      solve_cg(L, w, rr, st, apply);
    }
    // delta = J^T y, with backtracking: the constraints are only multi-affine, so a full step
    // from a poor configuration can overshoot; halve it while the residual grows.
    w.delta.resize(s.P.size());
    for_each(L.verts.size(), [&](std::size_t k) {
      const int i = L.verts[k];
      w.delta[i] = use_mg ? w.ldelta[k] : gather_jt(L, w, w.y, static_cast<int>(k));
      s.P[i] += w.delta[i];
    });
    double alpha = 1.0;
    int halvings = 0;
    bool undone = false;
    for (;; ++halvings) {
      compute_volumes(L, s, V);
      if (residual_norm2(L, h, V) <= rr0) break;
      if (halvings == 4) {
        // An exact step that does not reduce the residual even when halved 4 times is undone (the
        // damping below then grows); an inexact one is kept, as the cycles' regularization expects.
        if (direct) {
          for (int i : L.verts) s.P[i] -= alpha * w.delta[i];
          compute_volumes(L, s, V);
          undone = true;
        }
        break;
      }
      alpha *= 0.5;
      for (int i : L.verts) s.P[i] -= alpha * w.delta[i];
      ++st.step_halvings;
    }
    // The step's largest vertex move, for the polish's local end (exact steps only).
    double motion2 = 0.0;
    if (direct && !undone)
      for (int i : L.verts) motion2 = std::max(motion2, w.delta[i].squaredNorm());
    w.motion = alpha * std::sqrt(motion2);
    // Levenberg-Marquardt: after an exact step that had to be undone (the constraints are only
    // multi-affine, and a nearly singular J J^T gives long steps) the next is damped more; after
    // one taken in full, less.
    if (undone)
      w.damping = std::min(100 * w.damping, kMaxDamping);
    else if (direct && halvings == 0)
      w.damping = std::max(0.1 * w.damping, kMinDamping);
    st.constraint_updates += static_cast<long long>(m);
  }

  // ReconstructOptions::max_constraint_motion: zeroes the step's right-hand side w.r[j] of the
  // prisms whose own minimum-norm motion |r_j| / |grad_j| exceeds the bound times their size, the
  // longer of their longest rest edge and their longest displacement length at amplitude \p h
  // times the request's amplitude (w.diag holds the gradients' squared norms in a multigrid step;
  // otherwise they come from w.grad). Returns how many prisms were left out. A pass of its own
  // after the residual's norm, whose loop stays as it was (a fused multiply-add there would change
  // its rounding, and with it every result).
  int defer_ill_posed(const Level& L, const State& s, double h, GnScratch& w, bool use_mg,
                      ReconstructStats& st) const {
    const double k2 = opt_.max_constraint_motion * opt_.max_constraint_motion;
    const double a = std::abs(h);
    int deferred = 0;
    for (std::size_t j = 0; j < w.r.size(); ++j) {
      const double n2 =
          use_mg ? w.diag[j]
                 : w.grad[j][0].squaredNorm() + w.grad[j][1].squaredNorm() + w.grad[j][2].squaredNorm();
      const double size = std::max<double>(L.edge_sizes[j], a * L.length_sizes[j]);
      if (!(w.r[j] * w.r[j] > k2 * size * size * n2)) continue;
      // A prism whose three vertices are pinned has no gradient but no step either: its row stays
      // as it was (its residual is the same in every step).
      const Face& f = L.faces[j];
      if (s.pinned(f[0]) && s.pinned(f[1]) && s.pinned(f[2])) continue;
      w.r[j] = 0.0;
      ++deferred;
    }
    st.deferred_constraints += deferred;
    return deferred;
  }

  // sum_j (h V*_j - V_j)^2.
  static double residual_norm2(const Level& L, double h, const std::vector<double>& V) {
    double rr = 0.0;
    for (std::size_t j = 0; j < V.size(); ++j) rr += (h * L.targets[j] - V[j]) * (h * L.targets[j] - V[j]);
    return rr;
  }

  // (J W^-1 J^T + eps I) y = r by the level's Cholesky factorization (numeric part only; the
  // symbolic analysis was done at construction). eps keeps the clean start, where all
  // gradients are normal and J J^T is singular, factorizable.
  void solve_direct(const Level& L, GnScratch& w, double, ReconstructStats& st) const {
    const std::size_t m = L.faces.size();
    assert(L.llt && "exact steps only on levels with J J^T's pattern (make_level)");
    assemble(L, w.grad, w.damping);
    const internal::SerialOpenMp serial;
    L.llt->factorize(L.jj);
    check_cancel();  // the factorization is not interrupted; the step's line search is not run
    if (L.llt->info() != Eigen::Success)
      throw SolverError("Cholesky factorization of the volume step failed");
    Eigen::Map<const Eigen::VectorXd> r(w.r.data(), static_cast<Eigen::Index>(m));
    const Eigen::VectorXd y = L.llt->solve(r);
    w.y.assign(y.data(), y.data() + m);
    ++st.factorizations;
  }

  // The step by the level's vertex-space multigrid (VolumeStepSolver::Multigrid): w.ldelta per
  // level vertex. An exact step's damping is at least the polish's and grows as the direct
  // steps' does (Levenberg-Marquardt).
  void solve_multigrid(const Level& L, GnScratch& w, bool exact, ReconstructStats& st) const {
    const MultigridStepOptions& mo = opt_.multigrid;
    double diag = 0.0;  // the mean diagonal of J^T J (w.diag: the rows' squared norms)
    for (double d : w.diag) diag += d;
    diag /= 3.0 * static_cast<double>(std::max<std::size_t>(1, L.verts.size()));
    if (!(diag > 0)) diag = 1.0;
    internal::VertexStepSystem sys;
    sys.faces = L.local_faces.empty() ? &L.faces : &L.local_faces;
    sys.gf = &w.gf;
    sys.vf_offsets = &L.vf_offsets;
    sys.vf = &L.vf;
    sys.r = &w.r;
    sys.fixed = L.fixed.empty() ? nullptr : &L.fixed;
    sys.eps = (exact ? std::max(mo.polish_damping, w.damping) : mo.damping) * diag;
    sys.eps_lap = (exact ? mo.polish_smoothness * std::pow(mo.polish_smoothness_decay, w.polish_steps++)
                         : mo.smoothness) *
                  diag;
    sys.smoothing_degree = exact ? 0 : mo.smoothing_degree;  // 0: the hierarchy's (2)
    if (!exact && w.tangential_damping > 0) {
      sys.normals = &w.damped_normals;
      sys.eps_tangential = w.tangential_damping * diag;
    }
    sys.stop = opt_.cancel;
    const internal::VertexStepResult res =
        L.mg->solve(sys, exact ? mo.polish_tolerance : mo.tolerance,
                    exact                 ? mo.polish_iterations
                    : w.mg_iterations > 0 ? w.mg_iterations
                                          : mo.iterations,
                    w.ldelta, w.mgw, arena_.get(),
                    /*single_precision_cycle=*/!exact && mo.single_precision_cycles);
    st.cg_iterations += res.iterations;
  }

  // z = D^-1 res with D the diagonal of J J^T.
  static void precondition(GnScratch& w, const std::vector<double>& res) {
    w.z.resize(res.size());
    for (std::size_t j = 0; j < res.size(); ++j) w.z[j] = w.diag[j] * res[j];
  }

  template <class Apply>
  void solve_cg(const Level& L, GnScratch& w, double rr, ReconstructStats& st, Apply&& apply) const {
    const std::size_t m = L.faces.size();
    // Preconditioned CG from y = 0.
    w.y.assign(m, 0.0);
    w.z.resize(m);
    std::vector<double>& res = w.r;  // r becomes the CG residual
    precondition(w, res);
    w.p = w.z;
    double rz = 0.0;
    for (std::size_t j = 0; j < m; ++j) rz += res[j] * w.z[j];
    const double stop = opt_.cg_tolerance * opt_.cg_tolerance * rr;
    int it = 0;
    const int max_it = w.cg_max_iterations > 0 ? w.cg_max_iterations : opt_.cg_max_iterations;
    for (; it < max_it && rr > stop; ++it) {
      check_cancel();
      apply(w.p, w.Ap);
      double pAp = 0.0;
      for (std::size_t j = 0; j < m; ++j) pAp += w.p[j] * w.Ap[j];
      if (!(pAp > 0)) break;
      const double alpha = rz / pAp;
      for_each(m, [&](std::size_t j) {
        w.y[j] += alpha * w.p[j];
        res[j] -= alpha * w.Ap[j];
        w.z[j] = w.diag[j] * res[j];
      });
      rr = 0.0;
      double rz_new = 0.0;
      for (std::size_t j = 0; j < m; ++j) {
        rr += res[j] * res[j];
        rz_new += res[j] * w.z[j];
      }
      const double beta = rz_new / rz;
      rz = rz_new;
      for_each(m, [&](std::size_t j) { w.p[j] = w.z[j] + beta * w.p[j]; });
    }
    st.cg_iterations += it;
  }

  // Section 4.2 on the displacements d_i = p_i - q_i (Jacobi sweep): the length filter
  // d -> d + lambda f Laplacian(d/f) and a tangential Laplacian (TangentialRegularization): of the
  // tangential displacement relative to its rest offset, or of the positions less the rest
  // detail's own, both with the original's weights.
  // \p only: the level-local vertices to move (nullptr: all).
  void regularize(const Level& L, State& s, double lambda_scale,
                  const std::vector<int>* only = nullptr) const {
    const int nv = static_cast<int>(L.verts.size());
    const bool positions = s.tangential == TangentialRegularization::RestLaplacian;
    s.rho.resize(nv);
    s.tdev.resize(nv);
    if (positions) s.pk.resize(nv);  // the positions before the sweep (a Jacobi sweep reads those)
    const std::vector<double>& guarded_f = *s.f;
    for_each(nv, [&](std::size_t k) {
      const int i = L.verts[k];
      const Vec3 d = s.P[i] - s.Q[i];
      const double hgt = d.dot(s.N[i]);
      s.rho[k] = hgt / guarded_f[i];
      s.tdev[k] = d - hgt * s.N[i] - s.R[i];
      if (positions) s.pk[k] = s.P[i];
    });
    // The rest Laplacian of the detail scaled by the amplitude, q + a (p - q): linear in a.
    const double amp = s.amplitude;
    const double ll = opt_.length_lambda * lambda_scale, lt = opt_.tangential_lambda * lambda_scale;
    const std::size_t count = only ? only->size() : static_cast<std::size_t>(nv);
    for_each(count, [&](std::size_t c) {
      const int k = only ? (*only)[c] : static_cast<int>(c);
      const int b = L.nb_offsets[k], e = L.nb_offsets[k + 1];
      if (b == e) return;
      double avg_rho = 0.0;
      Vec3 avg_t = Vec3::Zero();
      for (int t = b; t < e; ++t) {
        avg_rho += L.weights[t] * s.rho[L.nb[t]];
        if (!positions) avg_t += L.weights[t] * s.tdev[L.nb[t]];
      }
      const int i = L.verts[k];
      if (s.pinned(i)) return;
      const Vec3& n = s.N[i];
      const double hgt = (s.rho[k] + ll * (avg_rho - s.rho[k])) * guarded_f[i];
      Vec3 lap;
      if (positions) {
        lap.setZero();
        for (int t = b; t < e; ++t) lap += L.weights[t] * (s.pk[L.nb[t]] - s.pk[k]);
        // c_i in the edited base's frame (first tangent, normal x tangent), as R is carried.
        const Eigen::Vector2d c = (1.0 - amp) * L.rest_lap_base[k] + amp * L.rest_lap_detail[k];
        lap -= c[0] * s.T[i] + c[1] * n.cross(s.T[i]);
      } else {
        lap = avg_t - s.tdev[k];
      }
      lap -= lap.dot(n) * n;
      // On the boundary the one-sided Laplacian cannot hold the tangential deviation, which then
      // drifts; it is held at zero there (the detail's open edge keeps its rest offset).
      const Vec3 t = L.boundary[k] ? Vec3(Vec3::Zero()) : Vec3(s.tdev[k] + lt * lap);
      s.P[i] = s.Q[i] + hgt * n + s.R[i] + t;
    });
  }

  // Carries the coarse level's change since the pass started to the vertices the finer level
  // adds, each after the inserted vertices of its removal ring (Level::inserted's order): each takes
  // the mean change of that ring, as a change of d/f along its own normal and of the tangential
  // displacement in its own tangent plane.
  // \p coarse_verts: the coarse level's vertices, in \p s's ids (as \p fine's).
  void prolongate(const Level& fine, const std::vector<int>& coarse_verts, State& s) const {
    const std::vector<double>& guarded_f = *s.f;
    for (int i : coarse_verts) {
      const Vec3 d = s.P[i] - s.P0[i];
      const double dn = d.dot(s.N[i]);
      s.dRho[i] = dn / guarded_f[i];
      s.dT[i] = d - dn * s.N[i];
    }
    for (std::size_t k = 0; k < fine.inserted.size(); ++k) {
      const int i = fine.inserted[k];
      if (s.pinned(i)) {
        // Placed, not solved: unchanged since the pass started (the rings of later inserted
        // vertices read this, which must not be a previous pass's change).
        s.dRho[i] = 0.0;
        s.dT[i].setZero();
        continue;
      }
      const int b = fine.ring_offsets[k], e = fine.ring_offsets[k + 1];
      double rho = 0.0;
      Vec3 t = Vec3::Zero();
      for (int r = b; r < e; ++r) {
        rho += s.dRho[fine.ring_vertices[r]];
        t += s.dT[fine.ring_vertices[r]];
      }
      if (e > b) {
        rho /= (e - b);
        t /= (e - b);
      }
      t -= t.dot(s.N[i]) * s.N[i];
      s.dRho[i] = rho;
      s.dT[i] = t;
      s.P[i] = s.P0[i] + rho * guarded_f[i] * s.N[i] + t;
    }
  }

  // The coarse levels' state (compact ids) from \p s: every array at the second-finest level's
  // vertices, and the settings the level solves read. Solved in it, the coarse levels' sweeps
  // read a few MB where they read the whole detail's arrays at strides (at 1M prisms their
  // prisms cost 1.4-1.6 times the 100k's each).
  void gather_coarse(const State& s, State& c) const {
    const std::vector<int>& ids = compact_to_orig_;
    auto take = [&](const auto& from, auto& to) {
      if (from.empty()) return to.clear();
      to.resize(ids.size());
      for_each(ids.size(), [&](std::size_t k) { to[k] = from[ids[k]]; });
    };
    take(s.P, c.P);
    take(s.Q, c.Q);
    take(s.N, c.N);
    take(s.R, c.R);
    take(s.T, c.T);
    take(s.P0, c.P0);
    take(s.pinned_at, c.pinned_at);
    take(s.damping_weight, c.damping_weight);
    c.dRho.assign(ids.size(), 0.0);
    c.dT.assign(ids.size(), Vec3::Zero());
    c.f = &compact_f_;
    c.pin = s.pin ? &compact_pinned_ : nullptr;
    c.tangential = s.tangential;
    c.amplitude = s.amplitude;
    c.clean_start = s.clean_start;
    c.volume_iterations = s.volume_iterations;
    c.cycle_volume_iterations = s.cycle_volume_iterations;
    c.phase = s.phase;
    c.gn.damping = s.gn.damping;
    c.gn.cg_max_iterations = s.gn.cg_max_iterations;
    c.gn.mg_iterations = s.gn.mg_iterations;
  }

  // The coarse levels' solution back into \p s (their positions, and the damping their exact
  // steps adapted, as if solved in \p s).
  void scatter_coarse(const State& c, State& s) const {
    for_each(compact_to_orig_.size(), [&](std::size_t k) { s.P[compact_to_orig_[k]] = c.P[k]; });
    s.gn.damping = c.gn.damping;
  }

  DetailEncoding enc_;
  // The solver's numbering of the detail (empty: the caller's), each solver face's index in the
  // caller's encoding, and that encoding once encoding() restored it.
  internal::Renumbering renum_;
  std::vector<int> face_order_;
  mutable std::unique_ptr<DetailEncoding> original_;
  mutable std::once_flag original_once_;
  ReconstructOptions opt_;
  bool polish_by_multigrid_ = false;  // the exact steps' solver (multigrid_step())
  std::vector<double> guarded_f_;
  double mean_abs_f_ = 0.0;
  std::vector<Level> levels_;
  // The coarse levels' compact ids: the second-finest level's vertices, compact id -> original
  // id (empty with one level), and guarded_f_ and the pinned flags by compact id.
  std::vector<int> compact_to_orig_;
  std::vector<int> isolated_;  // vertices in no face (place_isolated())
  std::vector<double> compact_f_;
  std::vector<char> compact_pinned_;
  // Over a subdivision base: the cage's limit surface, kept so that a reconstruction from edited
  // control points does not rebuild the patch table. Mutable like the levels' factorizations.
  mutable std::unique_ptr<SubdivSurface> limit_;
  std::unique_ptr<LimitPointSet> limit_points_;  // the base points' patch weights
  // The rest detail's own intersecting pairs, searched only once a result's search is cut short
  // (whether that result counts depends on it); other results test their own pairs at rest.
  // Mutable like the levels' factorizations.
  mutable std::unique_ptr<IntersectionResult> rest_pairs_;
  // set_intersection_context(): the fixed triangles (detail vertices in the solver's numbering,
  // then the context's points), and the pairs (detail face, context face) that intersect at rest.
  IntersectionContext context_;
  struct ContextPairs {
    std::vector<std::pair<int, int>> pairs;
    bool cut = false;  // the search was cut short
  };
  mutable std::unique_ptr<ContextPairs> rest_context_;
  // The rest base points' crossings (near_base_crossings()), searched on first use.
  mutable std::unique_ptr<IntersectionResult> rest_base_pairs_;
  // The other preset's solver (ReconstructOptions::fallback_schedule), built on first use.
  mutable std::unique_ptr<Impl> fallback_;
  const char* phase_ = "reconstruct";  // "fallback" in the fallback's Impl
  double setup_seconds_ = 0.0;
  double rest_diagonal_ = 0.0;  // the rest detail's bounding-box diagonal
  // This object's number, unique in the process, which a DragState records (DragState::Impl::owner).
  const std::uint64_t serial_ = next_serial();
  static std::uint64_t next_serial() {
    static std::atomic<std::uint64_t> count{0};
    return ++count;
  }
  // The solver's threads (ReconstructOptions::threads); null: the calling thread only.
  std::unique_ptr<tbb::task_arena> arena_;
};

ReconstructOptions multigrid_reconstruct_options() {
  ReconstructOptions o;
  o.step_solver = VolumeStepSolver::Multigrid;
  o.polish_solver = VolumeStepSolver::Multigrid;
  o.volume_scales = 3;
  o.max_cycles = 2;
  o.final_max_cycles = 4;
  o.coarse_regularization_iterations = 8;  // 64 folded its 100k bends (see the field)
  o.tangential_regularization = TangentialRegularization::RestLaplacian;
  o.coarsest_regularization_iterations = 200;
  o.coarsest_max_cycles = 10;
  o.volume_iterations = 1;
  o.finest_intermediate_solves = false;
  o.intermediate_regularized_levels = 1;
  o.tolerance = 5e-4;
  o.local_polish_max_fraction = 0.25;
  o.multigrid.retry_iterations = 20;
  o.multigrid.polish_smoothness = 1e-3;
  o.multigrid.polish_smoothness_decay = 1e-2;
  return o;
}

ReconstructOptions cycle_schedule_reconstruct_options() {
  ReconstructOptions o = multigrid_reconstruct_options();
  o.volume_scales = 20;
  o.max_cycles = 1;
  o.finest_intermediate_solves = true;
  o.intermediate_regularized_levels = 0;
  o.multigrid.smoothing_degree = 1;
  o.multigrid.polish_smoothness = 0.0;
  o.multigrid.polish_smoothness_decay = 1.0;
  o.multigrid.polish_damping = 1e-7;     // its polish's solves stalled on the cuboid (see the header)
  o.multigrid.tangential_damping = 1.0;  // its round trip (see the header)
  return o;
}

ReconstructOptions named_reconstruct_options(const std::string& name) {
  if (name == "legacy") return ReconstructOptions{};
  if (name == "multigrid") return multigrid_reconstruct_options();
  if (name == "cycles") return cycle_schedule_reconstruct_options();
  throw InvalidInput("unknown reconstruction preset '" + name + "' (legacy, multigrid or cycles)");
}

void check_reconstruct_options(const ReconstructOptions& o) {
  // Each option by its name (set_reconstruct_option()'s), so that a --set NAME=VALUE out of
  // range is named in the error.
  auto check = [](bool ok, const char* name, double value, const char* range) {
    if (ok) return;
    std::ostringstream os;
    os << "reconstruction option " << name << " = ";
    if (value == std::floor(value) && std::abs(value) < 1e15)
      os << static_cast<long long>(value);  // a count in full, not 2.14748e+09
    else
      os << value;
    os << " is out of range (" << range << ")";
    throw InvalidInput(os.str());
  };
  // Counts have upper bounds too (the .strata reader's): 2^31 volume scales ran for ever.
  auto count = [&check](int value, const char* name, int lo, int hi, const char* note = nullptr) {
    const std::string range =
        std::to_string(lo) + "-" + std::to_string(hi) + (note ? std::string("; ") + note : "");
    check(value >= lo && value <= hi, name, value, range.c_str());
  };
  const MultigridStepOptions& mo = o.multigrid;
  count(o.volume_scales, "volume_scales", 1, 1000);
  count(o.max_levels, "max_levels", 1, 100);
  check(o.coarsest_vertices >= 1, "coarsest_vertices", o.coarsest_vertices, "at least 1");
  check(o.coarsening_ratio > 0 && o.coarsening_ratio < 1, "coarsening_ratio", o.coarsening_ratio,
        "between 0 and 1");
  count(o.volume_iterations, "volume_iterations", 1, 100000);
  count(o.retry_volume_iterations, "retry_volume_iterations", 0, 100000);
  // A ratio below 1 would call a fold's straight neighbours a contact; 1e6 bounds each search.
  check(o.contact_ratio == 0 || (o.contact_ratio >= 1 && o.contact_ratio <= 1e6), "contact_ratio",
        o.contact_ratio, "0 (off) or 1-1e6");
  count(o.base_crossing_rings, "base_crossing_rings", -1, 1000, "-1: off");
  count(o.intermediate_regularized_levels, "intermediate_regularized_levels", 0, 100);
  count(o.fold_repair_rounds, "fold_repair_rounds", 0, 1000);
  count(o.fold_repair_local_rings, "fold_repair_local_rings", 0, 1000);
  count(o.fold_repair_local_rounds, "fold_repair_local_rounds", -1, 1000, "-1: fold_repair_rounds");
  check(o.fold_repair_max_fraction >= 0, "fold_repair_max_fraction", o.fold_repair_max_fraction,
        "at least 0");
  count(o.fold_repair_rings, "fold_repair_rings", 0, 1000);
  count(o.fold_repair_sweeps, "fold_repair_sweeps", 0, 100000);
  check(o.local_polish_max_fraction >= 0 && o.local_polish_max_fraction <= 1, "local_polish_max_fraction",
        o.local_polish_max_fraction, "0 to 1");
  count(o.local_polish_rings, "local_polish_rings", 0, 1000);
  check(o.local_polish_max_motion >= 0 && o.local_polish_max_motion <= 1, "local_polish_max_motion",
        o.local_polish_max_motion, "0 to 1; 0 is no bound");
  check(o.direct_max_prisms >= 0, "direct_max_prisms", o.direct_max_prisms, "at least 0");
  count(o.finest_volume_iterations, "finest_volume_iterations", 1, 100000);
  count(o.regularization_iterations, "regularization_iterations", 0, 100000);
  count(o.coarse_regularization_iterations, "coarse_regularization_iterations", 0, 100000);
  count(o.coarsest_regularization_iterations, "coarsest_regularization_iterations", 0, 100000,
        "0 is as the coarse levels");
  count(o.coarsest_max_cycles, "coarsest_max_cycles", 0, 100000, "0 is max_cycles");
  count(o.max_cycles, "max_cycles", 1, 100000);
  count(o.final_max_cycles, "final_max_cycles", 1, 100000);
  // Weights of 1e308 overflowed the regularization into non-finite positions.
  check(o.tangential_lambda >= 0 && o.tangential_lambda <= 1000, "tangential_lambda", o.tangential_lambda,
        "0-1000");
  check(o.length_lambda >= 0 && o.length_lambda <= 1000, "length_lambda", o.length_lambda, "0-1000");
  check(o.level_tolerance > 0, "level_tolerance", o.level_tolerance, "above 0");
  check(o.tolerance > 0, "tolerance", o.tolerance, "above 0");
  count(o.max_final_steps, "max_final_steps", 0, 100000);
  count(o.max_factorized_steps, "max_factorized_steps", 0, 100000);
  check(o.max_constraint_motion >= 0 && o.max_constraint_motion <= 1e12, "max_constraint_motion",
        o.max_constraint_motion, "0 to 1e12; 0 keeps every constraint");
  // Finite: an infinite length floor made every ratio 0 and the solve diverged (named as the
  // edit's fault).
  check(o.min_length_fraction >= 0 && o.min_length_fraction <= 1000, "min_length_fraction",
        o.min_length_fraction, "0-1000");
  check(o.fixed_point_tolerance >= 0 && std::isfinite(o.fixed_point_tolerance), "fixed_point_tolerance",
        o.fixed_point_tolerance, "at least 0, finite");
  check(o.regularization_decay >= 0 && o.regularization_decay <= 1000, "regularization_decay",
        o.regularization_decay, "0-1000");
  check(o.cg_tolerance >= 0 && std::isfinite(o.cg_tolerance), "cg_tolerance", o.cg_tolerance,
        "at least 0, finite");
  count(o.cg_max_iterations, "cg_max_iterations", 1, 1000000);
  // TBB's arenas crashed from 65,537 threads; far more than any machine's cores anyway.
  check(o.threads >= 0 && o.threads <= 1024, "threads", o.threads, "0-1024; 0 is all cores");
  // An enum set from a cast integer (a wrapper's, a file's) reached a switch with no case for it.
  auto solver_ok = [](VolumeStepSolver v) {
    return v == VolumeStepSolver::JacobiCG || v == VolumeStepSolver::Direct ||
           v == VolumeStepSolver::Multigrid;
  };
  check(solver_ok(o.step_solver), "step_solver", static_cast<int>(o.step_solver),
        "jacobi_cg, direct or multigrid");
  check(solver_ok(o.polish_solver), "polish_solver", static_cast<int>(o.polish_solver),
        "direct or multigrid");
  check(o.tangential_regularization == TangentialRegularization::RestOffset ||
            o.tangential_regularization == TangentialRegularization::RestLaplacian,
        "tangential_regularization", static_cast<int>(o.tangential_regularization),
        "rest_offset or rest_laplacian");
  if (o.polish_solver == VolumeStepSolver::JacobiCG)
    throw InvalidInput(
        "reconstruction option polish_solver = jacobi_cg is out of range (direct or multigrid)");
  count(mo.iterations, "multigrid.iterations", 1, 100000);
  count(mo.polish_iterations, "multigrid.polish_iterations", 1, 100000);
  count(mo.retry_iterations, "multigrid.retry_iterations", 0, 100000);
  check(mo.tolerance >= 0, "multigrid.tolerance", mo.tolerance, "at least 0");
  check(mo.polish_tolerance >= 0, "multigrid.polish_tolerance", mo.polish_tolerance, "at least 0");
  check(mo.damping > 0, "multigrid.damping", mo.damping, "above 0");
  check(mo.polish_damping > 0, "multigrid.polish_damping", mo.polish_damping, "above 0");
  check(mo.smoothness >= 0, "multigrid.smoothness", mo.smoothness, "at least 0");
  check(mo.polish_smoothness >= 0, "multigrid.polish_smoothness", mo.polish_smoothness, "at least 0");
  check(mo.polish_smoothness_decay > 0 && mo.polish_smoothness_decay <= 1,
        "multigrid.polish_smoothness_decay", mo.polish_smoothness_decay, "above 0, at most 1");
  count(mo.smoothing_degree, "multigrid.smoothing_degree", 1, 8);
  check(mo.tangential_damping >= 0 && mo.tangential_damping <= 1e6, "multigrid.tangential_damping",
        mo.tangential_damping, "0-1e6");
  check(mo.tangential_damping_bend > 0 && mo.tangential_damping_bend <= 1e6,
        "multigrid.tangential_damping_bend", mo.tangential_damping_bend, "above 0, at most 1e6");
  check(mo.tangential_damping_margin >= 0 && mo.tangential_damping_margin <= 1e6,
        "multigrid.tangential_damping_margin", mo.tangential_damping_margin, "0-1e6");
}

VolumeReconstructor::VolumeReconstructor(DetailEncoding encoding, ReconstructOptions options)
    : impl_(std::make_unique<Impl>(std::move(encoding), std::move(options))) {}
VolumeReconstructor::~VolumeReconstructor() = default;
VolumeReconstructor::VolumeReconstructor(VolumeReconstructor&&) noexcept = default;
VolumeReconstructor& VolumeReconstructor::operator=(VolumeReconstructor&&) noexcept = default;

ReconstructResult VolumeReconstructor::reconstruct(const std::vector<Vec3>& edited_base) const {
  return reconstruct(edited_base, ReconstructRequest{});
}
ReconstructResult VolumeReconstructor::reconstruct(const BaseFrames& edited_frames) const {
  return reconstruct(edited_frames, ReconstructRequest{});
}
ReconstructResult VolumeReconstructor::reconstruct(const std::vector<Vec3>& edited_base,
                                                   const ReconstructRequest& request) const {
  return impl_->in_solver_order(nullptr, request, [&](const std::vector<Vec3>*, const ReconstructRequest& q) {
    return impl_->run(edited_base, nullptr, nullptr, q);
  });
}
ReconstructResult VolumeReconstructor::reconstruct(const BaseFrames& edited_frames,
                                                   const ReconstructRequest& request) const {
  BaseFrames copy;
  const BaseFrames& fr = impl_->solver_frames(edited_frames, copy);
  return impl_->in_solver_order(nullptr, request, [&](const std::vector<Vec3>*, const ReconstructRequest& q) {
    return impl_->run(fr, nullptr, nullptr, q);
  });
}
ReconstructResult VolumeReconstructor::reconstruct_from(const BaseFrames& edited_frames,
                                                        const std::vector<Vec3>& start,
                                                        const WarmStartOptions& warm,
                                                        const ReconstructRequest& request) const {
  BaseFrames copy;
  const BaseFrames& fr = impl_->solver_frames(edited_frames, copy);
  return impl_->in_solver_order(
      &start, request,
      [&](const std::vector<Vec3>* s, const ReconstructRequest& q) { return impl_->run(fr, s, &warm, q); });
}
ReconstructResult VolumeReconstructor::reconstruct_from(const std::vector<Vec3>& edited_base,
                                                        const std::vector<Vec3>& start,
                                                        const WarmStartOptions& warm,
                                                        const ReconstructRequest& request) const {
  return impl_->in_solver_order(&start, request,
                                [&](const std::vector<Vec3>* s, const ReconstructRequest& q) {
                                  return impl_->run(edited_base, s, &warm, q);
                                });
}
ReconstructResult VolumeReconstructor::drag_step(const BaseFrames& edited_frames, DragState& state,
                                                 const WarmStartOptions& warm,
                                                 const ReconstructRequest& request) const {
  if (!state.impl_) throw InvalidInput("drag_step() with a moved-from DragState: reset() it first");
  BaseFrames copy;
  const BaseFrames& fr = impl_->solver_frames(edited_frames, copy);
  return impl_->in_solver_order(nullptr, request, [&](const std::vector<Vec3>*, const ReconstructRequest& q) {
    return impl_->drag(fr, *state.impl_, warm, q);
  });
}
ReconstructResult VolumeReconstructor::drag_step(const std::vector<Vec3>& edited_base, DragState& state,
                                                 const WarmStartOptions& warm,
                                                 const ReconstructRequest& request) const {
  if (!state.impl_) throw InvalidInput("drag_step() with a moved-from DragState: reset() it first");
  const auto t0 = std::chrono::steady_clock::now();
  const BaseFrames fr = impl_->frames_for(edited_base);  // in the solver's numbering
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ReconstructResult r =
      impl_->in_solver_order(nullptr, request, [&](const std::vector<Vec3>*, const ReconstructRequest& q) {
        return impl_->drag(fr, *state.impl_, warm, q);
      });
  r.stats.seconds_frames += seconds;
  return r;
}
BaseFrames VolumeReconstructor::base_frames(const std::vector<Vec3>& edited_base) const {
  return impl_->caller_frames(impl_->frames_for(edited_base));
}
void VolumeReconstructor::set_intersection_context(IntersectionContext context) {
  impl_->set_intersection_context(std::move(context));
}
const DetailEncoding& VolumeReconstructor::encoding() const {
  return impl_->encoding();
}
const ReconstructOptions& VolumeReconstructor::options() const {
  return impl_->options();
}
double VolumeReconstructor::setup_seconds() const {
  return impl_->setup_seconds();
}
std::vector<int> VolumeReconstructor::level_vertex_counts() const {
  return impl_->level_vertex_counts();
}

IntersectionContext context_around(const std::vector<Face>& mesh_faces, const std::vector<char>& solved,
                                   const std::vector<int>& detail_vertices,
                                   const std::vector<Vec3>& positions,
                                   const std::vector<Vec3>* rest_positions) {
  if (solved.size() != positions.size())
    throw InvalidInput("context_around: " + std::to_string(solved.size()) + " vertex flags for " +
                       std::to_string(positions.size()) + " vertices");
  if (rest_positions && rest_positions->size() != positions.size())
    throw InvalidInput("context_around: " + std::to_string(rest_positions->size()) + " rest positions for " +
                       std::to_string(positions.size()) + " vertices");
  const auto nv = static_cast<long long>(positions.size());
  std::vector<int> id(positions.size(), -1);
  for (std::size_t k = 0; k < detail_vertices.size(); ++k) {
    const int v = detail_vertices[k];
    if (v < 0 || v >= nv)
      throw InvalidInput("context_around: detail vertex " + std::to_string(k) + " is mesh vertex " +
                         std::to_string(v) + ", not in [0, " + std::to_string(nv) + ")");
    if (id[v] >= 0)
      throw InvalidInput("context_around: mesh vertex " + std::to_string(v) + " is detail vertex " +
                         std::to_string(id[v]) + " and " + std::to_string(k));
    id[v] = static_cast<int>(k);
  }

  const auto nd = static_cast<int>(detail_vertices.size());
  IntersectionContext c;
  for (std::size_t j = 0; j < mesh_faces.size(); ++j) {
    const Face& f = mesh_faces[j];
    for (int v : f)
      if (v < 0 || v >= nv)
        throw InvalidInput("context_around: face " + std::to_string(j) + " has vertex index " +
                           std::to_string(v) + ", not in [0, " + std::to_string(nv) + ")");
    if (solved[f[0]] || solved[f[1]] || solved[f[2]]) {  // the detail's
      for (int v : f)
        if (id[v] < 0)
          throw InvalidInput("context_around: face " + std::to_string(j) +
                             " has a solved vertex, but its vertex " + std::to_string(v) +
                             " is no detail vertex");
      continue;
    }
    Face g;
    for (int k = 0; k < 3; ++k) {
      const int v = f[k];
      if (id[v] < 0) {
        id[v] = nd + static_cast<int>(c.points.size());
        c.points.push_back(positions[v]);
        if (rest_positions) c.rest_points.push_back((*rest_positions)[v]);
      }
      g[k] = id[v];
    }
    c.faces.push_back(g);
  }
  return c;
}

}  // namespace strata

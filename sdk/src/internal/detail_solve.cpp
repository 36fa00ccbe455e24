#include "internal/detail_solve.h"

#include <algorithm>
#include <chrono>

#include "strata/mesh.h"
#include "strata/metrics.h"

namespace strata::internal {
namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// Whether every base point of \p f is back at its rest position up to rounding (back_at_rest(),
// relative to the rest base points' diagonal; the frames' normals are not compared, as a base
// moved by no more than that cannot turn them beyond rounding either): an edit by the identity,
// or a drag back to its start, moves the base by nothing or by the last bits, and the rest detail
// is then the exact solution of its prisms, where a solve from the clean start lands elsewhere
// (within the round trip's 0.5% of the diagonal), and a layered model's finer bands would follow.
bool base_at_rest(const DetailEncoding& e, const BaseFrames& f) {
  const double scale = bbox_diagonal(e.base_rest_points);
  for (std::size_t i = 0; i < f.points.size(); ++i)
    if (!back_at_rest(f.points[i], e.base_rest_points[i], scale)) return false;
  return true;
}
}  // namespace

double DetailSolve::ensure_reconstructor() const {
  if (rec_) return 0.0;
  const auto t0 = Clock::now();
  auto rec = std::make_unique<VolumeReconstructor>(enc_, reconstruct_);
  if (!context_.faces.empty()) rec->set_intersection_context(context_);
  rec_ = std::move(rec);  // only once it is whole
  return seconds_since(t0);
}

std::vector<Vec3> DetailSolve::solve(const std::vector<Vec3>& base, EditResult& res, bool rigid) const {
  if (!rigid && !nonrigid_pins_.empty() && nonrigid_pins_ != enc_.pinned) {
    if (!nonrigid_) {
      nonrigid_ = std::make_unique<DetailSolve>(method_, reconstruct_, drag_, drag_end_, drag_end_cycles_);
      nonrigid_->enc_ = enc_;
      nonrigid_->enc_.pinned = nonrigid_pins_;
      nonrigid_->context_ = context_;
    }
    return nonrigid_->solve(base, res);
  }
  const BaseFrames frames = evaluate_base_frames(enc_, base);
  if (base_at_rest(enc_, frames)) {
    res.volume = volume_metrics(enc_, frames, enc_.detail_rest);
    if (method_ == EditOptions::Method::Volumes) {
      res.stats.max_relative_error = res.volume.max_relative_error;
      res.stats.rms_relative_error = res.volume.rms_relative_error;
      res.stats.converged = res.volume.max_relative_error <= reconstruct_.tolerance;
      res.stats.new_intersecting_pairs = 0;  // the rest detail itself
    }
    return enc_.detail_rest;
  }
  std::vector<Vec3> sub;
  if (method_ == EditOptions::Method::Volumes) {
    res.times.setup = ensure_reconstructor();
    const auto t0 = Clock::now();
    ReconstructResult r = rec_->reconstruct(base);
    res.times.solve = seconds_since(t0);
    sub = std::move(r.positions);
    res.stats = std::move(r.stats);
  } else {
    const auto t0 = Clock::now();
    sub = reconstruct_vectors(enc_, base);
    res.times.solve = seconds_since(t0);
  }
  res.volume = volume_metrics(enc_, frames, sub);
  return sub;
}

void DetailSolve::begin_drag(const std::vector<Vec3>& rest_base) {
  drag_sub_ = enc_.detail_rest;
  if (method_ != EditOptions::Method::Volumes) return;
  ensure_reconstructor();
  drag_state_.reset(rec_->base_frames(rest_base), enc_.detail_rest);
}

std::vector<Vec3> DetailSolve::end_drag(const std::vector<Vec3>& base, EditResult& res) {
  if (method_ != EditOptions::Method::Volumes || drag_end_ != EditOptions::DragEnd::FromDragState ||
      !drag_state_.started())
    return solve(base, res);
  const auto t0 = Clock::now();
  // One evaluation of the reconstructor's frames serves the solve and the metrics.
  const BaseFrames frames = rec_->base_frames(base);
  // At rest by the double-precision frames, as solve() tests it: the reconstructor's come from a
  // cage's single-precision stencil weights (LimitPointSet), 4e-8 off the rest points, so a
  // CageEditor drag back to the start never counted as at rest and ended 4e-8 off the mesh.
  if (base_at_rest(enc_, evaluate_base_frames(enc_, base))) return solve(base, res);
  // The finest level from the drag's state to the exact tolerance, with the reconstructor's own
  // check for new intersecting pairs (and fold repair).
  WarmStartOptions exact;
  exact.coarse_levels_only = false;
  exact.tolerance = reconstruct_.tolerance;
  exact.max_cycles = drag_end_cycles_;
  ReconstructResult r = rec_->drag_step(frames, drag_state_, exact);
  const double warm_seconds = seconds_since(t0);
  // Contacts the edit made (a limb bent into the body, ReconstructStats::contact_pairs) are no
  // fold: a clean start meets them again.
  const long long folds = r.stats.new_intersecting_pairs < 0
                              ? -1
                              : r.stats.new_intersecting_pairs - std::max(r.stats.contact_pairs, 0LL);
  if (!r.stats.converged || folds != 0) {
    // Not converged, folded, or not checked (the options count no pairs): the clean start. If
    // neither converges, the smaller error is kept, as the reconstructor's own retry does, but
    // not at the price of more new pairs (both results are counted when the options count).
    res.drag_end_fallback = true;
    std::vector<Vec3> sub = solve(base, res);
    res.times.solve += warm_seconds;
    if (r.stats.converged || res.stats.converged ||
        res.stats.max_relative_error <= r.stats.max_relative_error ||
        r.stats.new_intersecting_pairs > res.stats.new_intersecting_pairs)
      return sub;
    res.stats = std::move(r.stats);
    res.volume = volume_metrics(enc_, frames, r.positions);
    return std::move(r.positions);
  }
  res.times.solve = warm_seconds;
  res.stats = std::move(r.stats);
  res.volume = volume_metrics(enc_, frames, r.positions);
  return std::move(r.positions);
}

const std::vector<Vec3>& DetailSolve::drag_step(const std::vector<Vec3>& base) {
  if (method_ == EditOptions::Method::Volumes)
    drag_sub_ = rec_->drag_step(base, drag_state_, drag_).positions;
  else
    drag_sub_ = reconstruct_vectors(enc_, base);
  return drag_sub_;
}

}  // namespace strata::internal

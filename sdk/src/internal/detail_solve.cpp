#include "internal/detail_solve.h"

#include <chrono>

#include "strata/metrics.h"

namespace strata::internal {
namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}
}  // namespace

double DetailSolve::ensure_reconstructor() const {
  if (rec_) return 0.0;
  const auto t0 = Clock::now();
  rec_ = std::make_unique<VolumeReconstructor>(enc_, reconstruct_);
  return seconds_since(t0);
}

std::vector<Vec3> DetailSolve::solve(const std::vector<Vec3>& base, EditResult& res) const {
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
  res.volume = volume_metrics(enc_, evaluate_base_frames(enc_, base), sub);
  return sub;
}

void DetailSolve::begin_drag(const std::vector<Vec3>& rest_base) {
  drag_sub_ = enc_.detail_rest;
  if (method_ != EditOptions::Method::Volumes) return;
  ensure_reconstructor();
  drag_state_.reset(rec_->base_frames(rest_base), enc_.detail_rest);
}

const std::vector<Vec3>& DetailSolve::drag_step(const std::vector<Vec3>& base) {
  if (method_ == EditOptions::Method::Volumes)
    drag_sub_ = rec_->drag_step(base, drag_state_, drag_).positions;
  else
    drag_sub_ = reconstruct_vectors(enc_, base);
  return drag_sub_;
}

}  // namespace strata::internal

// Internal: the detail half of an editor (RegionEditor, CageEditor): one encoding, rebuilt over
// edited bases by volumes or vectors, exactly or as warm-started drag steps (paper, section 5).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "strata/editing.h"
#include "strata/exceptions.h"

namespace strata::internal {

class DetailSolve {
 public:
  DetailSolve(EditOptions::Method method, ReconstructOptions reconstruct, WarmStartOptions drag,
              EditOptions::DragEnd drag_end, int drag_end_cycles)
      : method_(method),
        reconstruct_(std::move(reconstruct)),
        drag_(drag),
        drag_end_(drag_end),
        drag_end_cycles_(drag_end_cycles) {
    // Enums cast from integers (a method of 9 ran as volumes).
    if (method != EditOptions::Method::Volumes && method != EditOptions::Method::Vectors)
      throw InvalidInput("edit option method = " + std::to_string(static_cast<int>(method)) +
                         " is not volumes or vectors");
    if (drag_end != EditOptions::DragEnd::FromDragState && drag_end != EditOptions::DragEnd::CleanStart)
      throw InvalidInput("edit option drag_end = " + std::to_string(static_cast<int>(drag_end)) +
                         " is not from_drag_state or clean_start");
  }

  //! Set once by the editor before the first solve (the reconstructor is built from it lazily).
  DetailEncoding& encoding() { return enc_; }
  //! VolumeReconstructor::set_intersection_context() of the reconstructor, once it is built.
  //! Set by the editor before the first solve, with the encoding.
  void set_intersection_context(IntersectionContext context) { context_ = std::move(context); }
  const DetailEncoding& encoding() const { return enc_; }

  //! The exact solve over \p base (the encoding's base vertices, or a cage's control points):
  //! from the clean start for volumes. A base back at rest to within rounding gives the encoded
  //! detail at rest exactly (no solve). Fills res.stats, res.times.setup/solve and res.volume.
  std::vector<Vec3> solve(const std::vector<Vec3>& base, EditResult& res) const;

  //! Starts a drag from the encoded detail at rest, over \p rest_base (the encoding's base vertices
  //! or the cage's control points at rest).
  void begin_drag(const std::vector<Vec3>& rest_base);
  //! One warm-started step over \p base; returns the detail positions.
  const std::vector<Vec3>& drag_step(const std::vector<Vec3>& base);
  //! The exact solve that ends a drag over \p base (EditOptions::drag_end): from the drag's state,
  //! checked, or solve(). Fills res as solve() does, and res.drag_end_fallback.
  std::vector<Vec3> end_drag(const std::vector<Vec3>& base, EditResult& res);

 private:
  //! Builds the volume reconstructor on first use; returns the seconds it took (0 if it existed).
  double ensure_reconstructor() const;

  EditOptions::Method method_;
  ReconstructOptions reconstruct_;
  WarmStartOptions drag_;
  EditOptions::DragEnd drag_end_;
  int drag_end_cycles_;
  DetailEncoding enc_;
  IntersectionContext context_;
  mutable std::unique_ptr<VolumeReconstructor> rec_;
  std::vector<Vec3> drag_sub_;
  DragState drag_state_;  // every multigrid level's last drag solution (volumes)
};

}  // namespace strata::internal

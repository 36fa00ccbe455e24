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
    // At the editor's construction, not at its first solve or drag step (threads = -1 passed the
    // constructor and failed apply(); a negative drag tolerance the first update_drag()).
    if (method == EditOptions::Method::Volumes) {
      check_reconstruct_options(reconstruct_);
      check_warm_start_options(drag_);
    }
  }

  //! Set once by the editor before the first solve (the reconstructor is built from it lazily).
  DetailEncoding& encoding() { return enc_; }
  //! VolumeReconstructor::set_intersection_context() of the reconstructor, once it is built.
  //! Set by the editor before the first solve, with the encoding.
  void set_intersection_context(IntersectionContext context) { context_ = std::move(context); }
  const DetailEncoding& encoding() const { return enc_; }

  //! The pinned flags for an edit whose map is not rigid (a scale, a shear): the encoding's pin
  //! the handle's inner vertices, placed by the vector rule, which keeps their volumes only under
  //! a rigid map (a scale of 1.5 left them at 3.4 times theirs, and the solve around them could
  //! not converge). Set by the editor with the encoding; empty: the encoding's flags always.
  void set_nonrigid_pins(std::vector<char> pinned) { nonrigid_pins_ = std::move(pinned); }

  //! The exact solve over \p base (the encoding's base vertices, or a cage's control points):
  //! from the clean start for volumes. A base back at rest to within rounding gives the encoded
  //! detail at rest exactly (no solve). Fills res.stats, res.times.setup/solve and res.volume.
  //! \p rigid false: with the pins of set_nonrigid_pins() (a second reconstructor, built on first
  //! use).
  std::vector<Vec3> solve(const std::vector<Vec3>& base, EditResult& res, bool rigid = true) const;

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
  std::vector<char> nonrigid_pins_;
  mutable std::unique_ptr<DetailSolve> nonrigid_;  // the solve with nonrigid_pins_, on first use
  std::vector<Vec3> drag_sub_;
  DragState drag_state_;  // every multigrid level's last drag solution (volumes)
};

}  // namespace strata::internal

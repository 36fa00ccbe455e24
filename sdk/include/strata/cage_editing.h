//! \file cage_editing.h
//! The editing operator over a subdivision base (issue 4, item 5): the mesh's detail is encoded
//! once over the limit surface of a control cage; region and handle select cage vertices; the
//! handle's transform is blended over the region's cage vertices (paper, section 5, with the
//! cage as the smooth base), the limit surface follows, and the detail is rebuilt over it.
//!
//! \code
//!   strata::CageFit fit = strata::fit_cage(scan);
//!   strata::CageEditor editor(scan, strata::SubdivSurface(fit.cage),
//!                             strata::select_vertices(fit.cage.vertices, region),
//!                             strata::select_vertices(fit.cage.vertices, handle));
//!   strata::EditResult r = editor.apply(strata::EditTransform::rotation(axis, 90.0, pivot));
//! \endcode
#pragma once

#include <memory>
#include <vector>

#include "strata/editing.h"
#include "strata/subdiv.h"

namespace strata {

//! Options of CageEditor, with their defaults.
struct CageEditOptions {
  //! Volumes (the paper) or displacement vectors along the limit normals (the baseline).
  EditOptions::Method method = EditOptions::Method::Volumes;
  //! Projection of the mesh's vertices onto the cage's limit surface (the encoding).
  ProjectOptions projection;
  //! Reconstruction (exact solves: apply() and end_drag()).
  ReconstructOptions reconstruct;
  //! Interactive steps (update_drag()), as EditOptions::drag.
  WarmStartOptions drag{true, 1e-2, 1, 30};
  //! How end_drag() runs the exact solve, as EditOptions::drag_end.
  EditOptions::DragEnd drag_end = EditOptions::DragEnd::FromDragState;
  //! As EditOptions::drag_end_cycles.
  int drag_end_cycles = 5;
  //! Detail vertices whose limit stencils reach handle cage vertices only move rigidly with the
  //! handle (their base frames do), so displacement vectors place them exactly and they are not
  //! solved, except within this many edges of a vertex whose frame does not move rigidly: those
  //! rings are solved with the blended part. Negative: every vertex that depends on the region is
  //! solved.
  int handle_solved_rings = 3;
};

//! The blend field of an edit on a cage (paper, section 5, with the cage as the base): s is
//! bi-harmonic: (L^T L s)_v = 0, the minimizer of |L s|^2 with L the row-normalized uniform
//! Laplacian of the cage graph (L^2 s = 0 where the valences are equal, L then symmetric; a
//! symmetric system everywhere), on the region's cage
//! vertices outside the handle, 0 outside the region and 1 on the handle (the region vertices
//! that \p handle flags).
//! \throw InvalidInput if the flags do not have one entry per cage vertex, the region or the
//!        handle is empty, the handle is the whole region, a cage face has fewer than 3 corners
//!        or an index out of range. A connected part of the region's vertices outside the handle
//!        that touches neither the rest of the cage nor the handle (a cage of several pieces, one
//!        of them in the region away from the handle) keeps s = 0: its field would be
//!        undetermined. A region that is the whole
//!        cage (of one piece) gives s = 1 everywhere: the edit moves the model rigidly. A cage vertex in no
//!        face (it shapes no surface) keeps s = 0, or 1 on the handle.
//! \throw SolverError if the field's system cannot be factorized or solved.
std::vector<double> cage_blend_field(const PolyMesh& cage, const std::vector<char>& region,
                                     const std::vector<char>& handle);

//! Editing of a mesh through the control cage of its subdivision base. Only the prisms whose
//! base points depend on a region cage vertex (through their limit stencils) are solved; every
//! other detail vertex keeps its position exactly, since its base frame cannot change.
//! Not thread-safe: one drag at a time, one thread per object.
class CageEditor {
 public:
  //! \p region and \p handle hold one flag per cage vertex; the handle is taken as the region
  //! vertices it flags. The blend field is bi-harmonic on the cage graph (uniform Laplacian) over
  //! the region minus the handle, 0 outside the region and 1 on the handle.
  //! \pre mesh is a valid triangle mesh (validate_mesh()); its face indices and coordinates are
  //! checked.
  //! \throw InvalidInput if a face index of the mesh is out of range or a coordinate is not finite
  //!        or beyond kMaxCoordinate, options.handle_solved_rings is above 1000 or
  //!        options.drag_end_cycles outside 1-100000, the flags do not match the cage's vertex count,
  //! the region or handle
  //!        is empty, the handle is the whole region, or no detail vertex depends on the region.
  //! \throw SolverError if the blend field cannot be solved.
  CageEditor(const TriMesh& mesh, SubdivSurface base, const std::vector<char>& region,
             const std::vector<char>& handle, CageEditOptions options = {});
  ~CageEditor();
  //! A moved-from object may only be assigned to or destroyed (its other calls are undefined).
  CageEditor(CageEditor&&) noexcept;
  CageEditor& operator=(CageEditor&&) noexcept;

  const TriMesh& mesh() const;
  const SubdivSurface& base() const;
  //! The blend field per cage vertex.
  const std::vector<double>& blend() const;
  const std::vector<int>& region_vertices() const;  //!< cage vertices
  const std::vector<int>& handle_vertices() const;  //!< cage vertices
  //! Prisms solved: the mesh faces with a vertex whose base point depends on the region.
  int region_faces() const;
  //! The solved part's encoding over the limit surface (submesh indices).
  const DetailEncoding& encoding() const;
  const CageEditOptions& options() const;

  //! The cage with \p transform blended over the region.
  //! \throw InvalidInput if the transform is not finite or its linear part is singular or
  //!        reflecting.
  std::vector<Vec3> edited_cage(const EditTransform& transform) const;

  //! The exact edit from the clean start. EditResult::base_positions holds the edited cage. A
  //! transform that leaves the limit surface's base points at rest to within rounding gives the
  //! mesh back bit for bit, with no solve (as RegionEditor::apply()).
  //! \throw as edited_cage(); SolverError if the reconstruction fails.
  EditResult apply(const EditTransform& transform) const;

  //! Interactive drag, as RegionEditor's: warm-started steps, the exact solve at the end.
  void begin_drag();
  //! \throw InvalidInput if no drag is active, or as edited_cage().
  const std::vector<Vec3>& update_drag(const EditTransform& transform);
  //! Ends the drag with the exact solve, as CageEditOptions::drag_end says (RegionEditor::end_drag).
  //! \throw InvalidInput if no drag is active; SolverError if the reconstruction fails; Cancelled
  //!        (ReconstructOptions::cancel). After a throw the drag is still active.
  EditResult end_drag();
  bool dragging() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace strata

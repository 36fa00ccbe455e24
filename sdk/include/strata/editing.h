//! \file editing.h
//! The modeling framework of the paper's section 5, after Kobbelt et al. 1998: a modifiable
//! region and a handle are selected on a mesh; the region is decomposed into a smooth base (a
//! thin-plate fairing) and its detail (displacement volumes or vectors); a transformation of the
//! handle is blended over the region's base; the detail is rebuilt over the edited base.
//!
//! Typical use (one selection, any number of transforms):
//! \code
//!   strata::RegionEditor editor(mesh, select_vertices(mesh.vertices, region),
//!                               select_vertices(mesh.vertices, handle));
//!   strata::EditResult r = editor.apply(EditTransform::rotation(axis, 90.0, pivot));
//!   // or, interactively:
//!   editor.begin_drag();
//!   for (double a : angles) show(editor.update_drag(EditTransform::rotation(axis, a, pivot)));
//!   strata::EditResult final_result = editor.end_drag();
//! \endcode
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "strata/encoding.h"
#include "strata/mesh.h"
#include "strata/metrics.h"
#include "strata/reconstruction.h"

namespace strata {

//! A vertex selection, evaluated on vertex positions (or given as indices).
struct Selection {
  enum class Kind {
    Sphere,     //!< |x - center| <= radius
    Halfspace,  //!< (x - point) . normal >= 0: the side the normal points to
    Box,        //!< min <= x <= max, componentwise
    Vertices,   //!< an explicit index list
  };
  Kind kind = Kind::Sphere;
  Vec3 center = Vec3::Zero();
  double radius = 0.0;
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Zero();
  std::vector<int> indices;

  static Selection sphere(const Vec3& center, double radius);
  static Selection halfspace(const Vec3& point, const Vec3& normal);
  static Selection box(const Vec3& min, const Vec3& max);
  static Selection vertices(std::vector<int> indices);
};

//! One flag per vertex of \p positions: whether \p selection contains it.
//! \throw InvalidInput if the selection is malformed (non-finite or negative radius, zero normal,
//! min > max, an index out of range for positions.size()).
std::vector<char> select_vertices(const std::vector<Vec3>& positions, const Selection& selection);

//! An affine map about a pivot: x -> pivot + linear (x - pivot) + translation. The editing
//! operator blends it over the region: a vertex with blend value s gets the rotation part of
//! `linear` (its polar decomposition) with s times the angle, the stretch part interpolated
//! linearly from the identity, and s times the translation. So a 90-degree rotation bends a limb
//! like an elbow instead of shearing it.
struct EditTransform {
  Eigen::Matrix3d linear = Eigen::Matrix3d::Identity();
  Vec3 translation = Vec3::Zero();
  Vec3 pivot = Vec3::Zero();
  //! The rotation as it was given (rotation(), a script's "rotate"), for blending: the linear part
  //! alone tells a turn of 270 degrees from one of -90 only the short way, so a blend weight of
  //! 0.5 turned -45 degrees, and a drag through 180 degrees flipped the bend. Used when the
  //! rotation of linear's polar decomposition is this one (to 1e-9); otherwise, and with a zero
  //! axis, the short way.
  Vec3 rotation_axis = Vec3::Zero();
  double rotation_degrees = 0.0;

  //! A rotation by \p degrees about \p axis through \p pivot, then a translation.
  //! \throw InvalidInput if the axis is zero or a value is not finite.
  static EditTransform rotation(const Vec3& axis, double degrees, const Vec3& pivot,
                                const Vec3& translation = Vec3::Zero());
  //! The full map applied to \p x.
  Vec3 apply(const Vec3& x) const;
  //! Whether the map is rigid (a rotation and a translation): the linear part is orthonormal to
  //! within \p tolerance (max |L^T L - I|) and keeps orientation. Prism volumes and the
  //! regularization are invariant only under such maps. False if the map is not finite.
  bool is_rigid(double tolerance = 1e-9) const;
  //! The map blended with weight \p s (0: identity, 1: the full map). Decomposes the linear part
  //! on every call (an SVD); RegionEditor decomposes once per transform for all vertices.
  //! \throw InvalidInput if the map is not finite or its linear part is singular or reflecting.
  Vec3 apply_blended(const Vec3& x, double s) const;
  //! The map blended with weight \p s as a transform of its own: apply_blended(x, s) for every x
  //! (a drag's partial edit). \throw as apply_blended().
  EditTransform partial(double s) const;
};

//! \p points with \p transform blended by the field \p s (one value per point): point i gets
//! transform.apply_blended(points[i], s[i]), the map decomposed once for all points; points with
//! s = 0 keep their positions exactly.
//! \throw InvalidInput if the sizes differ, as EditTransform::apply_blended(), or if a point is
//!        moved beyond kMaxCoordinate (the message names its index).
std::vector<Vec3> blend_transform(const std::vector<Vec3>& points, const std::vector<double>& s,
                                  const EditTransform& transform);

//! Options of RegionEditor, with their defaults.
struct EditOptions {
  //! Reconstruct the detail by displacement volumes (the paper) or by displacement vectors along
  //! the base normals (the baseline every figure compares with).
  enum class Method { Volumes, Vectors };
  Method method = Method::Volumes;
  //! Shape features longer than about this wavelength (world units) stay in the base, shorter
  //! ones become detail. 0 (default): smoothing_fraction times the region's bounding-box diagonal.
  double smoothing_wavelength = 0.0;
  //! The cut-off wavelength relative to the region's size when smoothing_wavelength is 0.
  double smoothing_fraction = 0.25;
  //! Handle vertices within this many edges of the blended part are solved with it; the handle's
  //! other vertices move rigidly with their base (placed like displacement vectors, which is
  //! exact there) and are not solved.
  int handle_solved_rings = 3;
  //! Fill the region's corners: a region vertex that is the only region vertex of two or more
  //! faces is the only free vertex of those faces' prisms, whose volumes are then two or more
  //! equations on its three coordinates: with three or more it can meet them at best exactly and
  //! in general not at all (the man's knee bent 90 degrees at smoothing 0.25 ended at a max
  //! error of 4.4e-3 at one such vertex, by either solver and any tolerance), with two only by a
  //! large tangential motion where the base is steep at the region's border (the camel's front
  //! leg at 60 degrees and smoothing 1.0: 0.14). With this on, the outside vertices of such faces
  //! are solved too (once; they keep the selection's base and blend, the mesh itself and s = 0,
  //! so their own faces outside keep their volumes where they stand): region_vertices() then holds
  //! more vertices than the selection (2.4% more in the median of the limb-bend survey, at most
  //! 9.6%). Measured on that survey (324 bends of six scans, engine log, twenty-sixth session):
  //! unconverged 52 -> 2, none above 1e-3. false: the region is the selection exactly.
  bool fill_region_corners = true;
  //! Encoding of the region's detail over its faired base.
  EncodeOptions encode;
  //! Reconstruction of the region's detail (exact solves: apply() and end_drag()).
  ReconstructOptions reconstruct;
  //! Interactive steps (update_drag()): volumes on the coarse levels only, the finest level by
  //! regularization (section 5); one volume step of at most 30 conjugate-gradient iterations per
  //! coarse level and step, each level going on from its own last solution, so that a step's time
  //! is bounded and the levels converge over the drag's frames.
  WarmStartOptions drag{true, 1e-2, 1, 30};
  //! How end_drag() runs the exact solve.
  //! - FromDragState (default): the finest level solved to the tolerance from the drag's own
  //!   state (every level's last solution, carried to the final base), so the result stays near
  //!   the last preview instead of jumping on release, at well under half the clean start's cost.
  //!   Its new intersecting pairs are counted (and repaired) as a clean-start solve's; if it does
  //!   not converge, or still adds pairs, or the reconstruction options count none
  //!   (ReconstructOptions::retry_on_new_intersections off), the clean-start solve runs instead
  //!   (EditResult::drag_end_fallback); if neither converges, the smaller error is kept.
  //! - CleanStart: apply() of the last transform (volume scaling from the clean configuration),
  //!   so a drag ends bit for bit where a scripted edit of the same transform does.
  enum class DragEnd { FromDragState, CleanStart };
  DragEnd drag_end = DragEnd::FromDragState;
  //! FromDragState: cycles (volume steps, then regularization) on the finest level at most before
  //! the exact polish. Measured on the 50k-prism elbow drag: 5 cycles 0.88 s, 10 cycles 1.26 s,
  //! both without new pairs; 1 to 4 cycles left new pairs.
  int drag_end_cycles = 5;
};

//! Timings of one edit, in seconds.
struct EditTimes {
  double decompose = 0.0;  //!< constructor: fairing and blend field (one factorization)
  double encode = 0.0;     //!< constructor: encoding the region's detail over its base
  double setup = 0.0;      //!< the volume reconstructor's multigrid hierarchy (first use only)
  double edit = 0.0;       //!< blending the transform over the base
  double solve = 0.0;      //!< reconstruction of the region's detail
};

//! The result of an edit: the whole mesh's new vertex positions (vertices outside the region keep
//! theirs exactly) and how well the region's prisms kept their volumes.
struct EditResult {
  std::vector<Vec3> positions;
  std::vector<Vec3> base_positions;  //!< the edited base, whole mesh
  VolumeMetrics volume;              //!< over the region's prisms
  ReconstructStats stats;            //!< volumes only (zero for vectors)
  EditTimes times;
  //! end_drag() only: the exact solve from the drag's state did not converge or added
  //! intersecting pairs, and the clean-start solve ran too (EditOptions::drag_end).
  bool drag_end_fallback = false;
};

//! Decomposition and editing of one region of a mesh (paper, section 5). The constructor
//! decomposes by low-pass filtering the region: the base minimizes the thin-plate energy
//! (bi-Laplacian, x^T L M^-1 L x with clamped cotangent L and barycentric areas M) plus a pull
//! towards the mesh (EditOptions::smoothing_wavelength sets the cut-off), with the rest of the
//! mesh held as the boundary condition, so the base is tangent-continuous with it. (Pure fairing
//! would neck a limb in and make its thickness "detail".) The blend field s is bi-harmonic on the
//! region minus the handle, 0 on the rest and 1 on the handle. Open edges (holes, a CAD part's
//! rims) have no Laplacian rows in either system, which would pull the rim in; where that leaves
//! the blend undetermined (free vertices whose neighbours all lie on open edges, or rims that no
//! interior row ties to the rest: the system is singular, or its solution leaves [-0.5, 1.5]),
//! the blend field takes the rim's rows too. The detail of the prisms
//! touching the region is encoded over that base; vertices outside the region are pinned, so only the region
//! is solved, and so are handle vertices away from the blended part (they move rigidly). The region solved is
//! the selection with its sharp corners filled (EditOptions::fill_region_corners; region_vertices()), over
//! the selection's base and blend. The rest of the mesh is the solver's intersection context
//! (VolumeReconstructor::set_intersection_context()): its fold check, retries and repair count the
//! region's new pairs with the fixed triangles around it too, so ReconstructStats::
//! new_intersecting_pairs is the whole mesh's count, but for contacts with triangles that lay far
//! from the region at rest.
//!
//! Every apply() starts from the editor's own decomposition of the mesh it was given. A new
//! editor on an edited mesh decomposes that anew (its base and blend field follow the bent
//! geometry), so an edit followed by its inverse in a new editor does not give the mesh back: on a
//! 2k-face tube, +45 then -45 degrees about the same vertices left it up to 1.5% of its diagonal
//! away, by displacement vectors as by volumes (engine log, sixteenth session). Keep the mesh to
//! undo.
//!
//! Not thread-safe: one drag at a time, one thread per object.
class RegionEditor {
 public:
  //! \p region and \p handle hold one flag per vertex of \p mesh; the handle is taken as the
  //! region vertices it flags.
  //! \pre mesh is a valid triangle mesh (validate_mesh()); its face indices and coordinates are
  //! checked.
  //! \throw InvalidInput if a face index is out of range or a coordinate is not finite or beyond
  //! kMaxCoordinate, an option is out of range (smoothing_wavelength at least 0,
  //! smoothing_fraction above 0, both finite, and the wavelength not so small that the fairing's
  //! weights overflow; handle_solved_rings 0-1000; drag_end_cycles 1-100000), the flags do not match the
  //! vertex count, the region or the handle is empty, the handle is the whole region (also once the parts
  //! that left_out_vertices() counts are left out), or the region is the whole mesh. \throw SolverError if
  //! the fairing system cannot be factorized.
  RegionEditor(const TriMesh& mesh, const std::vector<char>& region, const std::vector<char>& handle,
               EditOptions options = {});
  ~RegionEditor();
  //! A moved-from object may only be assigned to or destroyed (its other calls are undefined).
  RegionEditor(RegionEditor&&) noexcept;
  RegionEditor& operator=(RegionEditor&&) noexcept;

  const TriMesh& mesh() const;
  //! The faired base: the mesh's connectivity, region positions faired, others unchanged.
  const std::vector<Vec3>& base() const;
  //! The blend field s per mesh vertex (0 outside the region, 1 on the handle).
  const std::vector<double>& blend() const;
  //! The region solved: the selected vertices, and those that fill its corners
  //! (EditOptions::fill_region_corners). Vertices outside it keep their positions exactly.
  const std::vector<int>& region_vertices() const;
  const std::vector<int>& handle_vertices() const;
  //! Vertices of the selected region left out of it: those of its connected parts (without the
  //! handle) that touch neither the handle nor the rest of the mesh, whose blend would be
  //! undetermined (a part of a multi-part model, or a scan's loose fragment, taken in whole away
  //! from the handle). They stay where they are. 0 for a region of one piece.
  int left_out_vertices() const;
  //! Number of prisms solved: the faces with at least one region vertex.
  int region_faces() const;
  //! The region's detail encoding (submesh indices; see region_submesh_vertices()).
  const DetailEncoding& encoding() const;
  //! Mesh vertex id of each submesh vertex of the encoding.
  const std::vector<int>& region_submesh_vertices() const;
  const EditOptions& options() const;
  double decompose_seconds() const;
  double encode_seconds() const;

  //! The base with \p transform blended over the region.
  //! \throw InvalidInput if the transform is not finite or its linear part is singular or
  //! reflecting.
  std::vector<Vec3> edited_base(const EditTransform& transform) const;

  //! The exact edit from the clean start (volume scaling, the whole multigrid), with the
  //! options' method. A transform that leaves the region's base at rest to within rounding (the
  //! identity: every base point within 1e-12 of the base's diagonal plus 1e-14 of its own
  //! coordinates) gives the mesh back bit for bit, with no solve (stats: converged, no sweeps).
  //! \throw as edited_base(); SolverError if the reconstruction fails.
  EditResult apply(const EditTransform& transform) const;

  //! Starts a drag from the unedited mesh.
  void begin_drag();
  //! One interactive step: warm-started from the previous step, no volume scaling, volumes on the
  //! coarse levels only (section 5). Returns the whole mesh's positions.
  //! \throw InvalidInput if no drag is active, or as edited_base().
  const std::vector<Vec3>& update_drag(const EditTransform& transform);
  //! Ends the drag with the exact solve on the last transform, as EditOptions::drag_end says:
  //! from the drag's per-level state (default; checked for convergence and new intersecting
  //! pairs, with apply()'s clean start as the fallback), or apply() itself. A drag back to its
  //! start (the base at rest, as for apply()) gives the mesh back bit for bit.
  //! \throw InvalidInput if no drag is active; SolverError if the reconstruction fails; Cancelled
  //!        (ReconstructOptions::cancel). After a throw the drag is still active: end_drag() can
  //!        be called again (with the flag cleared) or the drag go on.
  EditResult end_drag();
  bool dragging() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace strata

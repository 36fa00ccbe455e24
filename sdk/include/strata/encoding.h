//! \file encoding.h
//! Detail encoding over a triangle-mesh base (paper, section 3): base points, target prism
//! volumes, displacement lengths and regularization weights.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "strata/mesh.h"
#include "strata/subdiv.h"

namespace strata {

//! A point on a base triangle mesh: a face and barycentric coordinates (summing to 1). Because
//! it refers to the base's connectivity, the same base point exists on every edited base with
//! that connectivity (the paper's mutual parameterization, section 4).
struct BasePoint {
  int face = -1;
  Vec3 bary = Vec3(1.0, 0.0, 0.0);
};

//! Options of encode_detail(), with their defaults.
struct EncodeOptions {
  //! Rings of base faces around the closest face that are searched for the normal projection.
  int search_rings = 3;
  //! Barycentric coordinates down to -tolerance still count as inside a face (then clamped).
  double barycentric_tolerance = 1e-7;
  //! A normal projection farther than this multiple of the closest-point distance is rejected as
  //! ambiguous (it belongs to another part of the surface), and the closest point is used.
  double max_distance_ratio = 3.0;
};

//! What encode_detail() found, for reports.
struct EncodeReport {
  int num_vertices = 0;
  int num_projected = 0;               //!< base point found by the normal projection (p - q parallel to n(q))
  int num_fallback = 0;                //!< no valid normal projection: the closest point on the base is used
  int num_ambiguous = 0;               //!< several normal projections: the nearest one was taken
  double max_tangential_offset = 0.0;  //!< largest |tangential part of p - q| (fallbacks only)
  double seconds = 0.0;
};

//! The detail of a mesh S~ over a base S, everything the reconstruction needs (no positions of S).
struct DetailEncoding {
  // The detail mesh's connectivity and its original positions (for the multigrid hierarchy's
  // coarse-level targets and weights).
  std::vector<Face> detail_faces;
  std::vector<Vec3> detail_rest;
  // The base's connectivity: an edited base must have the same. For a subdivision base,
  // base_num_vertices is the cage's control point count and base_faces is empty.
  int base_num_vertices = 0;
  std::vector<Face> base_faces;

  //! q_i on a triangle-mesh base, one per detail vertex (empty over a subdivision base).
  std::vector<BasePoint> base_points;
  //! q_i on a subdivision limit surface, one per detail vertex (empty over a triangle base).
  std::vector<LimitPoint> limit_points;
  //! Over a subdivision base: the cage's faces, tags and options (an edited cage has the same);
  //! with the edited control points they define the edited limit surface.
  std::vector<std::vector<int>> cage_faces;
  SubdivTags cage_tags;
  SubdivOptions cage_options;
  std::vector<Vec3> base_rest_points;  //!< q_i's positions on the original base S
  //! Signed displacement length f_i = (p_i - q_i) . n(q_i) along the unit interpolated normal.
  std::vector<double> normal_offsets;
  //! Tangential part of p_i - q_i in the base point's local frame (zero for normal projections;
  //! the fallbacks keep theirs so that nothing is lost).
  std::vector<Eigen::Vector2d> tangential_offsets;
  //! The original base's frame at each q_i (unit normal and first tangent, as
  //! evaluate_base_frames() gives them): the frame of the tangential offsets, and the one in which
  //! the regularization carries the rest detail's tangential Laplacian to an edited base
  //! (TangentialRegularization::RestLaplacian). Empty in an encoding built by hand; that mode then
  //! refuses it.
  std::vector<Vec3> base_rest_normals, base_rest_tangents;
  //! Target prism volume V*_j for each detail face.
  std::vector<double> target_volumes;
  //! Regularization weights from the original detail mesh (normalized clamped cotangent weights),
  //! in compressed rows: the neighbours of vertex i are weight_neighbors[weight_offsets[i] ..
  //! weight_offsets[i+1]).
  std::vector<int> weight_offsets;
  std::vector<int> weight_neighbors;
  std::vector<double> weights;

  //! Optional, empty or one flag per detail vertex: pinned vertices are placed like displacement
  //! vectors (reconstruct_vectors()) and never moved by the volume reconstruction. Regional
  //! editing pins the vertices outside the modifiable region, so that only the region is solved.
  std::vector<char> pinned;
  EncodeReport report;

  int num_detail_vertices() const { return static_cast<int>(detail_rest.size()); }
  //! The base is a subdivision limit surface (limit_points), not a triangle mesh (base_points).
  bool over_limit_surface() const { return !limit_points.empty(); }
};

//! Checks \p options against their ranges (search_rings 0 to 100, barycentric_tolerance 0 to 0.1,
//! max_distance_ratio 1 to 1e6: those a .strata file's are read with). encode_detail() calls it.
//! \throw InvalidInput naming the option.
void check_encode_options(const EncodeOptions& options);

//! Finds for each detail vertex p_i a base point q_i on \p base such that p_i - q_i is parallel
//! to the base's interpolated (Phong) vertex normal at q_i, then stores the target volumes, the
//! displacement lengths and the regularization weights (paper, sections 3 and 4.2). The base may
//! have any connectivity. Where no such point exists near the closest point, the closest point
//! is used and counted in the report. With several connected parts on both sides (a scan with
//! debris), q_i is sought only on the base of p_i's own part, the parts matched as by
//! project_mesh_to_limit(); over a base of the detail's own connectivity (a smoothed copy), on
//! p_i's part's own faces whenever the detail has several parts, however the base's positions
//! join them (a vertex of no face searches the whole base). The projections, the
//! target volumes and the weights run on TBB's threads (the caller's task arena); the result
//! does not depend on their number.
//! \pre detail and base are valid triangle meshes (see validate_mesh()).
//! \throw InvalidInput if a mesh is empty or has out-of-range indices or non-finite coordinates,
//!        or an option is out of range (check_encode_options()), or a base point's face has no
//!        normal (evaluate_base_frames()).
DetailEncoding encode_detail(const TriMesh& detail, const TriMesh& base, const EncodeOptions& options = {});

//! Encodes \p detail over the limit surface of a control cage (issue 4): each base point is the
//! foot point of the detail vertex on the limit surface along the limit normal, on its own
//! part's base (project_mesh_to_limit()), stored as (ptex face, u, v), which is exact on every
//! edited cage. Then, as over a triangle base, the target volumes, displacement lengths and
//! regularization weights.
//! Projections that do not converge are counted as fallbacks in the report (num_fallback) and
//! keep their tangential offset.
//! \throw InvalidInput if the detail mesh is empty or has out-of-range indices or non-finite
//!        coordinates, or the projection options are out of range.
DetailEncoding encode_detail(const TriMesh& detail, const SubdivSurface& base,
                             const ProjectOptions& options = {});

//! Encodes \p detail over \p base with the base points given (e.g. stored in a file, or found by
//! encode_detail()): the target volumes, displacement lengths, tangential offsets and
//! regularization weights, computed exactly as encode_detail() computes them, so that an encoding
//! restored from its base points is bit for bit the one first computed. The report counts every
//! vertex as projected.
//! \throw InvalidInput if a mesh is invalid as for encode_detail(), the point count differs from
//!        the detail's vertex count, or a base point's face is out of range or its barycentric
//!        coordinates are not those of a point on the face (each >= -1e-6, summing to 1 within
//!        1e-6).
DetailEncoding encode_detail_at(const TriMesh& detail, const TriMesh& base,
                                std::vector<BasePoint> base_points);

//! The same over a subdivision limit surface with the limit points given.
//! \throw InvalidInput as above, or if a limit point's face is out of range or its (u, v) lies
//!        outside [0, 1]^2 by over 1e-6.
DetailEncoding encode_detail_at(const TriMesh& detail, const SubdivSurface& base,
                                std::vector<LimitPoint> limit_points);

//! Checks that every limit point lies on a ptex face of \p surface with (u, v) in [0, 1]^2 (to
//! 1e-6), as encode_detail_at() requires of them.
//! \throw InvalidInput "limit point <i> is not on a ptex face".
void check_limit_points(const std::vector<LimitPoint>& points, const SubdivSurface& surface);

//! Checks that \p encoding's arrays fit together, so that what reads them stays within them: one
//! offset, rest base point, base point (or limit point) and, if any, rest frame and pinned flag per
//! detail vertex; one target volume per detail face; face indices within the detail and the base;
//! base points on existing base faces with finite barycentric coordinates; not both base and
//! limit points; the weight graph's rows and neighbours. An encoding from encode_detail() passes;
//! every function here that takes one checks it first. Other values are not checked (the
//! reconstruction checks those it reads; limit points are checked against a surface by
//! check_limit_points(), and where a limit surface evaluates them).
//! \throw InvalidInput "encoding is empty (no detail faces)" for one without detail faces (as a
//!        default-constructed DetailEncoding), or naming the first array that does not fit.
void check_encoding(const DetailEncoding& encoding);

//! The part of \p encoding spanned by the detail faces \p faces (indices into detail_faces): its
//! vertices renumbered in order of first use (\p vertices receives each one's original index),
//! with their base points, offsets, rest positions, pinned flags and the faces' target volumes
//! copied, and the regularization weights recomputed on the part's own connectivity (as
//! encode_detail() would for that submesh). The base connectivity is kept whole, so the part is
//! reconstructed over the same edited bases.
//! \throw InvalidInput if \p faces is empty or holds an index out of range, or as check_encoding().
DetailEncoding restrict_encoding(const DetailEncoding& encoding, const std::vector<int>& faces,
                                 std::vector<int>& vertices);

//! Positions, unit normals and local frames of the base points on a base with the encoding's base
//! connectivity.
struct BaseFrames {
  std::vector<Vec3> points;    //!< q'_i
  std::vector<Vec3> normals;   //!< unit interpolated vertex normal at q'_i
  std::vector<Vec3> tangents;  //!< unit first tangent: the face's first edge, orthogonalized to the normal
};

//! Evaluates the base points of \p encoding on the base positions \p base_vertices (the vertices of
//! a triangle base, or the control points of a subdivision base's cage).
//! \throw InvalidInput if base_vertices does not match the encoding's base vertex count or holds
//! non-finite coordinates, if a base point's face has no normal (its corners, and its neighbours',
//! coincide or are collinear), or if the base points or base faces do not fit (check_encoding()'s
//! checks of them; the rest of the encoding is not read).
BaseFrames evaluate_base_frames(const DetailEncoding& encoding, const std::vector<Vec3>& base_vertices);

//! Evaluates the limit base points of \p encoding on \p surface (the edited cage, with the
//! encoding's cage topology): the limit position, the unit limit normal du x dv and the tangent du
//! made orthogonal to it. Runs in parallel.
//! \throw InvalidInput if the encoding is not over a limit surface or the control point count
//!        differs from the encoding's.
BaseFrames evaluate_base_frames(const DetailEncoding& encoding, const SubdivSurface& surface);

//! The same with the base points' patch weights computed once (a LimitPointSet over the
//! encoding's limit_points): after a cage edit this is one sparse product per frame component.
//! \throw InvalidInput as above, or if \p points does not hold one point per detail vertex.
BaseFrames evaluate_base_frames(const DetailEncoding& encoding, const LimitPointSet& points,
                                const SubdivSurface& surface);

//! The limit surface of an encoding's cage with the control points \p control_points.
//! \throw InvalidInput if the encoding is not over a limit surface, or as SubdivSurface's
//!        constructor.
SubdivSurface limit_surface_for(const DetailEncoding& encoding, const std::vector<Vec3>& control_points);

//! The normal-displacement baseline (the paper's "displacement vectors"): each detail vertex is
//! rebuilt as q'_i + f_i n'(q'_i) plus its stored tangential offset in the rotated local frame.
//! Over the original base it returns the original detail positions.
//! \throw InvalidInput as evaluate_base_frames(), or as check_encoding() (the whole encoding is read).
std::vector<Vec3> reconstruct_vectors(const DetailEncoding& encoding, const std::vector<Vec3>& base_vertices);

//! The largest amplitude magnitude a reconstruction takes (ReconstructRequest::amplitude,
//! reconstruct_vectors()): the target volumes scale with it, and 1e300 overflowed the solve.
constexpr double kMaxAmplitude = 1000.0;

//! Same, from already evaluated base frames, with the displacements scaled by \p amplitude (a
//! band's amplitude in a layered model: 0 puts every vertex on its base point).
//! \throw InvalidInput if \p frames does not hold one frame per detail vertex, if |amplitude|
//!        is not within kMaxAmplitude, if a frame or an offset is not finite, if a frame's normal
//!        and tangent are not orthonormal (within 1e-6), or as check_encoding().
std::vector<Vec3> reconstruct_vectors(const DetailEncoding& encoding, const BaseFrames& frames,
                                      double amplitude = 1.0);

}  // namespace strata

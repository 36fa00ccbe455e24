//! \file cage_fit.h
//! A subdivision control cage fitted to a scan (issue 4): the coarsest band of a layered model and
//! the base a scan's detail is encoded over. The scan is smoothed, decimated to the cage's face
//! count by quadric error collapses, and the cage's vertex positions are then solved so that its
//! Loop limit surface approximates the smoothed scan in least squares. The limit position at a
//! fixed (face, u, v) is linear in the cage (its limit stencil), so each fitting round is one
//! sparse linear solve; the foot points are projected again between rounds.
//!
//! \code
//!   strata::CageFit fit = strata::fit_cage(scan);               // about 1% of the scan's faces
//!   strata::SubdivSurface base(fit.cage);                       // Loop limit surface
//!   strata::DetailEncoding e = strata::encode_detail(scan, base);
//! \endcode
#pragma once

#include <vector>

#include "strata/mesh.h"
#include "strata/subdiv.h"

namespace strata {

//! Options of fit_cage(), with their defaults.
struct CageFitOptions {
  //! Faces of the cage. 0 (default): face_fraction of the scan's faces, at least min_faces, but
  //! at most a quarter of the scan's (default_cage_faces()).
  int faces = 0;
  double face_fraction = 0.01;
  int min_faces = 400;
  //! Taubin smoothing steps (lambda 0.5, mu -0.53, uniform weights) applied to the scan before
  //! decimation and as the fitting target: the cage carries the scan's low frequencies only.
  //! Open boundaries are smoothed along themselves.
  int smoothing_steps = 10;
  //! Weight of the smoothness term, sum |L (c - c0)|^2 over cage vertices with the uniform
  //! Laplacian L and c0 the decimated cage, relative to the data term's mean weight per cage
  //! vertex: the fit moves the decimated cage by a smooth displacement. It keeps cage vertices
  //! that few scan points see in place and the cage's faces regular without shrinking curved
  //! parts; larger values trade fitting error for a displacement closer to a uniform offset.
  double smoothness = 0.02;
  //! Rounds of (project the targets onto the limit surface, solve for the cage).
  int rounds = 3;
  //! Limit surface options of the cage (the scheme is Loop: the cage is a triangle mesh).
  SubdivOptions subdiv;
  //! Projection of the targets onto the limit surface in each round.
  ProjectOptions projection;
};

//! The cage's face count that \p options give for a scan of \p scan_faces faces: options.faces
//! if set, else face_fraction of the scan's faces, at least min_faces and at most a quarter of
//! the scan's faces (but at least 4), so that a small scan (a 320-face sphere)
//! gets a cage four times coarser than itself instead of one as fine as itself.
int default_cage_faces(const CageFitOptions& options, int scan_faces);

//! Checks \p options as fit_cage() does before any work, for a scan of \p scan_faces faces: the
//! ranges of its fields, and a subdiv.max_refined_faces within the ceiling
//! (SubdivSurface::max_refined_faces_ceiling()) of a cage of default_cage_faces() triangles. For
//! callers that fit a cage after other work (LayeredModel::build()).
//! \throw InvalidInput naming the first field out of range.
void check_cage_fit_options(const CageFitOptions& options, int scan_faces);

//! The fitted cage and its measured fitting error.
struct CageFit {
  PolyMesh cage;  //!< triangles, counter-clockwise like the scan
  //! Distances from the smoothed scan (the fitting target) to the final cage's limit surface
  //! (projected onto it once more after the last round), relative to the scan's bounding-box
  //! diagonal.
  double rms_error = 0.0, max_error = 0.0;
  //! The same for the scan's own vertices: the magnitude of the detail the cage leaves out.
  double scan_rms_distance = 0.0, scan_max_distance = 0.0;
  //! Scan vertices whose foot point on the final limit surface took the closest-point fallback.
  int scan_fallback = 0;
  int rounds = 0;
  double seconds_smooth = 0.0, seconds_decimate = 0.0, seconds_fit = 0.0;
};

//! Fits a Loop control cage to \p scan. Vertices in no face are ignored (neither decimated nor
//! fitted to). The decimation keeps the scan's connected parts apart, and each point's foot point
//! is sought on its own part's base (project_mesh_to_limit()), so that each part of the cage is
//! fitted to its own part's points: scan debris near the surface is not pulled onto it.
//! \pre nothing: the scan is checked.
//! \throw InvalidInput if the scan fails validate_mesh(), has a coordinate beyond kMaxCoordinate,
//!        or fewer faces than the cage would have, or if an option is out of range (faces not 0
//!        and below 4, face_fraction outside (0, 1], min_faces < 4, smoothing_steps outside
//!        0-1000, smoothness outside 0-1e12, rounds outside 1-100).
//! \throw SolverError if the decimation cannot reach a valid cage or the least-squares system
//!        cannot be factorized.
CageFit fit_cage(const TriMesh& scan, const CageFitOptions& options = {});

}  // namespace strata

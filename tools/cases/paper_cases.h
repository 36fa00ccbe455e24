//! \file paper_cases.h
//! The synthetic cases of the paper's Fig. 6: a smooth base cylinder S, a detail surface D that is
//! a normal displacement of the analytic cylinder, and the edited base S' (S bent by 90 degrees).
//!
//! Frame: the cylinder's axis is the z axis, from z = 0 to z = length; theta is the angle around
//! it, measured from +x towards +y. All meshes are open tubes (no caps), consistently oriented with
//! outward normals. D has its own connectivity, unrelated to S's; every detail vertex p equals
//! q + h * n(q) for q = (R cos theta, R sin theta, z) on the analytic cylinder, its outward normal
//! n(q) = (cos theta, sin theta, 0) and h = detail_offset(options, theta, z) > 0.
//!
//! The bend (bend_point) turns the section z in [bend_start, bend_end] around an axis parallel to y
//! through (bend_radius, 0, bend_start), towards +x; the part beyond bend_end follows rigidly. It
//! keeps the length of the cylinder's axis, so bend_end - bend_start = bend_radius * bend angle.
//! With the defaults the inner side of the bend (x = +R) has curvature radius 0.2, less than the
//! detail height: displacement vectors fold there, which is the point of these cases.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "strata/mesh.h"
#include "strata/subdiv.h"

namespace strata::cases {

//! The detail surface D carried by the base cylinder.
enum class DetailKind {
  //! Egg-crate bumps: the offset varies smoothly around and along the cylinder, with 8 bumps around
  //! and, along z, the whole number of bumps of about the same wavelength that fits (8 by default).
  Bumps,
  //! Sinusoidal ridges around the cylinder: the offset varies with z only, with the same
  //! wavelength along z as Bumps.
  Rings,
  Cuboid,  //!< a square tube around the cylinder, with sharp edges (the paper's Fig. 6, right)
};

//! "bumps", "rings" or "cuboid".
const char* to_string(DetailKind kind);
//! The inverse of to_string (exact, lower case); nullopt for any other text.
std::optional<DetailKind> parse_detail_kind(std::string_view text);

//! Parameters of a case. All lengths are in world units; the defaults reproduce Fig. 6.
struct CylinderCaseOptions {
  //! Which detail surface D to build. Default: Bumps.
  DetailKind detail = DetailKind::Bumps;
  //! Radius R of the base cylinder. Default: 1.
  double radius = 1.0;
  //! Length of the cylinder along z, from z = 0 to z = length. Default: 6.
  double length = 6.0;
  //! Base vertices around the cylinder (>= 3). The number of base rings along z follows so that
  //! the triangles are near-equilateral (alternate rings are shifted by half a segment).
  //! Default: 48, i.e. 54 rings, 2592 vertices and 5088 triangles.
  int base_segments = 48;
  //! Detail vertices around (>= 3; rounded to a multiple of 4, at least 4, for Cuboid so that the
  //! square's corners are vertices). The detail rings along z follow as for the base.
  //! Default: 96. Ignored when target_detail_triangles > 0.
  int detail_segments = 96;
  //! Height of the detail above the base (> 0). Bumps and Rings: the mean offset; the offset is
  //! detail_height * (1 + 0.5 * pattern) with a pattern in [-1, 1], so it stays within
  //! [0.5, 1.5] * detail_height. Cuboid: half the square's side minus R, the smallest offset (at the
  //! middle of the sides); the corners reach (R + detail_height) * sqrt(2) - R. Default: 0.35.
  double detail_height = 0.35;
  //! Bend angle in degrees, in [0, 360]. Default: 90.
  double bend_degrees = 90.0;
  //! Radius of the bend arc at the cylinder's axis (> radius, so that S' does not fold). The inner
  //! side of the bend has curvature radius bend_radius - radius. Default: 1.2 (inner radius 0.2).
  double bend_radius = 1.2;
  //! Start of the bent section along z; the cylinder below it stays put. Default: 2.
  double bend_start = 2.0;
  //! End of the bent section along z; beyond it the cylinder is rigidly rotated and translated.
  //! 0 (default) derives it as bend_start + bend_radius * bend angle in radians (2 + 0.6 pi, about
  //! 3.885, for the defaults), which keeps the length of the axis. Any other value must equal
  //! that one (checked): the bend is set by bend_radius and bend_degrees. See effective_bend_end().
  double bend_end = 0.0;
  //! If > 0, choose the detail resolution (segments around and rings along z) to get about this many
  //! detail triangles, i.e. prisms (for 10k / 100k / 1M-prism benchmarks); detail_segments is
  //! then ignored. Default: 0 (use detail_segments).
  int target_detail_triangles = 0;
  //! Irregular detail triangulation, as a scan's: every detail vertex off the two end rings moves
  //! by up to this fraction of the grid spacing within the surface (deterministically; the
  //! cuboid's corner columns only along the axis), and the triangulation is made Delaunay in the
  //! tube's parameter plane. In [0, 0.45]. Default: 0 (the regular staggered or square grid).
  double jitter = 0.0;

  //! The bend angle in radians.
  double bend_angle() const;
  //! bend_end as used: bend_start + bend_radius * bend_angle() (see bend_end).
  double effective_bend_end() const;
};

//! A generated case: the detail D, the base S and the edited base S' (same faces as S).
struct CylinderCase {
  TriMesh detail;                  //!< D: the detail surface, with its own connectivity
  TriMesh base;                    //!< S: the smooth base cylinder
  TriMesh edited_base;             //!< S': bend_point applied to S's vertices; S's faces
  std::string name;                //!< "cylinder-bumps", "cylinder-rings" or "cuboid"
  double inner_bend_radius = 0.0;  //!< curvature radius of S' on the inner side: bend_radius - radius
  double max_detail_height = 0.0;  //!< the largest offset h over D's vertices
};

//! Builds the case described by \p options.
//! \throws InvalidInput for out-of-range options (see each option's constraints).
CylinderCase make_cylinder_case(const CylinderCaseOptions& options = {});

//! The analytic bend that maps S to S' (see the file comment). Points with z <= bend_start are
//! returned unchanged; the map is C1 across bend_start and effective_bend_end(), an isometry along
//! the axis and a rigid motion beyond the bend. Inside the bent section it scales lengths along z
//! by (bend_radius - x) / bend_radius.
//! \throws InvalidInput unless bend_radius > 0, bend_degrees is in [0, 360] and bend_end is
//! consistent (radius, length and the detail options are not looked at).
Vec3 bend_point(const Vec3& p, const CylinderCaseOptions& options);

//! The offset h > 0 of the analytic detail surface above the analytic cylinder at angle \p theta
//! (radians) and height \p z: the detail point there is (R + h) * (cos theta, sin theta) at z.
double detail_offset(const CylinderCaseOptions& options, double theta, double z);

//! A Catmull-Clark control cage for the base cylinder S (issue 4: a limit surface as the base):
//! an open tube of quads, \p segments around and rings about as far apart as the segments, with
//! the ring radius scaled so that the limit surface passes through radius R at the cage's vertex
//! angles. Its limit surface spans z in [0, length] (open-boundary rule EdgeOnly).
//! \throws InvalidInput if segments < 6 or the options are out of range.
PolyMesh make_cylinder_cage(const CylinderCaseOptions& options = {}, int segments = 16);

//! \p mesh with its vertices and faces in a random order (seeded; each face keeps its corners'
//! order), as a tool that hashes its vertices writes a scan: the renumbering's case
//! (ReconstructOptions::renumber_for_locality).
TriMesh shuffled_numbering(const TriMesh& mesh, unsigned seed);

}  // namespace strata::cases

//! \file subdiv.h
//! Subdivision limit surfaces (OpenSubdiv) as base surfaces: a control cage with crease, corner
//! and boundary tags, exact limit evaluation at (ptex face, u, v), tessellation, and the foot
//! points of detail vertices on the limit surface (paper, section 3, with the limit surface as
//! the smooth base S). OpenSubdiv's types stay inside the implementation.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "strata/mesh.h"

namespace strata {

//! A polygonal mesh (a control cage): faces of 3 or more corners, counter-clockwise seen from
//! outside.
struct PolyMesh {
  std::vector<Vec3> vertices;
  std::vector<std::vector<int>> faces;

  int num_vertices() const { return static_cast<int>(vertices.size()); }
  int num_faces() const { return static_cast<int>(faces.size()); }
};

//! Subdivision scheme of a cage.
enum class SubdivScheme {
  Auto,          //!< Loop for an all-triangle cage, Catmull-Clark otherwise
  Loop,          //!< triangles only
  CatmullClark,  //!< any polygons; non-quads are split into quad sub-faces (one ptex face each)
};

//! How the limit surface treats the cage's open boundary.
enum class BoundaryRule {
  EdgeOnly,       //!< boundary edges are sharp, boundary vertices of valence 2 stay smooth
  EdgeAndCorner,  //!< also valence-2 boundary vertices are sharp corners
};

//! Sharpness tags of a cage (the semi-sharp creases of DeRose et al. 1998, as in OpenSubdiv).
//! A sharpness of 10 or more is infinitely sharp.
struct SubdivTags {
  struct Crease {
    int v0 = -1, v1 = -1;  //!< an edge of the cage, either direction
    double sharpness = 10.0;
  };
  struct Corner {
    int vertex = -1;
    double sharpness = 10.0;
  };
  std::vector<Crease> creases;
  std::vector<Corner> corners;
};

//! Options of a SubdivSurface, with their defaults.
struct SubdivOptions {
  SubdivScheme scheme = SubdivScheme::Auto;
  BoundaryRule boundary = BoundaryRule::EdgeOnly;
  //! Adaptive isolation depth of extraordinary vertices and creases. Gregory end caps close the
  //! remaining irregular patches; 4 keeps them within round-off of the true limit on typical
  //! cages (depth 2 leaves errors of ~1e-2 of an edge near extraordinary vertices).
  int isolation_level = 4;
  //! Most faces the adaptive refinement may make (all levels) when it isolates deeper than level
  //! 4; 0: max(2^20, 512 x the cage's face corners), above what any cage refined everywhere to
  //! level 4 makes (341 x its faces for triangles and quads, 85 n + 1 for an n-gon). Semi-sharp
  //! creases on every edge refine nearly everywhere, 3 to 4 times the faces a level: a 400-face
  //! Loop cage so creased, isolated to level 10, took 4.5 GB. Levels up to 4 are not checked (they
  //! refine at once, as they always did); deeper ones are refined one at a time and refused once
  //! past the budget, having taken at most about 4 times it. At most
  //! SubdivSurface::kMaxRefinedFacesFactor times the default: a budget read from a file bounds
  //! what reading it may take (4 times the default took 8.4 s and 962 MB on a 512-face Loop cage
  //! creased everywhere, isolated to level 10; 2^30, allowed before, 27.5 s and 4.5 GB on a
  //! 400-face one).
  long long max_refined_faces = 0;
};

//! A point of the limit surface's parameter domain: a ptex face and (u, v) in it. Loop ptex faces
//! are the cage's triangles with u, v >= 0, u + v <= 1 (corners 0, 1, 2 at (0,0), (1,0), (0,1));
//! Catmull-Clark ptex faces are the unit square (quad corners 0..3 at (0,0), (1,0), (1,1), (0,1);
//! sub-face k of a non-quad has its corner k at (0,0)).
//! Because it refers to the cage's topology only, the same limit point exists on every edited
//! cage: the exact correspondence between S and S'.
struct LimitPoint {
  int face = -1;
  double u = 0.0, v = 0.0;
};

//! The limit surface at a point: position and first derivatives (and optionally second ones)
//! with respect to the ptex face's (u, v). On the sub-faces of a non-quad (Catmull-Clark) these
//! are half of OpenSubdiv's limit-stencil derivatives, which are taken with respect to the
//! sub-face as a quadrant of its face.
struct LimitSample {
  Vec3 position = Vec3::Zero();
  Vec3 du = Vec3::Zero(), dv = Vec3::Zero();
  Vec3 duu = Vec3::Zero(), duv = Vec3::Zero(), dvv = Vec3::Zero();  //!< only if asked for
  //! Unit normal du x dv (zero where the derivatives are parallel).
  Vec3 normal() const;
};

//! A tessellation of the limit surface: a watertight triangle mesh whose vertices lie on the limit
//! surface, with the limit point of each vertex, and each triangle's ptex face and the (u, v) of
//! its corners in that face (a vertex on a ptex edge has its own (u, v) in each adjacent face).
struct LimitTessellation {
  TriMesh mesh;
  std::vector<LimitPoint> vertex_points;
  std::vector<int> face_ptex;
  std::vector<std::array<Eigen::Vector2d, 3>> face_uv;
};

//! A control cage and its subdivision limit surface. Construction builds the topology and the
//! patch table (adaptive refinement with Gregory end caps, double precision) once; moving the
//! control points (a cage edit) only recomputes the patches' local points.
//! Evaluation is thread-safe; set_control_points() is not (no evaluation may run meanwhile).
class SubdivSurface {
 public:
  //! \pre nothing: the cage is validated.
  //! \throw InvalidInput for an empty cage, non-finite coordinates, out-of-range or repeated face
  //!        indices, a face of fewer than 3 corners, a non-triangle under Loop, a non-manifold or
  //!        inconsistently oriented edge, a crease on a pair of vertices that is not a cage edge, a
  //!        corner on a missing vertex, a negative sharpness, an isolation level outside 1..10,
  //!        coordinates beyond kMaxCoordinate, a face of over kMaxCageValence corners or a
  //!        vertex in over kMaxCageValence faces, a max_refined_faces below 0 or above
  //!        kMaxRefinedFacesFactor times its default, or an isolation whose refinement exceeds
  //!        SubdivOptions::max_refined_faces.
  //! \throw SolverError if OpenSubdiv fails to build the topology or the patch table.
  explicit SubdivSurface(const PolyMesh& cage, const SubdivTags& tags = {},
                         const SubdivOptions& options = {});
  ~SubdivSurface();
  //! A moved-from object may only be assigned to or destroyed (its other calls are undefined).
  SubdivSurface(SubdivSurface&&) noexcept;
  //! The most corners of a cage face and faces at a cage vertex: building the patches grows with
  //! about the cube of either (measured: 64 took 0.07-0.33 s, 128 1-3.4 s, 200 5-16 s); a cage
  //! of a 300-corner face made a deform run 34 s. Modelling cages stay far below.
  static constexpr int kMaxCageValence = 64;
  //! SubdivOptions::max_refined_faces is at most this many times its default for the cage.
  static constexpr long long kMaxRefinedFacesFactor = 4;
  //! The largest SubdivOptions::max_refined_faces a cage of \p face_corners face corners takes:
  //! kMaxRefinedFacesFactor times the default, max(2^20, 512 x face_corners).
  static long long max_refined_faces_ceiling(long long face_corners);
  SubdivSurface& operator=(SubdivSurface&&) noexcept;

  //! Loop or CatmullClark (never Auto).
  SubdivScheme scheme() const;
  const PolyMesh& cage() const;
  const SubdivTags& tags() const;
  const SubdivOptions& options() const;
  int num_control_points() const;
  int num_ptex_faces() const;
  //! Corners of a ptex face's domain: 3 (Loop) or 4 (Catmull-Clark).
  int ptex_corners() const;
  //! The first ptex face of a cage face (a non-quad under Catmull-Clark has one per corner).
  int first_ptex_face(int cage_face) const;

  //! Moves the control points (the cage's connectivity and tags stay).
  //! \throw InvalidInput on a count mismatch or non-finite coordinates.
  void set_control_points(const std::vector<Vec3>& points);
  const std::vector<Vec3>& control_points() const;

  //! The limit surface at \p p; (u, v) outside the domain are clamped into it. With
  //! \p second_derivatives the sample also holds duu, duv, dvv. The derivatives are the patches'
  //! own, on Gregory end caps too (OpenSubdiv 3.5's leave out their blend weights' derivatives).
  //! \throw InvalidInput if p.face is out of range or u, v are not finite.
  LimitSample evaluate(const LimitPoint& p, bool second_derivatives = false) const;

  //! The linear weights of the limit position (and du, dv) at \p p on the control points: the
  //! limit stencil. Entries with equal indices are merged; the weights of the position sum to 1.
  struct Stencil {
    std::vector<int> indices;
    std::vector<double> position, du, dv;
  };
  Stencil stencil(const LimitPoint& p) const;

  //! Tessellates every ptex face into a grid of \p resolution segments per edge, watertight across
  //! ptex faces. With non-quads under Catmull-Clark the resolution is rounded up to even and their
  //! sub-faces get half of it (each covers half of its cage edges).
  //! \throw InvalidInput if resolution < 1 or the grid would exceed kMaxTessellationTriangles.
  LimitTessellation tessellate(int resolution) const;
  //! The largest tessellation tessellate() makes (about 2 GB of mesh).
  static constexpr double kMaxTessellationTriangles = 50e6;

  //! Where the adjacent ptex face continues edge \p edge of ptex face \p face (edges run from
  //! corner k to corner k+1) at the edge's parameter \p t in [0,1]: that face, its edge and the
  //! parameter there; face = -1 on the surface's open boundary. An edge between a quad and the
  //! sub-faces of a non-quad has a different neighbour on each half.
  //! \throw InvalidInput if face or edge is out of range or t is not finite.
  struct EdgeCrossing {
    int face = -1, edge = -1;
    double t = 0.0;
  };
  EdgeCrossing across_edge(int face, int edge, double t) const;

 private:
  friend class LimitPointSet;
  class Impl;
  std::unique_ptr<Impl> impl_;
};

//! Fixed limit points evaluated again after every cage edit (an encoding's base points): each
//! point's patch and basis weights are found once, so a re-evaluation is one weighted sum over
//! the patches' points per point, a sparse matrix-vector product. The weights are stored in single
//! precision relative to each patch's first point (about 1e-7 of the patch size).
class LimitPointSet {
 public:
  //! \throw InvalidInput if a point's face is out of range or its (u, v) is not finite.
  LimitPointSet(const SubdivSurface& surface, const std::vector<LimitPoint>& points);
  int size() const { return static_cast<int>(offsets_.size()) - 1; }
  //! Positions and first derivatives of the points on \p surface, which must have the topology
  //! the set was built on (e.g. the same SubdivSurface after set_control_points()). In parallel.
  //! \throw InvalidInput if the surface's patch layout differs (another patch count, or another
  //!        topology: faces, tags or options).
  void evaluate(const SubdivSurface& surface, std::vector<Vec3>& positions, std::vector<Vec3>& du,
                std::vector<Vec3>& dv) const;
  //! The same for the points [begin, end) into the arrays given (end - begin entries each), on
  //! the calling thread: for callers that use each point's values right away.
  //! \throw InvalidInput if the surface's patch layout differs or the range is out of bounds.
  void evaluate(const SubdivSurface& surface, int begin, int end, Vec3* positions, Vec3* du, Vec3* dv) const;

 private:
  void check(const SubdivSurface& surface) const;
  void evaluate_unchecked(const std::vector<Vec3>& patch_points, int begin, int end, Vec3* positions,
                          Vec3* du, Vec3* dv) const;
  int num_patch_points_ = 0;
  std::uint64_t topology_id_ = 0;  // the surface's fingerprint of its faces, tags and options
  std::vector<int> offsets_;       // per point: its entries [offsets_[i], offsets_[i+1])
  std::vector<int> index_;         // per entry: patch point; the first entry of a point is its origin
  std::vector<float> wp_, wu_, wv_;
};

//! Options of project_to_limit(), with their defaults.
struct ProjectOptions {
  //! Segments per ptex edge of the tessellation that seeds each projection with its closest point.
  int seed_resolution = 4;
  //! Newton iterations at most per point (each ptex face crossing counts as one).
  int max_iterations = 40;
  //! Converged when |(p - S) . S_u| / (|p - S| |S_u|) and the same for S_v are at most this (the
  //! foot point is orthogonal), or when |p - S| is below 1e-12 of the cage's bounding-box
  //! diagonal (the point lies on the surface).
  double orthogonality_tolerance = 1e-9;
  //! Where the iteration stalls, the foot point still counts as converged if orthogonal to within
  //! this: the Gregory end caps around extraordinary vertices meet their neighbours with tangent
  //! planes that differ by up to ~1e-4 rad, and a foot point on such a seam is a true (kinked)
  //! foot point. Must be >= orthogonality_tolerance.
  double seam_tolerance = 1e-3;
  //! Run over the points in parallel (TBB).
  bool parallel = true;
};

//! The foot points of \p points on the limit surface, and how they were found.
struct Projection {
  std::vector<LimitPoint> points;
  std::vector<char> converged;  //!< 1: Newton found an orthogonal (or boundary) foot point
  int num_converged = 0;
  //! Of the converged points, those whose foot point is the closest point on an open boundary
  //! curve of the surface (the point lies beyond the boundary; p - S is orthogonal to the curve).
  int num_on_boundary = 0;
  int num_fallback = 0;  //!< not converged: the best point Newton reached (at least as close as the seed)
  int max_iterations_used = 0;
  double seconds = 0.0;
};

//! Projects each point onto the limit surface along the limit normal: the foot point S(u, v)
//! where p - S is orthogonal to both tangents. Newton iterations on (u, v) (with the second
//! derivatives, damped where the Hessian is not positive definite) start from the closest point
//! on a tessellation and cross ptex-face boundaries. A point beyond an open boundary, which has no
//! orthogonal foot point, converges to the closest point of the boundary curve (counted in
//! num_on_boundary). A point whose iteration does not converge keeps the closest point found and
//! is counted as a fallback.
//! \throw InvalidInput if a point is not finite, the options are out of range, or the cage spans
//!        less than kMinExtent.
Projection project_to_limit(const SubdivSurface& surface, const std::vector<Vec3>& points,
                            const ProjectOptions& options = {});

//! The foot points of the vertices of \p mesh, as project_to_limit() finds them, except that each
//! vertex's is sought only on its own connected part's base: scan debris near a surface, with its
//! own small part of the cage, is not that surface's base, nor is the surface the debris's. The
//! parts of the mesh and of the surface (on its seed tessellation; both joined at bitwise-equal
//! positions, as unwelded seams) are matched both ways, each to the part of the other that its
//! sample points lie nearest to on average; a mesh part's base is the surface parts matched to it
//! and the surface part it is matched to. A vertex of no face searches the whole surface. With
//! one part on either side (the common case) the result is project_to_limit(surface,
//! mesh.vertices, options)'s. encode_detail() over a limit surface, fit_cage() and CageEditor
//! project this way.
//! \throw InvalidInput as project_to_limit(), or if a face index of \p mesh is out of range.
Projection project_mesh_to_limit(const SubdivSurface& surface, const TriMesh& mesh,
                                 const ProjectOptions& options = {});

}  // namespace strata

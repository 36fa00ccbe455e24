//! \file mesh.h
//! The flat triangle mesh the numeric core works on. OpenMesh stays behind the I/O adapter
//! (mesh_io.h); everything else sees plain arrays.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace strata {

using Vec3 = Eigen::Vector3d;
using Face = std::array<int, 3>;

//! An indexed triangle mesh. Faces are counter-clockwise seen from outside (normals point out).
struct TriMesh {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;

  int num_vertices() const { return static_cast<int>(vertices.size()); }
  int num_faces() const { return static_cast<int>(faces.size()); }
};

//! A file that a mesh file refers to by name and that has to sit beside it for its materials or
//! textures to show: an OBJ's material library, an image that library names, a PLY's texture
//! image. read_companion_files() and write_companion_files() (mesh_io.h) carry them.
struct CompanionFile {
  CompanionFile() = default;
  CompanionFile(std::string name, std::string bytes)
      : name(std::move(name)), data(std::make_shared<const std::string>(std::move(bytes))) {}

  //! Where the file sits relative to the mesh file's directory, '/' between directories, as
  //! companion_name_problem() allows.
  std::string name;
  //! The file's contents, shared by copies: images are large, and a model is copied for undo.
  std::shared_ptr<const std::string> data;

  const std::string& bytes() const {
    static const std::string none;
    return data ? *data : none;
  }
  bool operator==(const CompanionFile& o) const { return name == o.name && bytes() == o.bytes(); }
};

//! Why \p name cannot be a CompanionFile's name, or "" if it can. A name is relative and in
//! normal form: '/' between non-empty components, none of them "." or "..", none hidden (starting
//! with '.': a name from a scan's file must not put ".ssh/..." or ".bashrc" beside an output),
//! and no control character.
std::string companion_name_problem(const std::string& name);

//! What a scan's file may hold besides its geometry that Strata carries along: vertex colours,
//! texture coordinates (per vertex, or per face corner at texture seams) and OBJ materials. Read
//! and written with the mesh (read_mesh_file(), write_mesh() in mesh_io.h), kept by a layered
//! model with its finest band, and carried unchanged through edits and reconstructions, which
//! move vertices but keep the numbering of vertices and faces. Each per-vertex array is empty
//! (the file has no such data) or has one entry per vertex; each per-face array is empty or has
//! one entry per face (the triangles, in order).
struct MeshAttributes {
  //! RGBA per vertex. Integer channels in a file are scaled to [0, 1] (PLY: by the type's
  //! largest value, 255 for uchar; OFF: integers by 255); floating-point ones are kept as the
  //! file gives them. Alpha is 1 where the file gives none.
  std::vector<std::array<double, 4>> colors;
  //! Whether the colours came with an alpha channel (and are written with one).
  bool colors_have_alpha = false;
  //! (u, v) per vertex: PLY u/v, s/t or texture_u/texture_v; OFF's ST values; OBJ's vt where each
  //! vertex's corners use one.
  std::vector<std::array<double, 2>> texcoords;
  //! Texture coordinates per face corner, where a vertex has several (texture seams: OBJ's vt):
  //! a list of (u, v) and, per face, its three corners' indices into it. Never given together
  //! with per-vertex texcoords. (Written to OBJ without seams, they read back per vertex.)
  std::vector<std::array<double, 2>> corner_uv;
  std::vector<std::array<int, 3>> corner_uv_index;
  //! OBJ materials: the material library as the file names it (mtllib, relative to the file),
  //! the usemtl names, and per face the index of its material in material_names (-1: none).
  std::string material_library;
  std::vector<std::string> material_names;
  std::vector<int> face_materials;
  //! Texture images as a PLY names them (MeshLab's "comment TextureFile", relative to the file),
  //! and per face the index of its image in texture_files (PLY's texnumber; -1: none). An OBJ
  //! names its images in its material library instead.
  std::vector<std::string> texture_files;
  std::vector<int> face_textures;
  //! The contents of the files named above (the material libraries, the images they name, the
  //! PLY's images), so that they travel with a layered model and are written beside an exported
  //! mesh. read_companion_files() fills it and write_companion_files() writes it; read_mesh_file()
  //! leaves it empty and write_mesh() does not write it.
  std::vector<CompanionFile> files;

  bool empty() const {
    return colors.empty() && texcoords.empty() && corner_uv_index.empty() && face_materials.empty() &&
           material_names.empty() && material_library.empty() && texture_files.empty() &&
           face_textures.empty() && files.empty();
  }
};

//! Checks \p attributes against \p mesh: each non-empty per-vertex array has one entry per
//! vertex and each per-face one one per face; values are finite; corner indices lie in corner_uv
//! and material indices in material_names (or are -1); not both texcoords and corner_uv_index;
//! each of files has a name companion_name_problem() allows, and no name comes twice.
//! \throw InvalidInput "<what>: N vertex colours for M vertices", "<what>: vertex I has a
//!        non-finite colour", "<what>: face F's texture coordinate index ... out of range", ...
void check_mesh_attributes(const MeshAttributes& attributes, const TriMesh& mesh, const std::string& what);

//! Checks that every corner of \p faces indexes one of \p num_vertices vertices: what the
//! functions over a mesh's faces below need before they index its vertices.
//! \throw InvalidInput "<what>: face F has vertex index I, out of range (N vertices)".
void check_face_indices(std::size_t num_vertices, const std::vector<Face>& faces, const std::string& what);

//! Length of the diagonal of the axis-aligned bounding box of \p points (0 for no points),
//! computed without squares that underflow or overflow (points of 1e-200 have a diagonal).
double bbox_diagonal(const std::vector<Vec3>& points);
//! Centre of the axis-aligned bounding box of the vertices that \p faces use (the origin for no
//! faces; vertices in no face, which may hold anything, are left out). Algorithms whose precision
//! depends on the coordinates' size (quadrics, float boxes, least squares) work relative to it,
//! so that a scan far from the origin (a georeferenced one) is treated as at it.
//! \throw InvalidInput if a face index is out of range (check_face_indices()).
Vec3 bbox_centre(const std::vector<Vec3>& vertices, const std::vector<Face>& faces);
//! The per-axis median of \p points (the upper middle value for an even count; the origin for no
//! points): unlike the box centre, near most points whatever a few far ones do (a scan's stray
//! vertex).
Vec3 coordinate_median(const std::vector<Vec3>& points);

//! Whether \p p is \p rest up to rounding: within 1e-12 of \p scale (a diagonal of the points
//! it is one of) plus 1e-14 (about 45 units in the last place) of rest's largest coordinate. An
//! edit and its inverse, or an edit by the identity, bring a base back only to such rounding; the
//! editors and layered models then put the detail back at rest exactly. False for NaN.
bool back_at_rest(const Vec3& p, const Vec3& rest, double scale);

//! The largest coordinate magnitude the engine takes. Prism volumes are cubic in the coordinates
//! and the solver's inner products hold higher powers: a 3 x 6 tube case scaled as a whole
//! reconstructs alike from 1e-20 to 1e25, while a detail 1e28 from a unit base overflowed the
//! solver and one 1e80 away crashed the encoding (2026-11-28). Real scans are far inside.
constexpr double kMaxCoordinate = 1e20;

//! The smallest extent (bounding box diagonal) of a mesh the engine takes: its prism volumes are
//! cubic in it and the solver's inner products hold their squares, which underflow far below it
//! (a scan scaled by 1e-200 was decimated as is, its cage the whole scan, and its model then
//! refused by the reader). The paper's cases reconstruct alike down to 1e-20.
constexpr double kMinExtent = 1e-20;

//! Checks that the vertices \p faces use span at least kMinExtent (nothing for no faces).
//! \throw InvalidInput if a face index is out of range (check_face_indices()).
//! \throw InvalidInput "<what> has an extent (bounding box diagonal) of <x>, below the engine's
//!        range (1e-20): ...".
void check_extent(const std::vector<Vec3>& vertices, const std::vector<Face>& faces, const std::string& what);

//! Checks that every coordinate of \p points is finite and of magnitude at most kMaxCoordinate.
//! \throw InvalidInput "<what> vertex <i> has a non-finite coordinate" or "<what> vertex <i> has
//!        a coordinate of magnitude <x>, beyond the engine's range (1e+20)".
void check_coordinates(const std::vector<Vec3>& points, const std::string& what);

//! Unnormalized normal of triangle (a, b, c): twice its area times its unit normal.
inline Vec3 triangle_area_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  return (b - a).cross(c - a);
}

//! Unit vertex normals, each the angle-weighted average of the incident face normals.
//! A vertex with no incident face (or only degenerate ones) gets the zero vector.
//! \throw InvalidInput if a face index is out of range (check_face_indices()).
std::vector<Vec3> vertex_normals(const std::vector<Vec3>& vertices, const std::vector<Face>& faces);

//! Sum of the signed volumes of the tetrahedra (origin, a, b, c) over all faces: the enclosed
//! volume for a closed, outward-oriented mesh.
//! \throw InvalidInput if a face index is out of range (check_face_indices()).
double signed_volume(const TriMesh& mesh);

}  // namespace strata

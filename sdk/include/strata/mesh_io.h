//! \file mesh_io.h
//! Reading, writing and validating triangle meshes in OBJ, OFF, PLY and STL files.
//!
//! The format is chosen by the file extension (case-insensitive). Readers are strict: anything
//! that would otherwise be lost or silently changed (a truncated file, an index out of range, a
//! face a lenient reader would drop) is an error, never a smaller mesh. Vertex and face order are
//! preserved exactly, and coordinates are read and written at full double precision (ASCII
//! numbers use the shortest text that reads back to the identical double), so for OBJ, OFF and
//! PLY write_mesh followed by read_mesh gives back the identical mesh, bit for bit.
//!
//! STL is the exception: it stores each triangle's three corner positions (binary STL as
//! float32) and no vertex list. Reading STL welds bitwise-equal positions into one vertex,
//! numbered in order of first use; unreferenced vertices cannot be stored.
//!
//! Truncation is detected wherever the format allows: OFF and PLY element counts and binary STL's
//! triangle count are checked against the data (too much data is an error too), ASCII STL must
//! end with 'endsolid'. OBJ has no counts of its own: if a comment "# N vertices, M faces" precedes
//! the data (write_mesh and OpenMesh write one), the numbers of 'v' and 'f' lines must match it.
//! A text file cut inside its last number can still go unnoticed (e.g. "3 0 1 12" -> "3 0 1 1").
//!
//! Face and vertex numbers in error messages from validate_mesh are 0-based mesh indices (after
//! triangulation; read_mesh then adds which of the file's faces a triangle was cut from); reader
//! errors name the line (text formats) or element number in the file, with indices as written in
//! the file (1-based for OBJ).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "strata/mesh.h"

namespace strata {

//! Reads a triangle mesh from \p path; the format is chosen by the extension (.obj, .off, .ply,
//! .stl in any letter case). PLY may be ascii, binary_little_endian or binary_big_endian; STL
//! may be ASCII or binary (told apart by content, not by name). Polygons with more than three
//! corners are split into n - 2 triangles, stored consecutively in file order and oriented as the
//! polygon: a polygon of up to 32 corners that one corner sees whole (a fan whose every triangle
//! has over 1e-10 of its area) gets the fan from the corner whose smallest triangle is largest;
//! any other (a U-shaped face, a hole's cap of many corners) is cut by ear clipping in the plane of
//! its Newell normal, smallest ears first; where corners within rounding of a line through others
//! trap the clipping, a polygon of up to 256 corners gets the triangulation whose smallest
//! triangle is largest (an exact O(n^3) search). A simple polygon is thus covered without flipped
//! or overlapping triangles. One whose sides cross is an error (a quad that crosses itself has no
//! fan of positive triangles; for more corners a sweep over the sides, given up past 64 n +
//! 100,000 candidate pairs, as for spokes that all span one point), and so is a trapped one of
//! over 256 corners. A polygon with a part of zero width gets zero-area triangles, and a polygon of corners
//! all on one line is fanned: the validation reports their zero area.
//! OFF is free-form: a record's required values (3 coordinates; a corner count and its corners)
//! may run over lines, and the numbers after them on the line where they end are its optional
//! fields; records share a line only where the lines left are too few for one each (a whole body
//! on one line). OBJ statements continue over a line ending in '\'. Extra per-vertex and per-face
//! data (normals, colors, texture coordinates, materials) is ignored here; read_mesh_file() also
//! reads the vertices' colours and texture coordinates. The result has passed
//! validate_mesh(mesh, path). \pre nothing; any file content is handled (garbage gives an error, never a
//! crash). \throw IoError if the file is missing or unreadable, the extension is not supported, or the
//!        contents cannot be parsed or are truncated (e.g. fewer elements than a header declares).
//! \throw InvalidInput if the contents parse but do not form a valid mesh (see validate_mesh;
//!        also an OBJ/OFF/PLY face with fewer than three corners, or a polygon that crosses
//!        itself).
TriMesh read_mesh(const std::string& path);

//! As read_mesh(path), and also returns the faces as the file lists them, before triangulation
//! (polygons of 3 or more corners, 0-based; triangles for STL) in \p polygons (if not null). The
//! triangles of the result are those polygons' triangulations, in the same order.
//! \throw as read_mesh(path).
TriMesh read_mesh(const std::string& path, std::vector<std::vector<int>>* polygons);

//! Options of read_mesh(path, options, ...).
struct ReadOptions {
  //! Orient each connected part consistently (orient_faces(): the fewer faces flipped) before the
  //! validation, instead of refusing faces that disagree with their neighbours: STL exports and
  //! merged scans often hold some. Off by default: a file is read as it is.
  bool orient_faces = false;
};

//! As read_mesh(path, polygons), with \p options. *flipped_faces (if not null): the faces that
//! orient_faces flipped (their polygons in \p polygons are reversed too).
//! \throw as read_mesh(path), and InvalidInput if orient_faces is set and a part is not orientable.
TriMesh read_mesh(const std::string& path, const ReadOptions& options,
                  std::vector<std::vector<int>>* polygons, int* flipped_faces = nullptr);

//! A mesh file as read_mesh_file() reads it.
struct MeshFile {
  TriMesh mesh;  //!< as read_mesh(path, options, ...) returns it
  //! The faces as the file lists them, before triangulation (read_mesh(path, polygons)).
  std::vector<std::vector<int>> polygons;
  //! The file's colours, texture coordinates and materials (MeshAttributes), checked
  //! (check_mesh_attributes()):
  //! - OBJ: "v x y z r g b [a]" on every vertex (MeshLab's extension; a single extra number is the
  //!   weight w, ignored); vt per vertex when each vertex's corners use one (a vertex in no face
  //!   gets the vt of its own number if every corner's vt is its vertex's number and the counts
  //!   match, as write_mesh() writes them; else (0, 0)), per face corner where a vertex has
  //!   several (seams: corner_uv is the file's vt list); mtllib (the first) and usemtl.
  //! - OFF: the C and ST prefixes' values (integer colours on a 0-255 scale, floats on 0-1).
  //! - PLY: vertex properties red, green, blue [alpha] (or diffuse_*), any type, integer types
  //!   scaled by their largest value; u v, s t, texture_u texture_v or texture_s texture_t;
  //!   MeshLab's face list texcoord (2n numbers: per vertex where each vertex's corners agree,
  //!   else per face corner), face texnumber and "comment TextureFile" lines.
  //! - STL: none.
  MeshAttributes attributes;
  int flipped_faces = 0;  //!< faces ReadOptions::orient_faces flipped (their polygons reversed too)
  //! Colours or texture coordinates the file holds that MeshAttributes cannot represent, each
  //! a note for the user (e.g. "vertex colours: only 2 of the 4 vertices have one", texture
  //! coordinates on only some face corners, a PLY texcoord list of the wrong length). Normals and
  //! face colours are not kept and not listed: normals are recomputed from the geometry.
  std::vector<std::string> dropped;
};

//! Reads a mesh with its polygons and per-vertex attributes (MeshFile); the mesh is read and
//! checked as read_mesh(path, options, ...) does.
//! \throw as read_mesh(path, options, ...); InvalidInput "<path>: vertex I has a non-finite
//!        colour" (texture coordinate), or for a face corner's texture coordinate index out of
//!        range (OBJ); IoError for a vt line that does not parse.
MeshFile read_mesh_file(const std::string& path, const ReadOptions& options = {});

//! Encoding to use for formats that have both (PLY, STL).
enum class MeshEncoding {
  Default,  //!< Binary for PLY and STL, ASCII for OBJ and OFF.
  Ascii,
  Binary,  //!< Only valid for PLY (little-endian, double coordinates) and STL (float32).
};

//! Writes \p mesh to \p path in the format given by the extension (see read_mesh), replacing the
//! file atomically (write_file_atomically): on any error \p path is left as it was.
//! OBJ, OFF and PLY (ascii or binary) store everything exactly, including unreferenced vertices.
//! STL stores only the triangles, binary STL in float32 (see the file comment).
//! \pre validate_mesh(mesh, path) passes: files are only written if read_mesh would read them.
//! \throw InvalidInput if the mesh fails validation, \p encoding is Binary for OBJ or OFF, or a
//!        coordinate overflows float32 for binary STL.
//! \throw IoError if the extension is not supported or the file cannot be written.
void write_mesh(const TriMesh& mesh, const std::string& path, MeshEncoding encoding = MeshEncoding::Default);

//! As write_mesh(mesh, path, encoding), with \p attributes, so that read_mesh_file() gives back
//! the same values:
//! - OBJ: "v x y z r g b [a]"; one "vt u v" per vertex with "f i/i j/j k/k" faces, or the
//!   corner_uv list with each corner's index; "mtllib" and a "usemtl" wherever the face's
//!   material changes (a bare "usemtl" for none);
//! - OFF: [ST]COFF, colours as floats (always written with a decimal point or an exponent);
//! - PLY: red green blue [alpha] as uchar when every channel is k / 255 exactly (as 8-bit
//!   colours read), else as double; texture_u texture_v as double; per face corner, MeshLab's
//!   face list texcoord (as double), its texnumber and "comment TextureFile" lines;
//! - what a format cannot store is not written (attributes_not_stored()).
//! \throw as write_mesh(mesh, path, encoding), and InvalidInput if \p attributes fail
//!        check_mesh_attributes() for \p mesh, or an OBJ's material name or library ends in '\\'
//!        (read back, it would continue onto the next line).
void write_mesh(const TriMesh& mesh, const MeshAttributes& attributes, const std::string& path,
                MeshEncoding encoding = MeshEncoding::Default);

//! What of \p attributes the format of \p path (by its extension) cannot store, for a warning:
//! "materials" (all but OBJ; for a PLY with texture_files "materials (their diffuse images are
//! kept, as TextureFile)", attributes_for_format()), "texture images (PLY's TextureFile)" (all but PLY),
//! "texture coordinates per face corner (texture seams)" (OFF, STL), and for STL also "vertex colours" and
//! "texture coordinates". Empty if nothing is lost. \throw IoError if the extension is not
//! supported.
std::vector<std::string> attributes_not_stored(const MeshAttributes& attributes, const std::string& path);

//! Reads the files that \p attributes of the mesh file \p mesh_path name into attributes.files
//! (CompanionFile), from beside the mesh, so that its materials and textures can travel with it:
//! - each material library of material_library (OBJ's mtllib: the whole value if a file of that
//!   name is there, else each of its words);
//! - each image a library found names: the file name (the rest of the line, spaces included)
//!   after the options of map_Ka, map_Kd, map_Ks, map_Ke, map_Ns, map_d, map_bump, map_Pr, map_Pm,
//!   map_Ps, bump, disp, decal, refl and norm (any other map_* too), relative to the library's
//!   own directory;
//! - each of texture_files (PLY's TextureFile).
//! Each file once, in the order first named, under its name in normal form ("./a.png" is
//! "a.png"; "../x.png" from "sub/lib.mtl" is "x.png"). attributes.files is replaced.
//! \return notes on what is not carried along, each naming \p mesh_path (or the library) and the
//!         file: a file that is not there or cannot be read (a directory, a FIFO, no permission);
//!         a name that companion_name_problem() refuses (absolute, above the mesh's directory,
//!         hidden) or that goes into a directory and out again ("sub/../x.png", which resolves
//!         only where "sub" exists); a file reached through a symbolic link that leads out of the
//!         mesh's directory. The mesh still names these; nothing is thrown.
std::vector<std::string> read_companion_files(MeshAttributes& attributes, const std::string& mesh_path);

//! Writes one companion file: \p path, \p bytes. write_companion_files() calls it once per file
//! to write, after creating the file's directory; by default write_text_file_atomically().
using CompanionWriter = std::function<void(const std::string& path, const std::string& bytes)>;

//! Writes the files of attributes.files that the mesh file \p mesh_path names beside it (an OBJ:
//! its material libraries and the images they name; a PLY: its texture_files; OFF and STL name
//! none): each at its name relative to the mesh's directory (subdirectories are created), by
//! \p write (default: atomically, write_text_file_atomically()). Whatever is already at a name
//! (a file, a directory, a symbolic link, even to nothing) is left alone, never replaced; a note
//! says so unless it is a file with the same bytes.
//! \return the notes, each naming the file (also one whose directory cannot be created: a file
//!         or a link in the way), and for an OBJ each material library it names that is neither
//!         among the files nor beside it ("<mesh> refers to the material library 'x.mtl', which
//!         is not in its directory: ...").
//! \throw InvalidInput if a name fails companion_name_problem(); what \p write throws (IoError
//!        if a file cannot be written).
std::vector<std::string> write_companion_files(const MeshAttributes& attributes, const std::string& mesh_path,
                                               const CompanionWriter& write = {});

//! Per face, the index in attributes.files of its diffuse texture image, or -1: a PLY face's
//! image (face_textures into texture_files), else an OBJ face's material's map_Kd (in the first
//! of the material libraries among attributes.files that defines the material; its name relative
//! to the library's directory, as read_companion_files() resolves it). Empty if no face has one
//! (no images among the files, say). What a viewer needs to draw a textured scan.
std::vector<int> face_texture_files(const MeshAttributes& attributes);

//! \p attributes with their texture images named as the format of \p mesh_path names them, so
//! that a textured scan converted from PLY to OBJ or from OBJ to PLY keeps its textures (as
//! MeshLab converts them):
//! - to an OBJ, a PLY's images (texture_files and face_textures, without materials) become a
//!   material library with a material "material_<i>" per image (Kd 1 1 1, map_Kd the image),
//!   added to files, and face_materials; texture_files and face_textures are cleared. The
//!   library is named after the mesh: its file name stem, with '#', spaces, control characters
//!   and leading dots replaced or dropped ("materials" if nothing is left), then ".mtl"; "_1",
//!   "_2", .. are appended while that name is another of the files, or a file beside the mesh
//!   with other bytes (one with the same bytes, from an earlier run, is the same library). An
//!   image whose name MTL cannot hold (a '#') keeps its material, without map_Kd, and its faces
//!   none, with a note;
//! - to a PLY, an OBJ's materials' diffuse images (face_texture_files(): the libraries and
//!   images must be among attributes.files, read_companion_files()) become texture_files (the
//!   images' names, in the order the faces first use them) and face_textures; the materials
//!   stay (a PLY does not store them: attributes_not_stored() still names them). An image whose
//!   name a PLY cannot hold (a space at an end) is left out, with a note;
//! - anything else comes back unchanged (OFF and STL name no images).
//! Write the result with write_mesh() and write_companion_files(). \p notes: if given, notes
//! are appended, each naming \p mesh_path and the image.
MeshAttributes attributes_for_format(const MeshAttributes& attributes, const std::string& mesh_path,
                                     std::vector<std::string>* notes = nullptr);

//! Writes a polygon mesh (faces of 3 or more corners, e.g. a quad control cage) as OBJ, OFF or
//! PLY, keeping every polygon as it is, atomically as write_mesh(). read_mesh(path, &polygons)
//! gives back the same vertices and polygons. STL takes triangles only.
//! \pre the triangulated polygons (the triangles read_mesh makes) pass validate_mesh().
//! \throw InvalidInput if a face has fewer than 3 corners, an index out of range or repeated,
//!        the triangulation fails validation, a face is not a triangle for STL or has more than
//!        255 corners for PLY, or \p encoding is Binary for OBJ or OFF; IoError as write_mesh().
void write_polygon_mesh(const std::vector<Vec3>& vertices, const std::vector<std::vector<int>>& polygons,
                        const std::string& path, MeshEncoding encoding = MeshEncoding::Default);

//! Checks that \p mesh is a valid triangle mesh for the numeric core, in this order:
//! at least one face; every coordinate finite; every index in [0, num_vertices()); no index
//! repeated within a face; no zero-area face (twice its area, |(b-a)x(c-a)|, is 0 or at most
//! 2e-14 * bbox_diagonal(vertices)^2); no non-manifold edge (an undirected edge used by more than
//! two faces); no edge used twice in the same direction (inconsistently oriented neighbours).
//! Unreferenced vertices are allowed, and so are vertices where separate fans of faces meet (scans
//! hold them; the engine takes them, and decimate_mesh(), for the cage fit and a layered model's
//! bands, splits such a vertex into one per fan). The first problem found is reported.
//! \param name names the mesh in messages (usually its file path).
//! \throw InvalidInput "<name>: <problem>", e.g. "bunny.obj: face 12 has vertex index 99 out of
//!        range (mesh has 40 vertices)" or "z.ply: edge (4,7) is non-manifold: shared by 3 faces".
void validate_mesh(const TriMesh& mesh, const std::string& name);

//! The file extensions read_mesh and write_mesh accept, lower case with the leading dot:
//! {".obj", ".off", ".ply", ".stl"}.
std::vector<std::string> supported_mesh_extensions();

}  // namespace strata

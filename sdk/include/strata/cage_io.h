//! \file cage_io.h
//! Control cages and their sharpness tags in files: a cage is a mesh file (OBJ, OFF or PLY keep
//! its polygons: a triangle cage is a Loop cage, one with quads or other polygons a Catmull-Clark
//! cage under SubdivScheme::Auto), its tags a small JSON file:
//! \code{.json}
//! {"creases": [{"edge": [0, 1], "sharpness": 10}, {"edge": [1, 2]}],
//!  "corners": [{"vertex": 4, "sharpness": 3.5}]}
//! \endcode
//! Vertex numbers are 0-based indices into the cage's vertex list; a missing sharpness is 10
//! (infinitely sharp). Both keys are optional; unknown keys are errors.
#pragma once

#include <string>

#include "strata/subdiv.h"

namespace strata {

//! Parses sharpness tags; \p name (a file name) prefixes every error message.
//! \throw InvalidInput if the text is not JSON or not valid tags (the message says where). Whether
//!        the tags fit a cage is checked by SubdivSurface.
SubdivTags parse_subdiv_tags(const std::string& text, const std::string& name);

//! Reads and parses the tags file at \p path.
//! \throw IoError if the file cannot be read; InvalidInput as parse_subdiv_tags().
SubdivTags read_subdiv_tags(const std::string& path);

//! Reads a cage with its polygons as the file lists them (read_mesh(path, &polygons)); the file
//! must be a valid mesh once its polygons are triangulated.
//! \throw as read_mesh(); InvalidInput "<path>: vertex <i> has a coordinate of magnitude ..."
//!        beyond kMaxCoordinate; IoError for an .stl path (STL loses the vertex numbering that
//!        tags name, and rounds to floats).
PolyMesh read_cage(const std::string& path);

//! Checks that \p path's format keeps a cage as read_cage() and write_cage() need (for a
//! command's output, before its work). \throw IoError for .stl.
void check_cage_format(const std::string& path);

//! Writes a cage with its polygons (write_polygon_mesh, atomically); read_cage gives it back.
//! \throw IoError for an .stl path (as read_cage()); as write_polygon_mesh(); InvalidInput as
//!        check_coordinates() for what read_cage() would refuse, before anything is written.
void write_cage(const PolyMesh& cage, const std::string& path);

}  // namespace strata

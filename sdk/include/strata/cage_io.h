//! \file cage_io.h
//! Control cages and their sharpness tags in files: a cage is a mesh file (read_mesh: polygons
//! are triangulated, so a cage read from a file is a Loop cage), its tags a small JSON file:
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

//! Reads a cage (read_mesh, so triangles only).
//! \throw as read_mesh().
PolyMesh read_cage(const std::string& path);

//! Writes a triangle cage with write_mesh (atomically).
//! \throw InvalidInput if a face is not a triangle; as write_mesh().
void write_cage(const PolyMesh& cage, const std::string& path);

}  // namespace strata

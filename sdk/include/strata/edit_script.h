//! \file edit_script.h
//! Edit scripts: JSON files of region edits for `strata deform`, `strata edit` and the viewer.
//!
//! One edit is an object; a file holds one edit, a list of edits, or {"edits": [...]}, applied
//! one after another:
//! \code{.json}
//! {"region": {"sphere": {"center": [0.0, 0.4, 0.1], "radius": 0.3}},
//!  "handle": {"sphere": {"center": [0.0, 0.7, 0.1], "radius": 0.12}},
//!  "transform": {"rotate": {"axis": [1, 0, 0], "degrees": 60, "pivot": [0.0, 0.45, 0.1]},
//!                "translate": [0, 0, 0]}}
//! \endcode
//! Selections: {"sphere": {"center", "radius"}}, {"halfspace": {"point", "normal"}} (the side the
//! normal points to), {"box": {"min", "max"}}, {"vertices": [indices]}. Transform keys, all
//! optional: "rotate" {"axis", "degrees", "pivot" (default origin)}, "scale" (a number or three),
//! "matrix" (3x3, any linear map with positive determinant), "translate" [x, y, z], "pivot" (the
//! centre of scale and matrix when there is no rotation). The linear part is rotate * matrix *
//! scale, about the pivot, then the translation. Unknown keys are errors, so typos do not pass
//! silently.
#pragma once

#include <string>
#include <vector>

#include "strata/editing.h"

namespace strata {

//! One region edit: which vertices may move, which are the handle, and the handle's transform.
struct EditStep {
  Selection region;
  Selection handle;
  EditTransform transform;
};

struct EditScript {
  std::vector<EditStep> edits;
};

//! Parses an edit script; \p name (a file name) prefixes every error message.
//! \throw InvalidInput if the text is not JSON or not a valid script (the message says where).
EditScript parse_edit_script(const std::string& text, const std::string& name);

//! Reads and parses the edit script at \p path.
//! \throw IoError if the file cannot be read; InvalidInput as parse_edit_script().
EditScript read_edit_script(const std::string& path);

}  // namespace strata

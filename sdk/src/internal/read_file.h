// Internal: whole-file reading shared by the mesh, edit-script and tags readers.
#pragma once

#include <string>

namespace strata::internal {

//! The bytes of the regular file at \p path. A FIFO or device is refused (it could block or never
//! end), so a reader never hangs.
//! \throw IoError "<path>: <problem>" if the file is not regular, cannot be opened or read.
std::string read_whole_file(const std::string& path);

}  // namespace strata::internal

//! \file atomic_file.h
//! Whole-file reads that never hang, and atomic writes. Replace a file in one step: write a temporary file
//! next to it, flush it to disk, then rename it over the target. Readers of the target see either the old or
//! the new contents, never a half-written file, even if the writer fails or the process dies mid-write.
#pragma once

#include <functional>
#include <string>

namespace strata {

//! Calls \p writer(tmp_path) to write a temporary file in the same directory as \p path, then
//! renames it over \p path (creating or replacing it).
//!
//! The temporary file already exists (empty) when \p writer is called; the writer opens it
//! itself, writes it completely and closes it before returning. Its name is unique, so
//! concurrent writes of the same target do not collide (the last rename wins). A file that
//! already exists at \p path keeps its permission bits. A symbolic link at \p path (to a regular
//! file or to nothing) is replaced by the new file, not followed.
//!
//! \pre The directory containing \p path exists and is writable.
//! \throw IoError as check_replaceable(path), before anything is written.
//! \throw IoError if the temporary file cannot be created or synced, or the rename fails; the
//!        temporary file is removed and \p path is left untouched.
//! \throw anything \p writer throws: the temporary file is removed, \p path is left untouched,
//!        and the exception propagates unchanged.
void write_file_atomically(const std::string& path,
                           const std::function<void(const std::string& tmp_path)>& writer);

//! Checks that \p path may be replaced by a rename: it does not exist, or it is a regular file, or
//! a symbolic link to one (or to nothing). A device, FIFO, socket or directory (or a link to one)
//! is refused: a rename over /dev/null replaced the device with a regular file.
//! \throw IoError "<path>: is not a regular file (...); refusing to replace it".
void check_replaceable(const std::string& path);

//! Atomically replaces \p path with exactly the bytes of \p contents (no newline translation).
//! \pre The directory containing \p path exists and is writable.
//! \throw IoError if writing, syncing or renaming fails; \p path is then left untouched.
void write_text_file_atomically(const std::string& path, const std::string& contents);

//! The bytes of the regular file at \p path. A FIFO or a device is refused (it could block or
//! never end), so a reader built on this never hangs.
//! \throw IoError "<path>: <problem>" if the file is not regular, cannot be opened or read.
std::string read_file_bytes(const std::string& path);

}  // namespace strata

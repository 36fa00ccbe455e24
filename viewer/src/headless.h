//! \file headless.h
//! The --screenshot mode: loads the input, applies edits and amplitudes, renders one picture
//! without a window (EGL surfaceless on Mesa: an OpenGL 3.3 core context with no surface, drawn
//! into a framebuffer object and read back) and writes it as PNG atomically (a temporary file,
//! then a rename: never a half-written PNG).
#pragma once

#include <string>

#include "options.h"

namespace strata::viewer {

//! Runs the headless render of \p options (options.screenshot set) and returns one JSON line
//! (no newline) of timings and counts: seconds per phase, per-frame milliseconds, GL errors.
//! \throw strata::Error (IoError, InvalidInput, SolverError) or std::runtime_error (no GL
//!        context, GL errors); OUT.png is then untouched.
std::string run_headless(const Options& options);

}  // namespace strata::viewer

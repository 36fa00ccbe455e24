//! \file exceptions.h
//! The Strata exception hierarchy. Every error the SDK reports to its caller is one of these;
//! asserts guard only internal invariants.
#pragma once

#include <stdexcept>
#include <string>

namespace strata {

//! Base class of all Strata errors.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

//! The caller's input is unusable: malformed meshes, NaN coordinates, mismatched sizes, bad options.
class InvalidInput : public Error {
 public:
  using Error::Error;
};

//! A file could not be read or written (missing, unreadable, truncated, unknown format).
class IoError : public Error {
 public:
  using Error::Error;
};

//! A numerical solve failed (diverged, factorization failed, non-finite result).
class SolverError : public Error {
 public:
  using Error::Error;
};

//! The caller asked a long operation to stop (ReconstructOptions::cancel). Nothing is wrong with
//! the input; the object that threw stays usable.
class Cancelled : public Error {
 public:
  using Error::Error;
};

}  // namespace strata

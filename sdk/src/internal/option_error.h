// Internal: the one message of an option out of range, for the option structs' checks. Not part
// of the public API.
#pragma once

#include <sstream>

#include "strata/exceptions.h"

namespace strata::internal {

//! Throws InvalidInput "KIND option NAME = VALUE is out of range (RANGE)".
[[noreturn]] inline void option_out_of_range(const char* kind, const char* name, double value,
                                             const char* range) {
  std::ostringstream m;
  m << kind << " option " << name << " = " << value << " is out of range (" << range << ")";
  throw InvalidInput(m.str());
}

}  // namespace strata::internal

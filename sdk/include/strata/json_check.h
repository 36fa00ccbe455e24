//! \file json_check.h
//! The structural checks that Strata's JSON formats (edit scripts, `.strata` headers) run before a
//! value is built: depth, keys per object, and keys given twice.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace strata {

//! Limits for json_structure_problem(). Defaults are those of the `.strata` header
//! (layers/FORMAT.md) and of edit scripts.
struct JsonLimits {
  //! Deeper JSON is refused: serializing it, and copying a value of it, recurse once per level.
  int max_depth = 256;
  //! Objects with more keys are refused: an ordered JSON object finds a key by a linear search, so
  //! an object of n keys takes n^2 / 2 string comparisons to read (300k keys: 49 s). 0: no limit.
  std::size_t max_keys = 1024;
  //! A key given twice in one object is refused: JSON parsers keep one of the values silently.
  bool reject_duplicate_keys = true;
};

//! "" if \p text, as far as it is valid JSON, is within \p limits; otherwise its first problem,
//! e.g. `nested deeper than 256 levels`, `an object has more than 1024 keys` or `the key "a"
//! appears twice in one object` (the key's first 64 bytes, any outside printable ASCII as '?'). The
//! pass stops at a syntax error, which it leaves to the parse that follows to name: problems
//! before it are reported, those after it are not.
//!
//! One SAX pass that builds no value and stops at the first problem, in time linear in the text
//! (nlohmann's callback parser, used before, rescans a container after each object in it ends:
//! an array of 40k empty objects took 33 s).
//! \throw nothing but std::bad_alloc.
std::string json_structure_problem(std::string_view text, const JsonLimits& limits = {});

//! A key of a JSON file as Strata's messages show it: its first 64 bytes, any byte outside
//! printable ASCII as '?', and "..." if it was longer. A key is any JSON string: a megabyte, or
//! control characters that a terminal would act on.
std::string printable_key(std::string_view key);

//! The text of a JSON parser's exception (\p what, nlohmann's `e.what()`) as Strata's messages
//! show it: without the `[json.exception.parse_error.101] ` prefix, which names the library's
//! exception class rather than the problem; the rest (`parse error at line 1, column 27: ...`) is
//! kept. Text without such a prefix is returned as it is.
std::string json_error_text(std::string_view what);

}  // namespace strata

// Internal to layers: the limits of the JSON that .strata headers hold (layers/FORMAT.md), checked
// before any value is built. Not part of the API.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace strata::layers::internal {

// Deeper JSON is refused: serializing it, and copying a value of it, recurse once per level.
constexpr int kMaxJsonDepth = 256;
// Objects with more keys are refused: ordered_json finds a key by a linear search, so an object
// of n keys takes n^2 / 2 string comparisons to read (300k keys: 49 s). A model writes a few
// dozen keys an object.
constexpr std::size_t kMaxJsonKeys = 1024;

//! "" if \p text nests at most kMaxJsonDepth levels and has no object of more than kMaxJsonKeys
//! keys, as far as it is valid JSON (a syntax error is left to the parse that follows); otherwise
//! the first such problem. One SAX pass that builds no value and stops at the problem, in linear
//! time (nlohmann's callback parser, which did this before, scans a container's values after each
//! object in it ends: an array of 40k empty objects took 33 s).
inline std::string json_limit_problem(const char* begin, const char* end) {
  using J = nlohmann::json;
  struct Limits {
    std::vector<std::size_t> keys;  // per open object, its keys so far
    int depth = 0;
    std::string problem;
    bool open() {
      if (++depth <= kMaxJsonDepth) return true;
      problem = "nested deeper than " + std::to_string(kMaxJsonDepth) + " levels";
      return false;
    }
    bool null() { return true; }
    bool boolean(bool) { return true; }
    bool number_integer(J::number_integer_t) { return true; }
    bool number_unsigned(J::number_unsigned_t) { return true; }
    bool number_float(J::number_float_t, const J::string_t&) { return true; }
    bool string(J::string_t&) { return true; }
    bool binary(J::binary_t&) { return true; }
    bool start_object(std::size_t) {
      keys.push_back(0);
      return open();
    }
    bool key(J::string_t&) {
      if (++keys.back() <= kMaxJsonKeys) return true;
      problem = "an object has more than " + std::to_string(kMaxJsonKeys) + " keys";
      return false;
    }
    bool end_object() {
      keys.pop_back();
      --depth;
      return true;
    }
    bool start_array(std::size_t) { return open(); }
    bool end_array() {
      --depth;
      return true;
    }
    bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) { return false; }
  } limits;
  J::sax_parse(begin, end, &limits);
  return limits.problem;
}

}  // namespace strata::layers::internal

#include "strata/json_check.h"

#include <nlohmann/json.hpp>
#include <unordered_set>
#include <vector>

namespace strata {
namespace {

using J = nlohmann::json;

// The SAX handler: per open object its keys so far; stops (returns false) at the first problem.
class StructureCheck {
 public:
  explicit StructureCheck(const JsonLimits& limits) : limits_(limits) {}
  const std::string& problem() const { return problem_; }

  bool null() { return true; }
  bool boolean(bool) { return true; }
  bool number_integer(J::number_integer_t) { return true; }
  bool number_unsigned(J::number_unsigned_t) { return true; }
  bool number_float(J::number_float_t, const J::string_t&) { return true; }
  bool string(J::string_t&) { return true; }
  bool binary(J::binary_t&) { return true; }
  bool start_object(std::size_t) {
    objects_.emplace_back();
    return open();
  }
  bool key(J::string_t& k) {
    Keys& keys = objects_.back();
    ++keys.count;
    if (limits_.max_keys > 0 && keys.count > limits_.max_keys)
      return fail("an object has more than " + std::to_string(limits_.max_keys) + " keys");
    if (limits_.reject_duplicate_keys && !keys.seen.insert(k).second)
      return fail("the key \"" + printable_key(k) + "\" appears twice in one object");
    return true;
  }
  bool end_object() {
    objects_.pop_back();
    --depth_;
    return true;
  }
  bool start_array(std::size_t) { return open(); }
  bool end_array() {
    --depth_;
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) { return false; }

 private:
  struct Keys {
    std::size_t count = 0;
    std::unordered_set<std::string> seen;  // only with reject_duplicate_keys
  };
  bool open() {
    if (++depth_ <= limits_.max_depth) return true;
    return fail("nested deeper than " + std::to_string(limits_.max_depth) + " levels");
  }
  bool fail(std::string problem) {
    problem_ = std::move(problem);
    return false;
  }

  JsonLimits limits_;
  std::vector<Keys> objects_;
  int depth_ = 0;
  std::string problem_;
};

}  // namespace

std::string printable_key(std::string_view key) {
  constexpr std::size_t kMaxShown = 64;
  std::string out;
  for (std::size_t i = 0; i < key.size() && i < kMaxShown; ++i) {
    const auto c = static_cast<unsigned char>(key[i]);
    out += c >= 0x20 && c < 0x7f ? static_cast<char>(c) : '?';
  }
  if (key.size() > kMaxShown) out += "...";
  return out;
}

std::string json_structure_problem(std::string_view text, const JsonLimits& limits) {
  StructureCheck check(limits);
  J::sax_parse(text.begin(), text.end(), &check);
  return check.problem();
}

std::string json_error_text(std::string_view what) {
  constexpr std::string_view kPrefix = "[json.exception.";
  if (what.substr(0, kPrefix.size()) == kPrefix) {
    const std::size_t end = what.find("] ");
    if (end != std::string_view::npos) what.remove_prefix(end + 2);
  }
  return std::string(what);
}

}  // namespace strata

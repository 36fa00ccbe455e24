// Internal: one vertex per position, for welding (the STL readers, weld_vertices()). Not part of
// the API.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <unordered_map>
#include <vector>

#include "strata/mesh.h"

namespace strata::internal {

//! Bitwise-equal positions (with -0 == +0) become one vertex, numbered in order of first use.
class Welder {
 public:
  //! The vertex at \p p: a new one, appended to `vertices`, unless an earlier position equals it.
  long long index_of(const Vec3& p) {
    Key k;
    for (int c = 0; c < 3; ++c) {
      const double x = p[c] == 0.0 ? 0.0 : p[c];  // merge -0 and +0
      std::memcpy(&k[c], &x, sizeof x);
    }
    const auto [it, inserted] = map_.try_emplace(k, static_cast<long long>(vertices.size()));
    if (inserted) vertices.push_back(p);
    return it->second;
  }
  std::vector<Vec3> vertices;

 private:
  using Key = std::array<std::uint64_t, 3>;
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = 0x9E3779B97F4A7C15ull;
      for (std::uint64_t x : k) h = (h ^ x) * 0x100000001B3ull + (h >> 29);
      return static_cast<std::size_t>(h);
    }
  };
  std::unordered_map<Key, long long, KeyHash> map_;
};

}  // namespace strata::internal

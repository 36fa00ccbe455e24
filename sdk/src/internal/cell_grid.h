// Internal: the cells of a uniform grid, as keys for hash lookups. Not part of the public API.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "strata/mesh.h"

namespace strata::internal {

//! Cells of side `cell` (> 0). Coordinates are clamped, so that any finite point converts (one far
//! away, a tiny cell), and keys keep 21 bits an axis: distinct cells may share a key, so a lookup
//! through keys yields candidates to check, never misses one.
struct CellGrid {
  double cell = 1.0;

  std::int64_t coord(double x) const {
    return static_cast<std::int64_t>(std::clamp(std::floor(x / cell), -1e15, 1e15));
  }
  static std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) {
    const auto u = [](std::int64_t v) { return static_cast<std::uint64_t>(v) & 0x1fffff; };
    return u(x) | (u(y) << 21) | (u(z) << 42);
  }
  std::uint64_t key(const Vec3& p) const { return key(coord(p.x()), coord(p.y()), coord(p.z())); }
  //! The cells \p b covers, as a double (a huge box's count overflows no integer).
  double span(const Eigen::AlignedBox3d& b) const {
    double c = 1.0;
    for (int a = 0; a < 3; ++a) c *= static_cast<double>(coord(b.max()[a]) - coord(b.min()[a])) + 1.0;
    return c;
  }
  //! f(key) for each cell \p b covers. Two closed boxes that overlap share a point, and so a cell.
  //! \pre span(b) is small (the cells are enumerated).
  template <class F>
  void for_each_cell(const Eigen::AlignedBox3d& b, F&& f) const {
    const std::int64_t x1 = coord(b.max().x()), y1 = coord(b.max().y()), z1 = coord(b.max().z());
    for (std::int64_t x = coord(b.min().x()); x <= x1; ++x)
      for (std::int64_t y = coord(b.min().y()); y <= y1; ++y)
        for (std::int64_t z = coord(b.min().z()); z <= z1; ++z) f(key(x, y, z));
  }
};

}  // namespace strata::internal

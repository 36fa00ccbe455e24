#include "internal/contact.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace strata::internal {

ContactTest::ContactTest(const BaseGraph& graph, double ratio, double visits_per_vertex)
    : g_(graph),
      ratio_(ratio),
      visits_left_(visits_per_vertex * static_cast<double>(graph.vf_offsets->size() - 1)),
      dist_(graph.vf_offsets->size() - 1, INFINITY) {
  assert(ratio >= 1.0);
}

bool ContactTest::operator()(int a, int b) {
  if (a > b) std::swap(a, b);  // the test is symmetric
  const std::uint64_t key = static_cast<std::uint64_t>(a) << 32 | static_cast<std::uint32_t>(b);
  if (const auto it = known_.find(key); it != known_.end()) return it->second;
  const std::vector<Vec3>& q = *g_.base_points;
  const Face& fa = (*g_.faces)[static_cast<std::size_t>(a)];
  const Face& fb = (*g_.faces)[static_cast<std::size_t>(b)];
  auto at = [&](int v) -> const Vec3& { return q[static_cast<std::size_t>(v)]; };
  double straight = INFINITY, edge = 0.0;
  for (int u : fa)
    for (int v : fb) straight = std::min(straight, (at(u) - at(v)).norm());
  for (const Face* f : {&fa, &fb})
    for (int c = 0; c < 3; ++c) edge = std::max(edge, (at((*f)[c]) - at((*f)[(c + 1) % 3])).norm());
  const bool contact = !within(a, b, ratio_ * (straight + edge));
  known_.emplace(key, contact);
  return contact;
}

// A* from face a's corners to face b's: whether a path of length at most \p bound joins them.
bool ContactTest::within(int a, int b, double bound) {
  const std::vector<Vec3>& q = *g_.base_points;
  const std::vector<int>& off = *g_.vf_offsets;
  const std::vector<int>& vf = *g_.vf;
  const Face& fb = (*g_.faces)[static_cast<std::size_t>(b)];
  auto at = [&](int v) -> const Vec3& { return q[static_cast<std::size_t>(v)]; };
  // The straight distance to face b's nearest corner: never more than the path left (each edge
  // is a straight segment between base points), so the first path to reach b is the shortest.
  auto estimate = [&](int v) {
    return std::min({(at(v) - at(fb[0])).norm(), (at(v) - at(fb[1])).norm(), (at(v) - at(fb[2])).norm()});
  };
  auto relax = [&](int v, double d) {
    double& dv = dist_[static_cast<std::size_t>(v)];
    if (!(d < dv)) return;
    if (std::isinf(dv)) touched_.push_back(v);
    dv = d;
    heap_.emplace(d + estimate(v), v);
  };
  for (int v : (*g_.faces)[static_cast<std::size_t>(a)]) relax(v, 0.0);
  bool found = false;
  while (!heap_.empty()) {
    if (!(visits_left_ > 0)) {
      found = true;  // the budget is spent: a fold, as if every new pair were one
      break;
    }
    visits_left_ -= 1;
    const auto [f, v] = heap_.top();
    heap_.pop();
    if (f > bound) break;  // every path through the vertices left is longer
    const double d = dist_[static_cast<std::size_t>(v)];
    if (f > d + estimate(v)) continue;  // a stale entry
    if (v == fb[0] || v == fb[1] || v == fb[2]) {
      found = true;
      break;
    }
    for (int t = off[static_cast<std::size_t>(v)]; t < off[static_cast<std::size_t>(v) + 1]; ++t)
      for (int u : (*g_.faces)[static_cast<std::size_t>(vf[static_cast<std::size_t>(t)] / 3)])
        if (u != v) relax(u, d + (at(u) - at(v)).norm());
  }
  for (int v : touched_) dist_[static_cast<std::size_t>(v)] = INFINITY;
  touched_.clear();
  heap_ = {};
  return found;
}

}  // namespace strata::internal

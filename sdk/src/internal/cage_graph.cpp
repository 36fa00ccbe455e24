#include "internal/cage_graph.h"

#include <algorithm>
#include <map>
#include <utility>
#include <vector>

namespace strata::internal {

Eigen::SparseMatrix<double> cage_laplacian(const PolyMesh& cage, bool boundary_along_itself) {
  const int n = cage.num_vertices();
  std::map<std::pair<int, int>, int> uses;  // undirected edge -> faces using it
  for (const auto& f : cage.faces)
    for (std::size_t k = 0; k < f.size(); ++k) ++uses[std::minmax(f[k], f[(k + 1) % f.size()])];
  std::vector<std::vector<int>> all(n), boundary(n);
  for (const auto& [e, count] : uses) {
    all[e.first].push_back(e.second);
    all[e.second].push_back(e.first);
    if (count == 1) {
      boundary[e.first].push_back(e.second);
      boundary[e.second].push_back(e.first);
    }
  }
  std::vector<Eigen::Triplet<double>> t;
  for (int v = 0; v < n; ++v) {
    const std::vector<int>& ring = boundary_along_itself && !boundary[v].empty() ? boundary[v] : all[v];
    if (ring.empty()) continue;
    t.emplace_back(v, v, 1.0);
    for (int w : ring) t.emplace_back(v, w, -1.0 / ring.size());
  }
  Eigen::SparseMatrix<double> L(n, n);
  L.setFromTriplets(t.begin(), t.end());
  return L;
}

}  // namespace strata::internal

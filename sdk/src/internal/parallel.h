// Internal: the solver's parallel loop over independent indices. Not part of the public API.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cstddef>

namespace strata::internal {

//! f(i) for i in [0, n): on \p arena's threads when it is given and n is large enough to pay for
//! them, else on the calling thread. Every index must be independent, so that the result does not
//! depend on the threads (reductions stay serial in the callers).
template <class F>
void parallel_for_each(tbb::task_arena* arena, std::size_t n, F&& f) {
  constexpr std::size_t kGrain = 2048;
  if (!arena || n < 2 * kGrain) {
    for (std::size_t i = 0; i < n; ++i) f(i);
    return;
  }
  arena->execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
                      });
  });
}

}  // namespace strata::internal

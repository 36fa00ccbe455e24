// internal::SerialOpenMp: CHOLMOD's regions carry a hard-coded num_threads(4); the guard must cap
// such regions at one thread on the calling thread only, and restore the caller's settings.
// This file alone is compiled with -fopenmp (tests/CMakeLists.txt).
#include <gtest/gtest.h>
#include <omp.h>

#include <cstdlib>
#include <thread>

#include "internal/serial_openmp.h"

namespace {

// The team size of a region that asks for \p n threads, as CHOLMOD's do.
int team_size(int n) {
  int team = 0;
#pragma omp parallel num_threads(n)
  {
#pragma omp single
    team = omp_get_num_threads();
  }
  return team;
}

}  // namespace

TEST(SerialOpenMp, CapsRegionsWithANumThreadsClauseOnTheCallingThreadAndRestores) {
  const int max_threads = omp_get_max_threads();
  const int dynamic = omp_get_dynamic();
  const int levels = omp_get_max_active_levels();
  // Without the guard the clause gets its threads (the oversubscription the guard is for), unless
  // the environment limits them.
  const bool unlimited = !std::getenv("OMP_THREAD_LIMIT") && !dynamic;
  if (unlimited) {
    EXPECT_EQ(team_size(4), 4);
  }
  {
    const strata::internal::SerialOpenMp guard;
    EXPECT_EQ(team_size(4), 1);
    EXPECT_EQ(omp_get_max_threads(), 1);
    // Inactive regions, not dynamic adjustment: with it, libgomp asked the kernel for the load
    // average and the affinity at every region.
    EXPECT_EQ(omp_get_max_active_levels(), 0);
    EXPECT_EQ(omp_get_dynamic(), dynamic);
    // Another thread keeps the process's defaults.
    int other = 0;
    std::thread t([&] { other = team_size(2); });
    t.join();
    if (unlimited) {
      EXPECT_EQ(other, 2);
    }
    {
      const strata::internal::SerialOpenMp nested;  // guards nest
      EXPECT_EQ(team_size(4), 1);
    }
    EXPECT_EQ(team_size(4), 1);
  }
  EXPECT_EQ(omp_get_max_threads(), max_threads);
  EXPECT_EQ(omp_get_dynamic(), dynamic);
  EXPECT_EQ(omp_get_max_active_levels(), levels);
}

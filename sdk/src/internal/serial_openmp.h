// Internal: runs CHOLMOD's OpenMP regions on the calling thread.
#pragma once

namespace strata::internal {

//! While alive, OpenMP parallel regions started on the constructing thread run with one thread.
//!
//! Why: Debian's CHOLMOD 3 (SuiteSparse 5) opens its supernodal regions with a hard-coded
//! num_threads(4) (CHOLMOD_OMP_NUM_THREADS), which OMP_NUM_THREADS cannot lower. On a 2-core
//! machine four threads forking and joining per supernode cost more than the factorization itself
//! (measured: a 100k-prism reconstruction took 12.8 s with it, 7.3 s without). With
//! max-active-levels-var 0 every parallel region is inactive, so libgomp runs even one with a
//! num_threads clause on the encountering thread alone, and decides so before anything else.
//! (Dynamic adjustment with nthreads-var 1, used before, also gave one thread, but libgomp then
//! asked the kernel for the load average and the CPU affinity at every region that could have had
//! more threads: 18,220 of each call in one reconstruction of the regular 100k bend (strace); a
//! microbenchmark: 4.0 against 1.3 us a region. The bend's solve time did not change measurably: 3.50-4.40 s
//! against 3.35-4.56 s, medians of three, alternating.) nthreads-var is set to 1 too, for code that sizes
//! per-thread workspace by omp_get_max_threads(). Both are the calling thread's own ICVs (libgomp since GCC
//! 11), so other threads (and the caller's own OpenMP code after the guard ends) are unaffected; the previous
//! values are restored.
class SerialOpenMp {
 public:
  SerialOpenMp();
  ~SerialOpenMp();
  SerialOpenMp(const SerialOpenMp&) = delete;
  SerialOpenMp& operator=(const SerialOpenMp&) = delete;

 private:
  int max_active_levels_ = 1;
  int max_threads_ = 1;
};

}  // namespace strata::internal

// Internal: runs CHOLMOD's OpenMP regions on the calling thread.
#pragma once

namespace strata::internal {

//! While alive, OpenMP parallel regions started on the constructing thread run with one thread.
//!
//! Why: Debian's CHOLMOD 3 (SuiteSparse 5) opens its supernodal regions with a hard-coded
//! num_threads(4) (CHOLMOD_OMP_NUM_THREADS), which OMP_NUM_THREADS cannot lower. On a 2-core
//! machine four threads forking and joining per supernode cost more than the factorization itself
//! (measured: a 100k-prism reconstruction took 12.8 s with it, 7.3 s without). With dynamic
//! adjustment on and nthreads-var 1, libgomp caps every region, even one with a num_threads clause,
//! at one thread. Both settings are the calling thread's own ICVs, so other threads (and the
//! caller's own OpenMP code after the guard ends) are unaffected; the previous values are restored.
class SerialOpenMp {
 public:
  SerialOpenMp();
  ~SerialOpenMp();
  SerialOpenMp(const SerialOpenMp&) = delete;
  SerialOpenMp& operator=(const SerialOpenMp&) = delete;

 private:
  int dynamic_ = 0;
  int max_threads_ = 1;
};

}  // namespace strata::internal

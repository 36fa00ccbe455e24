//! \file process.h
//! Process set-up for programs built on the SDK: glibc's malloc on transparent huge pages, its
//! heap kept for reuse.
#pragma once

namespace strata {

//! Whether the environment sets the glibc tunable glibc.malloc.hugetlb, whatever its value
//! (GLIBC_TUNABLES holds it; glibc read it when this process started, if it was set then).
bool huge_page_malloc_configured();

//! For a program's main(), before anything else: re-executes the program (/proc/self/exe, the
//! same arguments and environment) with GLIBC_TUNABLES extended by glibc.malloc.hugetlb=1, so
//! that glibc's malloc advises its large blocks and its heap for transparent huge pages: where
//! the kernel gives them only to advised ranges ("madvise", as on the machine measured) this is
//! what puts the arrays on them; with "always" it changes little, with "never" nothing. The solver's arrays
//! at 1M prisms hold 4-45 MB each and its passes are bound by memory traffic: on 4 KB pages each
//! reconstruction pays a page fault per 4 KB of arrays it allocates and a TLB miss per 4 KB it sweeps.
//! Measured with strata_bench (the bumps bend at jitter 0.4, one thread, medians of three, runs with and
//! without interleaved, 2026-11-29): 1M prisms 6.68-7.40 s against 7.79-8.72 s a
//! reconstruction, setup 2.88-3.63 s against 3.71-4.10 s; at 10k and 100k the difference was
//! within the machine's noise (10k: 0.066-0.103 s against 0.076-0.100 s). The solutions' errors,
//! intersecting pairs and iteration counts are the same (placement changes no arithmetic).
//! With it, unless GLIBC_TUNABLES names them: glibc.malloc.mmap_threshold=33554432 (blocks under
//! 32 MB, the most glibc takes, come from the heap) and glibc.malloc.trim_threshold=4294967296 (the
//! heap is not returned to the kernel until 4 GB of it are free): a reconstruction's arrays are
//! freed when it ends (and some between its phases), and the next one took them back from the
//! kernel, a page fault and a zeroed page at a time. Measured (2026-12-02, strata_bench, the 1M
//! bumps bend, one thread): 680 page faults per further reconstruction, 0.7 s of page zeroing in
//! perf's samples, against 45 and none with them; the second reconstruction of six processes each,
//! alternating, 7.46 s against 8.02 s on average (each pair 0.79-1.08 times), the peak 794-808
//! against 798-841 bytes per prism (six runs each way). Arrays of 32 MB or more are still mapped and returned.
//! Does nothing (returns) if glibc.malloc.hugetlb is set already (GLIBC_TUNABLES=glibc.malloc.hugetlb=0
//! keeps malloc as it is), unless \p force (the caller changed other variables that are read
//! only at start, as OMP_NUM_THREADS). Never re-executes a program that it started (the
//! environment variable STRATA_REEXECUTED says so), a set-user-ID or otherwise secure program
//! (AT_SECURE: glibc ignores the tunable there), or one run through the dynamic loader by hand.
//! If the exec fails (no /proc) it returns with the environment as it was. Glibc takes tunables
//! only at start, hence the exec: a library cannot set them for the process that loaded it.
//! Profilers that follow one process (valgrind without --trace-children=yes) see only the exec:
//! run the program with GLIBC_TUNABLES=glibc.malloc.hugetlb=0 under them.
//! \param argv the program's argv (null-terminated), passed on unchanged.
void reexec_with_huge_page_malloc(char** argv, bool force = false);

}  // namespace strata

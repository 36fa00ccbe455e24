//! \file process.h
//! Process set-up for programs built on the SDK: glibc's malloc on transparent huge pages.
#pragma once

namespace strata {

//! Whether this process's malloc was started with the glibc tunable glibc.malloc.hugetlb set,
//! whatever its value (GLIBC_TUNABLES holds it).
bool huge_page_malloc_configured();

//! For a program's main(), before anything else: re-executes the program (/proc/self/exe, the
//! same arguments and environment) with GLIBC_TUNABLES extended by glibc.malloc.hugetlb=1, so
//! that glibc's malloc puts its large blocks and its heap on transparent huge pages where the
//! system's setting is "madvise" (Debian's default). The solver's arrays at 1M prisms hold
//! 4-45 MB each and its passes are bound by memory traffic: on 4 KB pages each reconstruction
//! pays a page fault per 4 KB of arrays it allocates and a TLB miss per 4 KB it sweeps. Measured
//! with strata_bench (the bumps bend at jitter 0.4, one thread, medians of three, runs with and
//! without interleaved, 2026-11-29): 1M prisms 6.68-7.40 s against 7.79-8.72 s a
//! reconstruction, setup 2.88-3.63 s against 3.71-4.10 s; at 10k and 100k the difference was
//! within the machine's noise (10k: 0.066-0.103 s against 0.076-0.100 s). The solutions' errors,
//! intersecting pairs and iteration counts are the same (placement changes no arithmetic).
//! Does nothing (returns) if the tunable is set already (GLIBC_TUNABLES=glibc.malloc.hugetlb=0
//! keeps malloc as it is), unless \p force (the caller changed other variables that are read
//! only at start, as OMP_NUM_THREADS); returns also if the exec fails (no /proc), the program
//! then going on as it is. Glibc takes tunables only at start, hence the exec: a library cannot
//! set them for the process that loaded it.
//! \param argv the program's argv (null-terminated), passed on unchanged.
void reexec_with_huge_page_malloc(char** argv, bool force = false);

}  // namespace strata

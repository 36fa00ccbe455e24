// reexec_with_huge_page_malloc() (strata/process.h): the program starts again with the glibc
// tunables added to its environment (the other tunables and the arguments kept), and not again
// once glibc.malloc.hugetlb is set, whatever its value.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "strata/process.h"
#include "test_files.h"

namespace {

constexpr const char* kOut = "STRATA_PROCESS_TEST_OUT";

// Runs only in the test binary that Process.* re-executes: writes what it sees.
TEST(ProcessChild, WritesWhatItSees) {
  const char* out = std::getenv(kOut);
  if (!out) GTEST_SKIP() << "runs only as the re-executed child of Process.*";
  const char* t = std::getenv("GLIBC_TUNABLES");
  std::ofstream(out) << "tunables " << (t ? t : "") << " configured "
                     << strata::huge_page_malloc_configured();
}

// Forks; the child starts with GLIBC_TUNABLES = \p tunables (null: unset) and calls
// reexec_with_huge_page_malloc(\p force) with argv naming ProcessChild alone. What the child
// wrote: the re-executed binary's view, or "returned" if the call returned. \p guard: as a
// program that the call started already (STRATA_REEXECUTED set).
std::string run_child(const std::string& out, const char* tunables, bool force, bool guard = false) {
  std::remove(out.c_str());
  const pid_t pid = fork();
  if (pid == 0) {
    for (const char* v : {"STRATA_REEXECUTED", "GTEST_TOTAL_SHARDS", "GTEST_SHARD_INDEX"}) unsetenv(v);
    if (guard) setenv("STRATA_REEXECUTED", "1", 1);
    setenv(kOut, out.c_str(), 1);
    if (tunables)
      setenv("GLIBC_TUNABLES", tunables, 1);
    else
      unsetenv("GLIBC_TUNABLES");
    char arg0[] = "strata_tests", arg1[] = "--gtest_filter=ProcessChild.WritesWhatItSees";
    char* argv[] = {arg0, arg1, nullptr};
    strata::reexec_with_huge_page_malloc(argv, force);
    std::ofstream(out) << "returned";
    _exit(0);
  }
  int status = 0;
  for (int waited = 0; waitpid(pid, &status, WNOHANG) == 0; ++waited) {
    if (waited == 600) {  // 60 s: a child that hangs fails the test instead of holding it
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      ADD_FAILURE() << "the child did not end";
      break;
    }
    usleep(100000);
  }
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  std::ifstream in(out);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(Process, TheProgramStartsAgainWithMallocOnHugePages) {
  strata::test::ScratchDir dir{"strata_process"};
  const std::string out = dir.file("seen.txt");
  const std::string keep_heap =
      ":glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=4294967296";
  EXPECT_EQ(run_child(out, nullptr, false), "tunables glibc.malloc.hugetlb=1" + keep_heap + " configured 1");
  EXPECT_EQ(run_child(out, "glibc.malloc.mmap_max=65536", false),
            "tunables glibc.malloc.mmap_max=65536:glibc.malloc.hugetlb=1" + keep_heap + " configured 1");
  // The caller's own thresholds are kept, and not named twice.
  EXPECT_EQ(
      run_child(out, "glibc.malloc.trim_threshold=0", false),
      "tunables glibc.malloc.trim_threshold=0:glibc.malloc.hugetlb=1:glibc.malloc.mmap_threshold=33554432 "
      "configured 1");
  EXPECT_EQ(run_child(out, "glibc.malloc.mmap_threshold=4096", false),
            "tunables "
            "glibc.malloc.mmap_threshold=4096:glibc.malloc.hugetlb=1:glibc.malloc.trim_threshold=4294967296 "
            "configured 1");
  // Set already (0 keeps malloc as it is): no second start, unless forced.
  EXPECT_EQ(run_child(out, "glibc.malloc.hugetlb=0", false), "returned");
  EXPECT_EQ(run_child(out, "glibc.malloc.hugetlb=1", false), "returned");
  EXPECT_EQ(run_child(out, "glibc.malloc.hugetlb=0", true), "tunables glibc.malloc.hugetlb=0 configured 1");
  // A program it started never starts again, whatever it sees (glibc drops tunables in a
  // set-user-ID program, which would otherwise loop).
  EXPECT_EQ(run_child(out, nullptr, false, /*guard=*/true), "returned");
  EXPECT_EQ(run_child(out, nullptr, true, /*guard=*/true), "returned");
}

}  // namespace

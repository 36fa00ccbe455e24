// reexec_with_huge_page_malloc() (strata/process.h): the program starts again with the glibc
// tunable added to its environment (the other tunables and the arguments kept), and not again
// once the tunable is set, whatever its value.
#include <gtest/gtest.h>
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
// wrote: the re-executed binary's view, or "returned" if the call returned.
std::string run_child(const std::string& out, const char* tunables, bool force) {
  std::remove(out.c_str());
  const pid_t pid = fork();
  if (pid == 0) {
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
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  std::ifstream in(out);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(Process, TheProgramStartsAgainWithMallocOnHugePages) {
  strata::test::ScratchDir dir{"strata_process"};
  const std::string out = dir.file("seen.txt");
  EXPECT_EQ(run_child(out, nullptr, false), "tunables glibc.malloc.hugetlb=1 configured 1");
  EXPECT_EQ(run_child(out, "glibc.malloc.mmap_max=65536", false),
            "tunables glibc.malloc.mmap_max=65536:glibc.malloc.hugetlb=1 configured 1");
  // Set already (0 keeps malloc as it is): no second start, unless forced.
  EXPECT_EQ(run_child(out, "glibc.malloc.hugetlb=0", false), "returned");
  EXPECT_EQ(run_child(out, "glibc.malloc.hugetlb=1", false), "returned");
  EXPECT_EQ(run_child(out, "glibc.malloc.hugetlb=0", true), "tunables glibc.malloc.hugetlb=0 configured 1");
}

}  // namespace

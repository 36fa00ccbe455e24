#include "strata/process.h"

#include <sys/auxv.h>
#include <unistd.h>

#include <cstdlib>
#include <optional>
#include <string>

namespace strata {

namespace {
constexpr const char* kTunable = "glibc.malloc.hugetlb=";
// Added with it unless GLIBC_TUNABLES names them already (process.h says why).
constexpr const char* kKeepHeap[] = {"glibc.malloc.mmap_threshold=33554432",
                                     "glibc.malloc.trim_threshold=4294967296"};
// Set in the environment of the re-executed program: it never re-executes again, whatever it
// sees (glibc drops tunables in secure-execution mode, which would otherwise loop).
constexpr const char* kGuard = "STRATA_REEXECUTED";
}  // namespace

bool huge_page_malloc_configured() {
  const char* t = std::getenv("GLIBC_TUNABLES");
  return t && std::string(t).find(kTunable) != std::string::npos;
}

void reexec_with_huge_page_malloc(char** argv, bool force) {
  if (!argv || !argv[0] || std::getenv(kGuard) || getauxval(AT_SECURE) != 0) return;
  // Started through the dynamic loader by hand (/lib64/ld-linux-x86-64.so.2 ./strata ...): the
  // executable is the loader, whose arguments we no longer have.
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  if (n <= 0) return;
  self[n] = '\0';
  const std::string exe(self), name = exe.substr(exe.rfind('/') + 1);
  if (name.rfind("ld-", 0) == 0 && name.find(".so") != std::string::npos) return;
  const char* t = std::getenv("GLIBC_TUNABLES");
  const std::optional<std::string> before = t ? std::optional<std::string>(t) : std::nullopt;
  if (!huge_page_malloc_configured()) {
    std::string value = (before && !before->empty() ? *before + ":" : std::string()) + kTunable + "1";
    for (const std::string tunable : kKeepHeap)
      if (!before || before->find(tunable.substr(0, tunable.find('=') + 1)) == std::string::npos)
        value += ":" + tunable;
    if (setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  } else if (!force) {
    return;
  }
  setenv(kGuard, "1", 1);
  execv("/proc/self/exe", argv);  // the running binary, even if its path was replaced since
  // Failed: go on as we are, with the environment as it was.
  unsetenv(kGuard);
  if (before)
    setenv("GLIBC_TUNABLES", before->c_str(), 1);
  else
    unsetenv("GLIBC_TUNABLES");
}

}  // namespace strata

#include "strata/process.h"

#include <unistd.h>

#include <cstdlib>
#include <string>

namespace strata {

bool huge_page_malloc_configured() {
  const char* t = std::getenv("GLIBC_TUNABLES");
  return t && std::string(t).find("glibc.malloc.hugetlb=") != std::string::npos;
}

void reexec_with_huge_page_malloc(char** argv, bool force) {
  if (!argv || !argv[0]) return;
  if (!huge_page_malloc_configured()) {
    const char* t = std::getenv("GLIBC_TUNABLES");
    const std::string value = (t && *t ? std::string(t) + ":" : std::string()) + "glibc.malloc.hugetlb=1";
    if (setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  } else if (!force) {
    return;
  }
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  if (n <= 0) return;
  self[n] = '\0';
  execv(self, argv);  // returns only on failure: go on as we are
}

}  // namespace strata

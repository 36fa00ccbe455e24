// Uses the installed Strata SDK: the installed headers and library are the same version, and the
// volume of a unit right prism over the triangle (0,0,0), (1,0,0), (0,1,0) with height 2 is 1
// (area 1/2 times height 2).
#include <strata/exceptions.h>
#include <strata/prism.h>
#include <strata/version.h>

#include <cmath>
#include <cstdio>
#include <cstring>

int main() {
  std::printf("Strata %s (headers %s)\n", strata::version(), STRATA_VERSION_STRING);
  if (std::strcmp(strata::version(), STRATA_VERSION_STRING) != 0) {
    std::fprintf(stderr, "library version %s, headers %s\n", strata::version(), STRATA_VERSION_STRING);
    return 1;
  }
  using strata::Vec3;
  const Vec3 q0(0, 0, 0), q1(1, 0, 0), q2(0, 1, 0);
  const Vec3 up(0, 0, 2);
  const double volume = strata::prism_volume(q0 + up, q1 + up, q2 + up, q0, q1, q2);
  std::printf("prism volume: %.6f\n", volume);
  if (std::abs(volume - 1.0) > 1e-12) {
    std::fprintf(stderr, "expected 1, got %.17g\n", volume);
    return 1;
  }
  return 0;
}

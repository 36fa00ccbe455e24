// Uses the installed Strata SDK: the volume of a unit right prism over the triangle (0,0,0),
// (1,0,0), (0,1,0) with height 2 is 1 (area 1/2 times height 2).
#include <strata/exceptions.h>
#include <strata/prism.h>

#include <cmath>
#include <cstdio>

int main() {
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

#include "internal/serial_openmp.h"

// omp.h comes with the compiler; no -fopenmp here (it would switch on Eigen's own OpenMP paths).
#include <omp.h>

namespace strata::internal {

SerialOpenMp::SerialOpenMp()
    : max_active_levels_(omp_get_max_active_levels()), max_threads_(omp_get_max_threads()) {
  omp_set_max_active_levels(0);
  omp_set_num_threads(1);
}

SerialOpenMp::~SerialOpenMp() {
  omp_set_num_threads(max_threads_);
  omp_set_max_active_levels(max_active_levels_);
}

}  // namespace strata::internal

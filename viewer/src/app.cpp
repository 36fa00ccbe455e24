#include <stdexcept>

#include "options.h"

int run_window(const strata::viewer::Options&) {
  throw std::runtime_error("the window is not built yet");
}

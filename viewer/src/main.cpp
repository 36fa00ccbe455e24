//! \file main.cpp
//! strata-viewer: the interactive viewer of layered models and scans (issue 6), or with
//! --screenshot a headless renderer. Every error prints "strata-viewer: error: <message>" and
//! exits 1.
#include <cstdio>
#include <exception>
#include <iostream>

#include "app.h"
#include "headless.h"
#include "options.h"
#include "strata/process.h"

int main(int argc, char** argv) {
  strata::reexec_with_huge_page_malloc(argv);  // the solver's big arrays on huge pages
  using namespace strata::viewer;
  try {
    const Options options = parse_options(argc, argv);
    if (options.help) {
      std::cout << usage_text();
      return 0;
    }
    if (!options.screenshot.empty() && options.script_drag.empty()) {
      std::cout << run_headless(options) << std::endl;
      return 0;
    }
    return run_window(options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "strata-viewer: error: %s\n", e.what());
    return 1;
  } catch (...) {
    std::fprintf(stderr, "strata-viewer: error: unknown failure\n");
    return 1;
  }
}

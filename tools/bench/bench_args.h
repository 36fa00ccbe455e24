// Shared by the benchmark programs whose options all take one value (--name VALUE).
#pragma once

#include <iostream>
#include <string>

namespace strata::bench {

//! For a command line of --name VALUE pairs: with --help or -h anywhere, prints \p usage on stdout
//! and returns 0; with an option left without its value, prints it on stderr and returns 2;
//! otherwise returns -1 (go on and parse the pairs).
inline int help_or_usage_error(int argc, char** argv, const char* usage) {
  for (int a = 1; a < argc; ++a)
    if (std::string(argv[a]) == "--help" || std::string(argv[a]) == "-h") {
      std::cout << usage;
      return 0;
    }
  if (argc % 2 == 0) {
    std::cerr << usage;
    return 2;
  }
  return -1;
}

}  // namespace strata::bench

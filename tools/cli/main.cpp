// The `strata` command-line tool: parses the command line, runs one subcommand and turns every
// error into a one-line message and an exit code (0 ok, 1 error, 2 usage error; `reconstruct
// --strict` returns 3 for a result that misses a target).
#include <exception>
#include <iostream>
#include <new>
#include <vector>

#include "common.h"
#include "strata/exceptions.h"
#include "strata/process.h"
#include "strata/version.h"

int main(int argc, char** argv) {
  strata::reexec_with_huge_page_malloc(argv);  // the solver's big arrays on huge pages
  using namespace strata::cli;
  CLI::App app{
      "strata: multiresolution detail of scanned surfaces with displacement volumes.\n"
      "Encodes a detail mesh over a base mesh and rebuilds it over an edited base,\n"
      "by displacement volumes (prism volumes preserved) or by displacement vectors.",
      "strata"};
  app.set_version_flag("--version", std::string("strata ") + strata::version(),
                       "Print the version of the strata tool and its SDK and exit");
  app.require_subcommand(1);
  app.get_formatter()->column_width(34);

  try {
    std::vector<Subcommand> commands = {register_reconstruct(app), register_stats(app),
                                        register_generate(app),    register_demo(app),
                                        register_deform(app),      register_cage(app)};
    for (Subcommand& c : register_model_commands(app)) commands.push_back(std::move(c));
    require_numbers(app);
    app.parse(argc, argv);
    for (const Subcommand& c : commands)
      if (c.app->parsed()) {
        const int rc = c.run();
        // Output that did not reach standard output (a full disk, a closed pipe) is a failure: a
        // `stats --json > /dev/full` exited 0 with nothing written.
        std::cout.flush();
        if (!std::cout) {
          std::cerr << "strata: error: writing to standard output failed" << std::endl;
          return 1;
        }
        return rc;
      }
    std::cerr << "strata: error: no subcommand given" << std::endl;
    return 2;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    const auto selected = app.get_subcommands();
    std::cerr << "strata: error: " << e.what() << "\n"
              << "Run 'strata" << (selected.empty() ? "" : " " + selected.front()->get_name())
              << " --help' for usage." << std::endl;
    return 2;
  } catch (const strata::Error& e) {
    std::cerr << "strata: error: " << e.what() << std::endl;
  } catch (const std::bad_alloc&) {
    std::cerr << "strata: error: out of memory" << std::endl;
  } catch (const std::exception& e) {
    std::cerr << "strata: error: " << e.what() << std::endl;
  }
  return 1;
}

// `strata cage fit`: a Loop control cage fitted to a scan (the coarsest band and a subdivision base).
#include <iostream>
#include <memory>
#include <string>

#include "common.h"
#include "strata/cage_fit.h"
#include "strata/cage_io.h"
#include "strata/exceptions.h"

namespace strata::cli {

namespace {

struct CageFitCmdOptions {
  std::string scan;
  std::string output;
  std::string report;
  CageFitOptions fit;
  bool quiet = false;
};

int run_cage_fit(const CageFitCmdOptions& o) {
  check_outputs(o.output, {}, o.report, {o.scan});
  check_cage_format(o.output);  // before the fit, not after it
  const Log log(o.quiet);
  Stopwatch sw;
  log.phase("reading " + o.scan);
  const NamedMesh scan = read_scan(o.scan);
  const double read_seconds = sw.seconds();
  log.phase("fitting a cage to " + std::to_string(scan.mesh.num_faces()) + " faces");
  const CageFit fit = [&] {
    try {
      return fit_cage(scan.mesh, o.fit);
    } catch (const InvalidInput& e) {
      throw InvalidInput(scan.name + ": " + e.what());  // name the file
    }
  }();
  sw.restart();
  StagedOutputs staged;  // the cage lands only with its report
  staged.write(o.output, [&](const std::string& p) { write_cage(fit.cage, p); });
  const double write_seconds = sw.seconds();
  const json r{{"scan", mesh_json(scan.mesh, scan.name)},
               {"cage",
                {{"path", o.output},
                 {"vertices", fit.cage.num_vertices()},
                 {"faces", fit.cage.num_faces()},
                 {"scheme", "loop"}}},
               {"fit",
                {{"rounds", fit.rounds},
                 {"smoothness", o.fit.smoothness},
                 {"smoothing_steps", o.fit.smoothing_steps},
                 {"rms_error", fit.rms_error},
                 {"max_error", fit.max_error},
                 {"scan_rms_distance", fit.scan_rms_distance},
                 {"scan_max_distance", fit.scan_max_distance},
                 {"scan_projection_fallback", fit.scan_fallback},
                 {"errors_relative_to", "scan bounding-box diagonal"}}},
               {"timing",
                {{"read", read_seconds},
                 {"smooth", fit.seconds_smooth},
                 {"decimate", fit.seconds_decimate},
                 {"fit", fit.seconds_fit},
                 {"write", write_seconds}}}};
  if (!o.report.empty()) staged.write(o.report, [&](const std::string& p) { write_json_report(r, p); });
  staged.commit();
  std::cout << "cage                 " << o.output << " (" << fit.cage.num_faces() << " faces, "
            << fit.cage.num_vertices() << " vertices, Loop)\n"
            << "fit to smoothed scan rms " << sci(fit.rms_error) << ", max " << sci(fit.max_error)
            << " of the bbox diagonal\n"
            << "scan to limit        rms " << sci(fit.scan_rms_distance) << ", max "
            << sci(fit.scan_max_distance) << " (" << fit.scan_fallback << " of " << scan.mesh.num_vertices()
            << " vertices took the projection fallback)\n"
            << "time                 "
            << fixed(fit.seconds_smooth + fit.seconds_decimate + fit.seconds_fit, 2) << " s (smooth "
            << fixed(fit.seconds_smooth, 2) << ", decimate " << fixed(fit.seconds_decimate, 2) << ", fit "
            << fixed(fit.seconds_fit, 2) << ")" << std::endl;
  return 0;
}

}  // namespace

Subcommand register_cage(CLI::App& parent) {
  auto o = std::make_shared<CageFitCmdOptions>();
  CLI::App* app = parent.add_subcommand("cage", "Subdivision control cages");
  app->require_subcommand(1);
  CLI::App* fit = app->add_subcommand(
      "fit",
      "Fit a Loop control cage to a scan: the scan is smoothed and decimated to the cage's face count,\n"
      "then the cage is solved so that its limit surface approximates the smoothed scan in least squares.");
  fit->add_option("scan", o->scan, "Scan mesh (.obj, .off, .ply, .stl)")->required();
  fit->add_option("-o,--output", o->output, "Cage to write (.obj, .off, .ply)")->required();
  fit->add_option("--faces", o->fit.faces,
                  "Cage faces (default: 1% of the scan's faces, at least " +
                      std::to_string(o->fit.min_faces) + " but at most a quarter of the scan's)")
      ->check(at_least(0));
  fit->add_option("--smoothness", o->fit.smoothness, "Weight of the cage's smoothness term")
      ->check(in_range(0.0, 1e12))
      ->capture_default_str();
  fit->add_option("--smoothing-steps", o->fit.smoothing_steps,
                  "Taubin smoothing steps applied to the scan first")
      ->check(in_range(0, 1000))
      ->capture_default_str();
  fit->add_option("--rounds", o->fit.rounds, "Rounds of projection and least-squares solve")
      ->check(in_range(1, 100))
      ->capture_default_str();
  fit->add_option("--report", o->report, "Write the fitting error and timing as JSON");
  fit->add_flag("-q,--quiet", o->quiet, "No progress lines on stderr");
  return {app, [o] { return run_cage_fit(*o); }};
}

}  // namespace strata::cli

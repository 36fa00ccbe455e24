// Layered models (issue 5): `strata build`, `strata info`, `strata edit`, `strata amplitude` and
// `strata export`.
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "common.h"
#include "strata/atomic_file.h"
#include "strata/cage_io.h"
#include "strata/edit_script.h"
#include "strata/exceptions.h"
#include "strata/json_check.h"
#include "strata/layers/model.h"
#include "strata/mesh_io.h"

namespace strata::cli {

namespace {

namespace fs = std::filesystem;
using layers::LayeredModel;

// --------------------------------------------------------------------------------------------
// strata build

struct BuildCmdOptions {
  std::vector<std::string> scans;
  std::string output;
  std::string out_dir;
  std::string report;
  int bands = 3;
  int cage_faces = 0;
  bool quiet = false;
};

// A progress bar on stderr: redrawn in place on a terminal, one line per step otherwise.
class ProgressBar {
 public:
  ProgressBar(int total, bool quiet) : total_(total), quiet_(quiet), tty_(isatty(STDERR_FILENO) != 0) {}
  void show(int done, const std::string& label) const {
    if (quiet_) return;
    constexpr int width = 30;
    const int filled = total_ > 0 ? done * width / total_ : width;
    std::string bar(filled, '#');
    bar.resize(width, '-');
    std::cerr << (tty_ ? "\r" : "") << "strata: [" << bar << "] " << done << "/" << total_ << " " << label
              << (tty_ ? "\x1b[K" : "\n") << std::flush;
  }
  void finish() const {
    if (!quiet_ && tty_) std::cerr << "\n";
  }

 private:
  int total_;
  bool quiet_, tty_;
};

json band_summary_json(const LayeredModel& model) {
  json bands = json::array();
  for (int k = 0; k < model.num_bands(); ++k) {
    const layers::Band& b = model.band(k);
    const layers::DetailMagnitude m = model.detail_magnitude(k);
    json j{{"band", k}, {"mean_edge_length", m.mean_edge_length}};
    if (k == 0) {
      j["kind"] = "cage";
      j["vertices"] = b.cage.num_vertices();
      j["faces"] = b.cage.num_faces();
      j["creases"] = b.tags.creases.size();
      j["corners"] = b.tags.corners.size();
    } else {
      j["kind"] = "triangles";
      j["vertices"] = b.mesh.num_vertices();
      j["faces"] = b.mesh.num_faces();
      j["amplitude"] = b.amplitude;
      j["detail_rms"] = m.rms;
      j["detail_max"] = m.max;
      j["encoding"] = encoding_json(b.encoding.report);
      if (!b.attributes.empty()) j["attributes"] = attributes_json(b.attributes);
    }
    bands.push_back(j);
  }
  return bands;
}

// A model output: a writable path ending in .strata (any other name was written as a model).
void check_model_output_path(const std::string& path) {
  check_output_path(path);
  const std::string ext = lower_extension(path);
  if (ext != ".strata") throw IoError(path + ": a layered model is written as a .strata file");
}

int run_build(const BuildCmdOptions& o) {
  // Usage errors (exit 2, with the pointer to --help), as CLI11's own.
  if (o.scans.size() > 1 && o.out_dir.empty())
    throw CLI::ValidationError(
        "several scans need --out-dir (each model is written as DIR/<scan name>.strata)");
  if (!o.output.empty() && !o.out_dir.empty())
    throw CLI::ValidationError("give either -o or --out-dir, not both");
  if (o.output.empty() && o.out_dir.empty())
    throw CLI::ValidationError("give -o MODEL.strata or --out-dir DIR");
  auto model_path = [&](const std::string& scan_path) {
    return o.output.empty()
               ? (fs::path(o.out_dir) / (fs::path(scan_path).stem().string() + ".strata")).string()
               : o.output;
  };
  // Two scans of one name in different directories would write one model, the second over the
  // first, both reported built.
  if (!o.out_dir.empty())
    for (std::size_t i = 0; i < o.scans.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        if (model_path(o.scans[i]) == model_path(o.scans[j]))
          throw InvalidInput(o.scans[j] + " and " + o.scans[i] + " would both be built into " +
                             model_path(o.scans[i]) + "; build them into different --out-dir directories");
  if (!o.out_dir.empty()) ensure_directory(o.out_dir);
  if (!o.output.empty()) check_model_output_path(o.output);
  if (!o.report.empty()) check_output_path(o.report);
  // Every model's path, not only -o's: `--out-dir od --report od/scan.strata` wrote the report over
  // the model just built and exited 0.
  std::vector<std::string> outputs{o.report};
  for (const std::string& scan : o.scans) outputs.push_back(model_path(scan));
  check_output_names(outputs, o.scans);
  // With -o, the model lands only with its report; with --out-dir each model is written as it is
  // built (a batch keeps what it built), the report at the end.
  StagedOutputs staged;
  const Log log(o.quiet);
  ProgressBar bar(static_cast<int>(o.scans.size()), o.quiet);
  json results = json::array();
  int failed = 0;
  for (std::size_t i = 0; i < o.scans.size(); ++i) {
    const std::string& scan_path = o.scans[i];
    const std::string out = model_path(scan_path);
    bar.show(static_cast<int>(i), scan_path);
    json r{{"scan", scan_path}, {"model", out}};
    Stopwatch sw;
    try {
      NamedMesh scan = read_scan(scan_path);
      read_companions(scan.attributes, scan_path);  // the model carries them
      layers::BuildOptions bo;
      bo.bands = o.bands;
      bo.cage.faces = o.cage_faces;
      LayeredModel model = [&] {
        try {
          return LayeredModel::build(scan.mesh, bo);
        } catch (const InvalidInput& e) {
          throw InvalidInput(scan.name + ": " + e.what());
        } catch (const SolverError& e) {
          throw SolverError(scan.name + ": " + e.what());
        }
      }();
      model.set_attributes(model.num_bands() - 1, scan.attributes);
      const double build_seconds = sw.seconds();
      std::string written = out;
      if (o.output.empty())
        write_model(model, out);
      else
        staged.write(out, [&](const std::string& p) {
          write_model(model, p);
          written = p;
        });
      r["ok"] = true;
      r["faces"] = scan.mesh.num_faces();
      r["vertices"] = scan.mesh.num_vertices();
      r["reoriented_faces"] = scan.reoriented_faces;
      r["bands"] = band_summary_json(model);
      r["build_seconds"] = build_seconds;
      r["seconds"] = sw.seconds();
      r["bytes"] = fs::file_size(written);
    } catch (const Error& e) {
      ++failed;
      r["ok"] = false;
      r["error"] = e.what();
      r["seconds"] = sw.seconds();
      // Errors go to stderr with -q too (-q quiets progress; a failure was only in the table).
      std::cerr << (!o.quiet && isatty(STDERR_FILENO) ? "\n" : "") << "strata: error: " << e.what()
                << std::endl;
    }
    results.push_back(r);
  }
  bar.show(static_cast<int>(o.scans.size()), "done");
  bar.finish();
  std::cout << "scan                          faces   bands  time [s]  model\n";
  for (const json& r : results) {
    std::string name = r["scan"].get<std::string>();
    if (name.size() > 28) name = "..." + name.substr(name.size() - 25);
    name.resize(28, ' ');
    if (r["ok"].get<bool>())
      std::cout << name << "  " << r["faces"].get<int>() << "  " << r["bands"].size() << "  "
                << fixed(r["seconds"].get<double>(), 2) << "  " << r["model"].get<std::string>() << " ("
                << r["bytes"].get<std::uintmax_t>() << " bytes)\n";
    else
      std::cout << name << "  FAILED: " << r["error"].get<std::string>() << "\n";
  }
  std::cout << results.size() - failed << " built, " << failed << " failed" << std::endl;
  const json report{{"command", "build"}, {"models", results}};
  if (o.output.empty() || failed) {
    if (!o.report.empty()) write_json_report(report, o.report);
  } else {
    if (!o.report.empty())
      staged.write(o.report, [&](const std::string& p) { write_json_report(report, p); });
    staged.commit();
  }
  return failed ? 1 : 0;
}

// --------------------------------------------------------------------------------------------
// strata info

struct InfoCmdOptions {
  std::string model;
  bool as_json = false;
};

int run_info(const InfoCmdOptions& o) {
  const LayeredModel model = layers::read_model(o.model);
  const json bands = band_summary_json(model);
  const double diag = bbox_diagonal(model.band(model.num_bands() - 1).mesh.vertices);
  if (o.as_json) {
    json h = json::array();
    // An entry that is not JSON (a file may keep text) is shown as a string: parse() without
    // exceptions gave a "discarded" value, printed as <discarded>, and the output was no JSON.
    // So is one beyond the header's limits (as write_model() stores it): an entry of 100k nested
    // brackets, which a file may hold as text, was parsed and dumped recursively and overflowed
    // the stack (a review, thirty-eighth session).
    JsonLimits entry_limits;
    entry_limits.max_depth -= 2;  // an entry sits two levels below the printed object
    for (const std::string& e : model.history()) {
      json v = json_structure_problem(e, entry_limits).empty() ? json::parse(e, nullptr, false) : json(e);
      h.push_back(v.is_discarded() ? json(e) : std::move(v));
    }
    // Paths and text that are not UTF-8 are printed with U+FFFD (the strict dump threw a JSON
    // library error naming no file).
    std::cout << json{{"model", o.model},
                      {"bytes", fs::file_size(o.model)},
                      {"bands", bands},
                      {"finest_bbox_diagonal", diag},
                      {"history", h}}
                     .dump(2, ' ', false, json::error_handler_t::replace)
              << std::endl;
    return 0;
  }
  std::cout
      << o.model << ": " << model.num_bands() << " bands, " << fs::file_size(o.model) << " bytes\n"
      << "band  kind       vertices     faces  amplitude  edge length  detail rms  detail max  fallbacks\n";
  for (const json& b : bands) {
    const bool cage = b["kind"] == "cage";
    char line[256];
    std::snprintf(line, sizeof line, "%4d  %-9s %9d %9d  %9s  %11.3e  %10s  %10s  %9s\n",
                  b["band"].get<int>(), cage ? "cage" : "triangles", b["vertices"].get<int>(),
                  b["faces"].get<int>(), cage ? "-" : fixed(b["amplitude"].get<double>(), 3).c_str(),
                  b["mean_edge_length"].get<double>(),
                  cage ? "-" : sci(b["detail_rms"].get<double>()).c_str(),
                  cage ? "-" : sci(b["detail_max"].get<double>()).c_str(),
                  cage ? "-" : std::to_string(b["encoding"]["fallback"].get<int>()).c_str());
    std::cout << line;
  }
  std::cout << "Band 0 is the cage's limit surface (shape longer than about twice its edge length); band k\n"
               "holds the detail between band k-1's resolution and its own, as displacement volumes over\n"
               "band k-1. Detail magnitudes are |p - q| at rest (finest band bbox diagonal "
            << sci(diag) << ").\n"
            << "history: " << model.history().size() << " operations\n";
  // Colours, texture coordinates and materials (the scan's, on the finest band).
  for (const json& b : bands)
    if (b.contains("attributes")) {
      const json& a = b["attributes"];
      std::cout << "band " << b["band"].get<int>() << " carries vertex colours "
                << a["vertex_colors"].get<std::string>() << ", texture coordinates "
                << a["texture_coordinates"].get<std::string>() << ", " << a["materials"].get<std::size_t>()
                << " materials, " << a["texture_files"].size() << " texture images, "
                << a["companion_files"].size() << " files (material libraries, images)\n";
    }
  // Control characters escaped: a history entry is the file's text, and raw newlines or terminal
  // escapes in it could fake lines of this output ("strata: error: ...").
  for (const std::string& e : model.history()) {
    std::string shown;
    for (const char c : e) {
      const auto u = static_cast<unsigned char>(c);
      if (u < 0x20 || u == 0x7f) {
        char esc[8];
        std::snprintf(esc, sizeof esc, "\\x%02x", u);
        shown += esc;
      } else {
        shown += c;
      }
    }
    std::cout << "  " << shown << "\n";
  }
  std::cout << std::flush;
  return 0;
}

// --------------------------------------------------------------------------------------------
// strata edit / strata amplitude

struct EditCmdOptions {
  std::string model;
  std::string output;
  std::string edit;
  std::string report;
  int band = 0;
  double scale = 1.0;
  bool intersections = false;
  bool quiet = false;
  bool strict = false;  // exit 3 when the result misses a target (the report's "warnings")
};

bool volumes(const LayeredModel& model) {
  return model.options().method == EditOptions::Method::Volumes;
}

// Whether the change solved the edited band's own region by volumes (an edit of a triangle
// band; not amplitude changes, cage edits or vectors).
bool edit_solved(const layers::CascadeReport& r, const LayeredModel& model) {
  return volumes(model) && r.edited_band > 0 && r.edit_volume.mean_abs_target > 0;
}

// What makes a change miss a target (volumes): the edited band's solve or a rebuilt band's not
// converged; \p where names the change (e.g. "edit 3").
void add_cascade_warnings(const layers::CascadeReport& r, const LayeredModel& model, const std::string& where,
                          json& warnings) {
  if (!volumes(model)) return;
  const double tolerance = model.options().reconstruct.tolerance;
  if (edit_solved(r, model) && !r.edit_stats.converged)
    warnings.push_back(where + ": band " + std::to_string(r.edited_band) + ": " +
                       not_converged_text(r.edit_stats, tolerance));
  for (const layers::BandRebuild& b : r.rebuilt)
    if (b.solved_prisms > 0 && !b.stats.converged)
      warnings.push_back(where + ": band " + std::to_string(b.band) +
                         " rebuilt: " + not_converged_text(b.stats, tolerance));
}

json cascade_json(const layers::CascadeReport& r, const LayeredModel& model) {
  json rebuilt = json::array();
  // The solver's statistics (the deform report's "iterations": cycles, retries, fallbacks, fold
  // repairs, new pairs, each phase's seconds), for a volume solve.
  const bool volumes = model.options().method == EditOptions::Method::Volumes;
  for (const layers::BandRebuild& b : r.rebuilt) {
    rebuilt.push_back({{"band", b.band},
                       {"solved_vertices", b.solved_vertices},
                       {"rest_vertices", b.rest_vertices},
                       {"rigid_vertices", b.rigid_vertices},
                       {"solved_prisms", b.solved_prisms},
                       {"volume_metrics", volume_metrics_json(b.volume)},
                       {"solver_converged", b.stats.converged},
                       {"seconds", b.seconds}});
    if (volumes && b.solved_prisms > 0) rebuilt.back()["iterations"] = iterations_json(b.stats);
  }
  json j{{"edited_band", r.edited_band},
         {"edit_seconds", r.edit_seconds},
         {"edit_volume_metrics", volume_metrics_json(r.edit_volume)},
         {"rebuilt", rebuilt},
         {"total_seconds", r.total_seconds}};
  if (edit_solved(r, model)) {
    j["edit_solver_converged"] = r.edit_stats.converged;
    if (volumes) j["edit_iterations"] = iterations_json(r.edit_stats);
  }
  return j;
}

void print_cascade(const layers::CascadeReport& r) {
  std::cout << "band " << r.edited_band << " edited in " << fixed(r.edit_seconds, 2) << " s\n";
  for (const layers::BandRebuild& b : r.rebuilt)
    std::cout << "band " << b.band << ": " << b.solved_vertices << " vertices solved (" << b.solved_prisms
              << " prisms), " << b.rest_vertices << " back at rest, " << b.rigid_vertices
              << " moved rigidly; volume error max " << sci(b.volume.max_relative_error) << ", rms "
              << sci(b.volume.rms_relative_error) << "; " << fixed(b.seconds, 2) << " s\n";
}

// Runs \p change on the model read from o.model, then writes it to o.output, with an optional
// count of the finest band's new self-intersections and a JSON report. \p change adds to the
// warnings what makes its result miss a target.
int run_change(const EditCmdOptions& o, const std::string& command,
               const std::function<json(LayeredModel&, const Log&, json& warnings)>& change) {
  check_model_output_path(o.output);
  if (!o.report.empty()) check_output_path(o.report);
  check_output_names({o.output, o.report}, {o.model, o.edit});
  const Log log(o.quiet);
  Stopwatch sw;
  log.phase("reading " + o.model);
  LayeredModel model = layers::read_model(o.model);
  const int finest = model.num_bands() - 1;
  const std::vector<Vec3> before = model.band(finest).mesh.vertices;
  json r{{"command", command}, {"model", o.model}, {"output", o.output}, {"read_seconds", sw.seconds()}};
  json warnings = json::array();
  r["changes"] = change(model, log, warnings);
  if (o.intersections) {
    log.phase("counting self-intersections of the finest band");
    const TimedIntersections in =
        find_intersections(before, model.band(finest).mesh.faces, "the finest band before");
    const TimedIntersections out = find_intersections(model.band(finest).mesh.vertices,
                                                      model.band(finest).mesh.faces, "the finest band after");
    const std::size_t fresh = count_new_intersections_at_least(in.result, out.result);
    const bool cut_short = in.result.truncated || out.result.truncated;
    r["finest_band_intersections"] = {{"input_pairs", in.result.num_pairs},
                                      {"output_pairs", out.result.num_pairs},
                                      {"new_pairs", fresh},
                                      {"cut_short", cut_short},
                                      {"seconds", in.seconds + out.seconds}};
    std::cout << "finest band: " << in.result.num_pairs << " intersecting pairs before, "
              << out.result.num_pairs << " after, " << fresh << " new" << cut_short_note(cut_short) << "\n";
    if (volumes(model))
      if (std::string w = new_pairs_warning(in.result, out.result); !w.empty())
        warnings.push_back("finest band: " + w);
  }
  r["warnings"] = warnings;
  sw.restart();
  log.phase("writing " + o.output);
  StagedOutputs staged;  // the model lands only with its report
  staged.write(o.output, [&](const std::string& p) { write_model(model, p); });
  r["write_seconds"] = sw.seconds();
  if (!o.report.empty()) staged.write(o.report, [&](const std::string& p) { write_json_report(r, p); });
  staged.commit();
  std::cout << "wrote " << o.output << std::endl;
  return finish_warnings(warnings, o.strict, true);
}

// --band within the model's bands (from \p first): named with the model, not by the SDK's check.
void check_band_option(const EditCmdOptions& o, const LayeredModel& model, int first) {
  if (o.band >= model.num_bands())
    throw InvalidInput("--band " + std::to_string(o.band) + " is out of range: " + o.model + " has bands " +
                       std::to_string(first) + " to " + std::to_string(model.num_bands() - 1));
}

int run_edit(const EditCmdOptions& o) {
  const std::string text = read_file_bytes(o.edit);
  const EditScript script = parse_edit_script(text, o.edit);
  // The raw edits, for the model's history (provenance).
  json raw = json::parse(text, nullptr, false);
  if (raw.is_object() && raw.contains("edits")) raw = raw["edits"];
  if (!raw.is_array()) raw = json::array({raw});
  return run_change(o, "edit", [&](LayeredModel& model, const Log& log, json& warnings) {
    // The band is the command line's, not the script's (it was reported as the script's edit 0).
    check_band_option(o, model, 0);
    json out = json::array();
    for (std::size_t i = 0; i < script.edits.size(); ++i) {
      log.phase("edit " + std::to_string(i + 1) + " of " + std::to_string(script.edits.size()) + " on band " +
                std::to_string(o.band));
      const json prov{{"script", o.edit}, {"index", i}, {"edit", i < raw.size() ? raw[i] : json()}};
      try {
        const layers::CascadeReport c =
            model.edit(o.band, script.edits[i], prov.dump(-1, ' ', false, json::error_handler_t::replace));
        print_cascade(c);
        out.push_back(cascade_json(c, model));
        add_cascade_warnings(c, model, "edit " + std::to_string(i + 1), warnings);
      } catch (const InvalidInput& e) {
        throw InvalidInput(o.edit + ": edit " + std::to_string(i + 1) + ": " + e.what());
      } catch (const SolverError& e) {  // which edit of a long script failed to solve
        throw SolverError(o.edit + ": edit " + std::to_string(i + 1) + ": " + e.what());
      }
    }
    return out;
  });
}

int run_amplitude(const EditCmdOptions& o) {
  return run_change(o, "amplitude", [&](LayeredModel& model, const Log& log, json& warnings) {
    check_band_option(o, model, 1);
    log.phase("band " + std::to_string(o.band) + " amplitude " + fixed(o.scale, 3));
    const layers::CascadeReport c = model.set_amplitude(o.band, o.scale);
    print_cascade(c);
    add_cascade_warnings(c, model, "amplitude", warnings);
    return json::array({cascade_json(c, model)});
  });
}

// --------------------------------------------------------------------------------------------
// strata export

struct ExportCmdOptions {
  std::string model;
  std::string output;
  int band = -1;
  int resolution = 4;
  bool resolution_given = false;
  bool cage = false;
};

int run_export(const ExportCmdOptions& o) {
  if (o.resolution_given && o.band != 0)
    throw CLI::ValidationError("--resolution applies to band 0 (the limit surface) only; add --band 0");
  check_mesh_output_path(o.output);
  check_output_names({o.output}, {o.model});
  const LayeredModel model = layers::read_model(o.model);
  const int k = o.band < 0 ? model.num_bands() - 1 : o.band;
  if (k >= model.num_bands())
    throw InvalidInput(o.model + ": band " + std::to_string(k) + " out of range (the model has bands 0 .. " +
                       std::to_string(model.num_bands() - 1) + ")");
  if (o.cage) {
    // Polygons as they are (a Catmull-Clark cage keeps its quads); not STL (check_cage_format()).
    const PolyMesh& c = model.band(0).cage;
    write_cage(c, o.output);
    std::cout << "wrote " << o.output << " (control cage, " << c.num_vertices() << " vertices, "
              << c.num_faces() << " faces)" << std::endl;
    return 0;
  }
  TriMesh mesh;
  try {
    mesh = model.band_mesh(k, o.resolution);
  } catch (const InvalidInput& e) {
    // The tessellation's limit: name the option that set it.
    if (k != 0) throw;
    throw InvalidInput(o.model + ": band 0 at --resolution " + std::to_string(o.resolution) + ": " +
                       e.what());
  }
  // A triangle band's colours and texture coordinates (the scan's, on the finest band).
  const MeshAttributes none;
  const MeshAttributes attributes = output_attributes(k >= 1 ? model.band(k).attributes : none, o.output);
  warn_stl_drops_vertices(mesh, o.output);
  warn_attributes_not_stored(attributes, o.output);
  validate_result(mesh, o.model + ": band " + std::to_string(k), o.output);  // the model's fault
  write_mesh(mesh, attributes, o.output);
  write_companions(attributes, o.output);
  std::cout << "wrote " << o.output << " (band " << k << ", " << mesh.num_vertices() << " vertices, "
            << mesh.num_faces() << " faces)" << std::endl;
  return 0;
}

// The options `edit` and `amplitude` share: the output model, the report, intersections, quiet.
void add_change_options(CLI::App& app, EditCmdOptions& o) {
  app.add_option("-o,--output", o.output, "Model to write")->required();
  app.add_option("--report", o.report, "Write a JSON report");
  app.add_flag("--intersections", o.intersections,
               "Count the finest band's self-intersections before and after");
  app.add_flag("-q,--quiet", o.quiet, "No progress lines on stderr");
  app.add_flag("--strict", o.strict,
               "Exit with 3 (model written) when the result misses a target: with volumes, a solve not "
               "converged, or new intersecting pairs in the finest band (with --intersections)");
}

}  // namespace

std::vector<Subcommand> register_model_commands(CLI::App& parent) {
  std::vector<Subcommand> out;
  {
    auto o = std::make_shared<BuildCmdOptions>();
    CLI::App* app = parent.add_subcommand(
        "build",
        "Build layered models from scans: a control cage (band 0) fitted to the scan, smoother\n"
        "intermediate bands, and the scan itself as the finest band, each encoded as displacement\n"
        "volumes over the next coarser band. Several scans need --out-dir; a bad file is reported\n"
        "and skipped, and the exit code is 1 if any failed.");
    app->add_option("scans", o->scans, "Scan meshes (.obj, .off, .ply, .stl)")->required();
    app->add_option("-o,--output", o->output, "Model to write (one scan)");
    app->add_option("--out-dir", o->out_dir, "Directory for the models (DIR/<scan name>.strata)");
    app->add_option("--bands", o->bands, "Bands in all, the cage included (2 to 8)")
        ->check(in_range(2, 8))
        ->capture_default_str();
    app->add_option(
           "--cage-faces", o->cage_faces,
           "Cage faces (default: 1% of the scan's, at least 400 but at most a quarter of the scan's)")
        ->check(at_least(0));
    app->add_option("--report", o->report, "Write a JSON report of every model");
    app->add_flag("-q,--quiet", o->quiet, "No progress on stderr");
    out.push_back({app, [o] { return run_build(*o); }});
  }
  {
    auto o = std::make_shared<InfoCmdOptions>();
    CLI::App* app = parent.add_subcommand("info",
                                          "Describe a layered model: its bands, their sizes, amplitudes and "
                                          "detail magnitudes, and its history.");
    app->add_option("model", o->model, "Model (.strata)")->required();
    app->add_flag("--json", o->as_json, "Print JSON");
    out.push_back({app, [o] { return run_info(*o); }});
  }
  {
    auto o = std::make_shared<EditCmdOptions>();
    CLI::App* app = parent.add_subcommand(
        "edit",
        "Edit one band of a layered model with an edit script (the format of 'strata deform'): band 0\n"
        "selects cage vertices, band k its vertices. The finer bands are rebuilt in cascade.");
    app->add_option("model", o->model, "Model (.strata)")->required();
    app->add_option("--band", o->band, "Band to edit")->required()->check(at_least(0));
    app->add_option("--edit", o->edit, "Edit script (JSON)")->required();
    add_change_options(*app, *o);
    out.push_back({app, [o] { return run_edit(*o); }});
  }
  {
    auto o = std::make_shared<EditCmdOptions>();
    CLI::App* app = parent.add_subcommand(
        "amplitude",
        "Scale one band's detail: 0 mutes it, 1 keeps it, above 1 exaggerates and below 0 inverts it.\n"
        "The finer bands are rebuilt in cascade.");
    app->add_option("model", o->model, "Model (.strata)")->required();
    app->add_option("--band", o->band, "Band (1 or more)")->required()->check(above(0));
    // A number (require_numbers()) within LayeredModel::set_amplitude()'s bound, checked here too so
    // that the usage error names --scale.
    app->add_option("--scale", o->scale, "Amplitude, within +-1000")
        ->required()
        ->check(in_range(-1000, 1000));
    add_change_options(*app, *o);
    out.push_back({app, [o] { return run_amplitude(*o); }});
  }
  {
    auto o = std::make_shared<ExportCmdOptions>();
    CLI::App* app = parent.add_subcommand(
        "export", "Write one band of a layered model as a mesh (default: the finest band, the edited scan).");
    app->add_option("model", o->model, "Model (.strata)")->required();
    app->add_option("-o,--output", o->output, "Mesh to write (.obj, .off, .ply, .stl)")->required();
    CLI::Option* band = app->add_option("--band", o->band, "Band (0: the cage's limit surface, tessellated)")
                            ->check(at_least(0));
    CLI::Option* resolution = app->add_option("--resolution", o->resolution, "Band 0: segments per ptex edge")
                                  ->check(above(0))
                                  ->capture_default_str()
                                  ->each([o](const std::string&) { o->resolution_given = true; });
    // Options the cage does not use are refused rather than ignored.
    app->add_flag("--cage", o->cage, "Write the control cage itself")->excludes(band)->excludes(resolution);
    out.push_back({app, [o] { return run_export(*o); }});
  }
  return out;
}

}  // namespace strata::cli

// `strata deform`: region edits of a mesh from an edit script (paper, section 5).
#include <iostream>
#include <memory>
#include <string>

#include "common.h"
#include "strata/edit_script.h"
#include "strata/editing.h"
#include "strata/exceptions.h"
#include "strata/mesh_io.h"

namespace strata::cli {

namespace {

struct DeformCmdOptions {
  std::string input;
  std::string edit;
  std::string method = "volumes";
  std::string output;
  std::string base_output;  // empty: not written
  std::string report;       // empty: no report
  double smoothing = 0.25;
  bool quiet = false;
};

json edit_json(const RegionEditor& editor, const EditResult& r, double select_seconds, double metrics_seconds) {
  const EditTimes& t = r.times;
  json j{{"region_vertices", editor.region_vertices().size()},
         {"handle_vertices", editor.handle_vertices().size()},
         {"region_faces", editor.region_faces()},
         {"encoding", encoding_json(editor.encoding().report)},
         {"volume_metrics", volume_metrics_json(r.volume)},
         {"timing_seconds",
          {{"select", select_seconds},
           {"decompose", t.decompose},
           {"encode", t.encode},
           {"setup", t.setup},
           {"edit", t.edit},
           {"solve", t.solve},
           {"metrics", metrics_seconds}}}};
  j["iterations"] = editor.options().method == EditOptions::Method::Volumes
                        ? iterations_json(std::optional<ReconstructStats>(r.stats))
                        : json(nullptr);
  return j;
}

int run_deform(const DeformCmdOptions& o) {
  const Log log(o.quiet);
  const Method method = parse_method(o.method);
  check_outputs(o.output, {o.base_output}, o.report);
  Stopwatch total;
  Stopwatch sw;
  log.phase("reading " + o.input + " and " + o.edit);
  const EditScript script = read_edit_script(o.edit);
  const NamedMesh input = read_named_mesh(o.input);
  const double read_seconds = sw.seconds();
  const TimedIntersections input_pairs = find_intersections(input.mesh.vertices, input.mesh.faces);

  EditOptions options;
  options.smoothing_fraction = o.smoothing;
  options.method = method == Method::Volumes ? EditOptions::Method::Volumes : EditOptions::Method::Vectors;
  TriMesh current = input.mesh;
  TriMesh base_out = input.mesh;
  json edits = json::array();
  for (std::size_t k = 0; k < script.edits.size(); ++k) {
    const EditStep& e = script.edits[k];
    const std::string label = "edit " + std::to_string(k + 1) + "/" + std::to_string(script.edits.size());
    const std::string where = o.edit + ": edit " + std::to_string(k + 1);
    sw.restart();
    std::vector<char> region, handle;
    try {
      region = select_vertices(current.vertices, e.region);
      handle = select_vertices(current.vertices, e.handle);
    } catch (const InvalidInput& ex) {
      throw InvalidInput(where + ": " + ex.what());
    }
    const double select_seconds = sw.seconds();
    log.phase(label + ": decomposing the region");
    options.reconstruct.progress = log.progress(label + ": " + to_string(method));
    std::unique_ptr<RegionEditor> editor;
    try {
      editor = std::make_unique<RegionEditor>(current, region, handle, options);
    } catch (const InvalidInput& ex) {
      throw InvalidInput(where + ": " + ex.what());
    }
    log.phase(label + ": " + std::to_string(editor->region_vertices().size()) + " region vertices, " +
              std::to_string(editor->handle_vertices().size()) + " handle vertices; reconstructing");
    EditResult r = editor->apply(e.transform);
    sw.restart();
    json ej = edit_json(*editor, r, select_seconds, 0.0);
    current.vertices = std::move(r.positions);
    base_out.vertices = std::move(r.base_positions);
    ej["timing_seconds"]["metrics"] = sw.seconds();
    edits.push_back(std::move(ej));
  }

  log.phase("counting self-intersections");
  const TimedIntersections output_pairs = find_intersections(current.vertices, current.faces);
  const std::size_t new_pairs = count_new_intersections(input_pairs.result, output_pairs.result);

  log.phase("writing " + o.output);
  sw.restart();
  write_mesh(current, o.output);
  if (!o.base_output.empty()) write_mesh(base_out, o.base_output);
  const double write_seconds = sw.seconds();

  json report{{"command", "deform"},
              {"method", to_string(method)},
              {"input", mesh_json(input.mesh, input.name)},
              {"edit_script", o.edit},
              {"output", mesh_json(current, o.output)},
              {"edits", edits},
              {"intersections",
               {{"input_pairs", input_pairs.result.num_pairs},
                {"output_pairs", output_pairs.result.num_pairs},
                {"new_pairs", new_pairs},
                {"seconds", input_pairs.seconds + output_pairs.seconds}}},
              {"timing_seconds",
               {{"read", read_seconds},
                {"intersections", input_pairs.seconds + output_pairs.seconds},
                {"write", write_seconds},
                {"total", total.seconds()}}}};
  if (!o.base_output.empty()) report["base_output"] = o.base_output;
  if (!o.report.empty()) {
    report["report"] = o.report;
    write_json_report(report, o.report);
  }
  std::cout << "method         " << to_string(method) << "\n"
            << "input          " << input.name << ": " << input.mesh.num_vertices() << " vertices, "
            << input.mesh.num_faces() << " faces\n";
  for (std::size_t k = 0; k < edits.size(); ++k) {
    const json& ej = edits[k];
    const json& vm = ej["volume_metrics"];
    const json& t = ej["timing_seconds"];
    std::cout << "edit " << k + 1 << "         " << ej["region_vertices"].get<std::size_t>() << " region / "
              << ej["handle_vertices"].get<std::size_t>() << " handle vertices, " << ej["region_faces"].get<int>()
              << " prisms; volume error max " << sci(vm["max_relative_error"].get<double>()) << ", RMS "
              << sci(vm["rms_relative_error"].get<double>()) << "; decompose "
              << fixed(t["decompose"].get<double>()) << " s, encode " << fixed(t["encode"].get<double>())
              << " s, setup " << fixed(t["setup"].get<double>()) << " s, solve " << fixed(t["solve"].get<double>())
              << " s\n";
  }
  std::cout << "intersections  " << input_pairs.result.num_pairs << " pairs in the input, "
            << output_pairs.result.num_pairs << " in the output, " << new_pairs << " new\n"
            << "time           total " << fixed(report["timing_seconds"]["total"].get<double>()) << " s\n"
            << "output         " << o.output << "\n";
  if (!o.report.empty()) std::cout << "report         " << o.report << "\n";
  return 0;
}

}  // namespace

Subcommand register_deform(CLI::App& parent) {
  auto o = std::make_shared<DeformCmdOptions>();
  CLI::App* app = parent.add_subcommand(
      "deform", "Edit a region of a mesh by an edit script; the detail follows by displacement volumes or vectors");
  app->add_option("input", o->input, "Mesh to edit (.obj, .off, .ply, .stl)")->required();
  app->add_option("--edit", o->edit, "Edit script (JSON; see README, \"Edit scripts\")")->required();
  app->add_option("--method", o->method, "volumes (prism volumes preserved) or vectors (normal displacements)")
      ->check(CLI::IsMember({"volumes", "vectors"}))
      ->capture_default_str();
  app->add_option("-o,--output", o->output, "Edited mesh to write (atomically)")->required();
  app->add_option("--write-base", o->base_output, "Also write the edited smooth base here");
  app->add_option("--report", o->report, "Also write a JSON report (metrics, sizes, timings) here");
  app->add_option("--smoothing", o->smoothing,
                  "Base cut-off wavelength as a fraction of the region's size: shape longer than this stays in "
                  "the smooth base, shorter becomes detail")
      ->check(CLI::Range(1e-3, 100.0))
      ->capture_default_str();
  app->add_flag("-q,--quiet", o->quiet, "No progress lines on stderr");
  app->footer("Example:\n  strata deform scan.off --edit bend.json --method volumes -o bent.obj --report report.json");
  return {app, [o] { return run_deform(*o); }};
}

}  // namespace strata::cli

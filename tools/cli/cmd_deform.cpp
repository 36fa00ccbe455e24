// `strata deform`: region edits of a mesh from an edit script (paper, section 5).
#include <algorithm>
#include <iostream>
#include <memory>
#include <string>

#include "common.h"
#include "strata/cage_editing.h"
#include "strata/cage_fit.h"
#include "strata/cage_io.h"
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
  bool smoothing_given = false;
  std::string base = "faired";  // or "subdiv"
  std::string cage;             // subdiv: given cage (empty: fitted)
  std::string cage_tags;        // subdiv: its sharpness tags (optional)
  int cage_faces = 0;           // subdiv, fitted cage: its face count (0: fit_cage's default)
  int handle_rings = 3;         // EditOptions / CageEditOptions::handle_solved_rings
  bool exact_region = false;    // faired: !EditOptions::fill_region_corners
  int threads = 0;              // ReconstructOptions::threads (0: all cores)
  SolverChoice solver;          // --solver, --set: solver_options()
  bool quiet = false;
  bool strict = false;  // exit 3 when the result misses a target (the report's "warnings")
};

// What the report says about one edit, whichever editor ran it.
struct EditFacts {
  std::size_t region_vertices = 0, handle_vertices = 0;
  int region_faces = 0;
  const EncodeReport* encoding = nullptr;
  int left_out_vertices = 0;  // RegionEditor::left_out_vertices()
};

int left_out_vertices(const RegionEditor& e) {
  return e.left_out_vertices();
}
int left_out_vertices(const CageEditor&) {
  return 0;
}  // floating cage parts keep s = 0

json edit_json(const EditFacts& editor, Method method, const EditResult& r, double select_seconds,
               double metrics_seconds) {
  const EditTimes& t = r.times;
  json j{{"region_vertices", editor.region_vertices},
         {"handle_vertices", editor.handle_vertices},
         {"region_faces", editor.region_faces},
         {"left_out_vertices", editor.left_out_vertices},
         {"encoding", encoding_json(*editor.encoding)},
         {"volume_metrics", volume_metrics_json(r.volume)},
         {"timing_seconds",
          {{"select", select_seconds},
           {"decompose", t.decompose},
           {"encode", t.encode},
           {"setup", t.setup},
           {"edit", t.edit},
           {"solve", t.solve},
           {"metrics", metrics_seconds}}}};
  const std::optional<ReconstructStats> stats =
      method == Method::Volumes ? std::optional<ReconstructStats>(r.stats) : std::nullopt;
  j["iterations"] = iterations_json(stats);
  j["solve_phases_seconds"] = solve_phases_json(stats);
  return j;
}

// f(), with \p where (the script and the edit) named in the InvalidInput or SolverError it throws
// (a transform that moved a vertex out of range, and a fairing system that could not be
// factorized, were reported without either).
template <class F>
auto named(const std::string& where, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const InvalidInput& ex) {
    throw InvalidInput(where + ": " + ex.what());
  } catch (const SolverError& ex) {
    throw SolverError(where + ": " + ex.what());
  }
}

int run_deform(const DeformCmdOptions& o) {
  const Log log(o.quiet);
  const Method method = parse_method(o.method);
  check_outputs(o.output, {o.base_output}, o.report, {o.input, o.edit, o.cage, o.cage_tags});
  const bool subdiv = o.base == "subdiv";
  if (subdiv && !o.base_output.empty()) check_cage_format(o.base_output);  // --write-base writes the cage
  // Options that do not go together: usage errors (exit 2, with the pointer to --help), as CLI11's.
  if (!subdiv && (!o.cage.empty() || !o.cage_tags.empty() || o.cage_faces > 0))
    throw CLI::ValidationError("--cage, --cage-tags and --cage-faces need --base subdiv");
  if (!o.cage_tags.empty() && o.cage.empty()) throw CLI::ValidationError("--cage-tags needs --cage");
  if (!subdiv && o.handle_rings < 0)
    throw CLI::ValidationError(
        "--handle-rings must be >= 0 with --base faired (negative: solve every vertex, --base subdiv)");
  if (subdiv && (o.exact_region || o.smoothing_given))
    throw CLI::ValidationError("--exact-region and --smoothing apply to --base faired, not to --base subdiv");
  if (!o.cage.empty() && o.cage_faces > 0)
    throw CLI::ValidationError("--cage-faces applies to a fitted cage, not to --cage");
  Stopwatch total;
  Stopwatch sw;
  log.phase("reading " + o.input + " and " + o.edit);
  const EditScript script = read_edit_script(o.edit);
  NamedMesh input = read_scan(o.input);
  read_companions(input.attributes, o.input);  // written beside the output
  const double read_seconds = sw.seconds();
  const TimedIntersections input_pairs =
      find_intersections(input.mesh.vertices, input.mesh.faces, input.name);
  PolyMesh cage;
  SubdivTags tags;
  json cage_json = nullptr;
  if (subdiv) {
    if (!o.cage.empty()) {
      log.phase("reading the cage " + o.cage);
      cage = read_cage(o.cage);
      if (!o.cage_tags.empty()) tags = read_subdiv_tags(o.cage_tags);
      // The cage and its tags make a surface, or the files are named (their problems were reported
      // as the edit script's).
      try {
        const SubdivSurface surface(cage, tags);
      } catch (const InvalidInput& ex) {
        throw InvalidInput(o.cage + (o.cage_tags.empty() ? "" : " with " + o.cage_tags) + ": " + ex.what());
      }
      const bool triangles = std::all_of(cage.faces.begin(), cage.faces.end(),
                                         [](const std::vector<int>& f) { return f.size() == 3; });
      cage_json = {{"path", o.cage},
                   {"faces", cage.num_faces()},
                   {"fitted", false},
                   {"scheme", triangles ? "loop" : "catmull-clark"}};
    } else {
      log.phase("fitting a cage to " + input.name);
      CageFitOptions fo;
      fo.faces = o.cage_faces;
      CageFit fit;
      try {
        fit = fit_cage(input.mesh, fo);
      } catch (const InvalidInput& ex) {
        throw InvalidInput(input.name + ": " + ex.what());
      }
      cage = std::move(fit.cage);
      cage_json = {{"faces", cage.num_faces()},
                   {"fitted", true},
                   {"scheme", "loop"},
                   {"rms_error", fit.rms_error},
                   {"max_error", fit.max_error},
                   {"seconds", fit.seconds_smooth + fit.seconds_decimate + fit.seconds_fit}};
    }
  }

  EditOptions options;
  options.reconstruct = solver_options(o.solver, o.threads);
  options.smoothing_fraction = o.smoothing;
  options.handle_solved_rings = o.handle_rings;
  options.fill_region_corners = !o.exact_region;
  options.method = method == Method::Volumes ? EditOptions::Method::Volumes : EditOptions::Method::Vectors;
  TriMesh current = input.mesh;
  TriMesh base_out = input.mesh;
  json edits = json::array();
  json warnings = json::array();  // what makes the result miss a target
  // Adopts one edit's result (the mesh, and the edited base or cage) and adds its report entry.
  auto record = [&](const auto& editor, EditResult r, double select_seconds, std::vector<Vec3>& base) {
    Stopwatch metrics;
    if (method == Method::Volumes && !r.stats.converged)
      warnings.push_back("edit " + std::to_string(edits.size() + 1) + ": " +
                         not_converged_text(r.stats, options.reconstruct.tolerance));
    const EditFacts facts{editor.region_vertices().size(), editor.handle_vertices().size(),
                          editor.region_faces(), &editor.encoding().report, left_out_vertices(editor)};
    json ej = edit_json(facts, method, r, select_seconds, 0.0);
    current.vertices = std::move(r.positions);
    base = std::move(r.base_positions);
    ej["timing_seconds"]["metrics"] = metrics.seconds();
    edits.push_back(std::move(ej));
  };
  for (std::size_t k = 0; k < script.edits.size(); ++k) {
    const EditStep& e = script.edits[k];
    const std::string label = "edit " + std::to_string(k + 1) + "/" + std::to_string(script.edits.size());
    const std::string where = o.edit + ": edit " + std::to_string(k + 1);
    sw.restart();
    // Over a subdivision base, the selections pick cage vertices.
    const std::vector<Vec3>& selectable = subdiv ? cage.vertices : current.vertices;
    std::vector<char> region, handle;
    try {
      region = select_vertices(selectable, e.region);
      handle = select_vertices(selectable, e.handle);
    } catch (const InvalidInput& ex) {
      throw InvalidInput(where + ": " + ex.what());
    }
    const double select_seconds = sw.seconds();
    if (subdiv) {
      log.phase(label + ": encoding over the cage's limit surface");
      CageEditOptions co;
      co.method = options.method;
      co.handle_solved_rings = o.handle_rings;
      co.reconstruct = solver_options(o.solver, o.threads);
      co.reconstruct.progress = log.progress(label + ": " + to_string(method));
      const auto editor = named(where, [&] {
        return std::make_unique<CageEditor>(current, SubdivSurface(cage, tags), region, handle, co);
      });
      log.phase(label + ": " + std::to_string(editor->region_vertices().size()) + " region cage vertices, " +
                std::to_string(editor->handle_vertices().size()) + " handle; reconstructing " +
                std::to_string(editor->region_faces()) + " prisms");
      record(*editor, named(where, [&] { return editor->apply(e.transform); }), select_seconds,
             cage.vertices);
      continue;
    }
    log.phase(label + ": decomposing the region");
    options.reconstruct.progress = log.progress(label + ": " + to_string(method));
    const auto editor =
        named(where, [&] { return std::make_unique<RegionEditor>(current, region, handle, options); });
    log.phase(label + ": " + std::to_string(editor->region_vertices().size()) + " region vertices, " +
              std::to_string(editor->handle_vertices().size()) + " handle vertices; reconstructing");
    if (editor->left_out_vertices() > 0)
      log.phase(label + ": " + std::to_string(editor->left_out_vertices()) +
                " selected vertices left out: their parts touch neither the handle nor the rest of the mesh");
    record(*editor, named(where, [&] { return editor->apply(e.transform); }), select_seconds,
           base_out.vertices);
  }

  log.phase("counting self-intersections");
  const TimedIntersections output_pairs = find_intersections(current.vertices, current.faces, "the output");
  const std::size_t new_pairs = count_new_intersections_at_least(input_pairs.result, output_pairs.result);
  const bool cut_short = input_pairs.result.truncated || output_pairs.result.truncated;
  if (method == Method::Volumes)
    if (std::string w = new_pairs_warning(input_pairs.result, output_pairs.result); !w.empty())
      warnings.push_back(w);

  log.phase("writing " + o.output);
  sw.restart();
  StagedOutputs staged;  // the outputs land together, or none does
  validate_result(current, "the mesh edited by " + o.edit, o.output);
  warn_stl_drops_vertices(current, o.output);
  const MeshAttributes attributes = output_attributes(input.attributes, o.output);
  warn_attributes_not_stored(attributes, o.output);
  staged.write(o.output, [&](const std::string& p) { write_mesh(current, attributes, p); });
  if (!o.base_output.empty()) {
    if (subdiv)
      staged.write(o.base_output, [&](const std::string& p) { write_cage(cage, p); });
    else {
      validate_result(base_out, "the smooth base edited by " + o.edit, o.base_output);
      warn_stl_drops_vertices(base_out, o.base_output);
      staged.write(o.base_output, [&](const std::string& p) { write_mesh(base_out, p); });
    }
  }
  const double write_seconds = sw.seconds();

  json report{{"command", "deform"},
              {"method", to_string(method)},
              {"solver", o.solver.solver},
              {"set", o.solver.sets},
              {"base", o.base},
              {"cage", cage_json},
              {"input", mesh_json(input.mesh, input.name)},
              {"input_reoriented_faces", input.reoriented_faces},
              {"edit_script", o.edit},
              {"output", mesh_json(current, o.output)},
              {"edits", edits},
              {"intersections",
               {{"input_pairs", input_pairs.result.num_pairs},
                {"output_pairs", output_pairs.result.num_pairs},
                {"new_pairs", new_pairs},
                {"cut_short", cut_short},
                {"seconds", input_pairs.seconds + output_pairs.seconds}}},
              {"timing_seconds",
               {{"read", read_seconds},
                {"intersections", input_pairs.seconds + output_pairs.seconds},
                {"write", write_seconds},
                {"total", total.seconds()}}},
              {"warnings", warnings}};
  if (!o.base_output.empty()) report["base_output"] = o.base_output;
  if (!o.report.empty()) {
    report["report"] = o.report;
    staged.write(o.report, [&](const std::string& p) { write_json_report(report, p); });
  }
  write_companions(attributes, o.output, &staged);
  staged.commit();
  std::cout << "method         " << to_string(method) << "\n"
            << "input          " << input.name << ": " << input.mesh.num_vertices() << " vertices, "
            << input.mesh.num_faces() << " faces\n";
  for (std::size_t k = 0; k < edits.size(); ++k) {
    const json& ej = edits[k];
    const json& vm = ej["volume_metrics"];
    const json& t = ej["timing_seconds"];
    std::cout << "edit " << k + 1 << "         " << ej["region_vertices"].get<std::size_t>() << " region / "
              << ej["handle_vertices"].get<std::size_t>() << " handle vertices, "
              << ej["region_faces"].get<int>() << " prisms; volume error max "
              << sci(vm["max_relative_error"].get<double>()) << ", RMS "
              << sci(vm["rms_relative_error"].get<double>()) << "; decompose "
              << fixed(t["decompose"].get<double>()) << " s, encode " << fixed(t["encode"].get<double>())
              << " s, setup " << fixed(t["setup"].get<double>()) << " s, solve "
              << fixed(t["solve"].get<double>()) << " s\n";
  }
  std::cout << "intersections  " << input_pairs.result.num_pairs << " pairs in the input, "
            << output_pairs.result.num_pairs << " in the output, " << new_pairs << " new"
            << cut_short_note(cut_short) << "\n"
            << "time           total " << fixed(report["timing_seconds"]["total"].get<double>()) << " s\n"
            << "output         " << o.output << "\n";
  if (!o.report.empty()) std::cout << "report         " << o.report << "\n";
  std::cout.flush();
  return finish_warnings(warnings, o.strict, true);
}

}  // namespace

Subcommand register_deform(CLI::App& parent) {
  auto o = std::make_shared<DeformCmdOptions>();
  CLI::App* app = parent.add_subcommand(
      "deform",
      "Edit a region of a mesh by an edit script; the detail follows by displacement volumes or vectors");
  app->add_option("input", o->input, "Mesh to edit (.obj, .off, .ply, .stl)")->required();
  app->add_option("--edit", o->edit, "Edit script (JSON; see README, \"Edit scripts\")")->required();
  app->add_option("--method", o->method,
                  "volumes (prism volumes preserved) or vectors (normal displacements)")
      ->check(CLI::IsMember({"volumes", "vectors"}))
      ->capture_default_str();
  app->add_option("-o,--output", o->output, "Edited mesh to write (atomically)")->required();
  app->add_option("--write-base", o->base_output,
                  "Also write the edited smooth base here (the edited cage with --base subdiv)");
  app->add_option(
         "--base", o->base,
         "faired: each region's thin-plate faired base; subdiv: the limit surface of a control cage, "
         "edited through its vertices (the edit script's selections pick cage vertices)")
      ->check(CLI::IsMember({"faired", "subdiv"}))
      ->capture_default_str();
  app->add_option("--cage", o->cage,
                  "With --base subdiv: the cage (OBJ, OFF or PLY; triangles: Loop, quads or other polygons: "
                  "Catmull-Clark); default: a Loop cage fitted to the input");
  app->add_option("--cage-tags", o->cage_tags,
                  "With --cage: its crease and corner tags (JSON, see cage_io.h)");
  app->add_option(
         "--handle-rings", o->handle_rings,
         "Handle vertices that move rigidly are placed exactly (as by vectors) and not solved, except "
         "within this many edges of the blended part (at most 1000); with --base subdiv a negative value "
         "solves all")
      ->check(in_range(-1000, 1000))
      ->capture_default_str();
  app->add_option(
         "--threads", o->threads,
         "Threads of the volume solver's sweeps (0: all cores, 1: one, at most 1024); the result is the same "
         "for any count")
      ->check(in_range(0, 1024))
      ->capture_default_str();
  app->add_flag(
      "--exact-region", o->exact_region,
      "With --base faired: edit exactly the selected region (by default a region vertex that is the "
      "only selected vertex of two or more faces gets those faces' other vertices added, so that "
      "their prisms can keep their volumes)");
  add_solver_option(app, o->solver);
  app->add_option("--cage-faces", o->cage_faces, "With --base subdiv and no --cage: faces of the fitted cage")
      ->check(at_least(0));
  app->add_option("--report", o->report, "Also write a JSON report (metrics, sizes, timings) here");
  app->add_option(
         "--smoothing", o->smoothing,
         "Base cut-off wavelength as a fraction of the region's size: shape longer than this stays in "
         "the smooth base, shorter becomes detail")
      ->check(in_range(1e-3, 100.0))
      ->capture_default_str()
      ->each([o](const std::string&) { o->smoothing_given = true; });
  app->add_flag("-q,--quiet", o->quiet, "No progress lines on stderr");
  app->add_flag(
      "--strict", o->strict,
      "Exit with 3 (outputs written) when the result misses a target: with volumes, an edit's solve "
      "not converged or new intersecting pairs");
  app->footer(
      "Example:\n  strata deform scan.off --edit bend.json --method volumes -o bent.obj --report "
      "report.json");
  return {app, [o] { return run_deform(*o); }};
}

}  // namespace strata::cli

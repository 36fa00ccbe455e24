// `strata reconstruct`: encode a detail mesh over a base, rebuild it over an edited base.
#include <iostream>
#include <memory>
#include <string>

#include "common.h"
#include "stats_json.h"
#include "strata/exceptions.h"
#include "strata/mesh_io.h"

namespace strata::cli {

namespace {

struct ReconstructCmdOptions {
  std::string detail;
  std::string base;
  std::string edited_base;
  std::string method = "volumes";
  std::string output;
  std::string report;               // empty: no report
  SolverChoice solver{"auto", {}};  // --solver, --set: solver_options()
  bool quiet = false;
  bool strict = false;  // exit 3 when the result misses a target (the report's "warnings")
};

void print_summary(std::ostream& os, const json& r) {
  const json& in = r["inputs"];
  const json& enc = r["encoding"];
  const json& vm = r["volume_metrics"];
  const json& dc = r["dihedral_change_degrees"];
  const json& is = r["intersections"];
  const json& t = r["timing_seconds"];
  auto mesh_line = [](const json& m) {
    return m["name"].get<std::string>() + ": " + std::to_string(m["vertices"].get<int>()) + " vertices, " +
           std::to_string(m["faces"].get<int>()) + " faces";
  };
  os << "method         " << r["method"].get<std::string>() << "\n"
     << "detail         " << mesh_line(in["detail"]) << "\n"
     << "base           " << mesh_line(in["base"]) << "\n"
     << "edited base    " << in["edited_base"]["name"].get<std::string>() << "\n"
     << "encoding       " << enc["projected"].get<int>() << " projected, " << enc["fallback"].get<int>()
     << " fallback, " << enc["ambiguous"].get<int>() << " ambiguous\n"
     << "prism volumes  max error " << sci(vm["max_relative_error"].get<double>()) << ", RMS "
     << sci(vm["rms_relative_error"].get<double>()) << " (relative to the mean prism volume)\n"
     << "total volume   change " << sci(vm["total_volume_change"].get<double>()) << " (relative)\n"
     << "shape          dihedral angles changed by median " << fixed(dc["median"].get<double>()) << ", 90% "
     << fixed(dc["p90"].get<double>()) << ", 99% " << fixed(dc["p99"].get<double>()) << ", max "
     << fixed(dc["max"].get<double>()) << " degrees (against the input detail)\n"
     << "intersections  " << is["input_pairs"].get<std::size_t>() << " pairs in the input, "
     << is["output_pairs"].get<std::size_t>() << " in the output, " << is["new_pairs"].get<std::size_t>()
     << " new" << cut_short_note(is["cut_short"].get<bool>()) << "\n";
  const json& it = r["iterations"];
  if (!it.is_null())
    os << "solver         " << r["solver"].get<std::string>()
       << (r["solver_requested"] == "auto" ? " (auto)" : "") << ": " << it["levels"].get<int>() << " levels, "
       << it["cycles"].get<int>() << " cycles, " << it["volume_sweeps"].get<int>() << " volume + "
       << it["regularization_sweeps"].get<int>() << " regularization sweeps, "
       << it["final_sweeps"].get<int>() << " final sweeps, " << it["cg_iterations"].get<long long>()
       << " CG iterations, " << (it["converged"].get<bool>() ? "converged" : "NOT converged") << "\n";
  os << "time           read " << fixed(t["read"].get<double>()) << " s, encode "
     << fixed(t["encode"].get<double>()) << " s, setup " << fixed(t["setup"].get<double>()) << " s, frames "
     << fixed(t["frames"].get<double>()) << " s, solve " << fixed(t["solve"].get<double>()) << " s, metrics "
     << fixed(t["metrics"].get<double>()) << " s, write " << fixed(t["write"].get<double>()) << " s, total "
     << fixed(t["total"].get<double>()) << " s\n"
     << "output         " << r["output"]["name"].get<std::string>() << "\n";
  if (r.contains("report")) os << "report         " << r["report"].get<std::string>() << "\n";
}

int run_reconstruct(const ReconstructCmdOptions& o) {
  const Log log(o.quiet);
  const Method method = parse_method(o.method);
  // Fail on an unwritable destination before the (possibly long) computation.
  check_outputs(o.output, {}, o.report, {o.detail, o.base, o.edited_base});

  PhaseTimes times;
  log.phase("reading " + o.detail + ", " + o.base + ", " + o.edited_base);
  Stopwatch sw;
  NamedMesh detail = read_named_mesh(o.detail);
  read_companions(detail.attributes, o.detail);  // written beside the output
  const auto [base, edited] = read_base_pair(o.base, o.edited_base);
  times.read = sw.seconds();
  const EncodedInput in = encode_input(detail, base, edited, log);
  const DetailEncoding& encoding = in.encoding;
  const TimedIntersections& input = in.input;
  times.encode = in.encode_seconds;

  // auto: chosen by the detail's size (kAutoMultigridPrisms); the report names both.
  SolverChoice solver = o.solver;
  solver.solver = resolve_solver(o.solver, detail.mesh.faces.size());
  ReconstructOptions options = solver_options(solver);
  options.progress = log.progress(to_string(method));
  MethodOutcome outcome =
      run_method(method, {encoding, edited.mesh.vertices, edited.name, input.result}, options, log);
  times.setup = outcome.times.setup;
  times.frames = outcome.times.frames;
  times.solve = outcome.times.solve;
  times.metrics = outcome.times.metrics + input.seconds;

  log.phase("writing " + o.output);
  sw.restart();
  TriMesh result;
  result.vertices = std::move(outcome.positions);
  result.faces = detail.mesh.faces;
  StagedOutputs staged;  // the mesh lands only with its report
  validate_result(result, "the reconstructed detail", o.output);
  warn_stl_drops_vertices(result, o.output);
  const MeshAttributes attributes = output_attributes(detail.attributes, o.output);
  warn_attributes_not_stored(attributes, o.output);
  staged.write(o.output, [&](const std::string& p) { write_mesh(result, attributes, p); });
  times.write = sw.seconds();

  json report{{"command", "reconstruct"},
              {"method", to_string(method)},
              {"solver", solver.solver},
              {"solver_requested", o.solver.solver},
              {"set", o.solver.sets},
              {"inputs",
               {{"detail", mesh_json(detail.mesh, detail.name)},
                {"base", mesh_json(base.mesh, base.name)},
                {"edited_base", mesh_json(edited.mesh, edited.name)}}},
              {"output", mesh_json(result, o.output)},
              {"encoding", encoding_json(encoding.report)},
              {"volume_metrics", volume_metrics_json(outcome.volume)},
              {"dihedral_change_degrees", tools::dihedral_change_json(outcome.shape)},
              {"intersections", intersections_json(input.result.num_pairs, outcome, input.seconds)},
              {"iterations", iterations_json(outcome.stats)},
              {"timing_seconds", timing_json(times)},
              {"solve_phases_seconds", solve_phases_json(outcome.stats)}};
  // What makes the result miss a target, for pipelines (--strict exits 3 on any).
  json warnings = json::array();
  if (!in.warning.empty()) warnings.push_back(in.warning);
  if (method == Method::Volumes) {
    if (outcome.stats && !outcome.stats->converged)
      warnings.push_back(not_converged_text(*outcome.stats, options.tolerance));
    if (!outcome.pairs_warning.empty()) warnings.push_back(outcome.pairs_warning);
  }
  report["warnings"] = warnings;
  if (!o.report.empty()) {
    report["report"] = o.report;
    staged.write(o.report, [&](const std::string& p) { write_json_report(report, p); });
  }
  write_companions(attributes, o.output, &staged);
  staged.commit();
  print_summary(std::cout, report);
  if (o.strict) return finish_warnings(warnings, true, false);
  json unprinted = warnings;  // the input's warning was printed when it was found
  if (!in.warning.empty()) unprinted.erase(0);
  return finish_warnings(unprinted, false, true);
}

}  // namespace

Subcommand register_reconstruct(CLI::App& parent) {
  auto o = std::make_shared<ReconstructCmdOptions>();
  CLI::App* app = parent.add_subcommand(
      "reconstruct", "Rebuild a detail mesh over an edited base, by displacement volumes or vectors");
  app->add_option("--detail", o->detail, "Detail mesh D (.obj, .off, .ply, .stl)")->required();
  app->add_option("--base", o->base, "Base mesh S that D's detail is measured from")->required();
  app->add_option("--edited-base", o->edited_base, "Edited base S': S's vertices moved, S's faces")
      ->required();
  app->add_option("--method", o->method,
                  "volumes (prism volumes preserved) or vectors (normal displacements)")
      ->check(CLI::IsMember({"volumes", "vectors"}))
      ->capture_default_str();
  app->add_option("-o,--output", o->output, "Reconstructed detail mesh to write (atomically)")->required();
  app->add_option("--report", o->report, "Also write a JSON report (metrics, timings, iterations) here");
  add_solver_option(app, o->solver, /*with_auto=*/true);
  app->add_flag("-q,--quiet", o->quiet, "No progress lines on stderr");
  app->add_flag(
      "--strict", o->strict,
      "Exit with 3 (outputs written) when the result misses a target: a detail that does not look like a "
      "displacement of its base; for the volumes also a solve not converged or new intersecting pairs");
  app->footer(
      "Example:\n  strata reconstruct --detail detail.obj --base base.obj --edited-base edited_base.obj \\\n"
      "      --method volumes -o out.obj --report report.json");
  return {app, [o] { return run_reconstruct(*o); }};
}

}  // namespace strata::cli

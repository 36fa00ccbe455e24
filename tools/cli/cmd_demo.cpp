// `strata demo`: the paper's Fig. 6 comparison. Every case (the three generated cylinder cases,
// plus any mesh triple under the assets directory) is rebuilt over its bent base by displacement
// volumes and by displacement vectors; both results are written side by side with the bent base,
// and a table of volume errors, new self-intersections and timings is printed.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "common.h"
#include "stats_json.h"
#include "strata/exceptions.h"
#include "strata/mesh_io.h"

namespace strata::cli {

namespace {

namespace fs = std::filesystem;

struct DemoCmdOptions {
  std::string out_dir = "out";
  int triangles = 0;
  std::string assets_dir = "assets";
  bool assets_dir_given = false;  // named on the command line: then it must exist
  bool no_assets = false;
  bool quiet = false;
};

//! Where a case's meshes come from: a generated paper case, or three files.
struct CaseSource {
  std::string name;  //!< also the prefix of its output files
  std::optional<cases::DetailKind> kind;
  std::string detail_path, base_path, edited_base_path;
  std::string origin() const { return kind ? "generated" : fs::path(detail_path).parent_path().string(); }
};

//! The first file <dir>/<stem>.<ext> for a supported extension, or "".
std::string find_mesh_file(const fs::path& dir, const std::string& stem) {
  for (const std::string& ext : supported_mesh_extensions()) {
    std::error_code ec;
    const fs::path p = dir / (stem + ext);
    if (fs::is_regular_file(p, ec)) return p.string();
  }
  return {};
}

//! The mesh triples in the subdirectories of \p assets_dir: <dir>/{detail,base,edited_base}.<ext>,
//! sorted by directory name. Directories without all three files are skipped with a note.
std::vector<CaseSource> find_asset_cases(const std::string& assets_dir, const Log& log) {
  std::vector<CaseSource> found;
  std::error_code ec;
  if (!fs::is_directory(assets_dir, ec)) return found;
  std::vector<fs::path> dirs;
  for (const fs::directory_entry& e : fs::directory_iterator(assets_dir, ec))
    if (e.is_directory(ec)) dirs.push_back(e.path());
  std::sort(dirs.begin(), dirs.end());
  for (const fs::path& d : dirs) {
    CaseSource c;
    c.name = d.filename().string();
    c.detail_path = find_mesh_file(d, "detail");
    c.base_path = find_mesh_file(d, "base");
    c.edited_base_path = find_mesh_file(d, "edited_base");
    if (c.detail_path.empty() || c.base_path.empty() || c.edited_base_path.empty()) {
      log.phase("skipping " + d.string() + ": it needs detail, base and edited_base mesh files");
      continue;
    }
    found.push_back(std::move(c));
  }
  return found;
}

struct Row {
  std::string case_name;
  std::string method;
  double max_error = 0, rms_error = 0, volume_change = 0;
  std::size_t new_pairs = 0;
  double p99_bend_change = 0;  //!< dihedral_change()'s 99th percentile, degrees
  double seconds = 0;
  std::string error;  //!< non-empty: the case failed
};

// A case's output file: <case>_<suffix>.obj in the output directory.
std::string case_output(const std::string& case_name, const std::string& suffix) {
  return case_name + "_" + suffix + ".obj";
}
// Every output file name a case writes (run_case()).
std::vector<std::string> case_outputs(const std::string& case_name) {
  std::vector<std::string> names;
  for (const char* suffix :
       {"detail", "base", "edited_base", to_string(Method::Volumes), to_string(Method::Vectors)})
    names.push_back(case_output(case_name, suffix));
  return names;
}

//! Runs one case; appends its table rows and returns its JSON block. Throws on failure.
json run_case(const CaseSource& src, const DemoCmdOptions& o, const Log& log, std::vector<Row>& rows) {
  PhaseTimes shared;  // read/generate, encode, input intersections: once for both methods
  Stopwatch sw;
  NamedMesh detail, base, edited;
  if (src.kind) {
    log.phase("generating the case");
    cases::CylinderCase c = cases::make_cylinder_case(paper_case_options(*src.kind, o.triangles, 90.0));
    detail = {std::move(c.detail), c.name + " detail"};
    base = {std::move(c.base), c.name + " base"};
    edited = {std::move(c.edited_base), c.name + " edited base"};
  } else {
    log.phase("reading " + src.detail_path + ", " + src.base_path + ", " + src.edited_base_path);
    detail = read_named_mesh(src.detail_path);
    std::tie(base, edited) = read_base_pair(src.base_path, src.edited_base_path);
  }
  shared.read = sw.seconds();
  const EncodedInput in = encode_input(detail, base, edited, log);
  const DetailEncoding& encoding = in.encoding;
  const TimedIntersections& input = in.input;
  shared.encode = in.encode_seconds;
  shared.metrics = input.seconds;

  const fs::path dir(o.out_dir);
  auto out_path = [&](const std::string& suffix) { return (dir / case_output(src.name, suffix)).string(); };
  // Both methods first, then the files: a case whose solve failed left its input copies in the
  // output directory (a review, thirty-eighth session).
  std::vector<std::pair<Method, MethodOutcome>> outcomes;
  for (const Method method : {Method::Volumes, Method::Vectors}) {
    ReconstructOptions options;
    options.progress = log.progress(to_string(method));
    outcomes.emplace_back(
        method,
        run_method(method, {encoding, edited.mesh.vertices, edited.name, input.result}, options, log));
  }
  json files = json::array();
  sw.restart();
  for (const auto& [mesh, suffix] : {std::pair<const TriMesh*, const char*>{&detail.mesh, "detail"},
                                     {&base.mesh, "base"},
                                     {&edited.mesh, "edited_base"}}) {
    write_mesh(*mesh, out_path(suffix));
    files.push_back(out_path(suffix));
  }
  shared.write = sw.seconds();

  json methods = json::object();
  for (auto& [method, outcome] : outcomes) {
    const std::string path = out_path(to_string(method));
    sw.restart();
    TriMesh result;
    result.vertices = std::move(outcome.positions);
    result.faces = detail.mesh.faces;
    write_mesh(result, path);
    outcome.times.write = sw.seconds();
    files.push_back(path);
    methods[to_string(method)] = {
        {"output", path},
        {"volume_metrics", volume_metrics_json(outcome.volume)},
        {"dihedral_change_degrees", tools::dihedral_change_json(outcome.shape)},
        {"intersections", intersections_json(input.result.num_pairs, outcome, input.seconds)},
        {"iterations", iterations_json(outcome.stats)},
        {"timing_seconds", timing_json(outcome.times)},
        {"solve_phases_seconds", solve_phases_json(outcome.stats)}};
    rows.push_back({src.name,
                    to_string(method),
                    outcome.volume.max_relative_error,
                    outcome.volume.rms_relative_error,
                    outcome.volume.total_volume_change,
                    outcome.new_pairs,
                    outcome.shape.p99_degrees,
                    outcome.times.reconstruction(),
                    {}});
  }
  return json{{"name", src.name},
              {"source", src.origin()},
              {"inputs",
               {{"detail", mesh_json(detail.mesh, detail.name)},
                {"base", mesh_json(base.mesh, base.name)},
                {"edited_base", mesh_json(edited.mesh, edited.name)}}},
              {"encoding", encoding_json(encoding.report)},
              {"input_intersecting_pairs", input.result.num_pairs},
              {"shared_timing_seconds",
               {{"read", shared.read},
                {"encode", shared.encode},
                {"input_intersections", shared.metrics},
                {"write_inputs", shared.write}}},
              {"methods", methods},
              {"files", files}};
}

void print_table(std::ostream& os, const std::vector<Row>& rows) {
  char line[256];
  std::snprintf(line, sizeof line, "%-14s %-8s %13s %13s %13s %10s %11s %9s", "case", "method", "max rel err",
                "RMS rel err", "volume change", "new pairs", "p99 bend", "time [s]");
  os << line << "\n" << std::string(std::string(line).size(), '-') << "\n";
  for (const Row& r : rows) {
    if (!r.error.empty()) {
      std::snprintf(line, sizeof line, "%-14s %-8s ", r.case_name.c_str(), "-");
      os << line << "FAILED: " << r.error << "\n";
      continue;
    }
    std::snprintf(line, sizeof line, "%-14s %-8s %13.3e %13.3e %+13.3e %10zu %11.1f %9.3f",
                  r.case_name.c_str(), r.method.c_str(), r.max_error, r.rms_error, r.volume_change,
                  r.new_pairs, r.p99_bend_change, r.seconds);
    os << line << "\n";
  }
}

int run_demo(const DemoCmdOptions& o) {
  const Log log(o.quiet);
  if (o.triangles < 0) throw InvalidInput("--triangles must be >= 0");

  std::vector<CaseSource> sources;
  for (const cases::DetailKind kind :
       {cases::DetailKind::Bumps, cases::DetailKind::Rings, cases::DetailKind::Cuboid}) {
    CaseSource s;
    s.name = cases::to_string(kind);
    s.kind = kind;
    sources.push_back(s);
  }
  if (!o.no_assets) {
    std::error_code ec;
    if (o.assets_dir_given && !fs::is_directory(o.assets_dir, ec))
      throw IoError(o.assets_dir + ": --assets-dir is not a directory");
    for (CaseSource& s : find_asset_cases(o.assets_dir, log)) sources.push_back(std::move(s));
  }
  // Outputs are named after the case: an asset named as a generated case overwrote its files, and
  // so did one whose name and a suffix make another case's name (bumps_edited's base is
  // bumps_edited_base.obj, as is bumps' edited base).
  std::map<std::string, std::string> writer;  // output name -> its case
  for (const CaseSource& s : sources)
    for (const std::string& name : case_outputs(s.name)) {
      const auto [it, fresh] = writer.emplace(name, s.name);
      if (!fresh)
        throw InvalidInput((s.kind ? s.name : (fs::path(o.assets_dir) / s.name).string()) + ": its output " +
                           name + " would also be written by case '" + it->second +
                           "'; rename the case's directory");
    }

  // After the cases are known: a bad --assets-dir leaves no output directory behind.
  ensure_directory(o.out_dir);
  const std::string report_path = (fs::path(o.out_dir) / "demo_report.json").string();

  std::cout << "strata demo: " << sources.size() << " cases, each rebuilt over its bent base by displacement "
            << "volumes and by displacement vectors\n"
            << "writing to " << o.out_dir << "/" << std::endl;
  Stopwatch total;
  std::vector<Row> rows;
  json cases_json = json::array();
  int failures = 0;
  for (const CaseSource& src : sources) {
    const Log case_log = log.nested(src.name + ": ");
    try {
      cases_json.push_back(run_case(src, o, case_log, rows));
    } catch (const std::exception& e) {
      ++failures;
      std::cerr << "strata: error: case " << src.name << ": " << e.what() << std::endl;
      rows.push_back({src.name, "", 0, 0, 0, 0, 0, 0, e.what()});
      cases_json.push_back({{"name", src.name}, {"source", src.origin()}, {"error", e.what()}});
    }
  }

  json summary = json::array();
  for (const Row& r : rows)
    if (r.error.empty())
      summary.push_back({{"case", r.case_name},
                         {"method", r.method},
                         {"max_relative_error", r.max_error},
                         {"rms_relative_error", r.rms_error},
                         {"total_volume_change", r.volume_change},
                         {"new_intersecting_pairs", r.new_pairs},
                         {"p99_dihedral_change_degrees", r.p99_bend_change},
                         {"reconstruction_seconds", r.seconds}});
  const json report{{"command", "demo"},        {"out_dir", o.out_dir},
                    {"triangles", o.triangles}, {"bend_degrees", 90.0},
                    {"cases", cases_json},      {"summary", summary},
                    {"failed_cases", failures}, {"total_seconds", total.seconds()}};
  write_json_report(report, report_path);

  std::cout << "\n";
  print_table(std::cout, rows);
  std::cout
      << "\nmax/RMS rel err: |V - V*| of the prisms relative to the mean |V*|; volume change: relative "
         "change "
         "of the total\nvolume between base and detail; new pairs: intersecting non-adjacent triangles "
         "absent "
         "from the input\ndetail; p99 bend: 99th percentile of the change of the angles between "
         "neighbouring triangles\n(degrees, dihedral_change()); time: reconstruction only (setup + frames + "
         "solve).\n"
      << "meshes: " << o.out_dir << "/<case>_{volumes,vectors,edited_base,detail,base}.obj\n"
      << "report: " << report_path << std::endl;
  if (failures > 0) {
    std::cerr << "strata: error: " << failures << " of " << sources.size() << " demo cases failed"
              << std::endl;
    return 1;
  }
  return 0;
}

}  // namespace

Subcommand register_demo(CLI::App& parent) {
  auto o = std::make_shared<DemoCmdOptions>();
  CLI::App* app = parent.add_subcommand(
      "demo", "Rebuild the paper's bent-cylinder cases by volumes and by vectors; print a comparison");
  app->add_option("--out-dir", o->out_dir,
                  "Directory for the meshes and demo_report.json (created if needed)")
      ->capture_default_str();
  app->add_option("--triangles", o->triangles,
                  "About this many detail triangles per generated case (0: the paper's "
                  "resolution)")
      ->check(in_range(0, 50000000))
      ->capture_default_str();
  CLI::Option* assets =
      app->add_option("--assets-dir", o->assets_dir,
                      "Also run every subdirectory holding detail.*, base.* and edited_base.* meshes")
          ->capture_default_str()
          ->each([o](const std::string&) { o->assets_dir_given = true; });
  app->add_flag("--no-assets", o->no_assets, "Run the generated cases only")->excludes(assets);
  app->add_flag("-q,--quiet", o->quiet, "No progress lines on stderr");
  return {app, [o] { return run_demo(*o); }};
}

}  // namespace strata::cli

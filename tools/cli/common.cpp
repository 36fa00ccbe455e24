#include "common.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>
#include <utility>

#include "stats_json.h"
#include "strata/atomic_file.h"
#include "strata/exceptions.h"
#include "strata/mesh_io.h"

namespace strata::cli {

namespace fs = std::filesystem;

void Log::phase(const std::string& text) const {
  if (!quiet_) std::cerr << "strata: " << prefix_ << text << std::endl;
}

ProgressCallback Log::progress(const std::string& label) const {
  if (quiet_) return {};
  // The last line's phase and percentage: a new phase (a retry) starts its lines again.
  auto last = std::make_shared<std::pair<std::string, int>>(std::string(), -1);
  return [label = prefix_ + label, last](const std::string& phase, double fraction) {
    const int percent = static_cast<int>(std::lround(100.0 * std::clamp(fraction, 0.0, 1.0)));
    if (percent == last->second && phase == last->first) return;
    *last = {phase, percent};
    std::cerr << "strata: " << label << ": " << phase << " " << percent << "%" << std::endl;
  };
}

const char* to_string(Method method) {
  return method == Method::Volumes ? "volumes" : "vectors";
}

Method parse_method(const std::string& text) {
  if (text == "volumes") return Method::Volumes;
  if (text == "vectors") return Method::Vectors;
  throw InvalidInput("unknown method '" + text + "' (expected 'volumes' or 'vectors')");
}

namespace {
// A numeric option's text as a number, or the message that it is not one.
// Numbers are decimal: CLI11 converts integers in base 0, so "0100" was 64, "08" failed to
// convert and "0x10" was 16, while the range checks read the same text as decimal. Leading
// zeros are dropped from \p text (validators may rewrite it) and 0x / 0b / 0o are refused.
std::string parse_number(std::string& text, double& v) {
  const std::size_t sign = !text.empty() && (text[0] == '+' || text[0] == '-') ? 1 : 0;
  if (text.size() > sign + 1 && text[sign] == '0' && std::strchr("xXbBoO", text[sign + 1]))
    return "'" + text + "' is not a decimal number";
  std::size_t zeros = sign;
  while (zeros + 1 < text.size() && text[zeros] == '0' &&
         std::isdigit(static_cast<unsigned char>(text[zeros + 1])))
    ++zeros;
  text.erase(sign, zeros - sign);
  if (text.empty() || !CLI::detail::lexical_cast(text, v) || std::isnan(v))
    return "'" + text + "' is not a number";
  return {};
}
// A bound as written: whole numbers in full ("50000000", where << printed "5e+07").
std::string bound_text(double x) {
  std::ostringstream os;
  if (x == std::floor(x) && std::abs(x) < 1e15)
    os << static_cast<long long>(x);
  else
    os << x;
  return os.str();
}
}  // namespace

CLI::Validator at_least(double lo, bool strict) {
  const std::string range = (strict ? "above " : "at least ") + bound_text(lo);
  return CLI::Validator(
      [lo, strict, range](std::string& text) -> std::string {
        double v = 0.0;
        if (std::string e = parse_number(text, v); !e.empty()) return e;
        if (strict ? v > lo : v >= lo) return {};
        return "must be " + range + ", not " + text;
      },
      (strict ? "> " : ">= ") + bound_text(lo));
}

CLI::Validator in_range(double lo, double hi) {
  const std::string range = bound_text(lo) + " to " + bound_text(hi);
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        double v = 0.0;
        if (std::string e = parse_number(text, v); !e.empty()) return e;
        if (v >= lo && v <= hi) return {};
        return "must be " + range + ", not " + text;
      },
      "in " + range);
}

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

void validate_result(const TriMesh& mesh, const std::string& what, const std::string& output) {
  try {
    validate_mesh(mesh, what);
  } catch (const InvalidInput& e) {
    throw InvalidInput(std::string(e.what()) + " (not written to " + output + ")");
  }
}

void warn_stl_drops_vertices(const TriMesh& mesh, const std::string& path) {
  if (lower_extension(path) != ".stl") return;
  std::vector<char> used(mesh.vertices.size(), 0);
  for (const Face& f : mesh.faces)
    for (int v : f) used[v] = 1;
  const int lost = static_cast<int>(std::count(used.begin(), used.end(), 0));
  if (lost > 0)
    std::cerr << "strata: warning: " << path << ": STL holds triangles only: " << lost
              << " vertices in no face are not written (OBJ, OFF and PLY keep them)" << std::endl;
}

namespace {
std::vector<std::string> companion_names(const MeshAttributes& a) {
  std::vector<std::string> names;
  for (const CompanionFile& f : a.files) names.push_back(f.name);
  return names;
}
}  // namespace

json attributes_json(const MeshAttributes& a) {
  return {{"vertex_colors", a.colors.empty()      ? "none"
                            : a.colors_have_alpha ? "rgba"
                                                  : "rgb"},
          {"texture_coordinates", !a.texcoords.empty()         ? "per_vertex"
                                  : !a.corner_uv_index.empty() ? "per_corner"
                                                               : "none"},
          {"materials", a.material_names.size()},
          {"material_library", a.material_library},
          {"texture_files", a.texture_files},
          {"companion_files", companion_names(a)}};
}

void warn_attributes_not_stored(const MeshAttributes& attributes, const std::string& path) {
  const std::vector<std::string> lost = attributes_not_stored(attributes, path);
  if (!lost.empty()) {
    std::string what;
    for (std::size_t i = 0; i < lost.size(); ++i)
      what += (i == 0 ? "" : i + 1 == lost.size() ? " and " : ", ") + lost[i];
    std::cerr << "strata: warning: " << path << ": this format does not store " << what << "; not written"
              << std::endl;
  }
}

MeshAttributes output_attributes(const MeshAttributes& attributes, const std::string& path) {
  std::vector<std::string> notes;
  MeshAttributes a = attributes_for_format(attributes, path, &notes);
  for (const std::string& note : notes) std::cerr << "strata: note: " << note << std::endl;
  return a;
}

void read_companions(MeshAttributes& attributes, const std::string& path) {
  for (const std::string& note : read_companion_files(attributes, path))
    std::cerr << "strata: note: " << note << std::endl;
}

void write_companions(const MeshAttributes& attributes, const std::string& path, StagedOutputs* staged) {
  CompanionWriter stage;
  if (staged)
    stage = [staged](const std::string& target, const std::string& bytes) {
      if (staged->stages(target))  // the mesh or the report: an output of the command wins
        std::cerr << "strata: note: " << target
                  << " is an output of this command; the scan's file of that name "
                  << "is not written" << std::endl;
      else
        staged->write(target, [&](const std::string& p) { write_text_file_atomically(p, bytes); });
    };
  for (const std::string& note : write_companion_files(attributes, path, stage))
    std::cerr << "strata: note: " << note << std::endl;
}

void require_numbers(CLI::App& app) {
  const CLI::Validator number(
      [](std::string& text) -> std::string {
        double v = 0.0;
        return parse_number(text, v);
      },
      "");
  for (CLI::Option* option : app.get_options()) {
    // The type name, then ':' and the validators' descriptions ("FLOAT:FLOAT in [0 - 360]").
    const std::string type = option->get_type_name().substr(0, option->get_type_name().find(':'));
    if (type == "INT" || type == "UINT" || type == "FLOAT" || type == "NUMBER") option->transform(number);
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) require_numbers(*sub);
}

namespace {

NamedMesh read_with(const std::string& path, const ReadOptions& options) {
  MeshFile f = read_mesh_file(path, options);  // its errors start with the path
  check_coordinates(f.mesh.vertices, path + ":");
  for (const std::string& d : f.dropped) std::cerr << "strata: note: " << path << ": not kept: " << d << "\n";
  NamedMesh m;
  m.name = path;
  m.mesh = std::move(f.mesh);
  m.reoriented_faces = f.flipped_faces;
  m.attributes = std::move(f.attributes);
  return m;
}

}  // namespace

NamedMesh read_named_mesh(const std::string& path) {
  return read_with(path, ReadOptions{});
}

NamedMesh read_scan(const std::string& path) {
  ReadOptions ro;
  ro.orient_faces = true;
  NamedMesh m = read_with(path, ro);
  if (m.reoriented_faces > 0)
    std::cerr << "strata: note: " << path << ": " << m.reoriented_faces
              << " faces flipped to agree with their neighbours' orientation\n";
  return m;
}

std::pair<NamedMesh, NamedMesh> read_base_pair(const std::string& base, const std::string& edited) {
  std::vector<std::vector<int>> base_polygons, edited_polygons;
  std::pair<NamedMesh, NamedMesh> r{{read_mesh(base, &base_polygons), base},
                                    {read_mesh(edited, &edited_polygons), edited}};
  check_coordinates(r.first.mesh.vertices, base + ":");
  check_coordinates(r.second.mesh.vertices, edited + ":");
  // The engine's range, named by file (an edited base scaled by 1e-150 was refused as "base face
  // 95 has no normal", naming no file; one by 1e-21 was solved, unconverged).
  check_extent(r.first.mesh.vertices, r.first.mesh.faces, base);
  check_extent(r.second.mesh.vertices, r.second.mesh.faces, edited);
  if (r.second.mesh.faces != r.first.mesh.faces && edited_polygons == base_polygons &&
      r.second.mesh.num_vertices() == r.first.mesh.num_vertices()) {
    r.second.mesh.faces = r.first.mesh.faces;
    validate_mesh(r.second.mesh, edited);
  }
  return r;
}

namespace {

std::string face_text(const Face& f) {
  return "(" + std::to_string(f[0]) + "," + std::to_string(f[1]) + "," + std::to_string(f[2]) + ")";
}

}  // namespace

void check_same_connectivity(const NamedMesh& base, const NamedMesh& edited) {
  const std::string what = "the edited base must have the base's connectivity (same vertices and faces)";
  if (edited.mesh.num_vertices() != base.mesh.num_vertices())
    throw InvalidInput(edited.name + ": edited base has " + std::to_string(edited.mesh.num_vertices()) +
                       " vertices, base " + base.name + " has " + std::to_string(base.mesh.num_vertices()) +
                       "; " + what);
  if (edited.mesh.num_faces() != base.mesh.num_faces())
    throw InvalidInput(edited.name + ": edited base has " + std::to_string(edited.mesh.num_faces()) +
                       " faces, base " + base.name + " has " + std::to_string(base.mesh.num_faces()) + "; " +
                       what);
  for (int j = 0; j < base.mesh.num_faces(); ++j) {
    const Face& a = base.mesh.faces[j];
    const Face& b = edited.mesh.faces[j];
    if (a != b)
      throw InvalidInput(edited.name + ": face " + std::to_string(j) + " of the edited base is " +
                         face_text(b) + ", in base " + base.name + " it is " + face_text(a) + "; " + what);
  }
}

void check_output_path(const std::string& path) {
  if (path.empty()) throw IoError("output path is empty");
  const fs::path p(path);
  std::error_code ec;
  if (fs::is_directory(p, ec)) throw IoError(path + ": is a directory, expected a file name");
  check_replaceable(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    throw IoError(path + ": cannot write: " +
                  (fs::exists(dir, ec) ? dir.string() + " is not a directory"
                                       : "directory " + dir.string() + " does not exist"));
}

bool same_file_name(const std::string& a, const std::string& b) {
  std::error_code ec;
  const fs::path pa = fs::weakly_canonical(fs::absolute(a, ec), ec);
  const fs::path pb = fs::weakly_canonical(fs::absolute(b, ec), ec);
  return pa.lexically_normal() == pb.lexically_normal();
}

void check_output_names(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs) {
  for (std::size_t a = 0; a < outputs.size(); ++a) {
    if (outputs[a].empty()) continue;
    for (std::size_t b = a + 1; b < outputs.size(); ++b)
      if (!outputs[b].empty() && same_file_name(outputs[a], outputs[b]))
        throw InvalidInput(outputs[b] +
                           ": two outputs would be written to the same file; give them different names");
    for (const std::string& in : inputs) {
      std::error_code ec;
      if (!in.empty() && (same_file_name(outputs[a], in) || fs::equivalent(outputs[a], in, ec)))
        throw InvalidInput(outputs[a] + ": would replace the input " + in +
                           "; write the output to another file");
    }
  }
}

void check_outputs(const std::string& output, const std::vector<std::string>& extra_meshes,
                   const std::string& report, const std::vector<std::string>& inputs) {
  std::vector<std::string> all{output};
  check_mesh_output_path(output);
  for (const std::string& m : extra_meshes)
    if (!m.empty()) {
      check_mesh_output_path(m);
      all.push_back(m);
    }
  if (!report.empty()) {
    check_output_path(report);
    all.push_back(report);
  }
  check_output_names(all, inputs);
}

StagedOutputs::~StagedOutputs() {
  for (const auto& [staging, target] : staged_) {
    std::error_code ec;
    fs::remove(staging, ec);  // may not exist (not written yet, or renamed); nothing to report
  }
}

void StagedOutputs::write(const std::string& target,
                          const std::function<void(const std::string& path)>& writer) {
  check_replaceable(target);
  const fs::path t(target);
  const fs::path dir = t.has_parent_path() ? t.parent_path() : fs::path(".");
  // The name cut as create_temp_file() cuts it: a 240-byte target name made a staging name past
  // NAME_MAX, refused after the whole computation. The extension stays (it picks the format).
  const std::string name = "." + t.filename().string().substr(0, 180) + ".staged." +
                           std::to_string(::getpid()) + "." + std::to_string(staged_.size()) +
                           t.extension().string();
  const std::string staging = (dir / name).string();
  staged_.emplace_back(staging, target);
  // The writers name the file they write; the user named the target.
  auto named = [&](const char* what) {
    std::string m = what;
    for (std::size_t at = m.find(staging); at != std::string::npos; at = m.find(staging, at + target.size()))
      m.replace(at, staging.size(), target);
    return m;
  };
  try {
    writer(staging);
  } catch (const IoError& e) {
    throw IoError(named(e.what()));
  } catch (const InvalidInput& e) {
    throw InvalidInput(named(e.what()));
  }
}

bool StagedOutputs::stages(const std::string& target) const {
  std::error_code ec;
  const fs::path t = fs::weakly_canonical(target, ec);
  for (const auto& [staging, staged_target] : staged_) {
    std::error_code ec2;
    if (staged_target == target || (!ec && fs::weakly_canonical(staged_target, ec2) == t)) return true;
  }
  return false;
}

void StagedOutputs::commit() {
  for (const auto& [staging, target] : staged_) {
    // A replaced file keeps its permission bits, as write_file_atomically() keeps them (a model
    // made private, 0600, became 0644 when an edit replaced it: a review, thirty-eighth session).
    struct stat st;
    if (::stat(target.c_str(), &st) == 0 && S_ISREG(st.st_mode))
      (void)::chmod(staging.c_str(), st.st_mode & 0777);
    if (::rename(staging.c_str(), target.c_str()) != 0)
      throw IoError(target + ": cannot replace it with the staged file " + staging + ": " +
                    std::strerror(errno));
  }
  staged_.clear();
}

void check_mesh_output_path(const std::string& path) {
  check_output_path(path);
  const std::string ext = lower_extension(path);
  const std::vector<std::string> supported = supported_mesh_extensions();
  if (std::find(supported.begin(), supported.end(), ext) == supported.end()) {
    std::string list;
    for (const std::string& s : supported) list += (list.empty() ? "" : ", ") + s;
    throw IoError(path + ": unsupported mesh file extension '" + ext + "' (supported: " + list + ")");
  }
}

void ensure_directory(const std::string& dir) {
  if (dir.empty()) throw IoError("output directory name is empty");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw IoError(dir + ": cannot create directory: " + ec.message());
  if (!fs::is_directory(dir, ec)) throw IoError(dir + ": exists and is not a directory");
}

cases::CylinderCaseOptions paper_case_options(cases::DetailKind kind, int triangles, double bend_degrees) {
  if (triangles < 0) throw InvalidInput("--triangles must be >= 0, got " + std::to_string(triangles));
  cases::CylinderCaseOptions o;
  o.detail = kind;
  o.target_detail_triangles = triangles;
  o.bend_degrees = bend_degrees;
  return o;
}

void add_solver_option(CLI::App* app, SolverChoice& choice, bool with_auto) {
  std::string help =
      "Volume solver: legacy (conjugate-gradient cycles, a factorized polish), multigrid (a "
      "vertex-space multigrid throughout, no factorization; for large meshes such as scans) or cycles "
      "(the multigrid in the paper's schedule: 20 volume scales of one cheap cycle each; slower to "
      "the answer, fewer seconds per cycle)";
  std::vector<std::string> solvers{"legacy", "multigrid", "cycles"};
  if (with_auto) {
    help += ", or auto: multigrid for a detail of at least " + std::to_string(kAutoMultigridPrisms) +
            " triangles, legacy below";
    solvers.insert(solvers.begin(), "auto");
  }
  app->add_option("--solver", choice.solver, help)->check(CLI::IsMember(solvers))->capture_default_str();
  std::string names;
  for (const std::string& n : reconstruct_option_names()) names += (names.empty() ? "" : ", ") + n;
  app->add_option("--set", choice.sets,
                  "NAME=VALUE: one reconstruction option after the solver's preset, for tuning (repeatable; "
                  "README, How the reconstruction works). Names: " +
                      names)
      ->check(CLI::Validator(
          [](std::string& kv) -> std::string {
            try {
              ReconstructOptions scratch;
              set_reconstruct_option(scratch, kv);
            } catch (const Error& e) {
              return e.what();
            }
            return {};
          },
          "NAME=VALUE"));
  // The values' ranges and their combinations, against each preset the choice can resolve to,
  // before any input is read: `--set tolerance=-1` was refused only after reading, encoding and
  // counting intersections (and passed unused with --method vectors).
  app->callback([&choice] {
    if (choice.sets.empty()) return;
    const std::vector<std::string> presets = choice.solver == "auto"
                                                 ? std::vector<std::string>{"legacy", "multigrid"}
                                                 : std::vector<std::string>{choice.solver};
    for (const std::string& preset : presets) {
      try {
        check_reconstruct_options(solver_options({preset, choice.sets}, 0));
      } catch (const Error& e) {
        throw CLI::ValidationError("--set", std::string(e.what()) + " (with the " + preset + " solver)");
      }
    }
  });
}

std::string resolve_solver(const SolverChoice& choice, std::size_t prisms) {
  if (choice.solver != "auto") return choice.solver;
  return prisms >= kAutoMultigridPrisms ? "multigrid" : "legacy";
}

ReconstructOptions solver_options(const SolverChoice& choice, int threads) {
  ReconstructOptions o = named_reconstruct_options(choice.solver);
  o.threads = threads;
  for (const std::string& kv : choice.sets) set_reconstruct_option(o, kv);
  return o;
}

std::string cut_short_text(const IntersectionResult& r, const std::string& name) {
  return name + ": the self-intersection search stopped after " + std::to_string(r.num_pairs) +
         " pairs and " + std::to_string(r.num_tests) + " exact tests (" +
         (r.out_of_tests ? "too many triangles whose boxes overlap: long, thin triangles?"
                         : "too many intersecting pairs") +
         "): its counts are lower bounds";
}

std::string new_pairs_warning(const IntersectionResult& before, const IntersectionResult& after) {
  if (before.truncated)
    return "new intersecting pairs not counted: the input's search was cut short (see the warning above)";
  const std::size_t n = count_new_intersections_at_least(before, after);
  if (after.truncated)
    return "at least " + std::to_string(n) + " new intersecting pairs: the output's search was cut short";
  return n > 0 ? std::to_string(n) + " new intersecting pairs of triangles" : std::string();
}

TimedIntersections find_intersections(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                                      const std::string& name) {
  TimedIntersections t;
  Stopwatch sw;
  IntersectionOptions o = bounded_intersection_options(faces.size());
  o.collect_pairs = true;
  t.result = find_self_intersections(vertices, faces, o);
  if (t.result.truncated) std::cerr << "strata: warning: " << cut_short_text(t.result, name) << std::endl;
  t.seconds = sw.seconds();
  return t;
}

// A warning when more than this fraction of the detail's vertices fell back to the closest point,
// or its median normal offset exceeds this fraction of the base's diagonal (the paper's bends:
// no fallbacks, median offsets below 2% of the diagonal).
constexpr double kFallbackWarningFraction = 0.1;
constexpr double kOffsetWarningFraction = 0.25;

EncodedInput encode_input(const NamedMesh& detail, const NamedMesh& base, const NamedMesh& edited,
                          const Log& log) {
  check_same_connectivity(base, edited);
  log.phase("encoding the detail (" + std::to_string(detail.mesh.num_vertices()) +
            " vertices) over the base (" + std::to_string(base.mesh.num_faces()) + " faces)");
  EncodedInput e;
  Stopwatch sw;
  try {  // the engine's errors name the meshes by role; the user named files
    e.encoding = encode_detail(detail.mesh, base.mesh);
  } catch (const InvalidInput& ex) {
    throw InvalidInput("encoding " + detail.name + " over " + base.name + ": " + ex.what());
  }
  e.encode_seconds = sw.seconds();
  // A detail that is not a displacement of this base (another object, units or placement) gives a
  // meaningless result; a warning says so up front. Its signs: many closest-point fallbacks, or
  // displacements as long as the base is large (a scan's detail is small against its base).
  const EncodeReport& er = e.encoding.report;
  std::vector<double> lengths;
  for (double f : e.encoding.normal_offsets) lengths.push_back(std::abs(f));
  double median = 0.0;
  if (!lengths.empty()) {
    std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
    median = lengths[lengths.size() / 2];
  }
  const double base_size = bbox_diagonal(base.mesh.vertices);
  if (er.num_vertices > 0 && (er.num_fallback > kFallbackWarningFraction * er.num_vertices ||
                              median > kOffsetWarningFraction * base_size)) {
    std::ostringstream w;
    w << detail.name << " does not look like a displacement of " << base.name << ": " << er.num_fallback
      << " of " << er.num_vertices
      << " vertices have no base point along its normals, and the median offset is " << median
      << " against a base diagonal of " << base_size << "; the result may be meaningless";
    e.warning = w.str();
    std::cerr << "strata: warning: " << e.warning << std::endl;
  }
  log.phase("counting self-intersections of the input detail");
  e.input = find_intersections(detail.mesh.vertices, detail.mesh.faces, detail.name);
  return e;
}

MethodOutcome run_method(Method method, const ReconstructionInputs& in, const ReconstructOptions& options,
                         const Log& log) {
  const DetailEncoding& encoding = in.encoding;
  const std::vector<Vec3>& edited_base = in.edited_base;
  MethodOutcome out;
  out.method = method;
  // The edited base's frames, once for the method and the metrics; their errors name its file.
  auto edited_frames = [&] {
    try {
      return evaluate_base_frames(encoding, edited_base);
    } catch (const InvalidInput& ex) {
      throw InvalidInput(in.edited_name + ": " + ex.what());
    }
  };
  BaseFrames frames;
  if (method == Method::Volumes) {
    Stopwatch sw;
    log.phase(std::string(to_string(method)) + ": building the multigrid hierarchy (" +
              std::to_string(encoding.detail_faces.size()) + " prisms)");
    VolumeReconstructor reconstructor(encoding, options);
    out.times.setup = sw.seconds();
    sw.restart();
    frames = edited_frames();
    const double frame_seconds = sw.seconds();
    log.phase(std::string(to_string(method)) + ": solving for the prism volumes");
    ReconstructResult r = reconstructor.reconstruct(frames);
    out.times.frames = frame_seconds + r.stats.seconds_frames;
    out.times.solve = r.stats.seconds_solve;
    out.positions = std::move(r.positions);
    out.stats = std::move(r.stats);
  } else {
    log.phase(std::string(to_string(method)) + ": displacing along the edited base's normals");
    Stopwatch sw;
    frames = edited_frames();
    out.times.frames = sw.seconds();
    sw.restart();
    out.positions = reconstruct_vectors(encoding, frames);
    out.times.solve = sw.seconds();
  }
  log.phase(std::string(to_string(method)) + ": measuring prism volumes and self-intersections");
  Stopwatch mw;
  out.volume = volume_metrics(encoding, frames, out.positions);
  out.shape = dihedral_change(encoding.detail_faces, encoding.detail_rest, out.positions);
  const TimedIntersections after = find_intersections(out.positions, encoding.detail_faces,
                                                      std::string("the ") + to_string(method) + " result");
  out.output_pairs = after.result.num_pairs;
  out.new_pairs = count_new_intersections_at_least(in.input_intersections, after.result);
  out.counts_cut_short = in.input_intersections.truncated || after.result.truncated;
  out.pairs_warning = new_pairs_warning(in.input_intersections, after.result);
  out.intersection_seconds = after.seconds;
  out.times.metrics += mw.seconds();
  return out;
}

json mesh_json(const TriMesh& mesh, const std::string& name) {
  return json{{"name", name}, {"vertices", mesh.num_vertices()}, {"faces", mesh.num_faces()}};
}

json encoding_json(const EncodeReport& r) {
  return json{{"vertices", r.num_vertices},
              {"projected", r.num_projected},
              {"fallback", r.num_fallback},
              {"ambiguous", r.num_ambiguous},
              {"max_tangential_offset", r.max_tangential_offset},
              {"seconds", r.seconds}};
}

json volume_metrics_json(const VolumeMetrics& m) {
  return json{{"max_relative_error", m.max_relative_error},
              {"rms_relative_error", m.rms_relative_error},
              {"total_volume_change", m.total_volume_change},
              {"total_target_volume", m.total_target},
              {"total_volume", m.total_volume},
              {"mean_abs_target_volume", m.mean_abs_target}};
}

json intersections_json(std::size_t input_pairs, const MethodOutcome& o, double input_seconds) {
  return json{{"input_pairs", input_pairs},     {"output_pairs", o.output_pairs},
              {"new_pairs", o.new_pairs},       {"cut_short", o.counts_cut_short},
              {"input_seconds", input_seconds}, {"output_seconds", o.intersection_seconds}};
}

json iterations_json(const std::optional<ReconstructStats>& stats) {
  return stats ? tools::stats_json(*stats) : json(nullptr);
}

json solve_phases_json(const std::optional<ReconstructStats>& stats) {
  return stats ? tools::solve_phases_json(*stats) : json(nullptr);
}

json timing_json(const PhaseTimes& t) {
  return json{{"read", t.read},
              {"encode", t.encode},
              {"setup", t.setup},
              {"frames", t.frames},
              {"solve", t.solve},
              {"metrics", t.metrics},
              {"write", t.write},
              {"reconstruction", t.reconstruction()},
              {"total", t.read + t.encode + t.setup + t.frames + t.solve + t.metrics + t.write}};
}

void write_json_report(const json& report, const std::string& path) {
  // Replace invalid UTF-8 (e.g. in a file name) instead of throwing.
  write_text_file_atomically(path, report.dump(2, ' ', false, json::error_handler_t::replace) + "\n");
}

std::string sci(double value, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*e", digits, value);
  return buf;
}

std::string number_text(double x) {
  std::ostringstream os;
  os << std::setprecision(std::numeric_limits<double>::max_digits10) << x;
  return os.str();
}

std::string not_converged_text(const ReconstructStats& stats, double tolerance) {
  return "not converged: the max relative prism volume error " + number_text(stats.max_relative_error) +
         " is above the tolerance " + number_text(tolerance);
}

int finish_warnings(const json& warnings, bool strict, bool print) {
  if (strict && !warnings.empty()) {
    for (const json& w : warnings) std::cerr << "strata: error: --strict: " << w.get<std::string>() << "\n";
    return kStrictExit;
  }
  if (print)
    for (const json& w : warnings) std::cerr << "strata: warning: " << w.get<std::string>() << "\n";
  return 0;
}

std::string fixed(double value, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, value);
  return buf;
}

}  // namespace strata::cli

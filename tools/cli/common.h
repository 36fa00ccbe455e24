//! \file common.h
//! Shared pieces of the `strata` command-line tool: subcommand registration, progress lines on
//! stderr, timing, the reconstruction pipeline both `reconstruct` and `demo` run, and the JSON
//! blocks of their reports (so that the two reports have the same schema).
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "paper_cases.h"
#include "strata/encoding.h"
#include "strata/intersections.h"
#include "strata/mesh.h"
#include "strata/metrics.h"
#include "strata/reconstruction.h"

namespace strata::cli {

using json = nlohmann::json;

//! What a subcommand's registration gives back: run() is called after a successful parse when the
//! subcommand was selected, and returns the process exit code. It may throw strata::Error.
struct Subcommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

// Each subcommand registers its options (held in a struct owned by the returned closure).
Subcommand register_reconstruct(CLI::App& parent);
Subcommand register_stats(CLI::App& parent);
Subcommand register_generate(CLI::App& parent);
Subcommand register_demo(CLI::App& parent);
Subcommand register_deform(CLI::App& parent);
Subcommand register_cage(CLI::App& parent);
//! Layered models: build, info, edit, amplitude, export.
std::vector<Subcommand> register_model_commands(CLI::App& parent);

//! Wall-clock seconds since construction (or the last restart()).
class Stopwatch {
 public:
  Stopwatch() : t0_(std::chrono::steady_clock::now()) {}
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }
  void restart() { t0_ = std::chrono::steady_clock::now(); }

 private:
  std::chrono::steady_clock::time_point t0_;
};

//! Phase and progress lines on stderr ("strata: <text>"); silent when quiet.
class Log {
 public:
  //! \p prefix starts every line after "strata: " (e.g. "bumps: ").
  explicit Log(bool quiet = false, std::string prefix = {}) : quiet_(quiet), prefix_(std::move(prefix)) {}
  //! The same log with \p prefix appended to the prefix.
  Log nested(const std::string& prefix) const { return Log(quiet_, prefix_ + prefix); }
  void phase(const std::string& text) const;
  //! A callback for ReconstructOptions::progress that prints "<label>: <phase> NN%" when the
  //! percentage changes (nothing when quiet).
  ProgressCallback progress(const std::string& label) const;
  bool quiet() const { return quiet_; }

 private:
  bool quiet_;
  std::string prefix_;
};

//! The two reconstruction methods the CLI compares.
enum class Method { Volumes, Vectors };
const char* to_string(Method method);
//! "volumes" or "vectors"; throws InvalidInput for anything else.
Method parse_method(const std::string& text);

//! A numeric option's lower bound, \p lo (above it with \p strict): CLI11's NonNegativeNumber and
//! PositiveNumber printed their upper bound, DBL_MAX, in 310 digits.
CLI::Validator at_least(double lo, bool strict = false);
//! A numeric option within [lo, hi]; a value that is not a number is named as such (CLI11's Range,
//! checked before the number check, called '' out of range).
CLI::Validator in_range(double lo, double hi);

//! Adds to every numeric option of \p app and its subcommands a check that its value is a number
//! ('' was read as 0, and "nan" passed every range).
void require_numbers(CLI::App& app);
inline CLI::Validator above(double lo) {
  return at_least(lo, true);
}

//! A mesh and the name it is known by in messages (its path, or a generated case's name).
struct NamedMesh {
  TriMesh mesh;
  std::string name;
  int reoriented_faces = 0;  //!< read_scan(): faces flipped to agree with their neighbours
  //! The file's vertex colours and texture coordinates (read_mesh_file()), written with the
  //! command's result mesh, which keeps the vertex numbering.
  MeshAttributes attributes{};
};

//! read_mesh_file(path) with the path in the name; what the file holds that cannot be kept
//! (MeshFile::dropped) is a note on stderr.
NamedMesh read_named_mesh(const std::string& path);

//! A scan to build, fit or edit: read_named_mesh(), but faces that disagree with their
//! neighbours' orientation are flipped (ReadOptions::orient_faces: the fewer of a part's faces)
//! instead of refused, with a note on stderr naming the file and the count.
NamedMesh read_scan(const std::string& path);

//! The extension of \p path with its dot, lower case ("a/B.OBJ" -> ".obj").
std::string lower_extension(const std::string& path);

//! Warns on stderr when \p mesh is to be written to an STL \p path and some of its vertices are
//! in no face: STL holds triangles only, so they would be lost without a word.
void warn_stl_drops_vertices(const TriMesh& mesh, const std::string& path);

//! What \p attributes hold, as `stats` and the model reports give it: vertex_colors ("none", "rgb"
//! or "rgba"), texture_coordinates ("none", "per_vertex" or "per_corner"), materials (how many),
//! material_library, texture_files and companion_files (the names of attributes.files).
json attributes_json(const MeshAttributes& attributes);

//! \p attributes as the mesh written to \p path names its textures (attributes_for_format(): a
//! PLY's images as an OBJ's material library, an OBJ's materials' images as a PLY's TextureFile),
//! with its notes on stderr.
MeshAttributes output_attributes(const MeshAttributes& attributes, const std::string& path);

//! Warns on stderr about what of \p attributes (colours, texture coordinates, materials) the
//! format of \p path cannot store (attributes_not_stored()).
void warn_attributes_not_stored(const MeshAttributes& attributes, const std::string& path);

//! Reads the files that \p attributes of the mesh file \p path name (its material library and
//! textures: read_companion_files()) into attributes.files, and prints a note on stderr for each
//! that cannot travel (not there, or named outside the mesh's directory).
void read_companions(MeshAttributes& attributes, const std::string& path);

//! Writes attributes.files beside the mesh written to \p path (write_companion_files(): whatever
//! is already there is never replaced), through \p staged if given (they then land with the
//! other outputs, or none does), printing its notes (also on an OBJ's material library that is
//! neither among the files nor beside \p path).
class StagedOutputs;
void write_companions(const MeshAttributes& attributes, const std::string& path,
                      StagedOutputs* staged = nullptr);

//! Checks a computed mesh (validate_mesh) before it is written to \p output: an error names the
//! result (\p what) and says that \p output was not written, where the writer's own check names
//! the output as if its file were at fault (an edit that scaled a region by 1e6 left the rest of
//! the mesh zero area relative to it: "d.obj: face 0 has zero area").
//! \throw InvalidInput "<what>: <problem> (not written to <output>)".
void validate_result(const TriMesh& mesh, const std::string& what, const std::string& output);

//! A base S and its edited S2, read as read_named_mesh(). A polygon of more than 3 corners is cut
//! into triangles by its shape, so S and S2 listing the same polygons may be cut differently: S2
//! then takes S's triangles (validated at S2's positions), so that its connectivity is S's.
std::pair<NamedMesh, NamedMesh> read_base_pair(const std::string& base, const std::string& edited);

//! Throws InvalidInput unless \p edited has exactly \p base's connectivity (vertex count and face
//! list), naming both meshes and the first difference.
void check_same_connectivity(const NamedMesh& base, const NamedMesh& edited);

//! Throws IoError unless \p path can be created: its directory exists and \p path is not a
//! directory. Checked before a long computation so that a typo fails at once.
void check_output_path(const std::string& path);
//! Whether \p a and \p b name the same file (after making them absolute and normal).
bool same_file_name(const std::string& a, const std::string& b);
//! Same as check_output_path, and the extension must be one write_mesh supports.
void check_mesh_output_path(const std::string& path);

//! check_mesh_output_path for \p output and each non-empty path of \p extra_meshes, and
//! check_output_path for \p report unless empty; all of them must name different files, and none
//! may name one of \p inputs (InvalidInput: an output would replace an input the command reads).
//! Called before a long computation so that a typo fails at once.
void check_outputs(const std::string& output, const std::vector<std::string>& extra_meshes,
                   const std::string& report, const std::vector<std::string>& inputs = {});

//! Throws InvalidInput if two of \p outputs name the same file, or one names one of \p inputs (by
//! name or, for existing files, by identity: a link to it). Empty paths are skipped.
void check_output_names(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs);

//! A command's outputs, committed together: each is written to a staging file beside its target
//! (a hidden name ending in the target's extension, so that the writers choose the format by it)
//! and renamed into place only by commit(), once every output is written. If the command fails
//! before (a report that cannot be written, a full disk), the destructor removes the staging
//! files and no target changes. A rename in commit() can still fail after others succeeded; the
//! targets renamed before it then hold the new files.
class StagedOutputs {
 public:
  StagedOutputs() = default;
  StagedOutputs(const StagedOutputs&) = delete;
  StagedOutputs& operator=(const StagedOutputs&) = delete;
  ~StagedOutputs();
  //! Calls \p writer(path) to write \p target's contents to its staging file (atomically, as
  //! write_mesh() does). An IoError or InvalidInput it throws names \p target, not the staging file.
  void write(const std::string& target, const std::function<void(const std::string& path)>& writer);
  //! Whether \p target (as the same file: paths compared after weakly_canonical) is staged.
  bool stages(const std::string& target) const;
  //! Renames every staged file over its target, in staging order.
  //! \throw IoError naming the target whose rename failed.
  void commit();

 private:
  std::vector<std::pair<std::string, std::string>> staged_;  // (staging file, target)
};

//! Creates \p dir (and its parents) if needed; throws IoError if that fails or it is not a directory.
void ensure_directory(const std::string& dir);

//! Options of a paper case (Fig. 6) with \p triangles detail triangles (0: the case's default
//! resolution) and the given bend angle.
cases::CylinderCaseOptions paper_case_options(cases::DetailKind kind, int triangles, double bend_degrees);

//! The volume solver a command line chose: `--solver legacy|multigrid|cycles` (or auto, where the command
//! offers it) and any number of `--set NAME=VALUE` (set_reconstruct_option()), applied in order
//! after the solver's preset.
struct SolverChoice {
  std::string solver = "legacy";
  std::vector<std::string> sets;
};
//! `--solver auto` takes the multigrid preset for a detail of at least this many prisms, the
//! default options below. Measured on the paper's 90-degree bends, one thread (engine log): at 100k
//! prisms the preset took 1.2-1.3 s on the three scan-like (jitter 0.4) bends against 6.0-31 s, and
//! on the regular grids 4.9 s against 6.8 s (bumps), 21.7 s against 69 s (rings) and 6.9 s against
//! 6.8 s (cuboid), in less than half the memory; at 50k the two were even (median solve 2.4 s
//! against 3.0 s over six bends, each the slower on some), and the default options reach 1e-4 where
//! the preset stops at 5e-4.
constexpr std::size_t kAutoMultigridPrisms = 80000;
//! Adds `--solver` and `--set` to \p app, stored in \p choice; `--solver auto` too if \p with_auto.
//! A --set whose name or value set_reconstruct_option() refuses is a usage error.
void add_solver_option(CLI::App* app, SolverChoice& choice, bool with_auto = false);
//! \p choice's solver for a detail of \p prisms prisms: auto resolved by kAutoMultigridPrisms,
//! the others as they are.
std::string resolve_solver(const SolverChoice& choice, std::size_t prisms);
//! The reconstruction options \p choice stands for (its solver legacy, multigrid or cycles:
//! resolve auto first): the defaults (legacy: conjugate-gradient cycles and a factorized polish),
//! multigrid_reconstruct_options() or cycle_schedule_reconstruct_options(), with \p threads solver
//! threads (0: all cores), then the --set values (the last word, threads included).
ReconstructOptions solver_options(const SolverChoice& choice, int threads = 0);

//! Self-intersecting pairs of one mesh, with all pairs collected (for count_new_intersections),
//! within bounded_intersection_options(): a search cut short prints a warning (cut_short_text()),
//! and its counts are lower bounds (count_new_intersections_at_least()).
struct TimedIntersections {
  IntersectionResult result;
  double seconds = 0.0;
};
//! \p name: the mesh searched, for the warning (e.g. "scan.obj", "the output").
TimedIntersections find_intersections(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                                      const std::string& name);
//! "NAME: the self-intersection search stopped after N pairs and M exact tests (why): its counts
//! are lower bounds".
std::string cut_short_text(const IntersectionResult& r, const std::string& name);
//! The report's warning about the pairs of \p after that \p before lacks: "" if there are none;
//! "N new intersecting pairs of triangles"; or, when a search was cut short, which one and what
//! the count then means.
std::string new_pairs_warning(const IntersectionResult& before, const IntersectionResult& after);
//! Appended to a summary's count of new pairs when a search was cut short.
inline const char* cut_short_note(bool cut_short) {
  return cut_short ? " (at least: the search stopped early)" : "";
}

//! What reconstruct and demo share before the methods run: the detail encoded over the base and
//! the input detail's own intersections.
struct EncodedInput {
  DetailEncoding encoding;
  TimedIntersections input;
  double encode_seconds = 0.0;
  //! Non-empty when the detail does not look like a displacement of its base (printed as a
  //! warning on stderr too): its result is then meaningless.
  std::string warning;
};
//! Checks that \p edited has \p base's connectivity, encodes \p detail over \p base and counts
//! the detail's self-intersections, logging each phase.
EncodedInput encode_input(const NamedMesh& detail, const NamedMesh& base, const NamedMesh& edited,
                          const Log& log);

//! Wall-clock seconds of the phases of one reconstruction (0 for a phase the method lacks).
struct PhaseTimes {
  double read = 0.0;     //!< reading (or generating) the three meshes
  double encode = 0.0;   //!< encode_detail
  double setup = 0.0;    //!< building the multigrid hierarchy (volumes only)
  double frames = 0.0;   //!< evaluating the base points on the edited base
  double solve = 0.0;    //!< the multigrid solve, or the vector displacement
  double metrics = 0.0;  //!< volume metrics and self-intersection counts
  double write = 0.0;    //!< writing the output mesh(es)
  //! Reconstruction proper: setup + frames + solve.
  double reconstruction() const { return setup + frames + solve; }
};

//! Everything one method produced over one edited base, and how well it did.
struct MethodOutcome {
  Method method = Method::Volumes;
  std::vector<Vec3> positions;
  VolumeMetrics volume;
  DihedralChange shape;  //!< the result's bends against the input detail's (dihedral_change())
  std::size_t output_pairs = 0;
  std::size_t new_pairs = 0;              //!< a lower bound if counts_cut_short
  bool counts_cut_short = false;          //!< the input's or the output's search hit its limits
  std::string pairs_warning;              //!< new_pairs_warning()
  double intersection_seconds = 0.0;      //!< of the output only (the input's is counted once per case)
  std::optional<ReconstructStats> stats;  //!< volumes only
  PhaseTimes times;                       //!< setup, frames, solve, metrics filled in here
};

//! What every method runs on: one encoded detail, one edited base.
struct ReconstructionInputs {
  const DetailEncoding& encoding;
  const std::vector<Vec3>& edited_base;           //!< the edited base's vertices (the base's connectivity)
  const std::string& edited_name;                 //!< its file, named in the errors it causes
  const IntersectionResult& input_intersections;  //!< the input detail's own, with pairs collected
};

//! Runs \p method on \p in, then measures the prism volumes and the self-intersections that are new
//! against the input detail's. \p options configures the volumes method (its progress callback is
//! used as is).
MethodOutcome run_method(Method method, const ReconstructionInputs& in, const ReconstructOptions& options,
                         const Log& log);

// JSON blocks shared by the reports of `reconstruct` and `demo`.
json mesh_json(const TriMesh& mesh, const std::string& name);
json encoding_json(const EncodeReport& report);
json volume_metrics_json(const VolumeMetrics& metrics);
//! {"input_pairs", "output_pairs", "new_pairs", "cut_short", "input_seconds", "output_seconds"};
//! with "cut_short" true the counts are lower bounds.
json intersections_json(std::size_t input_pairs, const MethodOutcome& outcome, double input_seconds);
//! ReconstructStats as JSON; null for the vectors method (no iterations).
json iterations_json(const std::optional<ReconstructStats>& stats);
// The volume solve's phases (ReconstructStats::seconds_levels, _polish, _folds), or null.
json solve_phases_json(const std::optional<ReconstructStats>& stats);
json timing_json(const PhaseTimes& times);

//! Writes \p report (pretty-printed, newline-terminated) to \p path atomically.
void write_json_report(const json& report, const std::string& path);

//! Exit status of --strict when a result misses a target (its "warnings"); errors exit 1, usage
//! errors 2. The outputs are written all the same.
constexpr int kStrictExit = 3;
//! A number with the digits to read back the same; "nan" and "inf" as such (a JSON dump prints
//! null for them).
std::string number_text(double x);
//! "not converged: the max relative prism volume error E is above the tolerance T".
std::string not_converged_text(const ReconstructStats& stats, double tolerance);
//! The end of a command whose result may miss a target: with \p strict each warning is printed as
//! an error ("strata: error: --strict: W") and kStrictExit returned; otherwise, if \p print, each
//! is printed as a warning; 0 then.
int finish_warnings(const json& warnings, bool strict, bool print);

//! printf-style "%.*e" / "%.*f" formatting helpers for the human summaries.
std::string sci(double value, int digits = 2);
std::string fixed(double value, int digits = 2);

}  // namespace strata::cli

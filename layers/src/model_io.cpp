// LayeredModel in .strata files (layers/FORMAT.md, "Model header and sections"). A band's
// encoding is stored as its base points and its base at rest; everything else (target volumes,
// offsets, weights) is recomputed on reading by encode_detail_at(), the code that computed it
// first, so a model read back is bit for bit the model written.
#include <cmath>
#include <cstring>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "model_access.h"
#include "options_io.h"
#include "strata/exceptions.h"
#include "strata/json_check.h"
#include "strata/layers/model.h"
#include "strata/layers/strata_file.h"

namespace strata::layers {
namespace {

// Band 1's base surface is band 0's cage at band 1's rest base points: a cage that fails on its
// own points too is band 0's fault, reported as such.
struct CageFault {
  std::string problem;
};

using json = nlohmann::json;

// Whether \p s is valid UTF-8, the only text a JSON header holds.
bool is_utf8(const std::string& s) {
  try {
    (void)json(s).dump();
    return true;
  } catch (const json::exception&) {
    return false;
  }
}

// A name of the scan's (a material, a texture or companion file) in the header: as a string, or,
// if it is not UTF-8 (an OBJ written in Latin-1), as {"hex": "<its bytes>"}, so that nothing is
// lost (dump() threw a JSON library error for it: `strata build` of such a scan failed).
json header_string(const std::string& s) {
  if (is_utf8(s)) return s;
  static const char* digits = "0123456789abcdef";
  std::string hex;
  hex.reserve(2 * s.size());
  for (unsigned char ch : s) hex.push_back(digits[ch >> 4]), hex.push_back(digits[ch & 15]);
  return json{{"hex", hex}};
}
json header_strings(const std::vector<std::string>& v) {
  json out = json::array();
  for (const std::string& s : v) out.push_back(header_string(s));
  return out;
}

std::vector<double> flatten(const std::vector<Vec3>& x) {
  std::vector<double> out;
  out.reserve(3 * x.size());
  for (const Vec3& p : x) out.insert(out.end(), {p.x(), p.y(), p.z()});
  return out;
}
std::vector<Vec3> unflatten(const std::vector<double>& v) {
  std::vector<Vec3> out(v.size() / 3);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
  return out;
}
std::vector<std::int32_t> flatten(const std::vector<Face>& faces) {
  std::vector<std::int32_t> out;
  out.reserve(3 * faces.size());
  for (const Face& f : faces) out.insert(out.end(), {f[0], f[1], f[2]});
  return out;
}

const char* scheme_name(SubdivScheme s) {
  return s == SubdivScheme::Loop ? "loop" : s == SubdivScheme::CatmullClark ? "catmull-clark" : "auto";
}
const char* method_name(EditOptions::Method m) {
  return m == EditOptions::Method::Vectors ? "vectors" : "volumes";
}

const char* solver_name(VolumeStepSolver s) {
  switch (s) {
    case VolumeStepSolver::Direct:
      return "direct";
    case VolumeStepSolver::Multigrid:
      return "multigrid";
    case VolumeStepSolver::JacobiCG:
      break;
  }
  return "jacobi-cg";
}

json options_json(const ModelOptions& o) {
  const ReconstructOptions& r = o.reconstruct;
  return {{"method", method_name(o.method)},
          {"smoothing_fraction", o.smoothing_fraction},
          {"handle_solved_rings", o.handle_solved_rings},
          {"reconstruct",
           {{"volume_scales", r.volume_scales},
            {"max_levels", r.max_levels},
            {"coarsest_vertices", r.coarsest_vertices},
            {"coarsening_ratio", r.coarsening_ratio},
            {"volume_iterations", r.volume_iterations},
            {"finest_volume_iterations", r.finest_volume_iterations},
            {"finest_intermediate_solves", r.finest_intermediate_solves},
            {"intermediate_regularized_levels", r.intermediate_regularized_levels},
            {"retry_volume_iterations", r.retry_volume_iterations},
            {"retry_on_new_intersections", r.retry_on_new_intersections},
            {"renumber_for_locality", r.renumber_for_locality},
            {"contact_ratio", r.contact_ratio},
            {"base_crossing_rings", r.base_crossing_rings},
            {"fallback_schedule", r.fallback_schedule},
            {"retry_other_regularization", r.retry_other_regularization},
            {"fold_repair_rounds", r.fold_repair_rounds},
            {"fold_repair_local_first", r.fold_repair_local_first},
            {"fold_repair_local_rings", r.fold_repair_local_rings},
            {"fold_repair_local_rounds", r.fold_repair_local_rounds},
            {"fold_repair_rings", r.fold_repair_rings},
            {"fold_repair_sweeps", r.fold_repair_sweeps},
            {"fold_repair_max_fraction", r.fold_repair_max_fraction},
            {"regularization_iterations", r.regularization_iterations},
            {"coarse_regularization_iterations", r.coarse_regularization_iterations},
            {"coarsest_regularization_iterations", r.coarsest_regularization_iterations},
            {"coarsest_max_cycles", r.coarsest_max_cycles},
            {"tangential_regularization", to_string(r.tangential_regularization)},
            {"max_cycles", r.max_cycles},
            {"final_max_cycles", r.final_max_cycles},
            {"tangential_lambda", r.tangential_lambda},
            {"length_lambda", r.length_lambda},
            {"regularization_decay", r.regularization_decay},
            {"level_tolerance", r.level_tolerance},
            {"tolerance", r.tolerance},
            {"max_final_steps", r.max_final_steps},
            {"max_factorized_steps", r.max_factorized_steps},
            {"max_constraint_motion", r.max_constraint_motion},
            {"local_polish_max_fraction", r.local_polish_max_fraction},
            {"local_polish_rings", r.local_polish_rings},
            {"local_polish_max_motion", r.local_polish_max_motion},
            {"min_length_fraction", r.min_length_fraction},
            {"fixed_point_tolerance", r.fixed_point_tolerance},
            {"step_solver", solver_name(r.step_solver)},
            {"polish_solver", solver_name(r.polish_solver)},
            {"direct_max_prisms", r.direct_max_prisms},
            {"cg_tolerance", r.cg_tolerance},
            {"cg_max_iterations", r.cg_max_iterations},
            {"multigrid",
             {{"iterations", r.multigrid.iterations},
              {"tolerance", r.multigrid.tolerance},
              {"damping", r.multigrid.damping},
              {"smoothness", r.multigrid.smoothness},
              {"polish_iterations", r.multigrid.polish_iterations},
              {"polish_tolerance", r.multigrid.polish_tolerance},
              {"polish_damping", r.multigrid.polish_damping},
              {"polish_smoothness", r.multigrid.polish_smoothness},
              {"polish_smoothness_decay", r.multigrid.polish_smoothness_decay},
              {"retry_iterations", r.multigrid.retry_iterations},
              {"single_precision_cycles", r.multigrid.single_precision_cycles},
              {"smoothing_degree", r.multigrid.smoothing_degree},
              {"tangential_damping", r.multigrid.tangential_damping},
              {"tangential_damping_bend", r.multigrid.tangential_damping_bend},
              {"tangential_damping_margin", r.multigrid.tangential_damping_margin}}}}},
          {"projection",
           {{"seed_resolution", o.projection.seed_resolution},
            {"max_iterations", o.projection.max_iterations},
            {"orthogonality_tolerance", o.projection.orthogonality_tolerance},
            {"seam_tolerance", o.projection.seam_tolerance}}},
          {"encode",
           {{"search_rings", o.encode.search_rings},
            {"barycentric_tolerance", o.encode.barycentric_tolerance},
            {"max_distance_ratio", o.encode.max_distance_ratio}}}};
}

// Reads the model part of the header, every access checked: a corrupted or hand-edited header
// is an error naming the key, never an exception of the JSON library.
class HeaderReader {
 public:
  explicit HeaderReader(std::string file) : file_(std::move(file)) {}
  [[noreturn]] void fail(const std::string& what) const { throw InvalidInput(file_ + ": " + what); }
  const json& at(const json& j, const char* key, const std::string& where) const {
    if (!j.is_object() || !j.contains(key)) fail("missing '" + std::string(key) + "' in " + where);
    return j.at(key);
  }
  long long integer(const json& j, const char* key, const std::string& where, long long lo,
                    long long hi) const {
    const json& v = at(j, key, where);
    if (!v.is_number_integer()) fail("'" + std::string(key) + "' in " + where + " is not an integer");
    // Above 2^63 as itself (get<long long>() wrapped 2^64 - 1 to -1).
    if (v.is_number_unsigned() && v.get<unsigned long long>() > static_cast<unsigned long long>(hi))
      fail("'" + std::string(key) + "' in " + where + " is " + std::to_string(v.get<unsigned long long>()) +
           ", outside " + std::to_string(lo) + ".." + std::to_string(hi));
    const long long x = v.get<long long>();
    if (x < lo || x > hi)
      fail("'" + std::string(key) + "' in " + where + " is " + std::to_string(x) + ", outside " +
           std::to_string(lo) + ".." + std::to_string(hi));
    return x;
  }
  double number(const json& j, const char* key, const std::string& where) const {
    const json& v = at(j, key, where);
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      fail("'" + std::string(key) + "' in " + where + " is not a finite number");
    return v.get<double>();
  }
  std::string text(const json& j, const char* key, const std::string& where) const {
    const json& v = at(j, key, where);
    if (!v.is_string()) fail("'" + std::string(key) + "' in " + where + " is not a string");
    return v.get<std::string>();
  }
  // A string, or header_string()'s {"hex": ...} form of one that is not UTF-8.
  std::string name(const json& v, const std::string& what) const {
    if (v.is_string()) return v.get<std::string>();
    if (!v.is_object() || v.size() != 1 || !v.contains("hex") || !v["hex"].is_string())
      fail(what + " is not a string or {\"hex\": \"...\"}");
    const std::string& hex = v["hex"].get_ref<const std::string&>();
    auto digit = [&](char ch) {
      if (ch >= '0' && ch <= '9') return ch - '0';
      if (ch >= 'a' && ch <= 'f') return ch - 'a' + 10;
      fail(what + " has a 'hex' value that is not lower-case hexadecimal digits");
    };
    if (hex.size() % 2) fail(what + " has a 'hex' value of odd length");
    std::string out;
    for (std::size_t i = 0; i < hex.size(); i += 2)
      out.push_back(static_cast<char>(16 * digit(hex[i]) + digit(hex[i + 1])));
    return out;
  }
  bool boolean(const json& j, const char* key, const std::string& where) const {
    const json& v = at(j, key, where);
    if (!v.is_boolean()) fail("'" + std::string(key) + "' in " + where + " is not true or false");
    return v.get<bool>();
  }

 private:
  std::string file_;
};

constexpr long long kMaxCount = 1LL << 30;

ModelOptions read_options(const HeaderReader& h, const json& j) {
  ModelOptions o;
  const std::string w = "options";
  const std::string method = h.text(j, "method", w);
  if (method != "volumes" && method != "vectors") h.fail("options: unknown method '" + method + "'");
  o.method = method == "vectors" ? EditOptions::Method::Vectors : EditOptions::Method::Volumes;
  o.smoothing_fraction = h.number(j, "smoothing_fraction", w);
  o.handle_solved_rings = static_cast<int>(h.integer(j, "handle_solved_rings", w, 0, 1000));
  const json& r = h.at(j, "reconstruct", w);
  const std::string wr = "options.reconstruct";
  ReconstructOptions& ro = o.reconstruct;
  ro.volume_scales = static_cast<int>(h.integer(r, "volume_scales", wr, 1, 1000));
  ro.max_levels = static_cast<int>(h.integer(r, "max_levels", wr, 1, 100));
  ro.coarsest_vertices = static_cast<int>(h.integer(r, "coarsest_vertices", wr, 1, kMaxCount));
  ro.coarsening_ratio = h.number(r, "coarsening_ratio", wr);
  ro.volume_iterations = static_cast<int>(h.integer(r, "volume_iterations", wr, 1, 100000));
  // Files written before the option existed solved the finest level like the others.
  ro.finest_volume_iterations =
      r.contains("finest_volume_iterations")
          ? static_cast<int>(h.integer(r, "finest_volume_iterations", wr, 1, 100000))
          : ro.volume_iterations;
  // Files written before 2026-11-27 (ninth session) solved the finest level at every scale.
  ro.finest_intermediate_solves =
      !r.contains("finest_intermediate_solves") || h.boolean(r, "finest_intermediate_solves", wr);
  // Files written before the option existed did not retry.
  ro.retry_volume_iterations = r.contains("retry_volume_iterations")
                                   ? static_cast<int>(h.integer(r, "retry_volume_iterations", wr, 0, 100000))
                                   : 0;
  ro.retry_on_new_intersections =
      r.contains("retry_on_new_intersections") && h.boolean(r, "retry_on_new_intersections", wr);
  // Absent in files written before 2026-11-28, whose solves kept the band's numbering.
  ro.renumber_for_locality = r.contains("renumber_for_locality") && h.boolean(r, "renumber_for_locality", wr);
  // Absent in files written before 2026-11-28 (twenty-first session), whose solves solved every
  // coarse level at every scale.
  ro.intermediate_regularized_levels =
      r.contains("intermediate_regularized_levels")
          ? static_cast<int>(h.integer(r, "intermediate_regularized_levels", wr, 0, 100))
          : 0;
  // Absent in files written before 2026-11-28 (twenty-first session), whose solves counted every
  // new pair as a fold. (check_model_options() checks the ranges.)
  ro.contact_ratio = r.contains("contact_ratio") ? h.number(r, "contact_ratio", wr) : 0.0;
  ro.base_crossing_rings = r.contains("base_crossing_rings")
                               ? static_cast<int>(h.integer(r, "base_crossing_rings", wr, -1, 1000))
                               : -1;
  // Files written before the option existed did not fall back.
  ro.fallback_schedule = r.contains("fallback_schedule") && h.boolean(r, "fallback_schedule", wr);
  // Absent in files written before 2026-11-27, whose solves had no such retry.
  ro.retry_other_regularization =
      r.contains("retry_other_regularization") && h.boolean(r, "retry_other_regularization", wr);
  // Files written before fold repair existed did not repair (their results stay as they were).
  auto optional_count = [&](const char* key, int fallback) {
    return r.contains(key) ? static_cast<int>(h.integer(r, key, wr, 0, 100000)) : fallback;
  };
  ro.fold_repair_rounds = optional_count("fold_repair_rounds", 0);
  // Files written before 2026-11-27 (thirteenth session) polished the whole level in every round.
  ro.fold_repair_local_first =
      r.contains("fold_repair_local_first") && h.boolean(r, "fold_repair_local_first", wr);
  ro.fold_repair_local_rings = optional_count("fold_repair_local_rings", 0);
  // Files written before 2026-11-28 ran fold_repair_rounds local rounds (-1).
  ro.fold_repair_local_rounds =
      r.contains("fold_repair_local_rounds")
          ? static_cast<int>(h.integer(r, "fold_repair_local_rounds", wr, -1, 100000))
          : -1;
  ro.fold_repair_rings = optional_count("fold_repair_rings", ro.fold_repair_rings);
  ro.fold_repair_sweeps = optional_count("fold_repair_sweeps", ro.fold_repair_sweeps);
  if (r.contains("fold_repair_max_fraction"))
    ro.fold_repair_max_fraction = h.number(r, "fold_repair_max_fraction", wr);
  ro.regularization_iterations = static_cast<int>(h.integer(r, "regularization_iterations", wr, 0, 100000));
  // Files written before the option existed regularized every level alike.
  ro.coarse_regularization_iterations =
      optional_count("coarse_regularization_iterations", ro.regularization_iterations);
  // Files written before these options existed: the coarsest level as the others, rest offsets.
  ro.coarsest_regularization_iterations = optional_count("coarsest_regularization_iterations", 0);
  ro.coarsest_max_cycles = optional_count("coarsest_max_cycles", 0);
  if (r.contains("tangential_regularization")) {
    const std::string name = h.text(r, "tangential_regularization", wr);
    try {
      set_reconstruct_option(ro, "tangential_regularization", name);
    } catch (const InvalidInput&) {
      h.fail("options.reconstruct: unknown tangential_regularization '" + name + "'");
    }
  }
  ro.max_cycles = static_cast<int>(h.integer(r, "max_cycles", wr, 1, 100000));
  ro.final_max_cycles = static_cast<int>(h.integer(r, "final_max_cycles", wr, 1, 100000));
  ro.tangential_lambda = h.number(r, "tangential_lambda", wr);
  ro.length_lambda = h.number(r, "length_lambda", wr);
  ro.regularization_decay = h.number(r, "regularization_decay", wr);
  ro.level_tolerance = h.number(r, "level_tolerance", wr);
  ro.tolerance = h.number(r, "tolerance", wr);
  ro.max_final_steps = static_cast<int>(h.integer(r, "max_final_steps", wr, 0, 100000));
  // Files written before 2026-11-29 capped a stalled polish's factorized steps by max_final_steps.
  ro.max_factorized_steps = optional_count("max_factorized_steps", ro.max_final_steps);
  // Files written before 2026-11-29 (twenty-fifth session) read the default, the bound on: it
  // changes only solves that would otherwise follow a degenerate prism's step.
  if (r.contains("max_constraint_motion"))
    ro.max_constraint_motion = h.number(r, "max_constraint_motion", wr);
  // The local end's options were not written before 2026-11-27 (ninth session): such files read
  // as they did then, with the defaults (no local end).
  if (r.contains("local_polish_max_fraction"))
    ro.local_polish_max_fraction = h.number(r, "local_polish_max_fraction", wr);
  ro.local_polish_rings = optional_count("local_polish_rings", ro.local_polish_rings);
  if (r.contains("local_polish_max_motion"))
    ro.local_polish_max_motion = h.number(r, "local_polish_max_motion", wr);
  ro.min_length_fraction = h.number(r, "min_length_fraction", wr);
  ro.fixed_point_tolerance = h.number(r, "fixed_point_tolerance", wr);
  auto solver = [&](const char* key, bool cycle_steps) {
    const std::string name = h.text(r, key, wr);
    if (name == "direct") return VolumeStepSolver::Direct;
    if (name == "multigrid") return VolumeStepSolver::Multigrid;
    if (name == "jacobi-cg" && cycle_steps) return VolumeStepSolver::JacobiCG;
    h.fail("options.reconstruct: unknown " + std::string(key) + " '" + name + "'");
  };
  ro.step_solver = solver("step_solver", true);
  // Files written before the multigrid solver existed polished by factorizations.
  ro.polish_solver = r.contains("polish_solver") ? solver("polish_solver", false) : VolumeStepSolver::Direct;
  ro.direct_max_prisms = static_cast<int>(h.integer(r, "direct_max_prisms", wr, 0, kMaxCount));
  ro.cg_tolerance = h.number(r, "cg_tolerance", wr);
  ro.cg_max_iterations = static_cast<int>(h.integer(r, "cg_max_iterations", wr, 1, 1000000));
  if (r.contains("multigrid")) {
    const json& mg = h.at(r, "multigrid", wr);
    const std::string wm = wr + ".multigrid";
    MultigridStepOptions& mo = ro.multigrid;
    mo.iterations = static_cast<int>(h.integer(mg, "iterations", wm, 1, 1000000));
    mo.tolerance = h.number(mg, "tolerance", wm);
    mo.damping = h.number(mg, "damping", wm);
    mo.smoothness = h.number(mg, "smoothness", wm);
    mo.polish_iterations = static_cast<int>(h.integer(mg, "polish_iterations", wm, 1, 1000000));
    mo.polish_tolerance = h.number(mg, "polish_tolerance", wm);
    mo.polish_damping = h.number(mg, "polish_damping", wm);
    mo.polish_smoothness = h.number(mg, "polish_smoothness", wm);
    // Not written before 2026-12-03 (fiftieth session): the same smoothness at every step, as then.
    if (mg.contains("polish_smoothness_decay"))
      mo.polish_smoothness_decay = h.number(mg, "polish_smoothness_decay", wm);
    // Not written before 2026-11-27 (ninth session): such files read the defaults, as they did.
    if (mg.contains("retry_iterations"))
      mo.retry_iterations = static_cast<int>(h.integer(mg, "retry_iterations", wm, 0, 1000000));
    if (mg.contains("single_precision_cycles"))
      mo.single_precision_cycles = h.boolean(mg, "single_precision_cycles", wm);
    // Not written before 2026-12-02 (forty-second session): such files read the default (2), the
    // degree they were solved with.
    if (mg.contains("smoothing_degree"))
      mo.smoothing_degree = static_cast<int>(h.integer(mg, "smoothing_degree", wm, 1, 8));
    // Not written before 2026-12-02 (forty-fifth session): such files read the defaults (no
    // tangential damping), as they were solved.
    if (mg.contains("tangential_damping")) mo.tangential_damping = h.number(mg, "tangential_damping", wm);
    if (mg.contains("tangential_damping_bend"))
      mo.tangential_damping_bend = h.number(mg, "tangential_damping_bend", wm);
    if (mg.contains("tangential_damping_margin"))
      mo.tangential_damping_margin = h.number(mg, "tangential_damping_margin", wm);
  }
  const json& p = h.at(j, "projection", w);
  const std::string wp = "options.projection";
  o.projection.seed_resolution = static_cast<int>(h.integer(p, "seed_resolution", wp, 1, 64));
  o.projection.max_iterations = static_cast<int>(h.integer(p, "max_iterations", wp, 1, 100000));
  o.projection.orthogonality_tolerance = h.number(p, "orthogonality_tolerance", wp);
  o.projection.seam_tolerance = h.number(p, "seam_tolerance", wp);
  const json& e = h.at(j, "encode", w);
  const std::string we = "options.encode";
  o.encode.search_rings = static_cast<int>(h.integer(e, "search_rings", we, 0, 1000));
  o.encode.barycentric_tolerance = h.number(e, "barycentric_tolerance", we);
  o.encode.max_distance_ratio = h.number(e, "max_distance_ratio", we);
  return o;
}

}  // namespace

void internal::check_options_round_trip(const ModelOptions& options) {
  (void)read_options(HeaderReader("the model's options"), options_json(options));
}

void write_model(const LayeredModel& model, const std::string& path) {
  // A default-constructed model has no bands: nothing a reader would take ("band 0 out of range").
  if (model.num_bands() < 2)
    throw InvalidInput(path + ": the model has " + std::to_string(model.num_bands()) +
                       " bands, not written (a model has at least 2: build() or read_model() makes one)");
  // During a drag band(k) is the preview; the file gets the committed state (a copy is that).
  if (model.dragging()) return write_model(LayeredModel(model), path);
  StrataContainer c;
  json bands = json::array();
  const Band& cage = model.band(0);
  {
    std::vector<std::int32_t> sizes, indices;
    for (const auto& f : cage.cage.faces) {
      sizes.push_back(static_cast<std::int32_t>(f.size()));
      indices.insert(indices.end(), f.begin(), f.end());
    }
    json creases = json::array(), corners = json::array();
    for (const auto& cr : cage.tags.creases)
      creases.push_back({{"edge", {cr.v0, cr.v1}}, {"sharpness", cr.sharpness}});
    for (const auto& co : cage.tags.corners)
      corners.push_back({{"vertex", co.vertex}, {"sharpness", co.sharpness}});
    bands.push_back(
        {{"kind", "cage"},
         {"vertices", cage.cage.num_vertices()},
         {"faces", cage.cage.num_faces()},
         {"face_corners", indices.size()},
         {"scheme", scheme_name(cage.subdiv.scheme)},
         {"boundary", cage.subdiv.boundary == BoundaryRule::EdgeAndCorner ? "edge-and-corner" : "edge-only"},
         {"isolation_level", cage.subdiv.isolation_level},
         {"max_refined_faces", cage.subdiv.max_refined_faces},
         {"tags", {{"creases", creases}, {"corners", corners}}}});
    c.sections.push_back({"band0.points", pack_f64(flatten(cage.cage.vertices))});
    c.sections.push_back({"band0.face_sizes", pack_i32(sizes)});
    c.sections.push_back({"band0.face_indices", pack_i32(indices)});
  }
  for (int k = 1; k < model.num_bands(); ++k) {
    const Band& b = model.band(k);
    const DetailEncoding& e = b.encoding;
    const std::string p = "band" + std::to_string(k) + ".";
    const bool at_rest =
        b.mesh.vertices.size() == e.detail_rest.size() &&
        std::memcmp(b.mesh.vertices.data(), e.detail_rest.data(), sizeof(Vec3) * e.detail_rest.size()) == 0;
    const bool limit = e.over_limit_surface();
    bands.push_back({{"kind", "triangles"},
                     {"vertices", b.mesh.num_vertices()},
                     {"faces", b.mesh.num_faces()},
                     {"amplitude", b.amplitude},
                     {"base", limit ? "limit" : "mesh"},
                     {"base_vertices", b.base_rest.size()},
                     {"positions_at_rest", at_rest},
                     {"encoding_report",
                      {{"projected", e.report.num_projected},
                       {"fallback", e.report.num_fallback},
                       {"ambiguous", e.report.num_ambiguous},
                       {"max_tangential_offset", e.report.max_tangential_offset}}}});
    // Colours, texture coordinates, materials and images: a key and sections only where the band
    // has them, so that a model without them is written as before.
    const MeshAttributes& va = b.attributes;
    if (!va.empty()) {
      bands.back()["attributes"] = {
          {"colors", !va.colors.empty()},
          {"alpha", va.colors_have_alpha},
          {"texcoords", !va.texcoords.empty()},
          {"corner_texcoords", va.corner_uv_index.empty() ? 0 : va.corner_uv.size()},
          {"materials", !va.face_materials.empty()},
          {"material_library", header_string(va.material_library)},
          {"material_names", header_strings(va.material_names)},
          {"texture_files", header_strings(va.texture_files)},
          {"textures", !va.face_textures.empty()}};
      if (!va.files.empty()) {  // as above: no key where there are none
        json names = json::array();
        for (std::size_t i = 0; i < va.files.size(); ++i) {
          names.push_back(header_string(va.files[i].name));
          const std::string& bytes = va.files[i].bytes();
          c.sections.push_back(
              {p + "file" + std::to_string(i), std::vector<std::uint8_t>(bytes.begin(), bytes.end())});
        }
        bands.back()["attributes"]["files"] = names;
      }
      std::vector<double> values;
      for (const auto& col : va.colors) values.insert(values.end(), col.begin(), col.end());
      if (!va.colors.empty()) c.sections.push_back({p + "colors", pack_f64(values)});
      values.clear();
      for (const auto& t : va.texcoords) values.insert(values.end(), t.begin(), t.end());
      if (!va.texcoords.empty()) c.sections.push_back({p + "texcoords", pack_f64(values)});
      if (!va.corner_uv_index.empty()) {
        values.clear();
        for (const auto& t : va.corner_uv) values.insert(values.end(), t.begin(), t.end());
        c.sections.push_back({p + "corner_texcoords", pack_f64(values)});
        std::vector<std::int32_t> index;
        for (const auto& t : va.corner_uv_index) index.insert(index.end(), t.begin(), t.end());
        c.sections.push_back({p + "corner_texcoord_indices", pack_i32(index)});
      }
      if (!va.face_textures.empty())
        c.sections.push_back(
            {p + "face_textures", pack_i32({va.face_textures.begin(), va.face_textures.end()})});
      if (!va.face_materials.empty())
        c.sections.push_back(
            {p + "face_materials", pack_i32({va.face_materials.begin(), va.face_materials.end()})});
    }
    c.sections.push_back({p + "faces", pack_i32(flatten(b.mesh.faces))});
    c.sections.push_back({p + "rest", pack_f64(flatten(e.detail_rest))});
    if (!at_rest) c.sections.push_back({p + "positions", pack_f64(flatten(b.mesh.vertices))});
    std::vector<std::int32_t> faces;
    std::vector<double> coords;
    if (limit) {
      for (const LimitPoint& q : e.limit_points) {
        faces.push_back(q.face);
        coords.insert(coords.end(), {q.u, q.v});
      }
    } else {
      for (const BasePoint& q : e.base_points) {
        faces.push_back(q.face);
        coords.insert(coords.end(), {q.bary.x(), q.bary.y(), q.bary.z()});
      }
    }
    c.sections.push_back({p + "base_faces", pack_i32(faces)});
    c.sections.push_back({p + "base_coords", pack_f64(coords)});
    c.sections.push_back({p + "base_rest", pack_f64(flatten(b.base_rest))});
  }
  // An entry is stored as JSON where it is JSON within the header's limits (an entry is two levels
  // below the model object: at most 254 deep), otherwise as its text: a caller's entry deeper or
  // wider made every write fail (and one of 100k levels was parsed, and dumped, recursively).
  json history = json::array();
  JsonLimits entry_limits;
  entry_limits.max_depth -= 2;
  for (const std::string& h : model.history()) {
    try {
      if (!json_structure_problem(h, entry_limits).empty()) throw std::length_error("over the limits");
      json v = json::parse(h);
      // An object or array as JSON; a scalar as its text, which reads back the same (a string
      // entry "\"a\"" stored as the JSON string "a" read back as a, its quotes lost).
      history.push_back(v.is_structured() ? std::move(v) : json(h));
    } catch (const std::exception&) {
      history.push_back(h);
    }
  }
  c.model_json = json({{"type", "strata.layered_model"},
                       {"bands", bands},
                       {"options", options_json(model.options())},
                       {"history", history}})
                     .dump();
  write_strata_container(c, path);
}

LayeredModel read_model(const std::string& path) {
  const StrataContainer c = read_strata_container(path);
  const HeaderReader h(path);
  json m;
  try {
    m = json::parse(c.model_json);
  } catch (const json::exception& e) {
    h.fail("malformed model header: " + json_error_text(e.what()));
  }
  if (h.text(m, "type", "the model header") != "strata.layered_model")
    h.fail("not a layered model (type '" + m.at("type").get<std::string>() + "')");
  const json& bands_j = h.at(m, "bands", "the model header");
  if (!bands_j.is_array() || bands_j.size() < 2 || bands_j.size() > 64)
    h.fail("'bands' must be an array of 2 to 64 bands");
  const ModelOptions options = read_options(h, h.at(m, "options", "the model header"));
  // Options out of range were read and named only by the first edit, without the file (or as the
  // edit script's fault).
  try {
    check_model_options(options);
  } catch (const InvalidInput& e) {
    h.fail(e.what());
  }
  std::vector<std::string> history;
  const json& hist = h.at(m, "history", "the model header");
  if (!hist.is_array()) h.fail("'history' is not an array");
  for (const json& e : hist) history.push_back(e.is_string() ? e.get<std::string>() : e.dump());

  auto section = [&](const std::string& name) -> const Section& { return c.require(name, path); };
  std::vector<Band> bands(bands_j.size());
  // Band 0: the cage.
  {
    const json& b = bands_j[0];
    const std::string w = "band 0";
    if (h.text(b, "kind", w) != "cage") h.fail("band 0 is not a cage");
    const long long nv = h.integer(b, "vertices", w, 1, kMaxCount);
    const long long nf = h.integer(b, "faces", w, 1, kMaxCount);
    const long long nc = h.integer(b, "face_corners", w, 3, kMaxCount);
    Band& cage = bands[0];
    cage.cage.vertices = unflatten(unpack_f64(section("band0.points"), 3 * nv, path));
    const std::vector<std::int32_t> sizes = unpack_i32(section("band0.face_sizes"), nf, path);
    const std::vector<std::int32_t> idx = unpack_i32(section("band0.face_indices"), nc, path);
    long long at = 0;
    for (std::int32_t s : sizes) {
      if (s < 3 || at + s > nc) h.fail("band 0: face sizes do not match the face corner count");
      cage.cage.faces.emplace_back(idx.begin() + at, idx.begin() + at + s);
      at += s;
    }
    if (at != nc) h.fail("band 0: face sizes do not match the face corner count");
    const std::string scheme = h.text(b, "scheme", w);
    if (scheme != "loop" && scheme != "catmull-clark") h.fail("band 0: unknown scheme '" + scheme + "'");
    cage.subdiv.scheme = scheme == "loop" ? SubdivScheme::Loop : SubdivScheme::CatmullClark;
    const std::string boundary = h.text(b, "boundary", w);
    if (boundary != "edge-only" && boundary != "edge-and-corner")
      h.fail("band 0: unknown boundary rule '" + boundary + "'");
    cage.subdiv.boundary = boundary == "edge-only" ? BoundaryRule::EdgeOnly : BoundaryRule::EdgeAndCorner;
    cage.subdiv.isolation_level = static_cast<int>(h.integer(b, "isolation_level", w, 1, 10));
    // Absent in files written before 2026-11-28 (their refinement budget was the default, 0).
    if (b.contains("max_refined_faces"))
      cage.subdiv.max_refined_faces = h.integer(b, "max_refined_faces", w, 0, kMaxCount);
    const json& tags = h.at(b, "tags", w);
    const json& creases = h.at(tags, "creases", "band 0 tags");
    const json& corners = h.at(tags, "corners", "band 0 tags");
    if (!creases.is_array() || !corners.is_array()) h.fail("band 0: tags must hold arrays");
    for (const json& cr : creases) {
      const json& e = h.at(cr, "edge", "a crease");
      if (!e.is_array() || e.size() != 2 || !e[0].is_number_integer() || !e[1].is_number_integer())
        h.fail("band 0: a crease's edge is not two vertex numbers");
      // As long long: get<int>() wrapped 2^32 + 7 into 7, a crease on another edge.
      auto vertex = [&](const json& x) {
        const long long v = x.get<long long>();
        if (v < 0 || v >= nv)
          h.fail("band 0: a crease's edge has vertex " + std::to_string(v) + ", outside 0.." +
                 std::to_string(nv - 1));
        return static_cast<int>(v);
      };
      cage.tags.creases.push_back({vertex(e[0]), vertex(e[1]), h.number(cr, "sharpness", "a crease")});
    }
    for (const json& co : corners)
      cage.tags.corners.push_back({static_cast<int>(h.integer(co, "vertex", "a corner", 0, nv - 1)),
                                   h.number(co, "sharpness", "a corner")});
  }
  // Bands >= 1: meshes and encodings, coarsest first (each encoding needs its base's connectivity).
  for (std::size_t k = 1; k < bands.size(); ++k) {
    const json& b = bands_j[k];
    const std::string w = "band " + std::to_string(k), p = "band" + std::to_string(k) + ".";
    if (h.text(b, "kind", w) != "triangles") h.fail(w + " is not a triangle band");
    const long long nv = h.integer(b, "vertices", w, 3, kMaxCount);
    const long long nf = h.integer(b, "faces", w, 1, kMaxCount);
    const long long nb = h.integer(b, "base_vertices", w, 1, kMaxCount);
    Band& band = bands[k];
    band.amplitude = h.number(b, "amplitude", w);
    const std::string base_kind = h.text(b, "base", w);
    if (base_kind != (k == 1 ? "limit" : "mesh"))
      h.fail(w + ": its base must be " +
             (k == 1 ? "the cage's limit surface" : "the next coarser band's mesh"));
    const std::vector<std::int32_t> f = unpack_i32(section(p + "faces"), 3 * nf, path);
    TriMesh rest;
    for (long long j = 0; j < nf; ++j) rest.faces.push_back({f[3 * j], f[3 * j + 1], f[3 * j + 2]});
    rest.vertices = unflatten(unpack_f64(section(p + "rest"), 3 * nv, path));
    band.base_rest = unflatten(unpack_f64(section(p + "base_rest"), 3 * nb, path));
    const std::vector<std::int32_t> bf = unpack_i32(section(p + "base_faces"), nv, path);
    // Patch (u, v) over band 1's limit surface, barycentric coordinates over a mesh. Read before
    // the block below, which prefixes its errors with the file again.
    const std::vector<double> bc = unpack_f64(section(p + "base_coords"), (k == 1 ? 2 : 3) * nv, path);
    try {
      // Named as this band's (band 1's went into a copy of the cage, and read "cage vertex 0").
      check_coordinates(band.base_rest, "base at rest");
      if (k == 1) {
        std::vector<LimitPoint> lp(nv);
        for (long long i = 0; i < nv; ++i) lp[i] = LimitPoint{bf[i], bc[2 * i], bc[2 * i + 1]};
        PolyMesh base_cage = bands[0].cage;
        if (static_cast<long long>(base_cage.vertices.size()) != nb)
          throw InvalidInput("base_vertices differs from the cage");  // prefixed below
        base_cage.vertices = band.base_rest;
        std::unique_ptr<SubdivSurface> surface;
        try {
          surface = std::make_unique<SubdivSurface>(base_cage, bands[0].tags, bands[0].subdiv);
        } catch (const Error&) {  // InvalidInput or SolverError
          // Band 0's fault (its faces, tags or options) or band 1's (its base points at rest).
          try {
            const SubdivSurface cage(bands[0].cage, bands[0].tags, bands[0].subdiv);
          } catch (const Error& own) {
            throw CageFault{own.what()};
          }
          throw;
        }
        band.encoding = encode_detail_at(rest, *surface, std::move(lp));
      } else {
        std::vector<BasePoint> bp(nv);
        for (long long i = 0; i < nv; ++i)
          bp[i] = BasePoint{bf[i], Vec3(bc[3 * i], bc[3 * i + 1], bc[3 * i + 2])};
        const TriMesh base{band.base_rest, bands[k - 1].mesh.faces};
        if (static_cast<long long>(bands[k - 1].mesh.vertices.size()) != nb)
          throw InvalidInput("base_vertices differs from band " + std::to_string(k - 1));  // prefixed below
        band.encoding = encode_detail_at(rest, base, std::move(bp));
      }
    } catch (const CageFault& e) {
      h.fail("band 0: " + e.problem);
    } catch (const InvalidInput& e) {
      h.fail(w + ": " + e.what());
    } catch (const SolverError& e) {
      h.fail(w + ": " + e.what());
    }
    const json& rep = h.at(b, "encoding_report", w);
    band.encoding.report.num_projected = static_cast<int>(h.integer(rep, "projected", w, 0, nv));
    band.encoding.report.num_fallback = static_cast<int>(h.integer(rep, "fallback", w, 0, nv));
    band.encoding.report.num_ambiguous = static_cast<int>(h.integer(rep, "ambiguous", w, 0, nv));
    band.encoding.report.max_tangential_offset = h.number(rep, "max_tangential_offset", w);
    if (b.contains("attributes")) {  // files written before 2026-11-29 have none
      const json& at = h.at(b, "attributes", w);
      const std::string wa = w + "'s attributes";
      MeshAttributes& va = band.attributes;
      if (h.boolean(at, "colors", wa)) {
        const std::vector<double> v = unpack_f64(section(p + "colors"), 4 * nv, path);
        va.colors.resize(nv);
        for (long long i = 0; i < nv; ++i) std::copy(&v[4 * i], &v[4 * i] + 4, va.colors[i].begin());
      }
      va.colors_have_alpha = h.boolean(at, "alpha", wa);
      if (h.boolean(at, "texcoords", wa)) {
        const std::vector<double> v = unpack_f64(section(p + "texcoords"), 2 * nv, path);
        va.texcoords.resize(nv);
        for (long long i = 0; i < nv; ++i) va.texcoords[i] = {v[2 * i], v[2 * i + 1]};
      }
      const long long nuv = h.integer(at, "corner_texcoords", wa, 0, kMaxCount);
      if (nuv > 0) {
        const std::vector<double> v = unpack_f64(section(p + "corner_texcoords"), 2 * nuv, path);
        va.corner_uv.resize(nuv);
        for (long long i = 0; i < nuv; ++i) va.corner_uv[i] = {v[2 * i], v[2 * i + 1]};
        const std::vector<std::int32_t> index =
            unpack_i32(section(p + "corner_texcoord_indices"), 3 * nf, path);
        va.corner_uv_index.resize(nf);
        for (long long j = 0; j < nf; ++j)
          va.corner_uv_index[j] = {index[3 * j], index[3 * j + 1], index[3 * j + 2]};
      }
      if (h.boolean(at, "materials", wa)) {
        const std::vector<std::int32_t> m = unpack_i32(section(p + "face_materials"), nf, path);
        va.face_materials.assign(m.begin(), m.end());
      }
      va.material_library = h.name(h.at(at, "material_library", wa), "'material_library' in " + wa);
      auto strings = [&](const char* key) {
        const json& list = h.at(at, key, wa);
        if (!list.is_array()) h.fail(std::string("'") + key + "' in " + wa + " is not an array");
        std::vector<std::string> out;
        for (const json& n : list) out.push_back(h.name(n, std::string("a value of '") + key + "' in " + wa));
        return out;
      };
      va.material_names = strings("material_names");
      // texture_files and textures came later the same day (f6fed3b wrote files without them),
      // files (the companion files' names; their bytes in sections) on 2026-11-29.
      if (at.contains("texture_files")) va.texture_files = strings("texture_files");
      if (at.contains("files")) {
        const std::vector<std::string> files = strings("files");
        for (std::size_t i = 0; i < files.size(); ++i) {
          const Section& bytes = section(p + "file" + std::to_string(i));
          va.files.push_back({files[i], std::string(bytes.bytes.begin(), bytes.bytes.end())});
        }
      }
      if (at.contains("textures") && h.boolean(at, "textures", wa)) {
        const std::vector<std::int32_t> t = unpack_i32(section(p + "face_textures"), nf, path);
        va.face_textures.assign(t.begin(), t.end());
      }
    }
    band.mesh.faces = rest.faces;
    band.mesh.vertices = h.boolean(b, "positions_at_rest", w)
                             ? rest.vertices
                             : unflatten(unpack_f64(section(p + "positions"), 3 * nv, path));
  }
  try {
    return internal::ModelAccess::assemble_derived(std::move(bands), options, std::move(history));
  } catch (const InvalidInput& e) {
    h.fail(e.what());
  }
}

}  // namespace strata::layers

// ReconstructOptions by field name (set_reconstruct_option()): one table of the fields, so that
// tools (the CLI's and the benchmark's --set) do not each keep a list of their own.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <variant>

#include "strata/exceptions.h"
#include "strata/reconstruction.h"

namespace strata {
namespace {

using Field = std::variant<int*, double*, bool*, VolumeStepSolver*, TangentialRegularization*>;

struct Named {
  const char* name;
  Field field;
};

// Every field but progress (a callback), in the header's order.
std::vector<Named> fields(ReconstructOptions& o) {
  MultigridStepOptions& m = o.multigrid;
  return {{"volume_scales", &o.volume_scales},
          {"max_levels", &o.max_levels},
          {"coarsest_vertices", &o.coarsest_vertices},
          {"coarsening_ratio", &o.coarsening_ratio},
          {"volume_iterations", &o.volume_iterations},
          {"retry_volume_iterations", &o.retry_volume_iterations},
          {"retry_on_new_intersections", &o.retry_on_new_intersections},
          {"contact_ratio", &o.contact_ratio},
          {"base_crossing_rings", &o.base_crossing_rings},
          {"renumber_for_locality", &o.renumber_for_locality},
          {"fallback_schedule", &o.fallback_schedule},
          {"retry_other_regularization", &o.retry_other_regularization},
          {"fold_repair_rounds", &o.fold_repair_rounds},
          {"fold_repair_local_first", &o.fold_repair_local_first},
          {"fold_repair_local_rings", &o.fold_repair_local_rings},
          {"fold_repair_local_rounds", &o.fold_repair_local_rounds},
          {"fold_repair_max_fraction", &o.fold_repair_max_fraction},
          {"fold_repair_rings", &o.fold_repair_rings},
          {"fold_repair_sweeps", &o.fold_repair_sweeps},
          {"finest_volume_iterations", &o.finest_volume_iterations},
          {"finest_intermediate_solves", &o.finest_intermediate_solves},
          {"intermediate_regularized_levels", &o.intermediate_regularized_levels},
          {"regularization_iterations", &o.regularization_iterations},
          {"coarse_regularization_iterations", &o.coarse_regularization_iterations},
          {"coarsest_regularization_iterations", &o.coarsest_regularization_iterations},
          {"coarsest_max_cycles", &o.coarsest_max_cycles},
          {"tangential_regularization", &o.tangential_regularization},
          {"max_cycles", &o.max_cycles},
          {"final_max_cycles", &o.final_max_cycles},
          {"tangential_lambda", &o.tangential_lambda},
          {"length_lambda", &o.length_lambda},
          {"regularization_decay", &o.regularization_decay},
          {"level_tolerance", &o.level_tolerance},
          {"tolerance", &o.tolerance},
          {"max_final_steps", &o.max_final_steps},
          {"max_factorized_steps", &o.max_factorized_steps},
          {"max_constraint_motion", &o.max_constraint_motion},
          {"local_polish_max_fraction", &o.local_polish_max_fraction},
          {"local_polish_rings", &o.local_polish_rings},
          {"local_polish_max_motion", &o.local_polish_max_motion},
          {"min_length_fraction", &o.min_length_fraction},
          {"fixed_point_tolerance", &o.fixed_point_tolerance},
          {"step_solver", &o.step_solver},
          {"direct_max_prisms", &o.direct_max_prisms},
          {"cg_tolerance", &o.cg_tolerance},
          {"cg_max_iterations", &o.cg_max_iterations},
          {"polish_solver", &o.polish_solver},
          {"threads", &o.threads},
          {"multigrid.iterations", &m.iterations},
          {"multigrid.retry_iterations", &m.retry_iterations},
          {"multigrid.tolerance", &m.tolerance},
          {"multigrid.damping", &m.damping},
          {"multigrid.smoothness", &m.smoothness},
          {"multigrid.polish_iterations", &m.polish_iterations},
          {"multigrid.polish_tolerance", &m.polish_tolerance},
          {"multigrid.polish_damping", &m.polish_damping},
          {"multigrid.polish_smoothness", &m.polish_smoothness},
          {"multigrid.polish_smoothness_decay", &m.polish_smoothness_decay},
          {"multigrid.single_precision_cycles", &m.single_precision_cycles},
          {"multigrid.smoothing_degree", &m.smoothing_degree},
          {"multigrid.tangential_damping", &m.tangential_damping},
          {"multigrid.tangential_damping_bend", &m.tangential_damping_bend},
          {"multigrid.tangential_damping_margin", &m.tangential_damping_margin}};
}

// Plain decimal notation only: [+-]digits[.digits][e[+-]digits] (a fraction and exponent only
// if \p real). strtod alone took leading blanks but not trailing ones, and hexadecimal ("0x10").
bool decimal(const std::string& t, bool real) {
  std::size_t i = 0, digits = 0;
  auto run = [&] {
    const std::size_t start = i;
    while (i < t.size() && t[i] >= '0' && t[i] <= '9') ++i;
    return i - start;
  };
  if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
  digits = run();
  if (real && i < t.size() && t[i] == '.') {
    ++i;
    digits += run();
  }
  if (digits == 0) return false;
  if (real && i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
    ++i;
    if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
    if (run() == 0) return false;
  }
  return i == t.size();
}

[[noreturn]] void bad_value(const std::string& name, const std::string& value, const char* expected) {
  throw InvalidInput("reconstruction option " + name + ": '" + value + "' is not " + expected);
}

}  // namespace

void set_reconstruct_option(ReconstructOptions& options, const std::string& name, const std::string& value) {
  for (const Named& f : fields(options)) {
    if (name != f.name) continue;
    const char* text = value.c_str();
    char* end = nullptr;
    errno = 0;
    if (auto* i = std::get_if<int*>(&f.field)) {
      const long v = std::strtol(text, &end, 10);
      if (!decimal(value, false) || *end != '\0' || errno == ERANGE || v < -2147483647L || v > 2147483647L)
        bad_value(name, value, "a whole number");
      **i = static_cast<int>(v);
    } else if (auto* d = std::get_if<double*>(&f.field)) {
      const double v = std::strtod(text, &end);
      // ERANGE with a finite result is an underflow (a subnormal, or 0): a number all the same.
      if (!decimal(value, true) || *end != '\0' || !std::isfinite(v) ||
          (errno == ERANGE && std::abs(v) == HUGE_VAL))
        bad_value(name, value, "a finite number");
      **d = v;
    } else if (auto* b = std::get_if<bool*>(&f.field)) {
      if (value != "true" && value != "false") bad_value(name, value, "true or false");
      **b = value == "true";
    } else if (auto* r = std::get_if<TangentialRegularization*>(&f.field)) {
      if (value == to_string(TangentialRegularization::RestOffset))
        **r = TangentialRegularization::RestOffset;
      else if (value == to_string(TangentialRegularization::RestLaplacian))
        **r = TangentialRegularization::RestLaplacian;
      else
        bad_value(name, value, "rest_offset or rest_laplacian");
    } else {
      VolumeStepSolver* s = std::get<VolumeStepSolver*>(f.field);
      if (value == "jacobi_cg")
        *s = VolumeStepSolver::JacobiCG;
      else if (value == "direct")
        *s = VolumeStepSolver::Direct;
      else if (value == "multigrid")
        *s = VolumeStepSolver::Multigrid;
      else
        bad_value(name, value, "jacobi_cg, direct or multigrid");
    }
    return;
  }
  throw InvalidInput("unknown reconstruction option '" + name + "'");
}

void set_reconstruct_option(ReconstructOptions& options, const std::string& name_equals_value) {
  const auto eq = name_equals_value.find('=');
  if (eq == std::string::npos) throw InvalidInput("not NAME=VALUE: '" + name_equals_value + "'");
  set_reconstruct_option(options, name_equals_value.substr(0, eq), name_equals_value.substr(eq + 1));
}

const char* to_string(TangentialRegularization form) {
  return form == TangentialRegularization::RestLaplacian ? "rest_laplacian" : "rest_offset";
}

std::vector<std::string> reconstruct_option_names() {
  ReconstructOptions o;
  std::vector<std::string> out;
  for (const Named& f : fields(o)) out.emplace_back(f.name);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace strata

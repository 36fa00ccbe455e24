#include "stats_json.h"

namespace strata::tools {

nlohmann::json stats_json(const ReconstructStats& s) {
  return nlohmann::json{{"levels", s.levels},
                        {"level_vertices", s.level_vertices},
                        {"level_faces", s.level_faces},
                        {"renumbered", s.renumbered},
                        {"dense_levels", s.dense_levels},
                        {"cycles", s.cycles},
                        {"finest_cycles_per_scale", s.finest_cycles_per_scale},
                        {"volume_sweeps", s.volume_sweeps},
                        {"regularization_sweeps", s.regularization_sweeps},
                        {"cg_iterations", s.cg_iterations},
                        {"factorizations", s.factorizations},
                        {"local_factorizations", s.local_factorizations},
                        {"local_ends", s.local_ends},
                        {"local_ends_undone", s.local_ends_undone},
                        {"max_local_end_prisms", s.max_local_end_prisms},
                        {"retries", s.retries},
                        {"fallbacks", s.fallbacks},
                        {"fallback_kept", s.fallback_kept},
                        {"fold_repairs", s.fold_repairs},
                        {"fold_repair_polishes", s.fold_repair_polishes},
                        {"solver_new_intersecting_pairs", s.new_intersecting_pairs},
                        {"solver_contact_pairs", s.contact_pairs},
                        {"solver_base_crossing_pairs", s.base_crossing_pairs},
                        {"final_sweeps", s.final_sweeps},
                        {"deferred_constraints", s.deferred_constraints},
                        {"constraint_updates", s.constraint_updates},
                        {"solver_max_relative_error", s.max_relative_error},
                        {"solver_rms_relative_error", s.rms_relative_error},
                        {"converged", s.converged}};
}

nlohmann::json solve_phases_json(const ReconstructStats& s) {
  return nlohmann::json{
      {"levels", s.seconds_levels}, {"polish", s.seconds_polish}, {"folds", s.seconds_folds}};
}

nlohmann::json dihedral_change_json(const DihedralChange& d) {
  return nlohmann::json{{"edges", d.edges},     {"mean", d.mean_degrees}, {"median", d.median_degrees},
                        {"p90", d.p90_degrees}, {"p99", d.p99_degrees},   {"max", d.max_degrees}};
}

}  // namespace strata::tools

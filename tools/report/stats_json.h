// The solver's statistics and the result's smoothness as JSON, one mapping for the tools' reports
// (the CLI's `iterations`, `solve_phases_seconds` and `dihedral_change_degrees`, and the benchmark
// programs' per-run and per-band stats).
#pragma once

#include <nlohmann/json.hpp>

#include "strata/metrics.h"
#include "strata/reconstruction.h"

namespace strata::tools {

//! Every counter of \p stats, under the names README's *Report fields* lists for `iterations`.
nlohmann::json stats_json(const ReconstructStats& stats);

//! The solve's phases in seconds: `levels` (coarsest first), `polish`, `folds`.
nlohmann::json solve_phases_json(const ReconstructStats& stats);

//! A dihedral_change() result: `edges`, and `mean`, `median`, `p90`, `p99`, `max` in degrees.
nlohmann::json dihedral_change_json(const DihedralChange& d);

}  // namespace strata::tools

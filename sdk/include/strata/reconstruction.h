//! \file reconstruction.h
//! Volumetric detail reconstruction (paper, section 4): finds detail positions over an edited base
//! so that every prism regains its target volume.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "strata/encoding.h"
#include "strata/mesh.h"

namespace strata {

//! Reports progress: a phase name and the fraction done in [0,1].
using ProgressCallback = std::function<void(const std::string& phase, double fraction)>;

//! How the linear system (J J^T) y = r of a Gauss-Newton volume step is solved during the
//! multigrid cycles. The final polish always factorizes.
enum class VolumeStepSolver {
  //! Conjugate gradients with a diagonal preconditioner, stopped at cg_tolerance or
  //! cg_max_iterations: an inexact Newton step, cheap per step.
  JacobiCG,
  //! A sparse Cholesky factorization (CHOLMOD) per step, its symbolic analysis kept per level.
  Direct,
  //! The step as a least-squares problem over the vertices,
  //! (J^T J + eps I + eps_lap L) delta = J^T r with L the level's regularization Laplacian, by
  //! conjugate gradients preconditioned with an aggregation multigrid of the level's vertex graph
  //! (MultigridStepOptions). No factorization: memory and time linear in the mesh size. Made for
  //! irregular triangulations (scans); on a regular one (every vertex of valence 6) the volume
  //! constraints have slow checkerboard modes that it does not resolve.
  Multigrid
};

//! What the tangential part of the regularization (section 4.2) smooths. Both leave an unedited
//! base's rest detail a fixed point; they differ in where they pull an edited one.
enum class TangentialRegularization {
  //! The tangential displacement's deviation from its rest offset (rotated into the edited base's
  //! frame): p' is pulled towards q' + d n' + the rest offset, the displacement vectors' shape
  //! with other lengths, which folds in a bend tighter than the detail is high.
  RestOffset,
  //! The paper's operator p' -> p' + lambda (I - n n^T) (Laplacian(p') - c_i), the Laplacian of
  //! the positions with the original's weights, where c_i is the rest detail's own tangential
  //! Laplacian at p_i, carried from the original base's frame to the edited one (so the rest
  //! shape stays a fixed point; without c_i the round trip came back 2-11% off). Its smoothed
  //! state spreads the vertices over the detail surface instead of following the base's normals,
  //! so smoothing it to convergence does not fold a bend (see ReconstructOptions::
  //! coarsest_regularization_iterations). Needs the encoding's base_rest_normals and tangents.
  RestLaplacian
};

//! Options of VolumeStepSolver::Multigrid. eps and eps_lap are relative to the mean diagonal of
//! J^T J, so they do not depend on the mesh's scale.
struct MultigridStepOptions {
  //! Conjugate-gradient iterations per Gauss-Newton step during the cycles: a fixed budget (the
  //! regularization that follows each step does not need the step exact). On the 100k bends over
  //! scan-like triangulations 6 took 1.73-1.80 s against 10's 1.95-2.15 s (best of three, back to
  //! back), the polish taking one or two more steps.
  int iterations = 6;
  //! > 0: if the solve, and the retry of ReconstructOptions::retry_volume_iterations, still end
  //! unconverged or with new intersecting pairs, one more retry from the clean start with this many
  //! iterations per cycle step (and retry_volume_iterations steps per cycle). More accurate steps
  //! folded less on the bear's arm bend (1,433 prisms on one level: 0 new pairs with 20
  //! iterations, 113-164 with 6), but more on the regular 100k rings (6 new pairs where the first
  //! retry leaves 0), hence second. 0: no such retry.
  int retry_iterations = 0;
  //! A cycle step's solve stops earlier once the linearized residual ||r - J delta|| falls to this
  //! fraction of ||r|| (0: never).
  double tolerance = 0.0;
  //! Relative eps of the ||delta||^2 term during the cycles.
  double damping = 1e-6;
  //! Relative eps_lap of the smoothness term during the cycles. It keeps the part of a step that
  //! the volumes do not determine smooth: without it (measured on the 100k bumps) the inexact
  //! steps left rough tangential motion that folded the detail (178k intersecting pairs).
  double smoothness = 1e-2;
  //! Conjugate-gradient iterations per exact (polish) step at most.
  int polish_iterations = 25;
  //! A polish step's solve stops once the linearized residual falls to this fraction (the
  //! Newton iteration's forcing term).
  double polish_tolerance = 3e-2;
  //! Relative eps of the polish's ||delta||^2 term, at least (Levenberg-Marquardt raises it after
  //! a step that had to be undone).
  double polish_damping = 1e-8;
  //! Relative eps_lap of the polish's smoothness term.
  double polish_smoothness = 0.0;
  //! The smoothness term of the polish's k-th multigrid step (k = 0, 1, ..) is polish_smoothness
  //! times this to the power k (0 < decay <= 1; 1: the same for every step). The polish's
  //! least-squares steps leave the motions that keep the volumes to the V-cycle, which crumples a
  //! bent detail (README, Known limits of the engine); with the term the first steps make the
  //! smooth part of the correction and, the term fading, the later ones converge. Measured on the
  //! 100k scan-like bumps bend with the cycles preset (90th / 99th percentile of
  //! dihedral_change(), solve time; single runs, 0 new pairs): without 51.9 / 140.3 degrees, 1.3
  //! s; polish_smoothness 1e-3 with decay 0.1: 14.9 / 67.5, 1.7 s; 1e-2 with 0.3: 12.2 / 52.3,
  //! 2.5 s. The multigrid preset takes 1e-3 with 1e-2 (see multigrid_reconstruct_options()); the
  //! cycles preset none (its 1M polish took 7.0 s against 2.0 s with them, 2026-12-03).
  double polish_smoothness_decay = 1.0;
  //! The V-cycle's vectors in single precision during the cycles (its operators always are; the
  //! conjugate gradients around it run in double). The polish's V-cycle stays in double: its
  //! nearly singular systems stalled in single precision (the 100k cuboid: 4 factorizations).
  bool single_precision_cycles = true;
  //! Degree of the Chebyshev block-Jacobi smoother before and after each coarse correction of
  //! the cycle steps' V-cycles (1 to 8). A V-cycle applies the fine operator 2 * degree times, so
  //! degree 1 halves its fine-level work against a weaker smoothing. The polish keeps degree 2.
  //! Measured (2026-12-02, one thread, the 100k bumps bend at jitter 0.4, single runs, with the
  //! degree in the polish too): one cycle per level and scale over 16 scales took 1.49 s with
  //! degree 1 against 1.72 s with 2 and 2.08 s with 3, 0 new pairs each; in
  //! multigrid_reconstruct_options() degree 1 took 0.54 s against 0.56 s at 100k, but its 1M bend
  //! folded (one retry, 43.5 s against 7.6 s), so that preset keeps 2.
  int smoothing_degree = 2;
  //! Relative weight (as `damping`) of a term eps_t ||(I - n n^T) delta_i||^2 in the cycle steps
  //! of a clean start's intermediate volume scales, n the base normal at vertex i's base point:
  //! it makes a step grow the detail along the base's normals rather than slide it over the base.
  //! At volume scale t it takes (1 - t) of this weight; none at the full scale, in the polish, in
  //! drags or in warm starts. Vertices where the edit bends the base get none
  //! (tangential_damping_bend, tangential_damping_margin). Why: the steps are least-squares
  //! (minimum-norm) steps, which on a sloped detail move vertices along the base too, and with
  //! one cycle a scale and level (cycle_schedule_reconstruct_options()) no regularization undoes
  //! that drift: over an unedited base the clean start came back 0.84-14.8% of the diagonal off
  //! (the three paper cases, regular and scan-like, 10k-100k prisms); with 1 it comes back
  //! 0.07-0.17% off at 20k. Where the base is bent, growing along its normals is what makes
  //! displacement vectors fold; applied there too, the 100k bends folded (retries, 17-49 s).
  //! 0: none (the default; the cycles preset takes 1).
  double tangential_damping = 0.0;
  //! A vertex gets no tangential damping where the edited base bends differently from the rest
  //! base: where, for one of its neighbours, the change of the angle between their base normals
  //! over their rest distance (a change of curvature), times the larger of their displacement
  //! lengths, exceeds this. 0 over an unedited base or a rigid motion; about 2 on the inner side of
  //! the paper's 90-degree bend.
  double tangential_damping_bend = 0.1;
  //! The damping's weight rises from 0 at those vertices to full over this many mean displacement
  //! lengths along the rest detail's edges (smoothstep). With 4 the scan-like 100k bumps and rings
  //! bends folded where the bend begins and ends (40 and 115 new pairs before any repair), with 12
  //! they did not.
  double tangential_damping_margin = 12.0;
};

//! User options of the reconstruction (the paper's k, g, n, m, lambdas and tolerances). The
//! defaults reach a max relative prism volume error of 1e-4 on the paper's 90-degree bends.
struct ReconstructOptions {
  //! k: the target volumes are scaled by h_s = (s+1)/k, s = 0..k-1, starting from the clean
  //! configuration p' = q' (section 4.1). The paper uses 5 to 8.
  int volume_scales = 5;
  //! g: multigrid levels at most, the finest included (section 4.3).
  int max_levels = 10;
  //! Decimation stops when a level would have fewer vertices than this (at least 1).
  int coarsest_vertices = 200;
  //! Vertex count of a level relative to the next finer one.
  double coarsening_ratio = 0.25;
  //! n: volume-preservation steps (Gauss-Newton projections onto the prism volumes, section 4.1)
  //! per cycle at most; a cycle's volume steps stop once the level's tolerance holds. The paper
  //! uses 10; Strata's steps are Gauss-Newton steps, and on the 100k-prism bends 5 of them per
  //! cycle took 1.3 to 1.6 times as long as 2 with no fewer intersecting pairs (rings: 157
  //! against 104; bumps and cuboid 0 either way).
  int volume_iterations = 2;
  //! If a clean-start solve ends above `tolerance` (or, with retry_on_new_intersections, with
  //! intersecting triangle pairs that the rest detail does not have), it runs once more from the
  //! clean start with this many volume steps per cycle, and the better result is kept: converged
  //! first, then fewer new pairs (0 or equal to volume_iterations: no retry). The fold outcome of
  //! a schedule is erratic from case to case: measured, 2 steps left 8 new pairs on the paper's
  //! bumps at its own resolution where 5 left none, and 5 steps left 166 on the camel neck over a
  //! cage where 2 left none; 2 steps also failed to converge on the armadillo's top bent 90 degrees
  //! in a layered model (strata_bench_layers; max error 2.2), which 5 steps solve.
  int retry_volume_iterations = 5;
  //! Count the new intersecting pairs of a converged clean-start solve (exactly, on the solver's
  //! `threads`; at 100k prisms 0.05 s per count on one; each pair of the result is tested at the
  //! rest positions, with the same exact predicate, rather than the rest detail searched) and
  //! retry if there are any. The searches stay within bounded_intersection_options(): a result
  //! whose search is cut short (its triangles mostly cross each other, or long thin triangles'
  //! boxes mostly overlap) counts as its max_pairs (10 million) new pairs, unless the rest
  //! detail's search is cut short too, which leaves it and every later result of the solver
  //! unchecked (ReconstructStats::new_intersecting_pairs -1).
  //! See retry_volume_iterations.
  bool retry_on_new_intersections = true;
  //! New intersecting pairs that the edited base explains are not the solver's folds: they
  //! trigger no retry or fallback schedule (no schedule undoes what is in the base), and the fold
  //! repair takes on only the second kind below; the result kept is chosen by all its new pairs,
  //! as before. Two kinds, counted apart in
  //! ReconstructStats::contact_pairs and base_crossing_pairs:
  //! - a contact: the shortest path between the pair's two triangles' base points along the
  //!   detail's edges (over the edited base) is longer than contact_ratio times their straight
  //!   distance plus the longer of their base edges. A fold's triangles lie over one stretch of
  //!   base, while the path between the sides of a contact (a limb bent into the body) runs around
  //!   through the base. 0: no pair is a contact. Must be 0 or at least 1.
  //! - next to a crossing of the base itself: a triangle of the pair is within
  //!   base_crossing_rings vertex rings of a pair of detail triangles whose base points' triangles
  //!   cross on the edited base (and not on the rest base). -1: none is.
  //! Measured (2026-11-28, twenty-first session, strata_bench_layers on refined_elephant, the top
  //! bent 90 degrees at band 0): band 1's first solve had 560 new pairs, 240 contacts and the 320
  //! others all within 4 rings of the 421 crossings of its base (band 0's limit surface bent into
  //! itself); band 2's 2,686, 1,516 contacts and 1,170 within 4 rings of its base's 1,894
  //! crossings. Each band then ran five more solves (a retry, the other preset with its own
  //! retries), none with fewer new pairs. Both 0 / -1: every new pair is a fold, as in .strata
  //! files written before.
  double contact_ratio = 3.0;
  int base_crossing_rings = 8;
  //! The solver renumbers the detail's vertices (along a Morton curve of their rest positions) and
  //! faces for memory locality when the encoding's numbering scatters neighbours: at least 16,384
  //! vertices, and more than 10% of the face edges joining vertices more than 4,096 indices apart
  //! (as a scan whose tools hashed or shuffled its vertices: refined_elephant in assets/scans has
  //! 83%, a generated grid 0%). Every array of the API stays in the caller's numbering. The scan-like
  //! 1M bumps bend numbered at random took 14.6 s in that numbering, 7.0 s renumbered, and 6.2-6.4 s
  //! in its grid order (strata_bench --shuffle 7, one thread, 2026-11-28).
  //! The solve's path changes with the numbering (the hierarchy's ties), so results differ by more
  //! than rounding between numberings. false: the caller's numbering (.strata files written before
  //! 2026-11-28).
  bool renumber_for_locality = true;
  //! With TangentialRegularization::RestLaplacian: a clean-start solve that ends unconverged or
  //! with new intersecting pairs (after its fold repair rounds) is first retried with the rest
  //! offsets' tangential regularization (TangentialRegularization::RestOffset, on the same
  //! hierarchy, the options otherwise the same), before the retries of retry_volume_iterations and
  //! MultigridStepOptions::retry_iterations, which run only if that retry fails as well; the
  //! better result is kept (as for them). Why: the two regularizations fold on different regular
  //! grids (first attempts at 20k prisms: the rest Laplacian 2,630 new pairs on the regular
  //! cuboid and 3 on the rings, the rest offsets 0 and 104; on the scan-like ones, jitter 0.4,
  //! neither). Measured (2026-11-27, the multigrid preset, one thread): the regular 100k cuboid
  //! bend 39.4 -> 18.8 s, the regular 20k cuboid 5.8 -> 1.6 s and the regular 50k bumps 6.6 -> 7.4
  //! s, all ending with 0 new pairs; the other 33 runs of the 3 cases x regular / jitter 0.4 x 20k,
  //! 50k, 100k bends and round trips do not retry and end as before. Requires
  //! retry_on_new_intersections for the pair count.
  bool retry_other_regularization = true;
  //! If a clean-start solve still has new intersecting pairs after its retries and fold repairs,
  //! solve once more with the other solver's preset (the multigrid preset,
  //! multigrid_reconstruct_options(), for a step_solver other than Multigrid; these defaults for
  //! Multigrid), with the same tolerance, threads, fold repair options and
  //! intermediate_regularized_levels, and keep the better result (converged first,
  //! then fewer new pairs; Outcome as for the retry). It builds that solver's hierarchy on first use
  //! and costs a second solve, only then. Why: which schedule folds depends on the mesh, and the
  //! two presets fail on different ones. Measured (2026-11-26): the defaults left 18 new pairs on
  //! the rings bend at 50k prisms, jitter 0.4 (16.8 s), where the multigrid preset has none (0.56
  //! s at this tolerance); the multigrid preset left 1 and 20 on the regular 20k rings and cuboid,
  //! where the defaults have none. Requires retry_on_new_intersections.
  bool fallback_schedule = true;
  //! Local fold repair, before any retry: a converged clean-start solve with new intersecting
  //! pairs (counted as for retry_on_new_intersections, which must be on) gets up to this many
  //! repair rounds; so does the result kept when no schedule converged, whose rounds are kept only
  //! if worse in neither the new pairs nor the max error (within 1% of `tolerance`).
  //! A round smooths the vertices of the new pairs' triangles and fold_repair_rings + round rings
  //! around them by fold_repair_sweeps regularization sweeps at full weight, then exact steps
  //! restore the volumes; the best result is kept (converged first, then fewer new pairs). Folds
  //! after the solve are local (on the 100k bumps, one triangle through three neighbours two
  //! rings away), so the rounds first restore the volumes locally (a small system); only if folds
  //! remain do they run again from the solve's result, each round also polishing the whole level,
  //! and the better of the two passes is kept (fold_repair_local_first). Measured on the rings,
  //! with a whole-level polish every round: at the
  //! paper's resolution 3 rounds left 10 new pairs and 4 rounds none; at 100k prisms 3
  //! rounds left 28 (after a retry) and 6 none, so the retry did not run. 0: no repair. The local
  //! pass (fold_repair_local_first) has its own limit, fold_repair_local_rounds.
  int fold_repair_rounds = 6;
  //! Rounds of the local pass at most (fold_repair_local_first), which cost a small solve and an
  //! intersection count each (0.05 s at 100k prisms), against a whole-level polish each in the
  //! other pass; both passes also stop after two rounds without progress. Measured on the
  //! scan-like 100k bumps bend renumbered at random (2026-11-28): the local pass took the solve's
  //! 267 new pairs to 184, 120, 105, 104, 65, 44, 25 and 0 in 8 rounds; with 6 it stopped at 44,
  //! and the whole-level pass and a retry took the solve from 1.2 s to 5.6 s. -1: fold_repair_rounds
  //! (the repair of .strata files written before 2026-11-28). fold_repair_rounds 0 turns the
  //! whole repair off.
  int fold_repair_local_rounds = 12;
  //! The repair's rounds first restore the volumes locally (the smoothed vertices and
  //! fold_repair_local_rings rings around them), and run again with whole-level polishes only if
  //! folds remain; the better result of the two passes is kept (converged first, then fewer new
  //! pairs), so the outcome is never worse by that order. On the scan-like 100k cuboid bend the
  //! local pass removed the solve's new pair in two rounds (one with fold_repair_local_rings 4),
  //! where a whole-level polish took 0.9 s of the 2.5 s solve. false: the whole-level polish in
  //! every round (the repair before 2026-11-27, and that of .strata files written before).
  bool fold_repair_local_first = true;
  //! In the local pass (fold_repair_local_first), the restoration moves the smoothed vertices and
  //! this many rings of vertices around them, so that the correction spreads beyond the smoothed
  //! patch as a whole-level polish's does (a local system still). Measured on the regular 100k bumps
  //! bend: with 0 the local pass left 15 new pairs and a whole-level round removed them; with 2 or
  //! 4 the local pass removed them (in 2 rounds or 1). With 4, on the 18 bends of the engine log's
  //! sweep, no whole-level polish was left, and the regular 50k cuboid took 2.7 s against 8.0 s.
  int fold_repair_local_rings = 4;
  //! No repair when the new pairs outnumber this fraction of the prisms: so many are a global
  //! self-contact (a limb bent into the body), not local folds. The repair also stops after two
  //! rounds without progress.
  double fold_repair_max_fraction = 0.01;
  //! Rings of vertices around the new pairs' triangles smoothed in the first repair round.
  int fold_repair_rings = 2;
  //! Regularization sweeps per repair round.
  int fold_repair_sweeps = 10;
  //! Volume steps per cycle at most on the finest level at the intermediate volume scales. One
  //! step between regularization rounds is enough there to grow the detail without folds (the
  //! full scale and the polish reach the tolerance); more steps cost time (measured on the 100k
  //! bends: 5 steps take about 1.6 times as long, with the same intersection counts).
  int finest_volume_iterations = 1;
  //! Whether the intermediate volume scales solve the finest level's volumes. false: there the
  //! finest level only follows the coarse levels' solution (prolongation, then m regularization
  //! sweeps, as in a warm start's coarse_levels_only), and its volumes are solved at the full scale
  //! alone (ReconstructStats::finest_cycles_per_scale is 0 at the others). The multigrid preset
  //! takes false: the coarse levels' scales are what keeps the detail from folding, and the
  //! finest level's cycles at the intermediate scales took 27-32% of the solve (on the
  //! scan-like 100k bends, jitter 0.4, medians of three: 1.88 / 1.85 / 2.57 s -> 1.28 / 1.35 /
  //! 1.79 s, bumps / rings / cuboid, 0 new pairs either way; see sdk/docs/engine-log.md,
  //! 2026-11-27, ninth session).
  bool finest_intermediate_solves = true;
  //! With finest_intermediate_solves false: at the clean start's intermediate volume scales, this
  //! many coarse levels next to the finest follow the coarser levels' solution by prolongation
  //! and m regularization sweeps too, as the finest does, instead of being solved (never the
  //! coarsest; drags and warm starts solve every coarse level). The multigrid preset takes 1: the
  //! second-finest level's cycles at the intermediate scales took about 70% of its time, whose
  //! volumes the full scale solves anyway. Measured (2026-11-28, twenty-first session,
  //! strata_bench --case bumps --sizes 100000,1000000 --jitter 0.4 --solver multigrid --repeat 3,
  //! one thread): 100k 0.581 -> 0.522 s, 1M 6.90 -> 6.11 s (the second-finest level 1.06 -> 0.40
  //! s), CG iterations 205 -> 181 and 268 -> 242, max error 4.84e-4 -> 4.66e-4 and 4.99e-4 ->
  //! 4.99e-4, 0 new pairs either way. 0: every coarse level solved (.strata files written before).
  int intermediate_regularized_levels = 0;
  //! m: regularization sweeps per cycle on the finest level.
  int regularization_iterations = 2;
  //! m on the coarse levels of the clean-start solve (cheap there: a quarter of the vertices and
  //! less per level). The coarse levels set the detail's large-scale shape, and their smoothing
  //! decides how close an unedited base's round trip comes back (max vertex distance over the
  //! diagonal, the 0.5% target): on the cuboid, whose sharp corners are the hardest, 8 sweeps gave
  //! 0.10-0.36% at 4k, 8k, 15k and 30k prisms but 0.81% at 5k, 1.17% at 20k and 0.90% at 100k;
  //! 32 give at most 0.41% over the three cases at 5k-100k, regular and scan-like. More smoothing
  //! there brings the coarse shape nearer the displacement vectors', which fold in a bend: every
  //! 90-degree bend measured still ends without new pairs, some of the rings after more repair
  //! rounds (20k at jitter 0.4: 7.0 s, 1.4 s with 8 sweeps); 64 made the multigrid preset's 100k
  //! bend fold (18 s), so the preset keeps 8.
  int coarse_regularization_iterations = 32;
  //! m on the coarsest level at the clean start's last volume scale (not in drag or warm steps),
  //! if the hierarchy has more than one level (0: as the other coarse levels). The coarsest level sets the
  //! detail's largest-scale shape, whose slowest modes (a rotation of the detail about a tube's axis,
  //! anchored only at its open ends) a few sweeps per cycle do not smooth out; they are what a round trip
  //! keeps. The multigrid preset takes 200 sweeps and 10 cycles there with
  //! TangentialRegularization::RestLaplacian (see multigrid_reconstruct_options()).
  int coarsest_regularization_iterations = 0;
  //! Cycles at most on the coarsest level at the clean start's last volume scale (0: max_cycles).
  int coarsest_max_cycles = 0;
  //! See TangentialRegularization.
  TangentialRegularization tangential_regularization = TangentialRegularization::RestOffset;
  //! Cycles (volume steps, then m regularization sweeps) per level and volume scale at most.
  int max_cycles = 3;
  //! Cycles at most on the finest level at full volume scale, where the regularization settles
  //! the final shape.
  int final_max_cycles = 10;
  //! Damping of the tangential Laplacian of the displacements (section 4.2); on boundary vertices
  //! the tangential deviation is held at zero.
  double tangential_lambda = 0.5;
  //! Damping of the displacement-length filter d -> d + lambda f Laplacian(d / f) (section 4.2).
  double length_lambda = 0.5;
  //! The regularization weights are multiplied by this after every cycle, so the volume terms
  //! gain weight as the solve goes on (as in augmented Lagrangian methods, section 4.2).
  double regularization_decay = 0.8;
  //! Max relative volume error (|V - h V*| / mean |h V*|) at which a coarse level, or the finest
  //! level of an intermediate volume scale, counts as converged.
  double level_tolerance = 1e-2;
  //! Max relative volume error required on the finest level at full scale.
  double tolerance = 1e-4;
  //! Whole-level exact Gauss-Newton steps (the polish) at most on the finest level at full scale
  //! after the cycles, to reach `tolerance`: a sparse Cholesky factorization each with the Direct
  //! polish solver, a multigrid solve with the Multigrid one (which, if that stalls, then takes up
  //! to max_factorized_steps factorized steps). Also the rounds of each local end at most
  //! (local_polish_max_fraction) and the steps of each fold-repair round's local polish.
  int max_final_steps = 10;
  //! Factorized steps at most that finish a multigrid polish (polish_solver Multigrid) that
  //! stalls, as on regular grids, whose checkerboard volume patterns the multigrid does not
  //! represent (see MultigridStepOptions). Each is a sparse Cholesky factorization over the whole
  //! finest level. On large regular grids they converge slowly at first, each step cut to an
  //! eighth by the line search, before the fast end: measured (2026-11-29, `strata_bench --jitter
  //! 0 --sizes 1000000 --solver multigrid`), the regular 1M rings bend converged after 23
  //! factorizations in 78.9 s, where with 10 it ended unconverged after three retries (330 s, max
  //! error 2.0e-2). Layered models' files written before this option read it as max_final_steps.
  int max_factorized_steps = 30;
  //! A prism constraint is left out of a whole-level Gauss-Newton step (the cycles', the polish's;
  //! not the local end's or the fold repair's local steps, which are undone when they do not help)
  //! when the motion that would satisfy it alone, |r_j| / |grad V_j| (its residual over its
  //! gradient's norm), exceeds this many times the prism's size (its longest rest edge, or its
  //! longest displacement length times the step's volume scale and amplitude): its linearization
  //! cannot be trusted there. Where the detail is no height field over the base (a limb longer than its
  //! faired base, whose tip's vertices fall back to the same closest point), prisms sit on
  //! degenerate base triangles, whose gradients vanish at the clean start; their minimum-norm
  //! steps moved the camel's tail by 3e3 times its size (region editing at smoothing 1.0,
  //! 2026-11-29). Such a prism rejoins the steps once the detail around it has grown; one that
  //! never does stays off the tolerance, and the solve reports it. None is left out on the paper's
  //! bends (20k and 100k prisms, both presets; the 1M scan-like bumps) nor on the five limb bends
  //! of tests/data/edits at smoothing 0.25-1.0 (measured 2026-11-29).
  //! 0: every constraint in every step.
  double max_constraint_motion = 20.0;
  //! The polish's local end. Once the prisms above the tolerance and local_polish_rings rings of
  //! vertices around them make a system of at most this fraction of the finest level's prisms
  //! (the prisms with a moving vertex), the polish ends in rounds of one factorized step that
  //! moves only those vertices, each round grown again from the prisms still above the tolerance
  //! (so the later rounds are small). If max_final_steps rounds do not reach the tolerance, two
  //! rounds in a row leave as many prisms above it, or a later round's system exceeds the limit,
  //! the positions go back and the whole-level steps go
  //! on; the local end is then tried again only once the prisms above the tolerance are at most
  //! half as many as at the failed attempt. 0: whole-level steps only (the default:
  //! with factorized whole-level steps the gain is small, 8.8 -> 8.5 s on the 100k bumps). The
  //! multigrid preset takes 0.25, where one local factorization costs less than a whole-level
  //! multigrid step: on the 1M bumps bend (jitter 0.4) the first whole-level step leaves 26,212
  //! prisms above the tolerance, whose local system (222k prisms, 22% of the level) took four
  //! rounds, 0.9-1.2 s, in place of a second whole-level step of about 2.4 s (the polish 4.3 ->
  //! 2.6-2.9 s, the peak 902 against 899 bytes per prism; with 0.2 that system was over the limit); on the
  //! 100k bumps the first step leaves 12,147 prisms off, whose system is over the limit, so a second
  //! whole-level step runs (0.12 s there) and the local end follows it (44 prisms). The fold
  //! repair's whole-level polish never ends locally: its wide correction is what unfolds (a local
  //! end there left 6 new pairs on the regular 100k rings).
  double local_polish_max_fraction = 0.0;
  //! Rings of vertices around the off prisms that a local polish step moves.
  int local_polish_rings = 2;
  //! The local end's rounds are undone, and the whole-level steps go on, once they have moved a
  //! vertex farther than this fraction of the rest detail's bounding-box diagonal and farther than
  //! the polish's last whole-level step moved any vertex (the step a local end stands in for; none
  //! before the first). Why: the prisms left above the tolerance can sit in checkerboard patterns
  //! that a step moving only a small patch, its border held, fixes by moving its vertices up and
  //! down, more in every round, where a whole-level step spreads the correction. Such a ripple
  //! shows where the solve should end near the rest detail: over the unedited base, where the
  //! polish ends locally before any whole-level step. The default, 0.25%, is half the round trip's
  //! acceptance (0.5%). Measured (2026-11-27, eleventh session; `strata reconstruct --solver
  //! multigrid` over the unedited base of the cuboid scan at 20k-200k prisms): with 0.5% the
  //! round trips came back up to 0.484% of the diagonal off (regular 160k) and 0.457% (jitter 0.4,
  //! 50k); with 0.25% up to 0.241% (regular 120k) and 0.265% (jitter 100k). Bends: a whole-level step moves
  //! far more (on the scan-like 100k cuboid the first two moved a vertex 11.9% and 8.1% of the diagonal, on
  //! the 1M bumps the first 5.2%), so their local ends (0.96-1.05% and 0.37-0.40% there) are kept; before
  //! that rule two of the 100k cuboid's three local ends were undone (2.24-2.55 s against
  //! 1.77-1.81 s). 0: no bound.
  double local_polish_max_motion = 2.5e-3;
  //! Displacement lengths |f_i| below this fraction of the mean |f| are clamped in the length
  //! filter's ratio d_i / f_i, which is undefined at f = 0.
  double min_length_fraction = 0.05;
  //! The cycles on a level stop once a regularization round moves no vertex farther than this
  //! fraction of the mean displacement length.
  double fixed_point_tolerance = 1e-3;
  //! Solver of the volume step's linear system.
  VolumeStepSolver step_solver = VolumeStepSolver::JacobiCG;
  //! Levels with at most this many prisms always take exact (factorized) steps: cheap there, and
  //! fewer steps.
  int direct_max_prisms = 0;
  //! Relative residual at which the conjugate-gradient solve of a Gauss-Newton step stops.
  double cg_tolerance = 1e-2;
  //! Conjugate-gradient iterations per Gauss-Newton step at most.
  int cg_max_iterations = 60;
  //! Solver of the final polish's exact steps: Direct (a CHOLMOD factorization per step) or
  //! Multigrid (multigrid-preconditioned CG to MultigridStepOptions::polish_tolerance, without a
  //! factorization's memory).
  VolumeStepSolver polish_solver = VolumeStepSolver::Direct;
  //! Options of VolumeStepSolver::Multigrid, wherever it is used.
  MultigridStepOptions multigrid;
  //! Threads of the solver's sweeps over prisms and vertices and of its counts of new intersecting
  //! pairs (TBB; the factorizations run on the calling thread). 0: as many as TBB allows the
  //! caller; 1: the calling thread only; at most 1024. Every sum is taken in the same order
  //! whatever the count, and the pairs are sorted, so results are identical for any value.
  int threads = 0;
  //! Optional progress reports (phase, fraction), on the calling thread: during a clean-start
  //! reconstruction after every level of every volume scale, the fraction weighted by the levels'
  //! prisms (the finest level's full-scale solve and polish three times its size), phase
  //! "reconstruct"; a retry from the clean start reports "retry", the fallback to the other
  //! preset "fallback", each from 0 to 1 again. The VolumeReconstructor's construction reports
  //! "setup" (during the decimation and after each level is made).
  ProgressCallback progress;
  //! Optional: a flag another thread may set to stop a reconstruction (a modeling tool's cancel
  //! button). Read between the solver's steps (every Gauss-Newton step and conjugate-gradient
  //! iteration, regularization round, local-end and fold-repair round, level and volume scale):
  //! once it reads true, the call throws Cancelled. Measured (the multigrid preset, one thread,
  //! the flag set at random times, 2026-11-30): at most 0.023 s later at 100k prisms (41 cancels
  //! over the whole solve), 0.14 s on the regular 100k grid, whose polish factorizes (17 cancels),
  //! and 0.51 s at 1M (18 cancels in the last 30% of the solve; the worst inside the local end's
  //! factorization). A factorization is not interrupted: the flag is read before and after each
  //! (and after a local end's ordering, which took 0.4 s of a 1.26 s cancel at 1M before it was).
  //! The counts of intersecting pairs read it too (IntersectionOptions::cancel: at 1M prisms, at
  //! most 0.18 s later, in the hierarchy's build). A call past its last check returns its result. The
  //! VolumeReconstructor keeps its hierarchy and stays usable (clear the flag before the next call). A drag
  //! step cancelled midway leaves its DragState valid for the next step. The VolumeReconstructor's
  //! construction reads it too (every 1024 queued edges of the decimation and between levels: at 1M prisms at
  //! most 0.19 s later) and throws Cancelled. The flag must outlive every call that reads it (copies of these
  //! options keep the pointer); layered models do not keep it.
  const std::atomic<bool>* cancel = nullptr;
};

//! The options of a reconstruction by VolumeStepSolver::Multigrid in the cycles and the polish,
//! with the schedule it was measured with: 3 volume scales, 2 cycles per level (4 on the finest at
//! full scale), one volume step a cycle, a tolerance of 5e-4 (half the acceptance's 1e-3), the
//! polish's local end (local_polish_max_fraction 0.25), a last retry with accurate steps
//! (MultigridStepOptions::retry_iterations 20), 8 regularization sweeps on the coarse levels, and
//! the rest Laplacian (TangentialRegularization::RestLaplacian) with the coarsest level smoothed
//! to convergence at full scale (200 sweeps, 10 cycles). The other fields keep their defaults.
//! Measured on one thread (2026-11-26, Intel VM): on the 100k bends over scan-like (irregular)
//! triangulations 1.3-1.6 s and 932 bytes per prism (bumps), where the defaults take 5-7 s and
//! 2 KB; 0 new pairs on the regular and scan-like bends at 20k, 50k and 100k (the regular cuboid
//! at 100k after two retries, 30 s); an unedited base's round trip within 0.07-0.34% of the
//! diagonal at 5k-100k (0.4-1.4% at 100k with the rest offsets and 8 coarsest sweeps); with the
//! hierarchy of 2026-11-27, tenth session, the cuboid's within 0.10-0.48% at 20k-200k. On regular
//! triangulations its polish stalls and factorized steps finish it (see Multigrid). Its fold
//! outcomes are erratic from mesh to mesh (sdk/docs/engine-log.md).
//! Since 2026-12-03 its polish has a smoothness term that fades step by step
//! (MultigridStepOptions::polish_smoothness 1e-3, polish_smoothness_decay 1e-2): without it the
//! polish's steps crumpled a bent detail at the scale of its triangles. Measured on the 100k bends
//! at jitter 0.4 (`strata reconstruct --solver multigrid --set threads=1`, single runs, 0 new
//! pairs each; 90th / 99th percentile of dihedral_change() in degrees, solve seconds), before ->
//! after: bumps 41.1 / 136.0, 0.51 s -> 15.1 / 79.8, 0.84 s; rings 23.6 / 115.7, 0.64 s -> 9.9 /
//! 44.9, 0.83 s; cuboid 51.0 / 140.7, 0.67 s -> 20.0 / 87.0, 0.83 s (`legacy`'s bumps 8.2 / 38.5 in
//! 4.6-6.7 s); the 1M bumps 54.7 / 148.8, 5.4-7.3 s -> 17.2 / 91.0, 11.1 s. On the regular grids
//! (jitter 0) little changes: rings 58.1 -> 41.9, 3.8 -> 4.1 s; cuboid 124.3 -> 119.5, 5.3 -> 7.7 s.
ReconstructOptions multigrid_reconstruct_options();

//! The multigrid preset in the schedule of the paper's Listing 1 (section 4.3): many volume
//! scales, each one multigrid cycle over every level, the finest included (one Gauss-Newton step
//! per level and cycle, finest_intermediate_solves), then the preset's final cycles and polish
//! at full scale. Its cycles are cheap (MultigridStepOptions::smoothing_degree 1), so it solves
//! more constraints per second per cycle than multigrid_reconstruct_options(), but its whole
//! reconstruction takes longer: use it where the cycles' cost matters (a pass per scale, as the
//! paper measured), the multigrid preset where the time to the answer does. Changed from
//! multigrid_reconstruct_options(): volume_scales 20, max_cycles 1, finest_intermediate_solves
//! true, intermediate_regularized_levels 0, multigrid.smoothing_degree 1, multigrid.polish_damping
//! 1e-7, multigrid.tangential_damping 1, and no polish smoothness (multigrid.polish_smoothness 0,
//! its decay 1): with the multigrid preset's, its 100k bumps bend came out smoother (90th
//! percentile of dihedral_change() 18.4 against 51.9 degrees) but its 1M polish took 7.0 s
//! against 2.0 s, its reconstructions 19.7-20.3 s against 1.56-1.60 s at 100k (12.7 times;
//! strata_bench, 2026-12-03). Its result over a bend is crumpled
//! (README, Known limits of the engine). The polish damping: with the multigrid preset's 1e-8 every
//! whole-level polish step's solve on the scan-like 100k cuboid bend ran its 25 iterations and stalled at
//! 0.04-0.14 of its residual, and the polish took five such steps (0.67-0.81 s); with 1e-7 they stop at 8
//! iterations, two steps and the local end (0.16-0.21 s), and the 1M bumps bend took 22.9 s against 29.4 s
//! (one fold repair round against two), the bumps and rings at 100k as before (2026-12-02, AMD EPYC VM). The
//! multigrid preset keeps 1e-8: with 1e-7 its 1M polish took 3.7 s against 2.2 s. On regular grids (not
//! scans) the regular 100k rings bend then needed a retry (17.6 s against 5.3 s). Its intermediate scales'
//! cycle steps damp the vertices' motion along the base (MultigridStepOptions::tangential_damping 1), except
//! where the edit bends the base: its single cycles regularize no level but the coarsest and, at full scale,
//! the finest, and without the damping the steps slid the detail over the base, so that over an unedited base
//! the clean start came back 0.84-14.8% of the diagonal off (the three cases, regular and scan-like, 10k-100k
//! prisms); with it 0.033-0.248% over the same 24 cases (the acceptance 0.5%; `strata_bench
//! --round-trip`, forty-fifth session), the bends still ending with 0 new pairs (the scan-like
//! ones without a retry, three regular ones after two; the 1M bumps after three repair rounds),
//! at about 0.1-0.15 s more on the 100k bends.
//! Regularizing the levels instead (every level's cycle ending with its sweeps, or the coarse
//! levels' only, or more finest sweeps at full scale) brought the round trip within 0.5% only
//! with folds in the 100k bends (retries, 17-21 s) or the 1M bumps bend (273 s; engine log).
//! Measured on one thread
//! (2026-12-02, AMD EPYC VM, the 90-degree bends at jitter 0.4, medians of three): bumps at 100k
//! 1.90-2.63 s (the multigrid preset 0.64-0.90 s the same hours), 0.76M-1.05M prisms per second
//! per finest pass, 0 new pairs; rings 2.28 s, cuboid 2.79 s; bumps at 1M 32.8 s, after two fold
//! repair rounds, 0 new pairs. The same day on an Intel Xeon VM, after the multigrid's prefetches
//! and single-precision cycle steps: bumps 1.67-1.77 s (1.13M-1.20M), rings 1.63 s, cuboid 2.26
//! s, bumps at 1M 28.8 s after two repair rounds (README, Measured results).
ReconstructOptions cycle_schedule_reconstruct_options();

//! The preset named \p name, as the strata tools' `--solver` names them: "legacy" (the defaults,
//! ReconstructOptions{}), "multigrid" (multigrid_reconstruct_options()) or "cycles"
//! (cycle_schedule_reconstruct_options()). For tools that offer the presets by name.
//! \throw InvalidInput naming \p name and the three names, for any other name.
ReconstructOptions named_reconstruct_options(const std::string& name);

//! Checks that every field of \p options is in the solver's range, as VolumeReconstructor does on
//! construction: for options that arrive apart from a solve (a file's, a --set's).
//! \throw InvalidInput "reconstruction option NAME = VALUE is out of range (RANGE)" for the
//!        first field out of range.
void check_reconstruct_options(const ReconstructOptions& options);

//! Sets one field of \p options by its name as spelled in ReconstructOptions ("multigrid.NAME"
//! for a MultigridStepOptions field) from text, as tools and configuration files give it: whole
//! numbers for counts, decimals for reals, true/false for flags, jacobi_cg/direct/multigrid for
//! step_solver and polish_solver, rest_offset/rest_laplacian for tangential_regularization. For
//! tuning a solve from a command line (`--set NAME=VALUE`); the ranges are checked by
//! VolumeReconstructor, as for any options.
//! \throw InvalidInput for an unknown name, or a value that is not of the field's type (the
//!        message names both).
void set_reconstruct_option(ReconstructOptions& options, const std::string& name, const std::string& value);

//! The same from one "NAME=VALUE" argument, as `--set` gives it (split at the first '=').
//! \throw InvalidInput without an '=', or as above.
void set_reconstruct_option(ReconstructOptions& options, const std::string& name_equals_value);

//! The names set_reconstruct_option() takes, sorted.
std::vector<std::string> reconstruct_option_names();

//! The value set_reconstruct_option() takes for \p form: "rest_offset" or "rest_laplacian".
const char* to_string(TangentialRegularization form);

//! Iteration counts and timings of one reconstruction.
struct ReconstructStats {
  int levels = 0;                   //!< multigrid levels used, finest included
  std::vector<int> level_vertices;  //!< vertex count per level, coarsest first
  std::vector<int> level_faces;     //!< prism count per level, coarsest first
  //! Whether the solver renumbered the detail (ReconstructOptions::renumber_for_locality).
  bool renumbered = false;
  //! Levels whose prisms' J J^T is too dense to factorize (a vertex in thousands of prisms: a fan,
  //! a CAD cylinder's cap): nothing is factorized there, their exact steps go by the vertex-space
  //! multigrid whatever polish_solver says, and no local end or factorized finish runs on them.
  int dense_levels = 0;
  int volume_sweeps = 0;          //!< Gauss-Newton volume steps over all levels and scales
  int regularization_sweeps = 0;  //!< regularization sweeps over all levels and scales
  int cycles = 0;                 //!< cycles (volume steps + regularization) over all levels and scales
  int final_sweeps = 0;           //!< exact Gauss-Newton polish steps on the finest level
  //! Cycles on the finest level per multigrid pass (a clean start's volume scales, retries
  //! appending theirs; a warm start's one pass); 0 where a clean start's intermediate scale did not
  //! solve it (ReconstructOptions::finest_intermediate_solves false).
  std::vector<int> finest_cycles_per_scale;
  double max_relative_error = 0.0;  //!< on the finest level at the end
  double rms_relative_error = 0.0;
  bool converged = false;       //!< max_relative_error <= tolerance
  double seconds_frames = 0.0;  //!< evaluating the base points on the edited base
  double seconds_solve = 0.0;   //!< the multigrid solve
  //! Phases of seconds_solve (the rest prepares the state and measures the result). Per level,
  //! coarsest first: its cycles (prolongation, volume steps, regularization) over every volume
  //! scale and retry.
  std::vector<double> seconds_levels;
  double seconds_polish = 0.0;  //!< the finest level's polish after its cycles
  //! Counting the result's new intersecting pairs and repairing folds (the repair's polish included).
  double seconds_folds = 0.0;
  long long step_halvings = 0;  //!< Gauss-Newton steps halved by the backtracking line search
  //! Prism constraints left out of Gauss-Newton steps (ReconstructOptions::max_constraint_motion),
  //! summed over the steps (prisms whose three vertices are pinned are never left out).
  long long deferred_constraints = 0;
  long long factorizations = 0;  //!< numeric Cholesky factorizations (direct step solver)
  //! Of these, those of steps that move a neighbourhood only (the local end of the polish, up to
  //! local_polish_max_fraction of the level, and the fold repair's local steps).
  long long local_factorizations = 0;
  //! The polish's local ends (ReconstructOptions::local_polish_max_fraction) tried (their first
  //! round's system within the limit), and of these those undone (the tolerance not reached in
  //! max_final_steps rounds, two rounds in a row without fewer prisms off, or a later round's
  //! system over the limit): the whole-level steps then went on from the positions before it.
  int local_ends = 0;
  int local_ends_undone = 0;
  //! Prisms of the largest system a local end solved (0 if none): at most
  //! local_polish_max_fraction of the finest level's prisms.
  long long max_local_end_prisms = 0;
  int retries = 0;  //!< clean-start solves run again (retry_other_regularization, retry_volume_iterations)
  //! Solves run again with the other preset (ReconstructOptions::fallback_schedule), 0 or 1, and
  //! whether that result was kept. The other counts here are of this solver's own solve; the other
  //! preset's work shows in seconds_solve only.
  int fallbacks = 0;
  bool fallback_kept = false;
  //! Fold repair rounds (ReconstructOptions::fold_repair_rounds), of both passes: the local one
  //! and, if folds remained, the one that polishes the whole level too.
  int fold_repairs = 0;
  //! Whole-level polishes run by those rounds: 0 when every repair's local pass ended converged
  //! without new pairs (and fold_repair_local_first).
  int fold_repair_polishes = 0;
  //! Intersecting pairs of the result's detail triangles that the rest detail does not have, as
  //! counted by the solver (retry_on_new_intersections: clean-start solves and exact solves from a
  //! drag's state, converged or not); -1 if not counted (also when the result's and the rest
  //! detail's searches were cut short), 10 million if only the result's search was (see
  //! retry_on_new_intersections).
  long long new_intersecting_pairs = -1;
  //! Of new_intersecting_pairs, those that are a contact made by the edit, and of the others those
  //! next to a crossing of the edited base itself (ReconstructOptions::contact_ratio,
  //! base_crossing_rings); the rest are the solver's folds. -1 if the new pairs were not counted
  //! or not listed (a search cut short).
  long long contact_pairs = -1;
  long long base_crossing_pairs = -1;
  long long cg_iterations = 0;       //!< conjugate-gradient iterations over all Gauss-Newton steps
  long long constraint_updates = 0;  //!< prism constraints visited by volume steps (for throughput)
};

//! Reconstructed detail positions and the statistics of the solve.
struct ReconstructResult {
  std::vector<Vec3> positions;
  ReconstructStats stats;
};

//! How a warm-started solve runs (interactive editing, paper section 5).
struct WarmStartOptions {
  //! Solve the volumes on the coarse levels only, and derive the finest level by regularization
  //! and prolongation (section 5). The exact solve uses false.
  bool coarse_levels_only = false;
  //! Max relative volume error to stop at on the finest level (when it is solved).
  double tolerance = 1e-4;
  //! drag_step() only: volume steps per coarse level and step at most, after one regularization
  //! round (0: solve each level to the level tolerance, up to max_cycles cycles). A small budget
  //! bounds the time of a step; the levels keep converging over the following steps, since each
  //! starts from its own last solution (the computation is spread over the frames, section 5).
  int level_steps = 0;
  //! drag_step() only: conjugate-gradient iterations per volume step at most (0: the
  //! reconstruction's own ReconstructOptions::cg_max_iterations).
  int cg_max_iterations = 0;
  //! Cycles on the finest level at most when it is solved (0: ReconstructOptions::final_max_cycles).
  int max_cycles = 0;
};

//! Checks that every field of \p options is in range, as VolumeReconstructor::drag_step() does.
//! \throw InvalidInput "warm-start option NAME = VALUE is out of range (RANGE)".
void check_warm_start_options(const WarmStartOptions& options);

//! Per-call inputs of a clean-start reconstruction beyond the edited base (layered models).
struct ReconstructRequest {
  //! Scales every target volume and rest offset (a band's amplitude, issue 5): 1 keeps the
  //! detail, 0 removes it (every vertex on its base point, no solve), values above 1 exaggerate
  //! it and negative values invert it. Must be within +-kMaxAmplitude.
  double amplitude = 1.0;
  //! Optional, one position per detail vertex (only the pinned vertices' entries are read):
  //! where the encoding's pinned vertices stay. Null: where displacement vectors put them. A
  //! layered model pins the vertices of a band whose base did not change at their current
  //! positions, which need not be the displacement vectors' after earlier edits.
  const std::vector<Vec3>* pinned_positions = nullptr;
};

//! Fixed triangles around a detail that its reconstructions must not newly intersect
//! (VolumeReconstructor::set_intersection_context()): the rest of the mesh a detail was cut from.
struct IntersectionContext {
  //! Triangles indexing the detail's vertices (0 .. n-1, at their positions in each solve: the
  //! pinned ones where the request puts them) and then `points` (n, n+1, ..).
  std::vector<Face> faces;
  //! The context's own vertices, where they stand in every solve.
  std::vector<Vec3> points;
  //! Where they stood when the detail was at rest (the encoding's detail_rest): the pairs at rest
  //! and the contact rule are taken there. Empty: at `points` (a context that never moved, as
  //! the rest of a mesh whose region is edited). Else one per point.
  std::vector<Vec3> rest_points;
};

//! The rest of a mesh around a detail cut from it, as the editors cut it (the faces with a vertex
//! to solve): the faces of \p mesh_faces none of whose vertices \p solved flags, their vertices
//! that are detail vertices (\p detail_vertices: detail vertex -> mesh vertex) numbered as the
//! detail's, the others as points at \p positions and, if \p rest_positions is not null, at rest
//! there (IntersectionContext::rest_points).
//! \throw InvalidInput if the sizes do not match (a flag, a position and, if given, a rest
//! position per mesh vertex), an index is out of range, a mesh vertex is listed twice in
//! \p detail_vertices, or a face with a solved vertex has a vertex not listed there.
IntersectionContext context_around(const std::vector<Face>& mesh_faces, const std::vector<char>& solved,
                                   const std::vector<int>& detail_vertices,
                                   const std::vector<Vec3>& positions,
                                   const std::vector<Vec3>* rest_positions = nullptr);

class VolumeReconstructor;

//! What an interactive drag carries from one step to the next (paper, section 5): every multigrid
//! level's own last solution and the base frames it was solved over. Each step starts every level
//! from its previous solution carried along with the base frames (each displacement keeps its
//! components in its frame), so a small change of the base costs a few steps per level instead of
//! a solve from the finest level's positions. Belongs to one VolumeReconstructor.
class DragState {
 public:
  DragState();
  ~DragState();
  DragState(DragState&&) noexcept;
  DragState& operator=(DragState&&) noexcept;

  //! Starts a drag from \p start, the detail positions (one per detail vertex) over \p frames
  //! (e.g. the encoded detail over the base at rest). Every level starts from these positions.
  //! \throw InvalidInput if the sizes differ, a value is not finite, or a frame's normal and
  //!        tangent are not orthonormal (within 1e-6).
  void reset(const BaseFrames& frames, std::vector<Vec3> start);
  //! Whether reset() was called (false for a moved-from state, which reset() starts anew).
  bool started() const;

 private:
  friend class VolumeReconstructor;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

//! The volumetric reconstruction operator for one encoding. Construction builds the multigrid
//! hierarchy (decimation of the detail connectivity, per-level targets and weights, and the
//! symbolic analysis of each level's volume system) once; every reconstruct() call over an
//! edited base reuses it. The calls refactorize that kept analysis, so one object must not be
//! used from two threads at once (use one object per thread).
class VolumeReconstructor {
 public:
  //! \throw InvalidInput if the encoding is inconsistent or options are out of range; Cancelled
  //! once options.cancel reads true (the setup of a 1M-prism encoding takes seconds).
  VolumeReconstructor(DetailEncoding encoding, ReconstructOptions options = {});
  ~VolumeReconstructor();
  //! A moved-from object may only be assigned to or destroyed (its other calls are undefined).
  VolumeReconstructor(VolumeReconstructor&&) noexcept;
  VolumeReconstructor& operator=(VolumeReconstructor&&) noexcept;

  //! Rebuilds the detail over the edited base: volume scaling from the clean start p' = q',
  //! multigrid cycles from the coarsest level to the finest on each scale (Listing 1).
  //! \pre edited_base has the encoding's base connectivity (same vertex count); over a subdivision
  //! base it holds the edited cage's control points.
  //! \throw InvalidInput on a vertex-count mismatch or non-finite coordinates; SolverError if the
  //! iteration produces non-finite positions or positions beyond 10 kMaxCoordinate; Cancelled once
  //! ReconstructOptions::cancel is set (every reconstruct(), reconstruct_from() and drag_step()).
  ReconstructResult reconstruct(const std::vector<Vec3>& edited_base) const;

  //! The same over base frames evaluated by the caller (e.g. evaluate_base_frames() on a
  //! SubdivSurface the application keeps and edits).
  //! \throw InvalidInput if the frames do not have one finite entry per detail vertex, or a frame's
  //!        normal and tangent are not orthonormal (within 1e-6).
  ReconstructResult reconstruct(const BaseFrames& edited_frames) const;

  //! The clean-start reconstruction with a request's amplitude and pinned positions. The hierarchy
  //! does not depend on either, so changing the amplitude rebuilds nothing.
  //! \throw InvalidInput as reconstruct(), or if the amplitude is not finite or pinned_positions
  //!        does not have one finite position per detail vertex.
  ReconstructResult reconstruct(const std::vector<Vec3>& edited_base,
                                const ReconstructRequest& request) const;
  ReconstructResult reconstruct(const BaseFrames& edited_frames, const ReconstructRequest& request) const;

  //! Warm-started solve without volume scaling, from \p start (e.g. the previous frame's result):
  //! the interactive mode of section 5.
  //! \throw InvalidInput if start does not have one position per detail vertex, or a warm option is
  //! out of range (tolerance above 0 and finite; level_steps, cg_max_iterations, max_cycles not
  //! negative).
  //! The request's amplitude scales the targets; its pinned positions replace the displacement
  //! vectors' placement of the pinned vertices.
  ReconstructResult reconstruct_from(const std::vector<Vec3>& edited_base, const std::vector<Vec3>& start,
                                     const WarmStartOptions& warm = {},
                                     const ReconstructRequest& request = {}) const;
  ReconstructResult reconstruct_from(const BaseFrames& edited_frames, const std::vector<Vec3>& start,
                                     const WarmStartOptions& warm = {},
                                     const ReconstructRequest& request = {}) const;

  //! One step of an interactive drag over \p edited_frames (paper, section 5). With
  //! warm.coarse_levels_only (a preview), every coarse level starts from its own solution of the
  //! previous step carried along with the base frames, plus the correction prolongated from the
  //! next coarser level, and takes volume steps (warm.level_steps of them, or until the level
  //! tolerance); the finest level starts from its previous positions carried along, plus the
  //! prolongated correction, and is regularized only. Without it (the exact solve at the drag's
  //! end), the finest level alone is solved to warm.tolerance from its carried positions. Updates
  //! \p state. No volume scaling: a drag's steps are small.
  //! \pre state.reset() was called with this encoding's vertex count.
  //! \throw InvalidInput as reconstruct_from(), or if the state was not started, has another size,
  //! or took a step with another VolumeReconstructor since its reset().
  ReconstructResult drag_step(const BaseFrames& edited_frames, DragState& state,
                              const WarmStartOptions& warm = {},
                              const ReconstructRequest& request = {}) const;
  //! The same over an edited base given by its vertices (or its cage's control points).
  ReconstructResult drag_step(const std::vector<Vec3>& edited_base, DragState& state,
                              const WarmStartOptions& warm = {},
                              const ReconstructRequest& request = {}) const;
  //! The base frames over an edited base given by its vertices (or its cage's control points), as
  //! the reconstruction evaluates them (keeping the subdivision surface's patch table).
  BaseFrames base_frames(const std::vector<Vec3>& edited_base) const;

  //! Triangles around the detail, not solved, that its reconstructions must not newly intersect:
  //! the rest of a mesh whose region is being edited (RegionEditor, CageEditor and a layered model's
  //! partial rebuilds set them; context_around() cuts them from a mesh). The fold check
  //! (ReconstructOptions::retry_on_new_intersections) counts the pairs of a detail triangle and
  //! one of these that intersect where they did not at rest as new pairs of the detail, so that
  //! the retries, the fold repair and the fallback schedule take them on, and
  //! ReconstructStats::new_intersecting_pairs includes them. Told apart by the distance at rest
  //! (not by the detail pairs' path along the base): a pair whose triangles' rest centroids lay
  //! farther apart than contact_ratio times their longest edges together is a contact the edit
  //! made (a limb bent into the body: contact_pairs, no retry, no repair); one that the
  //! displacement vectors' placement of the detail triangle makes too is the base's
  //! (base_crossing_pairs, no retry; none with base_crossing_rings < 0). Only the context
  //! triangles that lie within that distance of some detail triangle at rest are kept: the others
  //! can only make contacts, which are then not counted. Replaces any earlier context; an empty
  //! one removes it.
  //! \throw InvalidInput if an index is out of range, a point not finite or beyond the engine's
  //! range, or rest_points is neither empty nor one per point.
  void set_intersection_context(IntersectionContext context);

  const DetailEncoding& encoding() const;
  const ReconstructOptions& options() const;
  //! Seconds spent building the hierarchy in the constructor.
  double setup_seconds() const;
  //! Vertex counts of the hierarchy's levels, coarsest first.
  std::vector<int> level_vertex_counts() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace strata

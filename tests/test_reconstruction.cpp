#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>

#include "paper_cases.h"
#include "strata/encoding.h"
#include "strata/exceptions.h"
#include "strata/intersections.h"
#include "strata/metrics.h"
#include "strata/reconstruction.h"
#include "test_meshes.h"

using namespace strata;
using strata::test::max_distance;

namespace {

struct Outcome {
  VolumeMetrics volumes, vectors;
  DihedralChange volumes_shape;  // the result's bends against the rest detail's
  std::size_t volumes_pairs = 0, vectors_pairs = 0, input_pairs = 0;
  ReconstructStats stats;
};

// Encodes the case's detail over its base, rebuilds it over the bent base both ways and
// measures both results.
Outcome run_bend(const cases::CylinderCase& c) {
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const VolumeReconstructor rec(e);
  const ReconstructResult r = rec.reconstruct(c.edited_base.vertices);
  const BaseFrames fr = evaluate_base_frames(e, c.edited_base.vertices);
  const std::vector<Vec3> vec = reconstruct_vectors(e, fr);
  Outcome o;
  o.stats = r.stats;
  o.volumes = volume_metrics(e, fr, r.positions);
  o.vectors = volume_metrics(e, fr, vec);
  o.volumes_shape = dihedral_change(c.detail.faces, c.detail.vertices, r.positions);
  o.input_pairs = find_self_intersections(c.detail.vertices, c.detail.faces).num_pairs;
  o.volumes_pairs = find_self_intersections(r.positions, c.detail.faces).num_pairs;
  o.vectors_pairs = find_self_intersections(vec, c.detail.faces).num_pairs;
  return o;
}

cases::CylinderCase make_case(cases::DetailKind kind, int triangles) {
  cases::CylinderCaseOptions o;
  o.detail = kind;
  o.target_detail_triangles = triangles;
  return cases::make_cylinder_case(o);
}

// The solve's phase times: one per level, each one run, and together within the solve's time.
void expect_phases_within_solve(const ReconstructStats& st) {
  ASSERT_EQ(st.seconds_levels.size(), static_cast<std::size_t>(st.levels));
  double sum = st.seconds_polish + st.seconds_folds;
  for (double t : st.seconds_levels) {
    EXPECT_GT(t, 0.0);
    sum += t;
  }
  EXPECT_GT(st.seconds_polish, 0.0);
  EXPECT_GT(st.seconds_folds, 0.0);  // the result's new pairs are counted (retry_on_new_intersections)
  EXPECT_LE(sum, st.seconds_solve);
}

IntersectionOptions collecting() {
  IntersectionOptions all;
  all.collect_pairs = true;
  return all;
}

// The paper's rings at its resolution, solved without retry or fold repair (`none`) and with the
// coarse levels as lightly regularized as the finest (2 sweeps; the default 8 leave no pairs to
// repair there), which folds: the fold repair tests' case.
struct FoldingRings {
  cases::CylinderCase c = make_case(cases::DetailKind::Rings, 0);
  DetailEncoding e = encode_detail(c.detail, c.base);
  IntersectionResult rest = find_self_intersections(c.detail.vertices, c.detail.faces, collecting());
  ReconstructOptions none;

  FoldingRings() {
    none.retry_volume_iterations = 0;
    none.fold_repair_rounds = 0;
    none.fallback_schedule = false;
    none.coarse_regularization_iterations = 2;
  }
  ReconstructResult solve(const ReconstructOptions& o) const {
    return VolumeReconstructor(e, o).reconstruct(c.edited_base.vertices);
  }
  std::size_t new_pairs(const std::vector<Vec3>& p) const {
    return count_new_intersections(rest, find_self_intersections(p, c.detail.faces, collecting()));
  }
};

}  // namespace

// The paper's Fig. 6 cases (section 6): a 90-degree bend whose inner radius (0.2) is smaller
// than the detail height, so displacement vectors fold while displacement volumes do not.
class PaperBend : public ::testing::TestWithParam<cases::DetailKind> {};

TEST_P(PaperBend, VolumesAvoidTheFoldsThatVectorsMake) {
  const cases::CylinderCase c = make_case(GetParam(), 8000);
  ASSERT_LT(c.inner_bend_radius, c.max_detail_height);
  const Outcome o = run_bend(c);
  EXPECT_EQ(o.input_pairs, 0u);
  EXPECT_EQ(o.volumes_pairs, 0u) << c.name;
  EXPECT_GT(o.vectors_pairs, 0u) << c.name;
  EXPECT_TRUE(o.stats.converged);
  expect_phases_within_solve(o.stats);
  EXPECT_LE(o.volumes.max_relative_error, 1e-3);
  EXPECT_LE(o.volumes.rms_relative_error, 1e-4);
  EXPECT_LE(std::abs(o.volumes.total_volume_change), 1e-3);
  // Vectors do not keep the volumes: the bend changes them by far more than the tolerance.
  EXPECT_GT(o.vectors.max_relative_error, 0.1);
  // The default options keep the detail smooth: measured (2026-12-03) 99th percentiles of the
  // dihedral angles' change of 46 (bumps) and 82 degrees (cuboid, whose sharp corners bend); the
  // multigrid preset's polish leaves 102 and 155 (README, Known limits of the engine).
  EXPECT_LE(o.volumes_shape.p99_degrees, GetParam() == cases::DetailKind::Cuboid ? 110.0 : 65.0) << c.name;
}

INSTANTIATE_TEST_SUITE_P(Fig6, PaperBend,
                         ::testing::Values(cases::DetailKind::Bumps, cases::DetailKind::Cuboid),
                         [](const auto& info) { return std::string(cases::to_string(info.param)); });

TEST(Reconstruction, RingsBendKeepsVolumesAndCutsVectorFolds) {
  // Ring crests are taller than the inner bend radius and get squeezed together; volumes keep
  // the prisms exactly and leave far fewer intersecting pairs than vectors (not yet none: see
  // sdk/docs/engine-log.md).
  const Outcome o = run_bend(make_case(cases::DetailKind::Rings, 8000));
  EXPECT_LE(o.volumes.max_relative_error, 1e-3);
  EXPECT_LE(o.volumes.rms_relative_error, 1e-4);
  EXPECT_LT(o.volumes_pairs * 10, o.vectors_pairs);
}

TEST(Reconstruction, UneditedBaseGivesBackTheDetailFromTheCleanStart) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 8000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const VolumeReconstructor rec(e);
  const ReconstructResult r = rec.reconstruct(c.base.vertices);
  EXPECT_TRUE(r.stats.converged);
  // The solve starts from p' = q' (r.stats counts the scales it went through), not from the
  // stored positions.
  EXPECT_EQ(static_cast<int>(r.stats.finest_cycles_per_scale.size()), rec.options().volume_scales);
  EXPECT_LE(max_distance(r.positions, c.detail.vertices), 0.005 * bbox_diagonal(c.detail.vertices));
}

// A vertex in no face (a scan's stray point) has no prism: it is placed by its displacement
// vector, and the faces' vertices are solved as well as without it. Before (a review,
// thirty-eighth session) one 1e4 away raised the mean displacement length, which scales the
// length filter's floor and the fixed-point test: the round trip came back 0.150 off where it
// comes back 0.0014 off without it, and the stray vertex stayed on its base point. (The results
// with and without it are not the same numbers: an extra vertex changes sums over the vertices,
// and the solve lands on another of the volume-preserving results, README, Known limits.)
TEST(Reconstruction, AVertexInNoFaceIsPlacedByItsVectorAndChangesNothingElse) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 2000);
  const int n = c.detail.num_vertices();
  const double diag = bbox_diagonal(c.detail.vertices);
  const DetailEncoding e0 = encode_detail(c.detail, c.base);
  const ReconstructResult trip0 = VolumeReconstructor(e0).reconstruct(c.base.vertices);
  const double trip0_off = max_distance(trip0.positions, c.detail.vertices);
  ASSERT_LE(trip0_off, 1e-3 * diag);
  for (const Vec3& stray : {Vec3(3, 0, 0), Vec3(1e4, 0, 0), Vec3(0, 1e6, 3)}) {
    SCOPED_TRACE("stray vertex at " + std::to_string(stray.norm()));
    TriMesh with = c.detail;
    with.vertices.push_back(stray);
    const DetailEncoding e1 = encode_detail(with, c.base);
    const VolumeReconstructor rec(e1);
    const ReconstructResult trip = rec.reconstruct(c.base.vertices);
    ASSERT_TRUE(trip.stats.converged);
    const std::vector<Vec3> solved(trip.positions.begin(), trip.positions.begin() + n);
    EXPECT_LE(max_distance(solved, c.detail.vertices), 2 * trip0_off);
    EXPECT_LE((trip.positions[n] - stray).norm(), 1e-9 * std::max(1.0, stray.norm()));
    const ReconstructResult bent = rec.reconstruct(c.edited_base.vertices);
    EXPECT_TRUE(bent.stats.converged);
    EXPECT_EQ(bent.positions[n], reconstruct_vectors(e1, c.edited_base.vertices)[n]);
    const std::vector<Vec3> bent_solved(bent.positions.begin(), bent.positions.begin() + n);
    EXPECT_EQ(find_self_intersections(bent_solved, c.detail.faces).num_pairs, 0u);
    EXPECT_LE(
        volume_metrics(e0, evaluate_base_frames(e0, c.edited_base.vertices), bent_solved).max_relative_error,
        1e-3);
  }
}

// ReconstructStats::finest_cycles_per_scale has one entry per volume scale, 0 only where a scale
// did not solve the finest level: a one-level hierarchy solves it at every scale (its report had
// 5 entries, [2, 0, 2, 0, 4], for the preset's 3 scales; a review, thirty-eighth session).
TEST(Reconstruction, AOneLevelHierarchyCountsItsCyclesOncePerScale) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 2000);
  ReconstructOptions o = multigrid_reconstruct_options();
  o.max_levels = 1;
  const VolumeReconstructor rec(encode_detail(c.detail, c.base), o);
  ASSERT_EQ(rec.level_vertex_counts().size(), 1u);
  const ReconstructResult r = rec.reconstruct(c.edited_base.vertices);
  ASSERT_EQ(static_cast<int>(r.stats.finest_cycles_per_scale.size()), o.volume_scales);
  for (int cycles : r.stats.finest_cycles_per_scale) EXPECT_GT(cycles, 0);
}

// The cuboid's sharp corners carry the largest offsets: the hardest round trip. The acceptance
// bound, 0.5% of the diagonal. Measured with 32 coarse sweeps: 0.09% at 4k, 0.06% at 8k, 0.26% at
// 5k, 0.41% at 20k; with 8 (before) 5k and 20k were 0.81% and 1.17%, the sizes added here.
TEST(Reconstruction, CuboidRoundTripWithinHalfAPercentOfTheDiagonal) {
  for (int triangles : {4000, 5000, 8000, 20000}) {
    const cases::CylinderCase c = make_case(cases::DetailKind::Cuboid, triangles);
    const DetailEncoding e = encode_detail(c.detail, c.base);
    const ReconstructResult r = VolumeReconstructor(e).reconstruct(c.base.vertices);
    EXPECT_TRUE(r.stats.converged);
    EXPECT_LE(max_distance(r.positions, c.detail.vertices), 0.005 * bbox_diagonal(c.detail.vertices));
  }
}

TEST(Reconstruction, RigidMotionOfTheBaseMovesTheResultRigidly) {
  // Prism volumes are invariant under rigid motions, and so is every step of the solver. The
  // volume constraints leave one degree of freedom per vertex, and rounding differences can
  // stop the inexact (capped-CG) cycles at slightly different points of that solution set, so
  // the results agree to within a percent of the diagonal, not to round-off.
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 3000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const VolumeReconstructor rec(e);
  const ReconstructResult a = rec.reconstruct(c.edited_base.vertices);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(1.1, Vec3(0.3, -1, 2).normalized()).toRotationMatrix();
  const Vec3 t(2.0, 0.5, -1.0);
  std::vector<Vec3> moved;
  for (const Vec3& x : c.edited_base.vertices) moved.push_back(R * x + t);
  const ReconstructResult b = rec.reconstruct(moved);
  std::vector<Vec3> expected;
  for (const Vec3& x : a.positions) expected.push_back(R * x + t);
  EXPECT_LE(max_distance(b.positions, expected), 1e-2 * bbox_diagonal(c.detail.vertices));
  EXPECT_LE(b.stats.max_relative_error, 1e-4);
}

TEST(Reconstruction, SolverIsReusableAndDeterministic) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 3000);
  const VolumeReconstructor rec(encode_detail(c.detail, c.base));
  const std::vector<int> levels = rec.level_vertex_counts();
  ASSERT_GE(levels.size(), 2u);  // a real hierarchy
  for (std::size_t l = 1; l < levels.size(); ++l) EXPECT_LT(levels[l - 1], levels[l]);
  EXPECT_EQ(levels.back(), c.detail.num_vertices());
  const ReconstructResult a = rec.reconstruct(c.edited_base.vertices);
  const ReconstructResult b = rec.reconstruct(c.base.vertices);
  const ReconstructResult a2 = rec.reconstruct(c.edited_base.vertices);
  EXPECT_EQ(max_distance(a.positions, a2.positions), 0.0);
  EXPECT_GT(max_distance(a.positions, b.positions), 0.1);
  EXPECT_EQ(rec.level_vertex_counts(), levels);
}

// A clean-start solve that ends above the tolerance runs once more with
// retry_volume_iterations steps per cycle from the clean start (nothing of the first attempt
// carries over), and the one with the smaller error is kept; retry_volume_iterations = 0 turns
// it off.
TEST(Reconstruction, UnconvergedSolveIsRetriedFromTheCleanStart) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 3000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  ReconstructOptions cheap;
  cheap.volume_iterations = 1;
  cheap.max_final_steps = 0;  // no exact polish: neither attempt can reach the tolerance
  cheap.retry_volume_iterations = 3;
  const ReconstructResult retried = VolumeReconstructor(e, cheap).reconstruct(c.edited_base.vertices);
  EXPECT_EQ(retried.stats.retries, 1);
  EXPECT_FALSE(retried.stats.converged);
  ReconstructOptions one = cheap;
  one.retry_volume_iterations = 0;
  const ReconstructResult first = VolumeReconstructor(e, one).reconstruct(c.edited_base.vertices);
  EXPECT_EQ(first.stats.retries, 0);
  ReconstructOptions three = one;
  three.volume_iterations = 3;
  const ReconstructResult second = VolumeReconstructor(e, three).reconstruct(c.edited_base.vertices);
  ASSERT_NE(first.stats.max_relative_error, second.stats.max_relative_error);
  const ReconstructResult& better =
      second.stats.max_relative_error < first.stats.max_relative_error ? second : first;
  EXPECT_EQ(max_distance(retried.positions, better.positions), 0.0);
  EXPECT_EQ(retried.stats.max_relative_error, better.stats.max_relative_error);
  // A converged solve is not retried.
  EXPECT_EQ(VolumeReconstructor(e).reconstruct(c.edited_base.vertices).stats.retries, 0);
}

// With retry_on_new_intersections, a converged solve that folds is run again with the retry's
// schedule and the result with fewer new intersecting pairs is kept: the combined solve returns
// exactly the better of the two schedules' own results.
TEST(Reconstruction, FoldedSolveKeepsTheBetterOfTwoSchedules) {
  int retried = 0;
  for (cases::DetailKind kind : {cases::DetailKind::Bumps, cases::DetailKind::Rings}) {
    const cases::CylinderCase c = make_case(kind, 0);  // the paper's resolution
    const DetailEncoding e = encode_detail(c.detail, c.base);
    auto new_pairs = [&](const std::vector<Vec3>& p) {
      IntersectionOptions all;
      all.collect_pairs = true;
      return count_new_intersections(find_self_intersections(c.detail.vertices, c.detail.faces, all),
                                     find_self_intersections(p, c.detail.faces, all));
    };
    // Without the fold repair, which would leave nothing to retry for (it runs first), and with
    // the coarse levels regularized as lightly as the finest (2 sweeps), which folds here.
    ReconstructOptions retry;
    retry.fold_repair_rounds = 0;
    retry.fallback_schedule = false;
    retry.coarse_regularization_iterations = 2;
    ReconstructOptions only = retry;
    only.retry_volume_iterations = 0;
    const ReconstructResult two = VolumeReconstructor(e, only).reconstruct(c.edited_base.vertices);
    only.volume_iterations = 5;
    const ReconstructResult five = VolumeReconstructor(e, only).reconstruct(c.edited_base.vertices);
    const ReconstructResult both = VolumeReconstructor(e, retry).reconstruct(c.edited_base.vertices);
    ASSERT_TRUE(two.stats.converged && five.stats.converged && both.stats.converged);
    const std::size_t p2 = new_pairs(two.positions), p5 = new_pairs(five.positions);
    EXPECT_EQ(both.stats.retries, p2 > 0 ? 1 : 0);
    EXPECT_EQ(both.positions, p2 > 0 && p5 < p2 ? five.positions : two.positions);
    EXPECT_EQ(new_pairs(both.positions), std::min(p2, p5));
    retried += both.stats.retries;
  }
  EXPECT_GT(retried, 0);  // the cases do exercise the retry
}

// Fold repair: a converged solve with new intersecting pairs is smoothed around them and
// re-projected; the result keeps the tolerance and has fewer new pairs than the unrepaired solve.
// Measured on the paper's rings at its resolution with 2 regularization sweeps on the coarse
// levels (the default 8 leave no pairs to repair there): 62 new pairs without repair, 10 after
// three rounds, none after the default six.
TEST(Reconstruction, FoldRepairRemovesNewPairsAndKeepsTheVolumes) {
  const FoldingRings f;
  auto new_pairs = [&](const std::vector<Vec3>& p) { return f.new_pairs(p); };
  const ReconstructOptions& none = f.none;
  const ReconstructResult plain = f.solve(none);
  ASSERT_TRUE(plain.stats.converged);
  EXPECT_EQ(plain.stats.fold_repairs, 0);
  const std::size_t p0 = new_pairs(plain.positions);
  ASSERT_GT(p0, 0u);  // the case this test is about: the solve folds before repair
  ReconstructOptions repair = none;
  repair.fold_repair_rounds = 3;
  const ReconstructResult fixed = f.solve(repair);
  EXPECT_GE(fixed.stats.fold_repairs, 1);
  EXPECT_LE(fixed.stats.fold_repairs, 2 * 3);  // the local pass's rounds and the whole-level ones
  EXPECT_TRUE(fixed.stats.converged);
  EXPECT_LE(fixed.stats.max_relative_error, 1e-4);
  EXPECT_LT(new_pairs(fixed.positions), p0);
  // The default rounds (without the retry) remove them all.
  ReconstructOptions defaults = none;
  defaults.fold_repair_rounds = ReconstructOptions{}.fold_repair_rounds;
  const ReconstructResult all_rounds = f.solve(defaults);
  EXPECT_TRUE(all_rounds.stats.converged);
  EXPECT_EQ(all_rounds.stats.new_intersecting_pairs, 0);
  EXPECT_EQ(new_pairs(all_rounds.positions), 0u);
  // Without counting the pairs there is nothing to repair.
  repair.retry_on_new_intersections = false;
  const ReconstructResult blind = f.solve(repair);
  EXPECT_EQ(blind.stats.fold_repairs, 0);
  EXPECT_EQ(blind.positions, plain.positions);
}

// fold_repair_local_first: the repair's local pass (the smoothed vertices alone restore the
// volumes) runs first, and the rounds with whole-level polishes only if it leaves folds; the
// better result of the two passes is kept, so never worse than the whole-level rounds alone.
// Measured with the multigrid preset without its polish's smoothness term (with it this case
// does not fold): the regular 20k cuboid's bend folds, and three local rounds remove its pairs
// without a whole-level polish (five when the local restoration moved the smoothed vertices only,
// fold_repair_local_rings = 0); on the paper's rings (FoldingRings) the local pass does not
// suffice, and the result is the whole-level rounds' own.
TEST(Reconstruction, FoldRepairTriesTheLocalPassFirst) {
  {
    const cases::CylinderCase c = make_case(cases::DetailKind::Cuboid, 20000);
    const DetailEncoding e = encode_detail(c.detail, c.base);
    ReconstructOptions o = test::without_polish_smoothness(multigrid_reconstruct_options());
    o.fallback_schedule = false;
    o.retry_volume_iterations = 0;
    o.retry_other_regularization = false;
    const ReconstructResult local = VolumeReconstructor(e, o).reconstruct(c.edited_base.vertices);
    o.fold_repair_local_first = false;
    const ReconstructResult whole = VolumeReconstructor(e, o).reconstruct(c.edited_base.vertices);
    ASSERT_GE(local.stats.fold_repairs, 3);  // the case: the solve folds and is repaired
    EXPECT_EQ(local.stats.fold_repair_polishes, 0);
    EXPECT_GE(whole.stats.fold_repair_polishes, 1);
    // fold_repair_local_rounds bounds the local pass alone: with fewer rounds than it needs, it
    // runs that many, then the whole-level rounds run as without it (-1: fold_repair_rounds, 6).
    o.fold_repair_local_first = true;
    o.fold_repair_local_rounds = local.stats.fold_repairs - 1;
    const ReconstructResult short_local = VolumeReconstructor(e, o).reconstruct(c.edited_base.vertices);
    EXPECT_EQ(short_local.stats.fold_repairs, o.fold_repair_local_rounds + whole.stats.fold_repairs);
    EXPECT_EQ(short_local.stats.fold_repair_polishes, whole.stats.fold_repair_polishes);
    o.fold_repair_local_rounds = -1;
    const ReconstructResult as_before = VolumeReconstructor(e, o).reconstruct(c.edited_base.vertices);
    EXPECT_EQ(as_before.stats.fold_repairs, local.stats.fold_repairs);
    EXPECT_EQ(as_before.positions, local.positions);
    o.fold_repair_local_rounds = -2;
    EXPECT_THROW(VolumeReconstructor(e, o), InvalidInput);
    for (const ReconstructResult* r : {&local, &whole}) {
      EXPECT_TRUE(r->stats.converged);
      EXPECT_EQ(r->stats.new_intersecting_pairs, 0);
      IntersectionOptions all = collecting();
      EXPECT_EQ(count_new_intersections(find_self_intersections(c.detail.vertices, c.detail.faces, all),
                                        find_self_intersections(r->positions, c.detail.faces, all)),
                0u);
    }
  }
  {
    const FoldingRings f;
    ReconstructOptions o = f.none;
    o.fold_repair_rounds = ReconstructOptions{}.fold_repair_rounds;
    const ReconstructResult both = f.solve(o);
    o.fold_repair_local_first = false;
    const ReconstructResult whole = f.solve(o);
    ASSERT_GE(both.stats.fold_repair_polishes, 1);  // the case: the local pass leaves folds
    EXPECT_LE(f.new_pairs(both.positions), f.new_pairs(whole.positions));
    EXPECT_EQ(both.stats.new_intersecting_pairs, static_cast<long long>(f.new_pairs(both.positions)));
    // The local rounds come on top of the whole-level ones, which are the same as without them.
    EXPECT_GT(both.stats.fold_repairs, whole.stats.fold_repairs);
    EXPECT_EQ(both.stats.fold_repair_polishes, whole.stats.fold_repair_polishes);
    SCOPED_TRACE(f.new_pairs(both.positions) == f.new_pairs(whole.positions) ? "as the whole-level rounds"
                                                                             : "the local pass won");
    if (f.new_pairs(both.positions) == f.new_pairs(whole.positions)) {
      EXPECT_EQ(both.positions, whole.positions);
    }
    // The repair's counts run on the solver's threads: the same on one thread and three.
    ReconstructOptions three = f.none;
    three.fold_repair_rounds = ReconstructOptions{}.fold_repair_rounds;
    three.threads = 3;
    ReconstructOptions one = three;
    one.threads = 1;
    const ReconstructResult r3 = f.solve(three), r1 = f.solve(one);
    EXPECT_EQ(r3.positions, r1.positions);
    EXPECT_EQ(r3.stats.new_intersecting_pairs, r1.stats.new_intersecting_pairs);
    EXPECT_EQ(r3.stats.fold_repairs, r1.stats.fold_repairs);
    EXPECT_EQ(r3.stats.fold_repair_polishes, r1.stats.fold_repair_polishes);
    EXPECT_EQ(r3.positions, both.positions);  // threads = 0 (all cores) above
  }
}

// fallback_schedule: a solve left with new pairs is solved once more with the other preset, at
// its tolerance, and the better result kept: exactly that preset's own. Returns the kept
// result's new pairs.
static long long expect_fell_back_to(const FoldingRings& f, const ReconstructOptions& o,
                                     ReconstructOptions other) {
  ReconstructOptions alone = o;
  alone.fallback_schedule = false;
  const ReconstructResult first = f.solve(alone);
  EXPECT_GT(first.stats.new_intersecting_pairs, 0);  // the case: it folds
  const ReconstructResult r = f.solve(o);
  other.tolerance = o.tolerance;
  other.fallback_schedule = false;
  // The caller's, as its fold repair options (.strata files written before solve as then).
  other.intermediate_regularized_levels = o.intermediate_regularized_levels;
  const ReconstructResult theirs = f.solve(other);
  EXPECT_EQ(r.stats.fallbacks, 1);
  EXPECT_TRUE(r.stats.fallback_kept);
  EXPECT_EQ(r.positions, theirs.positions);
  EXPECT_EQ(r.stats.new_intersecting_pairs, static_cast<long long>(f.new_pairs(r.positions)));
  EXPECT_LT(r.stats.new_intersecting_pairs, first.stats.new_intersecting_pairs);
  EXPECT_TRUE(r.stats.converged);
  return r.stats.new_intersecting_pairs;
}

// On the paper's rings (FoldingRings' case) the multigrid preset as it was before the rest
// Laplacian (rest offsets, the coarsest level as the others, 3 final cycles), without retries or
// repair rounds, leaves new pairs (measured: 64; the current preset none); the default options,
// which have none there, are kept. A solve without new pairs does not fall back.
TEST(Reconstruction, FoldedSolveFallsBackToTheDefaultOptions) {
  const FoldingRings f;
  ReconstructOptions mg = test::rest_offset_multigrid_preset();
  mg.retry_volume_iterations = 0;
  mg.multigrid.retry_iterations = 0;
  mg.fold_repair_rounds = 0;
  EXPECT_EQ(expect_fell_back_to(f, mg, ReconstructOptions{}), 0);
  EXPECT_EQ(f.solve(ReconstructOptions{}).stats.fallbacks, 0);
}

// The other way (the longer solve, left out of the sanitizer run): the default options with the
// coarse levels lightly regularized, without retry or repair, leave more new pairs (56) than the
// multigrid preset with its retries (24), which is kept.
TEST(Reconstruction, FoldedSolveFallsBackToTheMultigridPreset) {
  const FoldingRings f;
  ReconstructOptions light = f.none;
  light.fallback_schedule = true;
  expect_fell_back_to(f, light, multigrid_reconstruct_options());
  // An encoding without the base's rest frames (built by hand) falls back too, to the preset
  // with rest offsets, where its rest Laplacian would refuse the encoding.
  DetailEncoding bare = f.e;
  bare.base_rest_normals.clear();
  bare.base_rest_tangents.clear();
  const ReconstructResult r = VolumeReconstructor(bare, light).reconstruct(f.c.edited_base.vertices);
  EXPECT_EQ(r.stats.fallbacks, 1);
  EXPECT_TRUE(r.stats.converged);
}

// A solve that ends above the tolerance is checked for new pairs too, and repaired: the result
// reports its own count, and a repair round is kept only if it is worse in neither the pairs nor
// the error. Here a tolerance below what the polish can reach keeps every solve unconverged, on
// the paper's rings with the coarse levels as lightly regularized as the finest, which folds
// (measured: 56 new pairs at an error of 6.3e-14; repaired, 14 at 4.2e-14 after four rounds).
TEST(Reconstruction, UnconvergedResultIsCheckedAndRepairedToo) {
  const FoldingRings f;
  auto new_pairs = [&](const std::vector<Vec3>& p) { return f.new_pairs(p); };
  ReconstructOptions none = f.none;
  none.tolerance = 1e-15;  // below rounding: the polish ends near 6e-14
  const ReconstructResult plain = f.solve(none);
  ASSERT_FALSE(plain.stats.converged);
  const std::size_t p0 = new_pairs(plain.positions);
  ASSERT_GT(p0, 0u);  // the case this test is about: an unconverged result that folds
  EXPECT_EQ(plain.stats.new_intersecting_pairs, static_cast<long long>(p0));  // counted all the same
  ReconstructOptions repair = none;
  repair.fold_repair_rounds = ReconstructOptions{}.fold_repair_rounds;
  const ReconstructResult fixed = f.solve(repair);
  EXPECT_FALSE(fixed.stats.converged);
  EXPECT_GE(fixed.stats.fold_repairs, 1);
  const std::size_t p1 = new_pairs(fixed.positions);
  EXPECT_EQ(fixed.stats.new_intersecting_pairs, static_cast<long long>(p1));
  EXPECT_LT(p1, p0);
  // Not worse in error, up to rounding (1e-12 of the mean volume, Outcome::better_than): at this
  // tolerance the errors are rounding, 4.1e-14 to 6.3e-14 with different BLAS kernels.
  EXPECT_LE(fixed.stats.max_relative_error, plain.stats.max_relative_error + 1e-12);
  // Not counted, nothing is checked.
  none.retry_on_new_intersections = false;
  EXPECT_EQ(f.solve(none).stats.new_intersecting_pairs, -1);
}

// A scan-like 90-degree bend (jitter 0.4) of \p kind at about \p triangles prisms, solved with
// given options: each solve must converge without new pairs; it returns the bends' change against
// the rest detail (dihedral_change()) and keeps the solve's statistics in `stats`.
struct SmoothnessBend {
  SmoothnessBend(cases::DetailKind kind, int triangles)
      : c(make(kind, triangles)), e(encode_detail(c.detail, c.base)) {
    rest = find_self_intersections(c.detail.vertices, c.detail.faces, collecting());
  }
  static cases::CylinderCase make(cases::DetailKind kind, int triangles) {
    cases::CylinderCaseOptions co;
    co.detail = kind;
    co.target_detail_triangles = triangles;
    co.jitter = 0.4;
    return cases::make_cylinder_case(co);
  }
  DihedralChange solve(const ReconstructOptions& o) {
    const ReconstructResult r = VolumeReconstructor(e, o).reconstruct(c.edited_base.vertices);
    EXPECT_TRUE(r.stats.converged);
    EXPECT_EQ(
        count_new_intersections(rest, find_self_intersections(r.positions, c.detail.faces, collecting())),
        0u);
    stats = r.stats;
    return dihedral_change(c.detail.faces, c.detail.vertices, r.positions);
  }
  cases::CylinderCase c;
  DetailEncoding e;
  IntersectionResult rest;
  ReconstructStats stats;
};

// MultigridStepOptions::polish_smoothness_decay: a polish smoothness that fades step by step
// leaves the scan-like bend far less crumpled than the preset's polish, still converged and
// without new pairs (measured: 90th / 99th percentiles of the dihedral angles' change 33.8 / 105.3
// degrees without, 24.3 / 69.0 with), and fading, it converges as fast: the same smoothness at
// every step stalled into factorized whole-level steps (15 polish steps, 2 whole-level
// factorizations, against 4 and none).
TEST(Reconstruction, AFadingPolishSmoothnessLeavesTheBendSmoother) {
  SmoothnessBend b(cases::DetailKind::Bumps, 8000);
  ReconstructOptions o = cycle_schedule_reconstruct_options();
  o.threads = 1;
  const DihedralChange plain = b.solve(o);
  o.multigrid.polish_smoothness = 1e-3;
  b.solve(o);
  const ReconstructStats constant = b.stats;
  o.multigrid.polish_smoothness_decay = 0.1;
  const DihedralChange fading = b.solve(o);
  const ReconstructStats& st = b.stats;
  EXPECT_LT(fading.p90_degrees, 0.85 * plain.p90_degrees);
  EXPECT_LT(fading.p99_degrees, 0.8 * plain.p99_degrees);
  EXPECT_LT(st.final_sweeps, constant.final_sweeps);
  EXPECT_EQ(st.factorizations, st.local_factorizations);  // no whole-level factorization
  EXPECT_GT(constant.factorizations, constant.local_factorizations);
}

// The multigrid preset's polish smoothness (MultigridStepOptions::polish_smoothness, fading by
// polish_smoothness_decay): on the three scan-like 20k bends its result is far less crumpled
// than with the polish before it, still converged and without new pairs (measured, 90th / 99th
// percentile of the dihedral angles' change in degrees, without -> with: bumps 30.0 / 114.0 ->
// 18.3 / 69.3, rings 19.3 / 96.9 -> 12.5 / 48.2, cuboid 42.2 / 126.7 -> 20.5 / 75.8; at 8k the
// bumps and rings gain less, 25.5 -> 20.7 and 20.9 -> 16.7 at the 90th).
TEST(MultigridPreset, ItsPolishSmoothnessLeavesTheBendsSmoother) {
  for (const cases::DetailKind kind :
       {cases::DetailKind::Bumps, cases::DetailKind::Rings, cases::DetailKind::Cuboid}) {
    SCOPED_TRACE(static_cast<int>(kind));
    SmoothnessBend b(kind, 20000);
    ReconstructOptions o = multigrid_reconstruct_options();
    o.threads = 1;
    ASSERT_GT(o.multigrid.polish_smoothness, 0.0);
    ASSERT_LT(o.multigrid.polish_smoothness_decay, 1.0);
    const DihedralChange smooth = b.solve(o);
    const DihedralChange before = b.solve(test::without_polish_smoothness(o));
    EXPECT_LT(smooth.p90_degrees, 0.7 * before.p90_degrees);
    EXPECT_LT(smooth.p99_degrees, 0.8 * before.p99_degrees);
  }
}

// A detail that crosses itself at rest (a small triangle of its own pierces one of its faces),
// rebuilt over its unedited base (a bend moves that triangle's corners apart from the face): the
// pairs it has at rest are not new in the result. The solver tests the result's
// pairs at the rest positions one by one, not by a whole search of the rest detail; its count
// must be count_new_intersections() against whole searches of both.
TEST(Reconstruction, PairsThatCrossAtRestAreNotNew) {
  cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 3000);
  std::vector<Vec3>& x = c.detail.vertices;
  int j = 0;
  auto centroid = [&](int k) {
    const Face& f = c.detail.faces[k];
    return Vec3((x[f[0]] + x[f[1]] + x[f[2]]) / 3.0);
  };
  for (int k = 0; k < static_cast<int>(c.detail.faces.size()); ++k)
    if (std::abs(centroid(k).z() - 2.9) < std::abs(centroid(j).z() - 2.9)) j = k;
  const Face f = c.detail.faces[j];
  const Vec3 m = centroid(j), along = x[f[1]] - x[f[0]];
  const Vec3 n = along.cross(x[f[2]] - x[f[0]]).normalized();
  const double h = 0.6 * along.norm();
  const int v = static_cast<int>(x.size());
  x.insert(x.end(), {m + h * n, m - h * n, m + h * along.normalized()});
  c.detail.faces.push_back(Face{v, v + 1, v + 2});
  const IntersectionResult rest = find_self_intersections(x, c.detail.faces, collecting());
  ASSERT_GT(rest.num_pairs, 0u);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const ReconstructResult r = VolumeReconstructor(e).reconstruct(c.base.vertices);
  const IntersectionResult now = find_self_intersections(r.positions, c.detail.faces, collecting());
  ASSERT_GT(now.num_pairs, 0u) << "the piercing triangle still crosses";
  EXPECT_EQ(r.stats.new_intersecting_pairs, static_cast<long long>(count_new_intersections(rest, now)));
  EXPECT_LT(r.stats.new_intersecting_pairs, static_cast<long long>(now.num_pairs));
}

// The solver's threads split independent per-prism and per-vertex work only (J^T x gathered per
// vertex in face order, reductions serial): the result is bit for bit the same for any count.
TEST(Reconstruction, ThreadCountDoesNotChangeTheResult) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 12000);  // above the grain
  const DetailEncoding e = encode_detail(c.detail, c.base);
  ReconstructOptions one, three;
  one.threads = 1;
  three.threads = 3;  // more threads than this 2-core machine's cores: the split still changes nothing
  const ReconstructResult a = VolumeReconstructor(e, one).reconstruct(c.edited_base.vertices);
  ASSERT_TRUE(a.stats.converged);
  EXPECT_EQ(VolumeReconstructor(e, three).reconstruct(c.edited_base.vertices).positions, a.positions);
  ReconstructOptions bad;
  bad.threads = -1;
  EXPECT_THROW(VolumeReconstructor(e, bad), InvalidInput);
}

TEST(Reconstruction, WarmStartFromTheSolutionStaysClose) {
  // The cold solve stops its regularization once it barely moves (with a decayed weight); a warm
  // restart regularizes a little further, so it stays close but not bitwise at the start. How far
  // depends on the hierarchy's coarse levels: measured at 2k-12k prisms, 0.9-2.2% of the diagonal;
  // at this 3k case 2.2% (1.1% before the decimation's order changed on 2026-11-27, tenth session;
  // that hierarchy reached 2.2% at 4k), so the bound is 3%.
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 3000);
  const VolumeReconstructor rec(encode_detail(c.detail, c.base));
  const ReconstructResult a = rec.reconstruct(c.edited_base.vertices);
  const ReconstructResult b = rec.reconstruct_from(c.edited_base.vertices, a.positions);
  EXPECT_TRUE(b.stats.converged);
  EXPECT_LE(b.stats.max_relative_error, 1e-4);
  EXPECT_LE(max_distance(a.positions, b.positions), 0.03 * bbox_diagonal(c.detail.vertices));
  // From a perturbed start, the exact warm solve restores the volumes.
  std::vector<Vec3> noisy = a.positions;
  for (std::size_t i = 0; i < noisy.size(); ++i)
    noisy[i] += 1e-3 * Vec3(std::sin(3.0 * i), std::cos(5.0 * i), std::sin(7.0 * i));
  const ReconstructResult n = rec.reconstruct_from(c.edited_base.vertices, noisy);
  EXPECT_TRUE(n.stats.converged);
  EXPECT_LE(n.stats.max_relative_error, 1e-4);
}

// The bumps bent (8k prisms) and reconstructed without a context, with the face the bend moved
// farthest, for the intersection context's tests.
struct BentBumps {
  cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 8000);
  DetailEncoding e = encode_detail(c.detail, c.base);
  VolumeReconstructor rec{e};
  ReconstructResult plain = rec.reconstruct(c.edited_base.vertices);
  int far = farthest();

  int farthest() const {
    auto centroid = [](const std::vector<Vec3>& p, const Face& f) {
      return (p[f[0]] + p[f[1]] + p[f[2]]) / 3.0;
    };
    int best = 0;
    double moved = 0.0;
    for (int j = 0; j < static_cast<int>(e.detail_faces.size()); ++j) {
      const double d =
          (centroid(plain.positions, e.detail_faces[j]) - centroid(e.detail_rest, e.detail_faces[j])).norm();
      if (d > moved) moved = d, best = j;
    }
    return best;
  }
  // A triangle across face \p j of the detail at \p p (in a plane through its normal, two of its
  // edge lengths in size), shifted by \p lift edge lengths along that normal.
  std::vector<Vec3> across(const std::vector<Vec3>& p, int j, double lift = 0.0) const {
    const Face& f = e.detail_faces[j];
    const Vec3 a = p[f[0]], b = p[f[1]], cc = p[f[2]];
    const Vec3 normal = (b - a).cross(cc - a).normalized(), along = (b - a).normalized();
    const double edge = (b - a).norm();
    const Vec3 mid = (a + b + cc) / 3.0 + lift * edge * normal;
    return {mid + 2 * edge * normal, mid - 2 * edge * normal + edge * along,
            mid - 2 * edge * normal - edge * along};
  }
  // How many detail triangles at \p p the triangle \p t crosses.
  int crossings(const std::vector<Vec3>& p, const std::vector<Vec3>& t) const {
    int k = 0;
    for (const Face& g : e.detail_faces)
      k += triangles_intersect({p[g[0]], p[g[1]], p[g[2]]}, {t[0], t[1], t[2]});
    return k;
  }
};

// VolumeReconstructor::set_intersection_context(): fixed triangles that the detail must not newly
// intersect. A small triangle set across the bent bumps' result, far from where the detail lay at
// rest: the pairs it makes with the result are counted as new, and as contacts the edit made (so
// no retry or repair runs and the result is the same); pairs that a context triangle has with
// the rest detail are not new.
TEST(Reconstruction, AnIntersectionContextCountsTheDetailsNewPairsWithIt) {
  BentBumps t;
  const cases::CylinderCase& c = t.c;
  const DetailEncoding& e = t.e;
  VolumeReconstructor& rec = t.rec;
  const ReconstructResult& plain = t.plain;
  ASSERT_TRUE(plain.stats.converged);
  ASSERT_GE(plain.stats.new_intersecting_pairs, 0);
  const auto n = static_cast<int>(e.detail_rest.size());
  const std::vector<Vec3> ctx = t.across(plain.positions, t.far);
  ASSERT_EQ(t.crossings(e.detail_rest, ctx), 0);
  const int expected = t.crossings(plain.positions, ctx);
  ASSERT_GT(expected, 0);
  // A second context triangle that crosses the rest detail (its pairs are there at rest, not new).
  const std::vector<Vec3> second = t.across(e.detail_rest, 0);
  ASSERT_GT(t.crossings(e.detail_rest, second), 0);
  std::vector<Vec3> points{ctx[0], ctx[1], ctx[2], second[0], second[1], second[2]};
  rec.set_intersection_context({{Face{n, n + 1, n + 2}, Face{n + 3, n + 4, n + 5}}, points, {}});
  const ReconstructResult with = rec.reconstruct(c.edited_base.vertices);
  EXPECT_EQ(with.positions, plain.positions);
  EXPECT_EQ(with.stats.new_intersecting_pairs, plain.stats.new_intersecting_pairs + expected);
  EXPECT_EQ(with.stats.contact_pairs, plain.stats.contact_pairs + expected);
  EXPECT_EQ(with.stats.retries, plain.stats.retries);
  // The same, with rest points equal to the points: as without them.
  rec.set_intersection_context({{Face{n, n + 1, n + 2}, Face{n + 3, n + 4, n + 5}}, points, points});
  EXPECT_EQ(rec.reconstruct(c.edited_base.vertices).stats.contact_pairs, with.stats.contact_pairs);
  // Removed again: as without.
  rec.set_intersection_context({});
  EXPECT_EQ(rec.reconstruct(c.edited_base.vertices).stats.new_intersecting_pairs,
            plain.stats.new_intersecting_pairs);
  // Bad contexts.
  EXPECT_THROW(rec.set_intersection_context({{Face{n, n + 1, n + 6}}, points, {}}), InvalidInput);
  EXPECT_THROW(rec.set_intersection_context({{Face{-1, n, n + 1}}, points, {}}), InvalidInput);
  EXPECT_THROW(rec.set_intersection_context({{Face{n, n + 1, n + 2}}, points, {points[0]}}), InvalidInput);
  std::vector<Vec3> nan_rest = points;
  nan_rest[4].y() = std::nan("");
  EXPECT_THROW(rec.set_intersection_context({{Face{n, n + 1, n + 2}}, points, nan_rest}), InvalidInput);
  points[2].x() = std::nan("");
  EXPECT_THROW(rec.set_intersection_context({{Face{n, n + 1, n + 2}}, points, {}}), InvalidInput);
}

// context_around(): a strip of four triangles over vertices 0-5, the detail the faces with a
// solved vertex (vertex 1): faces 0 and 1, over detail vertices (mesh 0, 1, 2, 3) -> (0, 1, 2, 3).
// The rest are faces 2 and 3, their detail vertices numbered as the detail's and the others
// after them, once each, at the given positions and rest positions.
TEST(Reconstruction, ContextAroundCutsTheRestOfAMesh) {
  const std::vector<Face> faces{{0, 1, 2}, {1, 3, 2}, {2, 3, 4}, {3, 5, 4}};
  std::vector<Vec3> pos, rest;
  for (int i = 0; i < 6; ++i) {
    pos.emplace_back(i / 2, i % 2, 0.0);
    rest.emplace_back(i / 2, i % 2, 1.0);
  }
  std::vector<char> solved(6, 0);
  solved[1] = 1;
  const std::vector<int> detail{0, 1, 2, 3};
  const IntersectionContext c = context_around(faces, solved, detail, pos, &rest);
  EXPECT_EQ(c.faces, (std::vector<Face>{{2, 3, 4}, {3, 5, 4}}));
  EXPECT_EQ(c.points, (std::vector<Vec3>{pos[4], pos[5]}));
  EXPECT_EQ(c.rest_points, (std::vector<Vec3>{rest[4], rest[5]}));
  // A detail numbered otherwise: the rest's faces follow it.
  const IntersectionContext d = context_around(faces, solved, {3, 2, 1, 0}, pos);
  EXPECT_EQ(d.faces, (std::vector<Face>{{1, 0, 4}, {0, 5, 4}}));
  EXPECT_TRUE(d.rest_points.empty());
  // Nothing solved: the whole mesh; everything solved: nothing.
  EXPECT_EQ(context_around(faces, std::vector<char>(6, 0), {}, pos).faces.size(), 4u);
  EXPECT_TRUE(context_around(faces, std::vector<char>(6, 1), {0, 1, 2, 3, 4, 5}, pos).faces.empty());
  // Bad input.
  EXPECT_THROW(context_around(faces, std::vector<char>(5, 0), detail, pos), InvalidInput);
  const std::vector<Vec3> short_rest(5, Vec3::Zero());
  EXPECT_THROW(context_around(faces, solved, detail, pos, &short_rest), InvalidInput);
  EXPECT_THROW(context_around(faces, solved, {0, 6}, pos), InvalidInput);
  EXPECT_THROW(context_around({{0, 1, 6}}, solved, detail, pos), InvalidInput);
  EXPECT_THROW(context_around(faces, solved, {0, 1, 2, 1}, pos), InvalidInput);  // listed twice
  EXPECT_THROW(context_around(faces, solved, {0, 2, 3}, pos), InvalidInput);     // solved, not listed
}

// IntersectionContext::rest_points: a context that moved with the detail (a layered band's part
// that followed its base) is judged where it lay at rest. The triangle across the bent bumps'
// result of the test above, at rest beside the same face's rest position (not crossing the rest
// detail): its new pairs are then no contacts but folds, which the solver takes on (it retries
// or repairs). At rest far away: it is no context at all (only the triangles within contact
// distance at rest are kept).
TEST(Reconstruction, AContextIsJudgedWhereItLayAtRest) {
  BentBumps t;
  const DetailEncoding& e = t.e;
  VolumeReconstructor& rec = t.rec;
  const ReconstructResult& plain = t.plain;
  ASSERT_TRUE(plain.stats.converged);
  const auto n = static_cast<int>(e.detail_rest.size());
  auto across = [&](const std::vector<Vec3>& p, double lift) { return t.across(p, t.far, lift); };
  auto crossings = [&](const std::vector<Vec3>& p, const std::vector<Vec3>& tri) {
    return t.crossings(p, tri);
  };
  const std::vector<Vec3> now = across(plain.positions, 0.0);
  const int expected = crossings(plain.positions, now);
  ASSERT_GT(expected, 0);
  // Beside the rest face: the side where it crosses no rest triangle.
  std::vector<Vec3> rest = across(e.detail_rest, 2.5);
  if (crossings(e.detail_rest, rest) > 0) rest = across(e.detail_rest, -2.5);
  ASSERT_EQ(crossings(e.detail_rest, rest), 0);
  const std::vector<Face> tri{Face{n, n + 1, n + 2}};

  rec.set_intersection_context({tri, now, rest});
  const ReconstructResult near = rec.reconstruct(t.c.edited_base.vertices);
  EXPECT_EQ(near.stats.contact_pairs, plain.stats.contact_pairs);  // none of its pairs is a contact
  EXPECT_GT(near.stats.retries + near.stats.fold_repairs + near.stats.fallbacks,
            plain.stats.retries + plain.stats.fold_repairs + plain.stats.fallbacks);
  // Its final count is the whole set's: the detail's own new pairs and those with the triangle.
  IntersectionOptions io;
  io.collect_pairs = true;
  const std::size_t own =
      count_new_intersections(find_self_intersections(e.detail_rest, e.detail_faces, io),
                              find_self_intersections(near.positions, e.detail_faces, io));
  EXPECT_EQ(near.stats.new_intersecting_pairs, static_cast<long long>(own) + crossings(near.positions, now));

  std::vector<Vec3> away = rest;
  for (Vec3& p : away) p += Vec3(100.0, 0.0, 0.0) * bbox_diagonal(e.detail_rest);
  rec.set_intersection_context({tri, now, away});
  const ReconstructResult gone = rec.reconstruct(t.c.edited_base.vertices);
  EXPECT_EQ(gone.positions, plain.positions);
  EXPECT_EQ(gone.stats.new_intersecting_pairs, plain.stats.new_intersecting_pairs);
}

// ReconstructOptions::max_constraint_motion scales a prism's displacement length by the amplitude
// (a layered band's, up to 1000): the bumps bend exaggerated 20 times leaves no prism out, as at
// 1. With the unscaled length it left 19 out (legacy) and changed the result.
TEST(Reconstruction, AnAmplifiedBendLeavesNoConstraintOut) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 8000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  ReconstructRequest q;
  q.amplitude = 20.0;
  const ReconstructResult r = VolumeReconstructor(e).reconstruct(c.edited_base.vertices, q);
  EXPECT_EQ(r.stats.deferred_constraints, 0);
  ReconstructOptions none;
  none.max_constraint_motion = 0.0;
  EXPECT_EQ(VolumeReconstructor(e, none).reconstruct(c.edited_base.vertices, q).positions, r.positions);
  EXPECT_EQ(VolumeReconstructor(e, multigrid_reconstruct_options())
                .reconstruct(c.edited_base.vertices, q)
                .stats.deferred_constraints,
            0);
}

TEST(Reconstruction, RejectsBadInput) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 1000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const VolumeReconstructor rec(e);
  std::vector<Vec3> wrong(c.base.vertices.begin(), c.base.vertices.end() - 2);
  EXPECT_THROW(rec.reconstruct(wrong), InvalidInput);
  std::vector<Vec3> nan_base = c.edited_base.vertices;
  nan_base[5][2] = std::nan("");
  EXPECT_THROW(rec.reconstruct(nan_base), InvalidInput);
  EXPECT_THROW(rec.reconstruct_from(c.base.vertices, std::vector<Vec3>(3)), InvalidInput);
  ReconstructOptions bad;
  bad.volume_scales = 0;
  EXPECT_THROW(VolumeReconstructor(e, bad), InvalidInput);
  bad = ReconstructOptions{};
  bad.coarsening_ratio = 1.5;
  EXPECT_THROW(VolumeReconstructor(e, bad), InvalidInput);
  bad = ReconstructOptions{};
  bad.coarsest_vertices = 0;
  EXPECT_THROW(VolumeReconstructor(e, bad), InvalidInput);
  bad = ReconstructOptions{};
  bad.fold_repair_rounds = -1;
  EXPECT_THROW(VolumeReconstructor(e, bad), InvalidInput);
  bad = ReconstructOptions{};
  bad.fold_repair_sweeps = -2;
  EXPECT_THROW(VolumeReconstructor(e, bad), InvalidInput);
  DetailEncoding broken = e;
  broken.target_volumes.pop_back();
  EXPECT_THROW(VolumeReconstructor{broken}, InvalidInput);
  // Non-finite rest detail (an encoding made by hand): two vertices at +inf made an edge of NaN
  // length, whose bucket in the decimation's queue lay past its end.
  broken = e;
  broken.detail_rest[c.detail.faces[0][0]] = broken.detail_rest[c.detail.faces[0][1]] =
      Vec3::Constant(std::numeric_limits<double>::infinity());
  EXPECT_THROW(VolumeReconstructor{broken}, InvalidInput);
}

// An encoding made or altered by hand is checked before anything indexes with it or solves with
// it: a regularization graph whose rows or neighbours are out of range, and any non-finite
// number the solve reads, are invalid input naming the array (not a crash, and not a solve that
// diverges into non-finite positions).
TEST(Reconstruction, RejectsAnEncodingWithABrokenWeightGraphOrNonFiniteValues) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 1000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const double nan = std::nan("");
  auto rejected = [](const DetailEncoding& broken, const std::string& names) {
    try {
      VolumeReconstructor rec(broken);
      ADD_FAILURE() << "accepted; expected an error naming " << names;
    } catch (const InvalidInput& x) {
      EXPECT_NE(std::string(x.what()).find(names), std::string::npos) << x.what();
    }
  };
  DetailEncoding broken = e;
  broken.weight_neighbors[7] = e.num_detail_vertices();
  rejected(broken, "weight_neighbors");
  broken = e;
  broken.weight_neighbors[3] = -1;
  rejected(broken, "weight_neighbors");
  broken = e;
  std::swap(broken.weight_offsets[10], broken.weight_offsets[11]);
  rejected(broken, "weight_offsets");
  broken = e;
  broken.weight_offsets.back() += 5;
  rejected(broken, "weight_offsets");
  broken = e;
  broken.weights.pop_back();
  rejected(broken, "weights");
  broken = e;
  broken.weights[20] = nan;
  rejected(broken, "weights");
  broken = e;
  broken.weights[21] = 1e31;  // beyond what the multigrid's single precision holds safely
  rejected(broken, "weights");
  broken = e;
  broken.normal_offsets[4] = nan;
  rejected(broken, "normal_offsets");
  broken = e;
  broken.tangential_offsets[4].y() = std::numeric_limits<double>::infinity();
  rejected(broken, "tangential_offsets");
  broken = e;
  broken.target_volumes[9] = nan;
  rejected(broken, "target_volumes");
  broken = e;
  broken.base_rest_points[2].x() = nan;
  rejected(broken, "base_rest_points");
  broken = e;
  broken.base_points[6].bary[1] = nan;
  rejected(broken, "base point");
  // Base faces beyond the base's vertices: the frames read past the edited base.
  broken = e;
  broken.base_faces[5][1] = e.base_num_vertices;
  rejected(broken, "base face index");
  broken = e;
  broken.base_num_vertices -= 1;  // the last vertex is still used by a face
  rejected(broken, "base face index");
}

// Options out of range that check_reconstruct_options() let through: an enum from a cast integer,
// reached a switch without its case (UBSan: a null reference); a NaN or negative motion bound; a
// negative direct-solve size.
TEST(Reconstruction, EnumAndBoundOptionsOutOfRangeAreRejected) {
  auto refused = [](const ReconstructOptions& o, const char* name) {
    try {
      check_reconstruct_options(o);
      ADD_FAILURE() << name << " accepted";
    } catch (const InvalidInput& x) {
      EXPECT_NE(std::string(x.what()).find(name), std::string::npos) << x.what();
    }
  };
  ReconstructOptions o;
  o.polish_solver = static_cast<VolumeStepSolver>(42);
  refused(o, "polish_solver");
  o = {};
  o.step_solver = static_cast<VolumeStepSolver>(-1);
  refused(o, "step_solver");
  o = {};
  o.tangential_regularization = static_cast<TangentialRegularization>(7);
  refused(o, "tangential_regularization");
  o = {};
  o.local_polish_max_motion = std::nan("");
  refused(o, "local_polish_max_motion");
  o.local_polish_max_motion = -1e-3;
  refused(o, "local_polish_max_motion");
  o = {};
  o.direct_max_prisms = -1;
  refused(o, "direct_max_prisms");
  o = {};
  o.max_constraint_motion = std::nan("");
  refused(o, "max_constraint_motion");
  o.max_constraint_motion = -1.0;
  refused(o, "max_constraint_motion");
  o.max_constraint_motion = std::numeric_limits<double>::infinity();
  refused(o, "max_constraint_motion");
  o = ReconstructOptions{};
  o.multigrid.smoothing_degree = 0;
  refused(o, "multigrid.smoothing_degree");
  o.multigrid.smoothing_degree = 9;
  refused(o, "multigrid.smoothing_degree");
  EXPECT_NO_THROW(check_reconstruct_options(ReconstructOptions{}));
  EXPECT_NO_THROW(check_reconstruct_options(multigrid_reconstruct_options()));
  EXPECT_NO_THROW(check_reconstruct_options(cycle_schedule_reconstruct_options()));
}

// A solve that diverges (regularization weights at 1e25: in range, but no solve follows them) is a
// SolverError naming the divergence, not non-finite positions handed on; with the multigrid
// preset's solver as with the default one.
TEST(Reconstruction, ADivergingSolveIsASolverError) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 1000);
  DetailEncoding e = encode_detail(c.detail, c.base);
  for (double& w : e.weights) w *= 1e25;
  for (const ReconstructOptions& o : {ReconstructOptions{}, multigrid_reconstruct_options()}) {
    const VolumeReconstructor rec(e, o);
    try {
      rec.reconstruct(c.edited_base.vertices);
      ADD_FAILURE() << "no error";
    } catch (const SolverError& x) {
      EXPECT_NE(std::string(x.what()).find("diverged"), std::string::npos) << x.what();
    }
  }
}

// Interactive drags (paper, section 5) through a DragState.
TEST(DragState, StepsBeforeResetOrOfAnotherSizeAreRejected) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 2000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const VolumeReconstructor rec(e);
  DragState state;
  EXPECT_FALSE(state.started());
  EXPECT_THROW(rec.drag_step(c.base.vertices, state), InvalidInput);
  const BaseFrames rest = rec.base_frames(c.base.vertices);
  std::vector<Vec3> short_start(e.detail_rest.begin(), e.detail_rest.end() - 1);
  EXPECT_THROW(state.reset(rest, short_start), InvalidInput);
  std::vector<Vec3> nan_start = e.detail_rest;
  nan_start[3].x() = std::nan("");
  EXPECT_THROW(state.reset(rest, nan_start), InvalidInput);
  // A state started for another encoding.
  const cases::CylinderCase other = make_case(cases::DetailKind::Bumps, 4000);
  const DetailEncoding oe = encode_detail(other.detail, other.base);
  state.reset(VolumeReconstructor(oe).base_frames(other.base.vertices), oe.detail_rest);
  EXPECT_TRUE(state.started());
  EXPECT_THROW(rec.drag_step(c.base.vertices, state), InvalidInput);
}

// A state stepped by one reconstructor and then by another of the same encoding (the same vertex
// count, another hierarchy) is refused: its per-level arrays follow the first one's levels, and the
// second read past them. After a reset() the second may use it.
TEST(DragState, AStateSteppedByAnotherReconstructorIsRejected) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 2000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  ReconstructOptions one_level, three_levels;
  one_level.max_levels = 1;
  three_levels.max_levels = 3;
  const VolumeReconstructor a(e, one_level), b(e, three_levels);
  ASSERT_NE(a.level_vertex_counts().size(), b.level_vertex_counts().size());
  const WarmStartOptions preview{true, 1e-2, 1, 30};
  for (const VolumeReconstructor* first : {&a, &b}) {
    const VolumeReconstructor* second = first == &a ? &b : &a;
    DragState state;
    state.reset(first->base_frames(c.base.vertices), e.detail_rest);
    first->drag_step(c.edited_base.vertices, state, preview);
    try {
      second->drag_step(c.edited_base.vertices, state, preview);
      ADD_FAILURE() << "a state of another reconstructor was stepped";
    } catch (const InvalidInput& x) {
      EXPECT_NE(std::string(x.what()).find("another VolumeReconstructor"), std::string::npos) << x.what();
    }
    state.reset(second->base_frames(c.base.vertices), e.detail_rest);
    const ReconstructResult r = second->drag_step(c.edited_base.vertices, state, preview);
    for (const Vec3& p : r.positions) ASSERT_TRUE(p.allFinite());
  }
}

// Warm-start options out of range are refused by the calls that take them (a NaN tolerance ended
// unconverged at once; negative counts passed).
TEST(Reconstruction, WarmStartOptionsOutOfRangeAreRejected) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 1000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const VolumeReconstructor rec(e);
  std::vector<WarmStartOptions> bad(5);
  bad[0].tolerance = std::nan("");
  bad[1].tolerance = 0;
  bad[2].level_steps = -1;
  bad[3].cg_max_iterations = -1;
  bad[4].max_cycles = -1;
  const char* names[] = {"tolerance", "tolerance", "level_steps", "cg_max_iterations", "max_cycles"};
  for (std::size_t k = 0; k < bad.size(); ++k) {
    try {
      rec.reconstruct_from(c.edited_base.vertices, e.detail_rest, bad[k]);
      ADD_FAILURE() << names[k] << " accepted";
    } catch (const InvalidInput& x) {
      EXPECT_NE(std::string(x.what()).find(names[k]), std::string::npos) << x.what();
    }
    DragState state;
    state.reset(rec.base_frames(c.base.vertices), e.detail_rest);
    EXPECT_THROW(rec.drag_step(c.edited_base.vertices, state, bad[k]), InvalidInput) << names[k];
  }
}

// Over the unedited base every level's state is the rest detail, which holds every level's target
// volumes and is a fixed point of the regularization, in both tangential forms (the rest
// Laplacian's only through its c_i: without it the bumps' flanks slide, the 100k round trips came
// back 2.3-11% off): a step gives the detail back. The bumps' flanks and the cuboid's corners have
// the largest tangential Laplacians, which c_i must cancel on every level.
TEST(DragState, AStepOverTheUneditedBaseKeepsTheDetail) {
  for (cases::DetailKind kind : {cases::DetailKind::Bumps, cases::DetailKind::Cuboid})
    for (TangentialRegularization form :
         {TangentialRegularization::RestOffset, TangentialRegularization::RestLaplacian}) {
      SCOPED_TRACE(static_cast<int>(form));
      const cases::CylinderCase c = make_case(kind, 4000);
      const DetailEncoding e = encode_detail(c.detail, c.base);
      ReconstructOptions o;
      o.tangential_regularization = form;
      const VolumeReconstructor rec(e, o);
      ASSERT_GE(rec.level_vertex_counts().size(), 2u);  // a coarse level, the coarsest
      DragState state;
      state.reset(rec.base_frames(c.base.vertices), e.detail_rest);
      WarmStartOptions preview{true, 1e-2, 1, 30};
      for (int k = 0; k < 3; ++k) {
        const ReconstructResult r = rec.drag_step(c.base.vertices, state, preview);
        EXPECT_LT(max_distance(r.positions, e.detail_rest), 1e-9 * bbox_diagonal(e.detail_rest)) << k;
        EXPECT_LE(r.stats.max_relative_error, 1e-6);
      }
    }
}

// A drag from the base to the paper's 90-degree bend in small steps: at release the preview has
// followed the bend (much closer to the exact result than the unbent detail is) and is finite;
// the exact step from the drag's state then holds the volumes to the tolerance without folds.
// (Known limit: held over an unchanged base, the preview drifts instead of converging, since one
// inexact volume step per coarse level and frame does not settle against the regularization.)
TEST(DragState, PreviewsFollowTheDrag) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 8000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const VolumeReconstructor rec(e);
  const std::vector<Vec3>& b0 = c.base.vertices;
  const std::vector<Vec3>& b1 = c.edited_base.vertices;
  const std::vector<Vec3> exact = rec.reconstruct(b1).positions;
  DragState state;
  state.reset(rec.base_frames(b0), e.detail_rest);
  const WarmStartOptions preview{true, 1e-2, 1, 30};
  const int steps = 15;
  ReconstructResult r;
  for (int k = 1; k <= steps; ++k) {
    std::vector<Vec3> b(b0.size());
    const double t = static_cast<double>(k) / steps;
    for (std::size_t v = 0; v < b.size(); ++v) b[v] = (1 - t) * b0[v] + t * b1[v];
    r = rec.drag_step(b, state, preview);
    ASSERT_EQ(r.positions.size(), e.detail_rest.size());
    for (const Vec3& p : r.positions) ASSERT_TRUE(p.allFinite());
  }
  EXPECT_LT(max_distance(r.positions, exact), 0.1 * max_distance(e.detail_rest, exact));
  // The exact step from the drag's state: the finest level solved to the tolerance.
  const ReconstructResult x = rec.drag_step(b1, state, WarmStartOptions{false, 1e-4, 0, 0, 3});
  EXPECT_TRUE(x.stats.converged);
  expect_phases_within_solve(x.stats);
  const BaseFrames fr = evaluate_base_frames(e, b1);
  EXPECT_LE(volume_metrics(e, fr, x.positions).max_relative_error, 1e-4);
  EXPECT_EQ(0u, find_self_intersections(x.positions, c.detail.faces).num_pairs);
  EXPECT_LT(max_distance(x.positions, exact), 0.1 * max_distance(e.detail_rest, exact));
}

// ReconstructOptions::progress: a clean start reports after every level of every volume scale,
// with fractions that only grow, within [0, 1], and end at 1.
TEST(ReconstructionProgress, ReportsEveryLevelOfEveryScaleInOrder) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 4000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  std::vector<std::pair<std::string, double>> reports;
  ReconstructOptions o;
  o.threads = 1;
  o.progress = [&](const std::string& phase, double f) { reports.emplace_back(phase, f); };
  const VolumeReconstructor rec(e, o);
  // The construction: "setup" from 0 to 1, never backwards, once per level at least.
  ASSERT_GE(reports.size(), rec.level_vertex_counts().size() + 1);
  EXPECT_EQ(reports.front(), std::make_pair(std::string("setup"), 0.0));
  for (std::size_t k = 1; k < reports.size(); ++k) {
    EXPECT_EQ(reports[k].first, "setup");
    EXPECT_GE(reports[k].second, reports[k - 1].second);
  }
  EXPECT_DOUBLE_EQ(reports.back().second, 1.0);
  reports.clear();
  const ReconstructResult r = rec.reconstruct(c.edited_base.vertices);
  ASSERT_TRUE(r.stats.converged);
  ASSERT_EQ(r.stats.retries, 0);  // so that every report is the first schedule's
  ASSERT_GE(r.stats.levels, 2);
  ASSERT_EQ(reports.size(), static_cast<std::size_t>(o.volume_scales * r.stats.levels));
  double last = 0.0;
  for (const auto& [phase, f] : reports) {
    EXPECT_EQ(phase, "reconstruct");
    EXPECT_GT(f, last);
    EXPECT_LE(f, 1.0);
    last = f;
  }
  EXPECT_DOUBLE_EQ(reports.back().second, 1.0);
  // Weighted by the levels' prisms: the finest level's full-scale solve is most of the work.
  EXPECT_LT(reports[reports.size() - 2].second, 0.8);
}

// ReconstructOptions::cancel: a flag set during a solve stops it with Cancelled; the reconstructor
// stays usable, and its next solve is the same, bit for bit, as a fresh one's.
TEST(ReconstructionCancel, StopsTheSolveAndLeavesTheReconstructorUsable) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 4000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  for (const bool multigrid : {false, true}) {
    SCOPED_TRACE(multigrid ? "multigrid preset" : "defaults");
    std::atomic<bool> stop{false};
    int reports = 0;
    ReconstructOptions o = multigrid ? multigrid_reconstruct_options() : ReconstructOptions{};
    o.threads = 1;
    o.cancel = &stop;
    o.progress = [&](const std::string& phase, double) {
      if (phase != "setup" && ++reports == 2) stop = true;  // after the second level of the first scale
    };
    const VolumeReconstructor rec(e, o);
    EXPECT_THROW(rec.reconstruct(c.edited_base.vertices), Cancelled);
    EXPECT_EQ(reports, 2);  // stopped before the next level ended
    stop = false;
    const ReconstructResult again = rec.reconstruct(c.edited_base.vertices);
    o.progress = nullptr;
    const ReconstructResult fresh = VolumeReconstructor(e, o).reconstruct(c.edited_base.vertices);
    EXPECT_TRUE(again.stats.converged);
    EXPECT_EQ(again.positions, fresh.positions);
    // Set before the call: nothing is solved.
    stop = true;
    reports = 0;
    EXPECT_THROW(rec.reconstruct(c.edited_base.vertices), Cancelled);
    EXPECT_EQ(reports, 0);
    DragState drag;
    drag.reset(rec.base_frames(c.base.vertices), fresh.positions);
    WarmStartOptions warm;
    warm.coarse_levels_only = true;
    EXPECT_THROW(rec.drag_step(c.edited_base.vertices, drag, warm), Cancelled);
    stop = false;
    EXPECT_NO_THROW(rec.drag_step(c.edited_base.vertices, drag, warm));
  }
}

// The construction (the hierarchy's decimation and levels) reads the flag too: set before it, it
// stops in the decimation; set once the first level is decimated, before the next level ends.
// Cleared, the same options build a reconstructor that solves as one built without the flag.
TEST(ReconstructionCancel, StopsTheSetup) {
  const cases::CylinderCase c = make_case(cases::DetailKind::Bumps, 4000);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  std::atomic<bool> stop{true};
  std::vector<double> setup;
  ReconstructOptions o;
  o.threads = 1;
  o.cancel = &stop;
  o.progress = [&](const std::string& phase, double f) {
    if (phase == "setup") setup.push_back(f);
  };
  EXPECT_THROW(VolumeReconstructor(e, o), Cancelled);
  EXPECT_EQ(setup, std::vector<double>{0.0});  // no level was finished
  stop = false;
  setup.clear();
  o.progress = [&](const std::string& phase, double f) {
    if (phase != "setup") return;
    setup.push_back(f);
    if (f > 0.0) stop = true;
  };
  EXPECT_THROW(VolumeReconstructor(e, o), Cancelled);
  ASSERT_EQ(setup.size(), 2u);
  EXPECT_GT(setup[1], 0.0);
  EXPECT_LT(setup[1], 1.0);
  stop = false;
  o.progress = nullptr;
  const ReconstructResult with_flag = VolumeReconstructor(e, o).reconstruct(c.edited_base.vertices);
  o.cancel = nullptr;
  const ReconstructResult without = VolumeReconstructor(e, o).reconstruct(c.edited_base.vertices);
  EXPECT_TRUE(with_flag.stats.converged);
  EXPECT_EQ(with_flag.positions, without.positions);
}

namespace {

// A fan of k triangles around one hub (a CAD cylinder's cap), bumped over a flat 800-face grid,
// and the grid bent into z = bend x^2.
struct HubFan {
  TriMesh detail, base, edited;
  explicit HubFan(int k) {
    detail.vertices.emplace_back(0.0, 0.0, 0.05);
    for (int i = 0; i < k; ++i) {
      const double a = 2.0 * M_PI * i / k;
      detail.vertices.emplace_back(std::cos(a), std::sin(a), 0.03 + 0.02 * std::sin(7.0 * a));
      detail.faces.push_back({0, 1 + i, 1 + (i + 1) % k});
    }
    const int n = 20;
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const double x = -1.1 + 2.2 * i / n, y = -1.1 + 2.2 * j / n;
        base.vertices.emplace_back(x, y, 0.0);
        edited.vertices.emplace_back(x, y, 0.15 * x * x);
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
        base.faces.push_back({a, b, d});
        base.faces.push_back({a, d, c});
      }
    edited.faces = base.faces;
  }
};

}  // namespace

// A hub in 4,000 prisms makes J J^T's block there dense (8M entries): no level with it is
// factorized, and every preset solves the fan to the tolerance with its exact steps on the vertex
// multigrid, where the default options' factorization took 20.9 s and 2.0 GB at 10,000 prisms. A
// fan of 1,000 stays factorizable (its block has 500k entries).
TEST(Reconstruction, AHubMakesNoDenseFactorization) {
  const HubFan small(1000);
  EXPECT_EQ(VolumeReconstructor(encode_detail(small.detail, small.base))
                .reconstruct(small.edited.vertices)
                .stats.dense_levels,
            0);
  const HubFan fan(4000);
  const DetailEncoding e = encode_detail(fan.detail, fan.base);
  const IntersectionResult rest =
      find_self_intersections(fan.detail.vertices, fan.detail.faces, collecting());
  for (const ReconstructOptions& o :
       {ReconstructOptions{}, multigrid_reconstruct_options(), cycle_schedule_reconstruct_options()}) {
    const ReconstructResult r = VolumeReconstructor(e, o).reconstruct(fan.edited.vertices);
    EXPECT_GE(r.stats.dense_levels, 1);
    EXPECT_EQ(r.stats.factorizations, 0);
    EXPECT_EQ(r.stats.local_factorizations, 0);
    EXPECT_TRUE(r.stats.converged);
    const VolumeMetrics m = volume_metrics(e, evaluate_base_frames(e, fan.edited.vertices), r.positions);
    EXPECT_LE(m.max_relative_error, o.tolerance);
    EXPECT_EQ(
        count_new_intersections(rest, find_self_intersections(r.positions, fan.detail.faces, collecting())),
        0u);
  }
  // A polish to 1e-6 with local ends allowed over the whole level: the off prisms all touch the
  // hub, so a local end's system would be as dense; none is factorized (without the local guards
  // this case took 16.8 s, one local and one whole-level factorization).
  ReconstructOptions tight = multigrid_reconstruct_options();
  tight.tolerance = 1e-6;
  tight.local_polish_max_fraction = 1.0;
  const ReconstructResult r = VolumeReconstructor(e, tight).reconstruct(fan.edited.vertices);
  EXPECT_GT(r.stats.final_sweeps, 0);  // the polish ran
  EXPECT_EQ(r.stats.local_factorizations, 0);
  EXPECT_EQ(r.stats.factorizations, 0);
  EXPECT_TRUE(r.stats.converged);
  EXPECT_LE(volume_metrics(e, evaluate_base_frames(e, fan.edited.vertices), r.positions).max_relative_error,
            tight.tolerance);
}

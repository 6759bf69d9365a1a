// The conservativeness property test, the most important test of the project: for random
// kinematic trees, volumes and interval boxes, no reported distance may exceed the true distance
// at any configuration sampled from the box (computed independently of libkccd).
//
// KCCD_SOAK=N runs N cases instead of the CI-sized default; KCCD_SEED=S reruns one case.
#include <gtest/gtest.h>

#include <cstdlib>
#include <iostream>
#include <random>

#include "kccd/checker.hpp"
#include "support/random_model.hpp"
#include "support/reference_distance.hpp"
#include "support/sanitized.hpp"

namespace kccd {
namespace {

long envOr(const char* name, long fallback) {
  const char* v = std::getenv(name);
  return v != nullptr ? std::atol(v) : fallback;
}

// A cheap lower bound on the distance of two SSCHs, to skip the exact oracle when it already
// proves the sample is farther than the reported bound.
double sphereLowerBound(const std::vector<Eigen::Vector3d>& a, double ra, const std::vector<Eigen::Vector3d>& b,
                        double rb) {
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  for (const auto& p : a) ca += p;
  for (const auto& p : b) cb += p;
  ca /= static_cast<double>(a.size());
  cb /= static_cast<double>(b.size());
  double ra2 = 0.0, rb2 = 0.0;
  for (const auto& p : a) ra2 = std::max(ra2, (p - ca).norm());
  for (const auto& p : b) rb2 = std::max(rb2, (p - cb).norm());
  return (ca - cb).norm() - ra2 - rb2 - ra - rb - 1e-12;
}

struct Tally {
  long cases = 0, pair_checks = 0, nontrivial = 0, oracle_calls = 0, split_pairs = 0;
  double worst_gap = -1.0;  // smallest (true - bound) seen over nontrivial checks
};

// Runs one case; returns false (with a message) on a violation.
bool runCase(std::uint64_t seed, Tally& tally, std::string& why, testing::MobileBase base = testing::MobileBase::None) {
  std::mt19937_64 rng(seed);
  const Model m = testing::randomModel(rng, 5, 4, base);
  std::vector<double> lower, upper;
  testing::randomBox(rng, m, lower, upper);
  Checker checker(m);
  QueryOptions opt;
  opt.type = QueryType::Distances;
  // Every third case refines every pair by the exact stage (those clear of the margin to
  // kExactDistanceTolerance), every third the default (the margin plus a band of 0.2 m or of 5 m:
  // every pair of most trees), every third none.
  opt.exact_below = seed % 3 == 0   ? std::numeric_limits<double>::infinity()
                    : seed % 3 == 1 ? -1.0
                                    : -std::numeric_limits<double>::infinity();
  opt.tight_volumes = (seed / 3) % 2 == 0;  // the display volumes are bounds too
  opt.exact_band = (seed / 6) % 2 == 0 ? 0.2 : 5.0;
  opt.exact_splits = (seed / 12) % 3 == 0 ? 0 : (seed / 12) % 3 == 1 ? 8 : kMaxExactSplits;  // box splitting
  const QueryResult& r = checker.query(lower, upper, opt);
  tally.split_pairs += r.stats.split_pairs;
  if (r.status != Status::Ok) {
    why = std::string("status ") + toString(r.status);
    return false;
  }
  std::vector<double> bound(m.pairs.size());
  for (const PairDistance& pd : r.pairs) bound[pd.pair] = pd.distance;
  ++tally.cases;
  constexpr int kSamples = 40;
  for (int s = 0; s < kSamples; ++s) {
    const testing::Sample sample = testing::sampleBox(rng, m, lower, upper, s % 3);
    const std::vector<Pose> poses = testing::jointPoses(m, sample);
    for (std::size_t p = 0; p < m.pairs.size(); ++p) {
      ++tally.pair_checks;
      if (bound[p] <= 0.0) continue;
      ++tally.nontrivial;
      const BodyPair& pair = m.pairs[p];
      const auto a = testing::worldPoints(m, poses, pair.a);
      const auto b = testing::worldPoints(m, poses, pair.b);
      const double ra = m.bodies[pair.a].radius, rb = m.bodies[pair.b].radius;
      if (sphereLowerBound(a, ra, b, rb) >= bound[p]) continue;
      ++tally.oracle_calls;
      const auto truth = static_cast<double>(testing::referenceSschDistance(a, ra, b, rb));
      tally.worst_gap = tally.worst_gap < 0.0 ? truth - bound[p] : std::min(tally.worst_gap, truth - bound[p]);
      if (bound[p] > truth + 1e-12) {
        why = "pair " + m.bodies[pair.a].name + "-" + m.bodies[pair.b].name + ": bound " + std::to_string(bound[p]) +
              " > sampled distance " + std::to_string(truth) + " (sample " + std::to_string(s) + ")";
        return false;
      }
    }
  }
  return true;
}

TEST(Conservative, BoundNeverExceedsSampledDistance) {
  const long single = envOr("KCCD_SEED", -1);
  // 50,000 cases (15,000 under the sanitizers); KCCD_SOAK=N for a long soak.
  const long cases = single >= 0 ? 1 : envOr("KCCD_SOAK", kccd::testing::casesFor(50000, 15000));
  const std::uint64_t base = 0x6b636364;  // "kccd"
  Tally tally;
  long failures = 0;
  for (long i = 0; i < cases; ++i) {
    const std::uint64_t seed = single >= 0 ? static_cast<std::uint64_t>(single) : base + static_cast<std::uint64_t>(i);
    std::string why;
    if (!runCase(seed, tally, why)) {
      ++failures;
      ADD_FAILURE() << "conservativeness violated, seed " << seed << " (rerun with KCCD_SEED=" << seed << "): " << why;
      if (failures >= 5) break;
    }
  }
  std::cout << "[ property ] " << tally.cases << " cases, " << tally.pair_checks << " pair samples, "
            << tally.nontrivial << " with a positive bound, " << tally.oracle_calls << " exact oracle calls, "
            << tally.split_pairs << " pairs split; tightest margin true - bound = " << tally.worst_gap << " m\n";
  EXPECT_EQ(failures, 0);
  if (single < 0) {
    EXPECT_EQ(tally.cases, cases);
    EXPECT_GT(tally.nontrivial, tally.pair_checks / 10);  // the test exercises separated pairs
    EXPECT_GT(tally.oracle_calls, tally.cases);           // and often needs the exact oracle
    EXPECT_GT(tally.split_pairs, tally.cases / 100);      // and splits boxes
  }
}

// Mobile bases as `kccd import` maps URDF planar and floating joints (a chain of prismatic,
// prismatic and revolute joints in one plane; translation3d then rotation3d), at the root of
// random trees: the same property.
TEST(Conservative, MobileBasesFromUrdfJointsAreConservative) {
  const long cases = envOr("KCCD_SOAK", 50000) / 10;
  for (const testing::MobileBase base : {testing::MobileBase::Planar, testing::MobileBase::Floating}) {
    Tally tally;
    long failures = 0;
    for (long i = 0; i < cases && failures < 5; ++i) {
      const std::uint64_t seed = 0x6d6f62 + static_cast<std::uint64_t>(i);
      std::string why;
      if (!runCase(seed, tally, why, base)) {
        ++failures;
        ADD_FAILURE() << (base == testing::MobileBase::Planar ? "planar" : "floating") << " base, seed " << seed << ": "
                      << why;
      }
    }
    std::cout << "[ property ] " << (base == testing::MobileBase::Planar ? "planar" : "floating")
              << " bases: " << tally.cases << " cases, " << tally.nontrivial << " pair samples with a positive bound, "
              << tally.oracle_calls << " exact oracle calls, " << tally.split_pairs
              << " pairs split; tightest true - bound = " << tally.worst_gap << " m\n";
    EXPECT_EQ(failures, 0);
    EXPECT_EQ(tally.cases, cases);
    EXPECT_GT(tally.oracle_calls, tally.cases);
  }
}

}  // namespace
}  // namespace kccd

namespace kccd {
namespace {

// The any-time table: across a sequence of moving boxes, with every query type and work budgets
// that leave most pairs unrefreshed, every bound the table holds must stay a valid lower bound.
TEST(Conservative, CarriedOverBoundsStayValidAcrossCycles) {
  const long cases = std::max(1L, envOr("KCCD_SOAK", 50000) / 10);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  long violations = 0, carried_checks = 0;
  for (long i = 0; i < cases && violations < 5; ++i) {
    const std::uint64_t seed = 0x616e7974 + static_cast<std::uint64_t>(i);
    std::mt19937_64 rng(seed);
    const Model m = testing::randomModel(rng);
    Checker checker(m);
    std::vector<double> lower, upper;
    testing::randomBox(rng, m, lower, upper);
    const int np = static_cast<int>(m.pairs.size());
    for (int cycle = 0; cycle < 8; ++cycle) {
      QueryOptions opt;
      opt.type = static_cast<QueryType>(std::uniform_int_distribution<int>(0, 3)(rng));
      opt.n = 1 + static_cast<int>(u(rng) * np);
      opt.max_pairs = u(rng) < 0.3 ? -1 : static_cast<int>(u(rng) * np);
      opt.exact_below = u(rng) < 0.5   ? -1.0
                        : u(rng) < 0.5 ? std::numeric_limits<double>::infinity()
                                       : 0.1 * u(rng) - 0.01;
      ASSERT_EQ(checker.query(lower, upper, opt).status, Status::Ok);
      // Read the whole table for this box without recomputing anything.
      QueryOptions peek;
      peek.type = QueryType::Distances;
      peek.max_pairs = 0;
      const QueryResult& r = checker.query(lower, upper, peek);
      ASSERT_EQ(r.pairs.size(), m.pairs.size());
      for (int s = 0; s < 12; ++s) {
        const testing::Sample sample = testing::sampleBox(rng, m, lower, upper, s % 3);
        const std::vector<Pose> poses = testing::jointPoses(m, sample);
        for (const PairDistance& pd : r.pairs) {
          if (pd.distance <= 0.0) continue;
          ++carried_checks;
          const BodyPair& pair = m.pairs[pd.pair];
          const double truth = testing::referencePairDistance(m, poses, pair);
          if (pd.distance > truth + 1e-12) {
            ++violations;
            ADD_FAILURE() << "carried-over bound invalid, seed " << seed << " cycle " << cycle << ": bound "
                          << pd.distance << " > " << truth;
            break;
          }
        }
      }
      // The next cycle: the box drifts and breathes, sometimes only shrinking.
      for (std::size_t k = 0; k < lower.size(); ++k) {
        const double width = upper[k] - lower[k];
        const double shift = (u(rng) < 0.3 ? 0.0 : (u(rng) - 0.5) * 0.1);
        const double grow = u(rng) < 0.5 ? -0.3 * width * u(rng) : 0.1 * u(rng) * width;
        if (lower[k] == upper[k] && u(rng) < 0.5) continue;  // exact joints keep zero width
        if (lower[k] == upper[k]) {
          lower[k] += shift;
          upper[k] += shift;
          continue;
        }
        lower[k] += shift - 0.5 * grow;
        upper[k] = std::max(lower[k], upper[k] + shift + 0.5 * grow);
      }
    }
  }
  std::cout << "[ property ] " << cases << " sequences of 8 cycles, " << carried_checks << " table checks\n";
  EXPECT_EQ(violations, 0);
  EXPECT_GT(carried_checks, cases * 10);
}

}  // namespace
}  // namespace kccd

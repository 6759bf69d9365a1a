// Proof that a query on a set-up Checker never allocates: every global operator new is counted.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <limits>
#include <new>
#include <random>

#include "kccd/checker.hpp"
#include "kccd/state_log.hpp"
#include "support/random_model.hpp"

// The replacements below pair malloc with free; GCC's -Wmismatched-new-delete cannot see that
// operator new itself is replaced and warns about every delete.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace {
std::atomic<long> g_allocations{0};
}

void* operator new(std::size_t size) {
  ++g_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace kccd {
namespace {

TEST(NoAllocation, QueriesAllocateNothingOnceSetUp) {
  // The counter works.
  const long before_probe = g_allocations;
  auto* probe = new std::vector<int>(100);
  delete probe;
  ASSERT_GT(g_allocations - before_probe, 0);

  std::mt19937_64 rng(123);
  long queries = 0, exact_calls = 0;
  for (int i = 0; i < 300; ++i) {
    const Model m = testing::randomModel(rng, 6, 6);
    std::vector<double> lower, upper;
    testing::randomBox(rng, m, lower, upper);
    std::vector<double> bad = lower;
    if (!bad.empty()) bad[0] = std::nan("");
    const std::vector<double> shorter(lower.size() + 1, 0.0);
    Checker checker(m);
    const long start = g_allocations;
    for (int type = 0; type < 4; ++type) {
      QueryOptions o;
      o.type = static_cast<QueryType>(type);
      o.n = 3;
      o.budget_us = (i % 3 == 0) ? 5.0 : 0.0;
      o.max_pairs = (i % 3 == 1) ? 2 : -1;
      // The exact stage on flagged pairs (the default) or on every pair, display volumes or not.
      o.exact_below = (i % 2 == 0) ? -1.0 : std::numeric_limits<double>::infinity();
      o.tight_volumes = (i % 4) < 2;
      exact_calls += checker.query(lower, upper, o).stats.exact_calls;
      checker.query(bad, upper, o);
      checker.query(shorter, shorter, o);
      queries += 3;
    }
    checker.sweptVolume(0, kWorld);
    ASSERT_EQ(g_allocations - start, 0) << "case " << i;
  }
  EXPECT_EQ(queries, 300 * 12);
  EXPECT_GT(exact_calls, 1000);  // the exact stage ran, allocation-free
}

TEST(NoAllocation, StateAtAllocatesNothing) {
  const Model m = parseModel(
      "kccd: 1\njoints:\n  - {name: a, parent: world, type: revolute, axis: [0, 0, 1]}\n"
      "  - {name: b, parent: a, type: prismatic, axis: [1, 0, 0]}\n"
      "bodies:\n  - {name: t, frame: b, points: [[0, 0, 0]], radius: 0.1}\n",
      "m.yaml");
  const StateLog plain = parseStateLog("time,a,b\n0,3.1,0\n0.1,-3.1,1\n0.3,0,2\n", "log.csv", m);
  const StateLog rates = parseStateLog("time,a,b,b.vel\n0,3.1,0,1\n0.1,-3.1,1,2\n0.3,0,2,3\n", "log.csv", m);
  std::vector<double> state(2), velocity(2);
  const long start = g_allocations;
  int found = 0;
  for (const StateLog* log : {&plain, &rates})
    for (const double t : {-1.0, 0.0, 0.05, 0.1, 0.2, 0.3, 0.4, std::nan("")}) {
      found += stateAt(*log, t, 0.15, state, velocity) != StateMatch::None;
      found += stateAt(*log, t, 0.15, state) != StateMatch::None;
    }
  EXPECT_EQ(g_allocations - start, 0);
  // 0, 0.05, 0.1 and 0.3 have a state (0.2 lies in a 0.2 s gap), but no rate at 0.3 (no neighbour
  // within 0.15 s, and `a` has no velocity column).
  EXPECT_EQ(found, 2 * (4 + 3));
}

}  // namespace
}  // namespace kccd

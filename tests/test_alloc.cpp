// Proof that a query on a set-up Checker never allocates: every global operator new is counted.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <random>

#include "kccd/checker.hpp"
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
  long queries = 0;
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
      checker.query(lower, upper, o);
      checker.query(bad, upper, o);
      checker.query(shorter, shorter, o);
      queries += 3;
    }
    checker.sweptVolume(0, kWorld);
    ASSERT_EQ(g_allocations - start, 0) << "case " << i;
  }
  EXPECT_EQ(queries, 300 * 12);
}

}  // namespace
}  // namespace kccd

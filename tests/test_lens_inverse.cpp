// The lens cache (kccd/render/lens_inverse.hpp): a cached inverse equals the computed one bit for
// bit, a damaged or foreign file is never used, "off" writes nothing, and the cache stays small.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "kccd/render/lens_inverse.hpp"
#include "kccd/render/projection.hpp"
#include "support/cameras.hpp"
#include "support/files.hpp"

namespace {

using kccd::calib::Camera;
using kccd::render::LensInverse;
using kccd::render::lensInverse;

Camera lens(double k1) {
  return kccd::testing::lookAt({2, 0, 1}, {0, 0, 0.5}, 320, 240, 300, {k1, 0.02, 0.001, -0.001, 0.0});
}

bool sameBits(const LensInverse& a, const LensInverse& b) {
  return a.valid == b.valid && a.normal.total() == b.normal.total() &&
         std::memcmp(a.normal.data, b.normal.data, a.normal.total() * a.normal.elemSize()) == 0;
}

std::size_t filesIn(const std::filesystem::path& dir) {
  std::size_t n = 0;
  if (std::filesystem::exists(dir))
    for (const auto& e : std::filesystem::directory_iterator(dir)) n += e.is_regular_file() ? 1 : 0;
  return n;
}

struct CacheFolder {
  std::filesystem::path dir = kccd::testing::scratchFolder("lens_cache") / "cache";
  CacheFolder() {
    std::filesystem::remove_all(dir);
    ::setenv("KCCD_CACHE_DIR", dir.c_str(), 1);
  }
  ~CacheFolder() {
    std::filesystem::remove_all(dir);
    ::unsetenv("KCCD_CACHE_DIR");
  }
};

TEST(LensInverse, ACachedInverseIsTheComputedOneBitForBit) {
  CacheFolder cache;
  ::setenv("KCCD_CACHE_DIR", "off", 1);
  const LensInverse fresh = lensInverse(lens(-0.3));
  EXPECT_FALSE(fresh.from_cache);
  ::setenv("KCCD_CACHE_DIR", cache.dir.c_str(), 1);
  const LensInverse first = lensInverse(lens(-0.3)), second = lensInverse(lens(-0.3));
  EXPECT_FALSE(first.from_cache);
  EXPECT_TRUE(second.from_cache);
  EXPECT_EQ(filesIn(cache.dir), 1u);
  EXPECT_TRUE(sameBits(fresh, first));
  EXPECT_TRUE(sameBits(fresh, second));
  // The maps a Projection draws with are the same from the cache.
  ::setenv("KCCD_CACHE_DIR", "off", 1);
  const kccd::render::Projection computed(lens(-0.3));
  ::setenv("KCCD_CACHE_DIR", cache.dir.c_str(), 1);
  const kccd::render::Projection read(lens(-0.3));
  ASSERT_TRUE(computed.warps());
  EXPECT_EQ(cv::norm(computed.mapX(), read.mapX(), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(computed.mapY(), read.mapY(), cv::NORM_INF), 0.0);
  EXPECT_EQ(computed.stretch(), read.stretch());
}

TEST(LensInverse, AnotherLensOrADamagedFileIsComputedAgain) {
  CacheFolder cache;
  const LensInverse a = lensInverse(lens(-0.3));
  const LensInverse b = lensInverse(lens(-0.2));  // another lens: another file, another inverse
  EXPECT_FALSE(b.from_cache);
  EXPECT_EQ(filesIn(cache.dir), 2u);
  EXPECT_FALSE(sameBits(a, b));
  // Every cache file cut short or with one byte changed in its key: not used, written again.
  for (const auto& e : std::filesystem::directory_iterator(cache.dir)) {
    std::filesystem::resize_file(e.path(), std::filesystem::file_size(e.path()) - 1);
  }
  const LensInverse again = lensInverse(lens(-0.3));
  EXPECT_FALSE(again.from_cache);
  EXPECT_TRUE(sameBits(a, again));
  for (const auto& e : std::filesystem::directory_iterator(cache.dir)) {
    std::fstream f(e.path(), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(20);
    f.put('\x7f');
  }
  const LensInverse changed = lensInverse(lens(-0.3));
  EXPECT_FALSE(changed.from_cache);
  EXPECT_TRUE(sameBits(a, changed));
  EXPECT_TRUE(lensInverse(lens(-0.3)).from_cache);
}

TEST(LensInverse, OffWritesNothingAndTheCacheKeepsEightLenses) {
  CacheFolder cache;
  ::setenv("KCCD_CACHE_DIR", "off", 1);
  EXPECT_EQ(kccd::render::lensCacheFolder(), "");
  EXPECT_FALSE(lensInverse(lens(-0.3)).from_cache);
  EXPECT_FALSE(lensInverse(lens(-0.3)).from_cache);
  EXPECT_FALSE(std::filesystem::exists(cache.dir));
  ::setenv("KCCD_CACHE_DIR", cache.dir.c_str(), 1);
  for (int i = 0; i < 11; ++i) lensInverse(lens(-0.3 + 0.01 * i));
  EXPECT_EQ(filesIn(cache.dir), 8u);
  EXPECT_TRUE(lensInverse(lens(-0.3 + 0.01 * 10)).from_cache);  // the newest are kept
}

}  // namespace

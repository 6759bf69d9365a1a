#include "kccd/render/lens_inverse.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <system_error>

namespace kccd::render {

namespace {

constexpr char kMagic[8] = {'K', 'C', 'C', 'D', 'L', 'N', 'S', '1'};
constexpr long kMaxCachedPixels = 2'100'000;
constexpr std::size_t kMaxCacheFiles = 8;

// What the inverse depends on, as bytes: the image size, the camera matrix, the distortion.
std::string lensKey(const calib::Camera& camera) {
  std::string key;
  const auto put = [&key](const void* p, std::size_t n) { key.append(static_cast<const char*>(p), n); };
  put(&camera.width, sizeof camera.width);
  put(&camera.height, sizeof camera.height);
  for (int i = 0; i < 9; ++i) {
    const double v = camera.camera_matrix(i / 3, i % 3);
    put(&v, sizeof v);
  }
  const std::uint64_t n = camera.distortion.size();
  put(&n, sizeof n);
  put(camera.distortion.data(), n * sizeof(double));
  return key;
}

// FNV-1a, 64 bits: the file name (the file holds the whole key, compared on reading).
std::string keyName(const std::string& key) {
  std::uint64_t h = 14695981039346656037ull;
  for (const unsigned char c : key) h = (h ^ c) * 1099511628211ull;
  char name[32];
  std::snprintf(name, sizeof name, "lens-%016llx.bin", static_cast<unsigned long long>(h));
  return name;
}

bool readCached(const std::filesystem::path& file, const std::string& key, int n, LensInverse& out) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return false;
  char magic[sizeof kMagic];
  std::uint64_t key_size = 0;
  if (!in.read(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof kMagic) != 0) return false;
  if (!in.read(reinterpret_cast<char*>(&key_size), sizeof key_size) || key_size != key.size()) return false;
  std::string stored(key.size(), '\0');
  if (!in.read(stored.data(), static_cast<std::streamsize>(stored.size())) || stored != key) return false;
  cv::Mat normal(n, 1, CV_64FC2);
  std::vector<unsigned char> valid(static_cast<std::size_t>(n));
  if (!in.read(reinterpret_cast<char*>(normal.data), static_cast<std::streamsize>(n) * 16) ||
      !in.read(reinterpret_cast<char*>(valid.data()), n) || in.peek() != std::char_traits<char>::eof())
    return false;
  out.normal = normal;
  out.valid = std::move(valid);
  out.from_cache = true;
  return true;
}

void writeCached(const std::filesystem::path& folder, const std::filesystem::path& file, const std::string& key,
                 const LensInverse& inverse) {
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) return;
  std::random_device random;
  const std::filesystem::path temporary =
      folder / (file.filename().string() + "." + std::to_string(::getpid()) + "." + std::to_string(random()) + ".tmp");
  {
    std::ofstream out(temporary, std::ios::binary);
    const std::uint64_t key_size = key.size();
    out.write(kMagic, sizeof kMagic);
    out.write(reinterpret_cast<const char*>(&key_size), sizeof key_size);
    out.write(key.data(), static_cast<std::streamsize>(key.size()));
    out.write(reinterpret_cast<const char*>(inverse.normal.data),
              static_cast<std::streamsize>(inverse.normal.total() * inverse.normal.elemSize()));
    out.write(reinterpret_cast<const char*>(inverse.valid.data()), static_cast<std::streamsize>(inverse.valid.size()));
    if (!out.flush()) {
      out.close();
      std::filesystem::remove(temporary, ec);
      return;
    }
  }
  std::filesystem::rename(temporary, file, ec);
  if (ec) std::filesystem::remove(temporary, ec);
  // At most kMaxCacheFiles lens files: the least recently written go.
  std::vector<std::pair<std::filesystem::file_time_type, std::filesystem::path>> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("lens-", 0) == 0 && entry.path().extension() == ".bin")
      files.emplace_back(entry.last_write_time(ec), entry.path());
  }
  if (files.size() <= kMaxCacheFiles) return;
  std::sort(files.begin(), files.end());
  for (std::size_t i = 0; i + kMaxCacheFiles < files.size(); ++i) std::filesystem::remove(files[i].second, ec);
}

}  // namespace

std::string lensCacheFolder() {
  const char* dir = std::getenv("KCCD_CACHE_DIR");
  if (dir != nullptr && *dir != '\0') return std::string(dir) == "off" ? std::string() : std::string(dir);
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg != nullptr && *xdg == '/') return std::string(xdg) + "/kccd";
  const char* home = std::getenv("HOME");
  if (home != nullptr && *home == '/') return std::string(home) + "/.cache/kccd";
  return {};
}

LensInverse lensInverse(const calib::Camera& camera) {
  const int n = camera.width * camera.height;
  const std::string folder = lensCacheFolder();
  const bool cached = !folder.empty() && static_cast<long>(n) <= kMaxCachedPixels;
  const std::string key = lensKey(camera);
  const std::filesystem::path file = cached ? std::filesystem::path(folder) / keyName(key) : std::filesystem::path();
  LensInverse inverse;
  if (cached && readCached(file, key, n, inverse)) return inverse;
  inverse.normal.create(n, 1, CV_64FC2);
  inverse.valid.assign(static_cast<std::size_t>(n), 0);
  // The blocks are independent: inverted in parallel (the set-up of a long recording's run), each
  // a few thousand pixels, so that the lens's slow corners spread over the threads.
  const int block_rows = std::max(1, (1 << 12) / camera.width);
  const int blocks = (camera.height + block_rows - 1) / block_rows;
  cv::parallel_for_(cv::Range(0, blocks), [&](const cv::Range& range) {
    for (int b = range.start; b < range.end; ++b) {
      const int v0 = b * block_rows;
      const int rows = std::min(block_rows, camera.height - v0), m = rows * camera.width, first = v0 * camera.width;
      cv::Mat pixels(m, 1, CV_64FC2), block_normal;
      for (int v = v0, i = 0; v < v0 + rows; ++v)
        for (int u = 0; u < camera.width; ++u, ++i) pixels.at<cv::Vec2d>(i) = cv::Vec2d(u, v);
      std::vector<unsigned char> block_valid;
      calib::undistortPixels(camera, pixels, block_normal, block_valid);
      block_normal.copyTo(inverse.normal.rowRange(first, first + m));
      std::copy(block_valid.begin(), block_valid.end(), inverse.valid.begin() + first);
    }
  });
  if (cached) writeCached(folder, file, key, inverse);
  return inverse;
}

}  // namespace kccd::render

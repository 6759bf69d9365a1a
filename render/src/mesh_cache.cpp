#include "kccd/render/mesh_cache.hpp"

#include <cstring>
#include <exception>
#include <string_view>

#include <opencv2/core/utility.hpp>

namespace kccd::render {

std::string MeshCache::key(const MeshRequest& r) {
  const std::size_t n = r.points.size() * sizeof(Vec3);
  std::string key(n + 2 * sizeof(double) + sizeof(int), '\0');
  std::memcpy(key.data(), r.points.data(), n);
  std::memcpy(key.data() + n, &r.radius, sizeof(double));
  std::memcpy(key.data() + n + sizeof(double), &r.level, sizeof(int));
  std::memcpy(key.data() + n + sizeof(double) + sizeof(int), &r.min_radius, sizeof(double));
  return key;
}

void MeshCache::makeRoom() {
  if (entries_.size() < capacity_) return;
  std::erase_if(entries_, [&](const auto& e) { return e.second.used + 2 < frame_; });
  if (entries_.size() >= capacity_) entries_.clear();
}

std::shared_ptr<const Mesh> MeshCache::get(std::span<const Vec3> points, double radius, int level, double min_radius) {
  const MeshRequest request{points, radius, level, min_radius};
  std::string k = key(request);
  auto it = entries_.find(k);
  if (it != entries_.end()) {
    it->second.used = frame_;
    ++reused_;
    return it->second.mesh;
  }
  makeRoom();
  auto mesh = std::make_shared<const Mesh>(buildSschMesh(points, radius, level, min_radius, meshing_));
  ++built_;
  entries_.emplace(std::move(k), Entry{mesh, frame_});
  return mesh;
}

std::vector<MeshCache::Found> MeshCache::getAll(std::span<const MeshRequest> requests) {
  std::vector<Found> out(requests.size());
  std::vector<std::string> keys(requests.size());
  std::vector<std::size_t> missing;  // requests to build, first of each key
  std::unordered_map<std::string_view, std::size_t> first;
  for (std::size_t i = 0; i < requests.size(); ++i) {
    keys[i] = key(requests[i]);
    const auto it = entries_.find(keys[i]);
    if (it != entries_.end()) {
      it->second.used = frame_;
      ++reused_;
      out[i].mesh = it->second.mesh;
    } else if (first.emplace(keys[i], i).second) {
      missing.push_back(i);
    }
  }
  cv::parallel_for_(cv::Range(0, static_cast<int>(missing.size())), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) {
      const MeshRequest& r = requests[missing[static_cast<std::size_t>(k)]];
      try {
        out[missing[static_cast<std::size_t>(k)]].mesh =
            std::make_shared<const Mesh>(buildSschMesh(r.points, r.radius, r.level, r.min_radius, meshing_));
      } catch (const std::exception&) {  // qhull on extreme coordinates: no mesh
      }
    }
  });
  for (const std::size_t i : missing) {
    if (!out[i].mesh) continue;
    out[i].built = true;
    ++built_;
    makeRoom();
    entries_.emplace(keys[i], Entry{out[i].mesh, frame_});
  }
  for (std::size_t i = 0; i < requests.size(); ++i)
    if (!out[i].mesh) {
      const auto it = first.find(keys[i]);
      if (it != first.end() && it->second != i) out[i].mesh = out[it->second].mesh;  // a repeated request
    }
  return out;
}

}  // namespace kccd::render

// The meshes of SSCHs kept across frames, keyed by exact volume shape.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "kccd/render/mesh.hpp"
#include "kccd/render/ssch_mesh.hpp"
#include "kccd/types.hpp"

namespace kccd::render {

/// One SSCH to mesh (see buildSschMesh).
struct MeshRequest {
  std::span<const Vec3> points;
  double radius = 0.0;
  int level = 0;
  double min_radius = kMinDrawRadius;
};

/// Meshes keyed by the exact volume shape (the bytes of the points, radius, level and minimum radius): a volume
/// that does not change (a static body, the same state) reuses its mesh; entries unused for a
/// while are dropped so a moving robot does not grow the cache.
class MeshCache {
 public:
  /// The number of entries beyond which unused ones are dropped, unless asked otherwise.
  static constexpr std::size_t kDefaultCapacity = 512;
  /// A cache of about `capacity` meshes, each built with `meshing`.
  explicit MeshCache(std::size_t capacity = kDefaultCapacity, SschMeshing meshing = SschMeshing::Direct)
      : capacity_(capacity), meshing_(meshing) {}
  /// The mesh of the SSCH, built on first use.
  std::shared_ptr<const Mesh> get(std::span<const Vec3> points, double radius, int level,
                                  double min_radius = kMinDrawRadius);
  /// A mesh from getAll: null when it could not be built (qhull failed on extreme coordinates).
  struct Found {
    std::shared_ptr<const Mesh> mesh;
    bool built = false;  ///< built by this call (not from the cache)
  };
  /// The meshes of several SSCHs in order; those not cached are built in parallel
  /// (cv::parallel_for_), equal requests once.
  std::vector<Found> getAll(std::span<const MeshRequest> requests);
  /// Marks the start of a frame (entries unused for a few frames may then be evicted).
  void nextFrame() { ++frame_; }
  /// The meshes held.
  std::size_t size() const { return entries_.size(); }
  /// Meshes built since construction.
  std::uint64_t built() const { return built_; }
  /// Requests answered from the cache since construction.
  std::uint64_t reused() const { return reused_; }
  /// How this cache builds its meshes.
  SschMeshing meshing() const { return meshing_; }

 private:
  struct Entry {
    std::shared_ptr<const Mesh> mesh;
    std::uint64_t used = 0;
  };
  static std::string key(const MeshRequest& r);
  void makeRoom();
  std::size_t capacity_;
  SschMeshing meshing_;
  std::uint64_t frame_ = 0, built_ = 0, reused_ = 0;
  std::unordered_map<std::string, Entry> entries_;
};

}  // namespace kccd::render

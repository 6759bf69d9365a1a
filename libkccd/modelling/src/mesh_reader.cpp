#include "mesh_reader.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <new>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <assimp/BaseImporter.h>
#include <assimp/config.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include "large_stack.hpp"
#include "part_messages.hpp"

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define KCCD_HAS_ASAN 1
#endif
#endif
#ifndef KCCD_HAS_ASAN
#define KCCD_HAS_ASAN 0
#endif

namespace kccd::modelling::detail {
namespace {

Eigen::Affine3d toEigen(const aiMatrix4x4& m) {
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) t.linear()(i, j) = m[i][j];
    t.translation()(i) = m[i][3];
  }
  return t;
}

// Assimp's message on one line, printable, the file's own path (already at the start of the
// message) left out.
std::string assimpMessage(const char* text, const std::string& path) {
  std::string s = text != nullptr ? text : "";
  const std::string replacement = "the file";
  // Each search resumes after the last replacement, so the text put in is never searched again.
  for (const std::string& own : {"\"" + path + "\"", path})
    for (std::size_t at = s.find(own); !own.empty() && at != std::string::npos;
         at = s.find(own, at + replacement.size()))
      s.replace(at, own.size(), replacement);
  for (char& c : s)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  if (s.size() > 200) s = s.substr(0, 200) + "...";
  return printable(s.empty() ? "unknown format or empty file" : s, 300);
}

bool hasTriangles(const aiScene& scene, const aiNode& node) {
  std::vector<const aiNode*> stack{&node};
  while (!stack.empty()) {
    const aiNode* n = stack.back();
    stack.pop_back();
    for (unsigned i = 0; i < n->mNumMeshes; ++i)
      if (n->mMeshes[i] < scene.mNumMeshes && scene.mMeshes[n->mMeshes[i]]->mNumFaces > 0) return true;
    for (unsigned i = 0; i < n->mNumChildren; ++i) stack.push_back(n->mChildren[i]);
  }
  return false;
}

std::string label(const aiNode& node, unsigned index) {
  const std::string name = node.mName.length > 0 ? printable(node.mName.C_Str()) : "";
  return name.empty() ? "node " + std::to_string(index) : "'" + name + "'";
}

// The triangles below `node` (placed by `to_file`, the transforms above it) into `part`.
void collect(const aiScene& scene, const aiNode& node, const Eigen::Affine3d& to_file, const Vec3& scale,
             const std::string& name, Part& part) {
  std::vector<std::pair<const aiNode*, Eigen::Affine3d>> stack{{&node, to_file}};
  while (!stack.empty()) {
    const auto [n, above] = stack.back();
    stack.pop_back();
    const Eigen::Affine3d t = above * toEigen(n->mTransformation);
    if (!t.matrix().allFinite()) throw PartError(name + ": node " + label(*n, 0) + ": non-finite transform");
    for (unsigned i = 0; i < n->mNumMeshes; ++i) {
      if (n->mMeshes[i] >= scene.mNumMeshes) throw PartError(name + ": a node names a mesh that does not exist");
      const aiMesh& mesh = *scene.mMeshes[n->mMeshes[i]];
      if (mesh.mNumFaces > 0 && (mesh.mFaces == nullptr || mesh.mVertices == nullptr))
        throw PartError(name + ": a mesh without vertices or faces");
      for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
        const aiFace& face = mesh.mFaces[f];
        if (face.mNumIndices < 3) continue;  // points and lines carry no volume
        if (face.mIndices == nullptr) throw PartError(name + ": a face without vertex indices");
        for (unsigned k = 0; k < face.mNumIndices; ++k)
          if (face.mIndices[k] >= mesh.mNumVertices) throw PartError(name + ": a face indexes past its vertices");
        auto point = [&](unsigned k) {
          const aiVector3D& v = mesh.mVertices[face.mIndices[k]];
          return Vec3((t * Vec3(v.x, v.y, v.z)).cwiseProduct(scale));
        };
        // Polygons as fans of triangles (the vertices, all a fit needs, are exactly the polygon's).
        for (unsigned k = 1; k + 1 < face.mNumIndices; ++k) {
          part.addTriangle(point(0), point(k), point(k + 1));
        }
      }
    }
    for (unsigned i = 0; i < n->mNumChildren; ++i) stack.emplace_back(n->mChildren[i], t);
  }
}

// A PLY header as the format defines it: `ply`, `format` ascii|binary_little_endian|
// binary_big_endian 1.0, `element NAME COUNT`, `property TYPE NAME` or `property list TYPE TYPE
// NAME` (after an element), `comment`/`obj_info` lines, `end_header`. Assimp's PLY reader loops
// forever on some malformed headers (seen by fuzz_part: `element 0`), so it only sees well-formed
// ones. Returns the problem, empty when the header is well formed.
std::string plyHeaderProblem(const std::string& data) {
  // The header: up to the first line `end_header`, which must end with a line break.
  std::size_t end = 0;
  for (std::size_t at = data.find("end_header"); at != std::string::npos; at = data.find("end_header", at + 1))
    if (at > 0 && data[at - 1] == '\n') {
      std::size_t after = at + 10;
      if (after < data.size() && data[after] == '\r') ++after;
      if (after >= data.size() || data[after] != '\n') return "PLY header: end_header must end its line";
      end = at + 10;
      break;
    }
  if (end == 0) return "PLY header: no end_header";
  std::istringstream in(data.substr(0, end));
  std::string line;
  int number = 0;
  bool element = false, format = false;
  static const std::set<std::string> types = {"char",  "uchar",  "short",   "ushort", "int",   "uint",
                                              "float", "double", "int8",    "uint8",  "int16", "uint16",
                                              "int32", "uint32", "float32", "float64"};
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string word; words >> word;) w.push_back(word);
    const std::string at = "PLY header line " + std::to_string(number) + ": ";
    if (number == 1) {
      if (w.size() != 1 || w[0] != "ply") return at + "expected 'ply'";
      continue;
    }
    if (w.empty()) return at + "empty line";
    if (w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") return format ? "" : at + "no format line before end_header";
    if (w[0] == "format") {
      if (w.size() != 3 || (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian"))
        return at + "expected 'format ascii|binary_little_endian|binary_big_endian VERSION'";
      format = true;
    } else if (w[0] == "element") {
      if (w.size() != 3 || w[2].find_first_not_of("0123456789") != std::string::npos || w[2].size() > 10)
        return at + "expected 'element NAME COUNT'";
      element = true;
    } else if (w[0] == "property") {
      if (!element) return at + "a property before any element";
      const bool list = w.size() == 5 && w[1] == "list" && types.count(w[2]) && types.count(w[3]);
      if (!list && !(w.size() == 3 && types.count(w[1])))
        return at + "expected 'property TYPE NAME' or 'property list TYPE TYPE NAME'";
    } else {
      return at + "unknown keyword '" + printable(w[0].substr(0, 40)) + "'";
    }
  }
  return "PLY header: no end_header";
}

}  // namespace

bool readsAsMesh(const std::string& extension) {
  if (extension == ".iv" || extension == ".wrl" || extension == ".vrml") return false;
  if (extension.size() < 2) return false;
  static const std::string known = [] {
    std::string list;
    Assimp::Importer().GetExtensionList(list);  // "*.3ds;*.obj;..."
    return list;
  }();
  return known.find("*" + extension + ";") != std::string::npos || known.ends_with("*" + extension);
}

namespace {

// The read itself (in the child process of readMesh).
Part readInProcess(const std::string& path, const std::string& name, const std::string& extension,
                   const ReadOptions& options) {
  Part part;
  // Assimp's parsers recurse per nesting level of the file (COLLADA and glTF nodes).
  onLargeStack([&] {
    Assimp::Importer importer;
    // Only the readers that claim the extension may read the file: Assimp would otherwise try
    // every format it knows on data that reader refuses (unregistered readers are ours to delete).
    std::vector<Assimp::BaseImporter*> others;
    for (std::size_t i = 0; i < importer.GetImporterCount(); ++i) {
      Assimp::BaseImporter* reader = importer.GetImporter(i);
      std::set<std::string> extensions;
      reader->GetExtensionList(extensions);
      if (extensions.count(extension.substr(1)) == 0) others.push_back(reader);
    }
    for (Assimp::BaseImporter* reader : others)
      if (importer.UnregisterLoader(reader) == aiReturn_SUCCESS) delete reader;
    // COLLADA: keep the file's axes (ROS tools place a mesh in the link frame as written);
    // Assimp still applies the <unit meter> scale to the root node.
    importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
    // No post-processing: Assimp's steps abort the process on some malformed files (seen by
    // fuzz_part in a PLY file); polygons, points and lines are handled by collect().
    const unsigned flags = 0;
    // From the file itself (its size and kind checked by the caller), so that files it names
    // (a .gltf's buffers, an OBJ's materials) are looked up beside it.
    const aiScene* scene = importer.ReadFile(path.c_str(), flags);
    if (scene == nullptr || scene->mRootNode == nullptr)
      throw PartError(name + ": not a readable " + printable(extension.substr(1)) + " mesh (" +
                      assimpMessage(importer.GetErrorString(), path) + ")");
    const aiNode& root = *scene->mRootNode;
    const Eigen::Affine3d identity = Eigen::Affine3d::Identity();
    if (!options.part.empty()) {
      const aiNode* node = root.FindNode(options.part.c_str());
      if (node == nullptr) throw PartError(name + ": no node named '" + printable(options.part) + "'");
      Eigen::Affine3d above = identity;  // the transforms of the node's ancestors
      std::vector<const aiNode*> chain;
      for (const aiNode* a = node->mParent; a != nullptr; a = a->mParent) chain.push_back(a);
      for (auto it = chain.rbegin(); it != chain.rend(); ++it) above = above * toEigen((*it)->mTransformation);
      collect(*scene, *node, above, options.scale, name, part);
      return;
    }
    // Top-level parts: the root's own meshes, and each child of the root with triangles below it.
    std::vector<std::string> parts;
    for (unsigned i = 0; i < root.mNumMeshes; ++i)
      if (root.mMeshes[i] < scene->mNumMeshes && scene->mMeshes[root.mMeshes[i]]->mNumFaces > 0) {
        parts.push_back(label(root, 0) + " (root)");
        break;
      }
    for (unsigned i = 0; i < root.mNumChildren; ++i)
      if (hasTriangles(*scene, *root.mChildren[i])) parts.push_back(label(*root.mChildren[i], i));
    if (parts.size() > 1 && !options.merge) {
      throw severalParts(name, parts);
    }
    collect(*scene, root, identity, options.scale, name, part);
  });
  return part;
}

// The child's answer on the pipe: a status byte ('P' part, 'E' error), then for a part the
// triangle count, the point count and the points (doubles), for an error its length and text.
bool writeAll(int fd, const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

[[noreturn]] void childRead(int fd, const std::string& path, const std::string& name, const std::string& extension,
                            const ReadOptions& options) {
#if !defined(__SANITIZE_ADDRESS__) && !KCCD_HAS_ASAN
  // Address space for the reader: what the process maps now plus the memory limit.
  long pages = 0;
  if (std::FILE* statm = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(statm, "%ld", &pages) != 1) pages = 0;
    std::fclose(statm);
  }
  const rlim_t limit = static_cast<rlim_t>(pages) * static_cast<rlim_t>(sysconf(_SC_PAGESIZE)) +
                       static_cast<rlim_t>(options.mesh_memory_limit_mb) * (1u << 20);
  const struct rlimit rl { limit, limit };
  setrlimit(RLIMIT_AS, &rl);
#endif
  bool ok = false;
  try {
    const Part part = readInProcess(path, name, extension, options);
    const std::uint64_t counts[2] = {static_cast<std::uint64_t>(part.triangles), part.points.size()};
    ok = writeAll(fd, "P", 1) && writeAll(fd, counts, sizeof counts) &&
         writeAll(fd, part.points.data(), part.points.size() * sizeof(Vec3));
  } catch (const std::bad_alloc&) {
    const std::string what =
        name + ": reading the mesh needs more than " + std::to_string(options.mesh_memory_limit_mb) + " MiB";
    const std::uint64_t n = what.size();
    ok = writeAll(fd, "E", 1) && writeAll(fd, &n, sizeof n) && writeAll(fd, what.data(), what.size());
  } catch (const std::exception& e) {
    const std::string what = e.what();
    const std::uint64_t n = what.size();
    ok = writeAll(fd, "E", 1) && writeAll(fd, &n, sizeof n) && writeAll(fd, what.data(), what.size());
  }
  ::_exit(ok ? 0 : 1);
}

}  // namespace

Part readMesh(const std::string& data, const std::string& path, const std::string& name, const std::string& extension,
              const ReadOptions& options) {
  if (data.empty()) throw PartError(name + ": empty file");
  if (extension == ".ply")
    if (const std::string problem = plyHeaderProblem(data); !problem.empty()) throw PartError(name + ": " + problem);
  // Assimp's readers are not hardened against malformed files (fuzzing found endless loops,
  // aborts and gigabyte allocations from kilobyte files): they run in a child process with a
  // time and a memory limit, and whatever happens there ends as a one-line error here.
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw PartError(name + ": cannot start the mesh reader (" + std::strerror(errno) + ")");
  const pid_t child = ::fork();
  if (child < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw PartError(name + ": cannot start the mesh reader (" + std::strerror(errno) + ")");
  }
  if (child == 0) {
    ::close(fds[0]);
    childRead(fds[1], path, name, extension, options);
  }
  ::close(fds[1]);
  std::string answer;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(options.mesh_time_limit_s);
  bool timed_out = false;
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timed_out = true;
      break;
    }
    struct pollfd pfd {
      fds[0], POLLIN, 0
    };
    const int ready = ::poll(&pfd, 1, static_cast<int>(std::min<long long>(left.count(), 1000)));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;
    char buffer[65536];
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    answer.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  if (timed_out) ::kill(child, SIGKILL);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out)
    throw PartError(name + ": reading the mesh took longer than " +
                    std::to_string(static_cast<int>(options.mesh_time_limit_s)) + " s (a malformed file?)");
  auto take = [&](std::size_t& at, void* out, std::size_t size) {
    if (answer.size() - at < size) return false;
    std::memcpy(out, answer.data() + at, size);
    at += size;
    return true;
  };
  std::size_t at = 1;
  if (!answer.empty() && answer[0] == 'E') {
    std::uint64_t n = 0;
    if (take(at, &n, sizeof n) && answer.size() - at == n) throw PartError(answer.substr(at));
  } else if (!answer.empty() && answer[0] == 'P') {
    std::uint64_t counts[2] = {0, 0};
    if (take(at, counts, sizeof counts) && counts[1] <= (answer.size() - at) / sizeof(Vec3) &&
        answer.size() - at == counts[1] * sizeof(Vec3)) {
      Part part;
      part.triangles = static_cast<int>(counts[0]);
      part.points.reserve(counts[1]);
      for (std::uint64_t k = 0; k < counts[1]; ++k) {
        double xyz[3];
        take(at, xyz, sizeof xyz);
        part.points.emplace_back(xyz[0], xyz[1], xyz[2]);
      }
      // The child writes each triangle's three points in turn (addTriangle).
      if (part.points.size() == 3 * counts[0])
        for (int k = 0; k + 2 < static_cast<int>(part.points.size()); k += 3) part.faces.push_back({k, k + 1, k + 2});
      return part;
    }
  }
  const std::string how = WIFSIGNALED(status) ? "stopped by signal " + std::to_string(WTERMSIG(status))
                                              : "ended with status " + std::to_string(WEXITSTATUS(status));
  throw PartError(name + ": the mesh reader " + how + " (out of memory, or a malformed file)");
}

}  // namespace kccd::modelling::detail

#include "mesh_reader.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include <assimp/BaseImporter.h>
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "large_stack.hpp"
#include "part_messages.hpp"

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
  for (const std::string& own : {"\"" + path + "\"", path})
    for (std::size_t at = s.find(own); !own.empty() && at != std::string::npos; at = s.find(own)) s.replace(at, own.size(), "the file");
  for (char& c : s)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  if (s.size() > 200) s = s.substr(0, 200) + "...";
  return printable(s.empty() ? "unknown format or empty file" : s);
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
      for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
        const aiFace& face = mesh.mFaces[f];
        if (face.mNumIndices != 3) continue;  // points and lines (removed by SortByPType) carry no volume
        for (unsigned k = 0; k < 3; ++k) {
          if (face.mIndices[k] >= mesh.mNumVertices) throw PartError(name + ": a face indexes past its vertices");
          const aiVector3D& v = mesh.mVertices[face.mIndices[k]];
          part.points.push_back((t * Vec3(v.x, v.y, v.z)).cwiseProduct(scale));
        }
        ++part.triangles;
      }
    }
    for (unsigned i = 0; i < n->mNumChildren; ++i) stack.emplace_back(n->mChildren[i], t);
  }
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

Part readMesh(const std::string& data, const std::string& path, const std::string& name, const std::string& extension,
              const ReadOptions& options) {
  if (data.empty()) throw PartError(name + ": empty file");
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
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    // COLLADA: keep the file's axes (ROS tools place a mesh in the link frame as written);
    // Assimp still applies the <unit meter> scale to the root node.
    importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
    const unsigned flags = aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_ValidateDataStructure;
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

}  // namespace kccd::modelling::detail

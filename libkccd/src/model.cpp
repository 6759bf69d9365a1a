#include "kccd/model.hpp"

#include <algorithm>

namespace kccd {

int Model::jointIndex(const std::string& joint) const {
  for (std::size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == joint) return static_cast<int>(i);
  return -1;
}

int Model::bodyIndex(const std::string& body) const {
  for (std::size_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].name == body) return static_cast<int>(i);
  return -1;
}

int Model::commonAncestor(int frame_a, int frame_b) const {
  // Parents precede children, so the larger index is never an ancestor of the smaller one.
  while (frame_a != frame_b) {
    if (frame_a > frame_b) {
      frame_a = joints[frame_a].parent;
    } else {
      frame_b = joints[frame_b].parent;
    }
  }
  return frame_a;
}

const std::string& Model::frameName(int frame) const {
  static const std::string world = "world";
  return frame == kWorld ? world : joints[frame].name;
}

void Model::finalize(bool check_all, const std::vector<std::array<int, 2>>& ignore,
                     const std::vector<std::array<int, 2>>& include) {
  state_size_ = 0;
  state_names_.clear();
  for (std::size_t i = 0; i < joints.size(); ++i) {
    Joint& j = joints[i];
    if (j.parent != kWorld && (j.parent < 0 || j.parent >= static_cast<int>(i)))
      throw ModelError("joint '" + j.name + "': parent must be a joint listed earlier");
    j.state_offset = state_size_;
    switch (j.type) {
      case JointType::Fixed:
        j.dof = 0;
        break;
      case JointType::Revolute:
      case JointType::Prismatic:
        j.dof = 1;
        state_names_.push_back(j.name);
        break;
      case JointType::Translation3d:
      case JointType::Rotation3d:
        j.dof = 3;
        for (const char* c : {".x", ".y", ".z"}) state_names_.push_back(j.name + c);
        break;
    }
    state_size_ += j.dof;
  }
  auto key = [](int a, int b) { return std::array<int, 2>{std::min(a, b), std::max(a, b)}; };
  // Sorted lists searched by halves: a model of thousands of bodies and pair lists stays quick.
  auto listed = [&](const std::vector<std::array<int, 2>>& list, int a, int b) {
    return std::binary_search(list.begin(), list.end(), key(a, b));
  };
  std::vector<std::array<int, 2>> ign, inc;
  for (const auto& p : ignore) ign.push_back(key(p[0], p[1]));
  for (const auto& p : include) {
    if (bodies[p[0]].frame == bodies[p[1]].frame)
      throw ModelError("pairs.include: '" + bodies[p[0]].name + "' and '" + bodies[p[1]].name +
                       "' are in the same frame and can never move relative to each other");
    inc.push_back(key(p[0], p[1]));
  }
  std::sort(ign.begin(), ign.end());
  std::sort(inc.begin(), inc.end());
  pairs.clear();
  const int n = static_cast<int>(bodies.size());
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      if (bodies[a].frame == bodies[b].frame) continue;
      const bool wanted = (check_all && !listed(ign, a, b)) || listed(inc, a, b);
      if (wanted) pairs.push_back({a, b, commonAncestor(bodies[a].frame, bodies[b].frame)});
    }
  }
}

const char* toString(JointType type) {
  switch (type) {
    case JointType::Fixed:
      return "fixed";
    case JointType::Revolute:
      return "revolute";
    case JointType::Prismatic:
      return "prismatic";
    case JointType::Translation3d:
      return "translation3d";
    case JointType::Rotation3d:
      return "rotation3d";
  }
  return "?";
}

const char* toString(SweepMode mode) {
  switch (mode) {
    case SweepMode::Exact:
      return "exact";
    case SweepMode::Accurate:
      return "accurate";
  }
  return "?";
}

const char* toString(IgnoreReason reason) {
  switch (reason) {
    case IgnoreReason::User:
      return "user";
    case IgnoreReason::Adjacent:
      return "adjacent";
    case IgnoreReason::Rigid:
      return "rigid";
    case IgnoreReason::Never:
      return "never";
    case IgnoreReason::AlwaysTouching:
      return "always_touching";
    case IgnoreReason::Srdf:
      return "srdf";
  }
  return "?";
}

bool parseIgnoreReason(const std::string& word, IgnoreReason& reason) {
  for (IgnoreReason r : {IgnoreReason::User, IgnoreReason::Adjacent, IgnoreReason::Rigid, IgnoreReason::Never,
                         IgnoreReason::AlwaysTouching, IgnoreReason::Srdf})
    if (word == toString(r)) {
      reason = r;
      return true;
    }
  return false;
}

}  // namespace kccd

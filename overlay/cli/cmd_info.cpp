// `kccd info MODEL`: joints, state values, bodies, points, checked pairs and visuals.
#include <algorithm>
#include <iomanip>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cli_args.hpp"
#include "cli_model.hpp"
#include "cli_output.hpp"
#include "commands.hpp"

namespace kccd::cli {
namespace {

const char* shapeName(Visual::Shape shape) {
  switch (shape) {
    case Visual::Shape::Mesh:
      return "mesh";
    case Visual::Shape::Box:
      return "box";
    case Visual::Shape::Cylinder:
      return "cylinder";
    case Visual::Shape::Sphere:
      return "sphere";
  }
  return "?";
}

// The links in model order, each with its bodies (pieces of a concave link share one link).
std::vector<std::pair<std::string, std::vector<std::string>>> linksOf(const Model& m) {
  std::vector<std::pair<std::string, std::vector<std::string>>> out;
  for (const Body& b : m.bodies) {
    auto it = std::find_if(out.begin(), out.end(), [&](const auto& l) { return l.first == b.linkName(); });
    if (it == out.end())
      out.push_back({b.linkName(), {b.name}});
    else
      it->second.push_back(b.name);
  }
  return out;
}

struct InfoArgs {
  std::string model;
  bool json = false;
};

Exit runInfo(const InfoArgs& args) {
  const Model m = loadOrExplain(args.model);
  int points = 0;
  for (const Body& b : m.bodies) points += static_cast<int>(b.points.size());
  if (args.json) {
    nlohmann::json j;
    j["name"] = m.name;
    j["safety_margin"] = m.safety_margin;
    j["point_budget"] = m.point_budget;
    j["state"] = m.stateNames();
    for (const Joint& jt : m.joints) {
      nlohmann::json o{
          {"name", jt.name}, {"type", toString(jt.type)}, {"parent", m.frameName(jt.parent)}, {"dof", jt.dof}};
      if (jt.type != JointType::Fixed) o["sweep"] = toString(jt.sweep);
      if (jt.limits) o["limits"] = {(*jt.limits)[0], (*jt.limits)[1]};
      if (jt.type == JointType::Translation3d || jt.type == JointType::Rotation3d) o["error"] = jt.error;
      j["joints"].push_back(o);
    }
    for (const Body& b : m.bodies) {
      nlohmann::json o{{"name", b.name},
                       {"frame", m.frameName(b.frame)},
                       {"points", b.points.size()},
                       {"radius", b.radius},
                       {"link", b.linkName()}};
      if (b.tolerance >= 0.0) o["tolerance"] = b.tolerance;
      j["bodies"].push_back(o);
    }
    j["links"] = nlohmann::json::array();
    for (const auto& [link, bodies] : linksOf(m)) j["links"].push_back({{"name", link}, {"bodies", bodies}});
    j["pairs"] = nlohmann::json::array();
    for (const BodyPair& p : m.pairs)
      j["pairs"].push_back({{"a", m.bodies[p.a].name}, {"b", m.bodies[p.b].name}, {"frame", m.frameName(p.lca)}});
    j["ignored"] = nlohmann::json::array();
    for (const IgnoredPair& p : m.ignored)
      j["ignored"].push_back({{"a", m.bodies[p.a].name}, {"b", m.bodies[p.b].name}, {"reason", toString(p.reason)}});
    j["visuals"] = nlohmann::json::array();
    for (const Visual& v : m.visuals) {
      nlohmann::json o{{"frame", m.frameName(v.frame)}, {"shape", shapeName(v.shape)}};
      if (v.shape == Visual::Shape::Mesh) o["mesh"] = v.mesh;
      j["visuals"].push_back(o);
    }
    j["totals"] = {{"joints", m.joints.size()},   {"dof", m.stateSize()},       {"bodies", m.bodies.size()},
                   {"links", linksOf(m).size()},  {"points", points},           {"pairs", m.pairs.size()},
                   {"ignored", m.ignored.size()}, {"visuals", m.visuals.size()}};
    std::cout << j.dump(2) << "\n";
    return Exit::Ok;
  }
  const std::size_t links = linksOf(m).size();
  std::cout << "model " << m.name << ": " << m.joints.size() << " joints, " << m.stateSize() << " state values, "
            << m.bodies.size() << " bodies"
            << (links != m.bodies.size() ? " (" + std::to_string(links) + " links, concave ones in pieces)"
                                         : std::string())
            << ", " << points << " points, " << m.pairs.size() << " checked pairs, " << m.ignored.size() << " ignored\n"
            << "safety margin " << m.safety_margin << " m, point budget " << m.point_budget << "\n\njoints:\n";
  for (const Joint& jt : m.joints) {
    std::cout << "  " << std::left << std::setw(20) << jt.name << std::setw(14) << toString(jt.type) << "parent "
              << std::setw(16) << m.frameName(jt.parent);
    if (jt.type != JointType::Fixed) std::cout << " sweep " << toString(jt.sweep);
    if (jt.limits) std::cout << "  limits [" << (*jt.limits)[0] << ", " << (*jt.limits)[1] << "]";
    std::cout << "\n";
  }
  std::cout << "\nstate values (order of --lower/--upper/--state):\n";
  for (std::size_t i = 0; i < m.stateNames().size(); ++i) std::cout << "  " << i << ": " << m.stateNames()[i] << "\n";
  std::cout << "\nbodies:\n";
  for (const Body& b : m.bodies) {
    std::cout << "  " << std::left << std::setw(20) << b.name << "frame " << std::setw(16) << m.frameName(b.frame)
              << b.points.size() << " points, radius " << b.radius;
    if (b.tolerance >= 0.0) std::cout << ", at most " << b.tolerance * 1e3 << " mm outside its hull";
    if (!b.link.empty()) std::cout << "  (a piece of link " << b.link << ")";
    std::cout << "\n";
  }
  std::cout << "\nchecked pairs (compared in their common-ancestor frame):\n";
  for (const BodyPair& p : m.pairs)
    std::cout << "  " << m.bodies[p.a].name << " - " << m.bodies[p.b].name << "  [" << m.frameName(p.lca) << "]\n";
  if (!m.ignored.empty()) {
    std::cout << "\nignored pairs (pairs: ignore) and why:\n";
    for (const IgnoredPair& p : m.ignored)
      std::cout << "  " << std::left << std::setw(42) << (m.bodies[p.a].name + " - " + m.bodies[p.b].name)
                << toString(p.reason) << "\n";
  }
  if (!m.visuals.empty()) {
    std::cout << "\nvisuals (drawing only, never checked):\n";
    for (const Visual& v : m.visuals)
      std::cout << "  frame " << std::left << std::setw(16) << m.frameName(v.frame) << shapeName(v.shape)
                << (v.shape == Visual::Shape::Mesh ? " " + v.mesh : std::string()) << "\n";
  }
  return Exit::Ok;
}

}  // namespace

Runner addInfo(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* sub = app.add_subcommand("info", "Show a model's joints, state values, bodies and checked pairs");
  sub->add_option("model", args->model, "Model file (YAML, kccd: 1)")->required();
  sub->add_flag("--json", args->json, "Machine-readable output");
  return [args] { return runInfo(*args); };
}

}  // namespace kccd::cli

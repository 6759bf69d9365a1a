// The real robots the benchmarks import: where their URDFs are and their models at an import
// setting, each imported once per program. The KR5 and WAM come from Debian's dart-doc; the
// Panda and xArm 7 from the folder $KCCD_REAL_ROBOTS (panda/panda.urdf,
// xarm7_realsense/description/xarm7.urdf); a robot that is not there is skipped by its benchmark.
// KCCD_BENCH_TOLERANCE_MM and KCCD_BENCH_CONCAVITY_MM set the default import's tolerance and
// concavity, and KCCD_BENCH_BUDGET every model's point budget, to measure other choices.
#pragma once

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "kccd/model.hpp"
#include "kccd/modelling/urdf_import.hpp"
#include "kccd/query.hpp"

namespace kccd::bench {

struct Robot {
  std::string urdf;
  std::map<std::string, std::string> packages;  ///< package:// NAME -> directory
  bool found() const { return std::filesystem::exists(urdf); }
};

inline Robot robotNamed(const std::string& name) {
  const std::string dart = "/usr/share/doc/dart/data/urdf/";
  const char* real = std::getenv("KCCD_REAL_ROBOTS");
  const std::string r = real ? real : "";
  if (name == "kr5") return {dart + "KR5/KR5 sixx R650.urdf", {}};
  if (name == "wam") return {dart + "wam/wam.urdf", {{"herb_description", dart + "wam"}}};
  if (name == "panda") return {r + "/panda/panda.urdf", {{"Panda", r + "/panda"}}};
  return {r + "/xarm7_realsense/description/xarm7.urdf", {{"xarm_description", r + "/xarm7_realsense/description"}}};
}

/// kccd import's defaults; K = 8 points per link in one piece (the expert knob); the links' hulls.
enum ImportMode { kDefault = 0, kEight = 1, kHulls = 2 };

inline const Model& importedModel(const std::string& robot, int mode) {
  namespace km = kccd::modelling;
  static std::map<std::pair<std::string, int>, std::unique_ptr<Model>> cache;
  auto& slot = cache[{robot, mode}];
  if (!slot) {
    const Robot r = robotNamed(robot);
    km::ImportOptions o;
    o.visuals = false;
    o.packages = r.packages;
    if (const char* t = std::getenv("KCCD_BENCH_TOLERANCE_MM")) o.fit.tolerance = std::atof(t) * 1e-3;
    if (const char* c = std::getenv("KCCD_BENCH_CONCAVITY_MM")) o.fit.concavity = std::atof(c) * 1e-3;
    if (mode == kEight) o.fit.method = km::FitMethod::Points, o.fit.max_pieces = 1;
    if (mode == kHulls) o.fit.method = km::FitMethod::Hull, o.fit.max_pieces = 1;
    const std::string text = km::importUrdf(r.urdf, o);
    slot = std::make_unique<Model>(parseModel(text, r.urdf));
    if (const char* budget = std::getenv("KCCD_BENCH_BUDGET")) slot->point_budget = std::atoi(budget);
    // The ignore rules of the import (rigid, adjacent) stay; every other pair is checked.
  }
  return *slot;
}

/// Per link pair (by name, in order) the smallest distance of `r` over its body pairs.
inline std::map<std::pair<std::string, std::string>, double> linkDistances(const Model& m, const QueryResult& r) {
  std::map<std::pair<std::string, std::string>, double> out;
  for (const PairDistance& d : r.pairs) {
    std::string a = m.bodies[m.pairs[d.pair].a].linkName(), b = m.bodies[m.pairs[d.pair].b].linkName();
    if (b < a) std::swap(a, b);
    auto [it, fresh] = out.try_emplace({a, b}, d.distance);
    if (!fresh) it->second = std::min(it->second, d.distance);
  }
  return out;
}

}  // namespace kccd::bench

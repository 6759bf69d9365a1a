#include "kccd/modelling/fit_request.hpp"

#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>

#include "kccd/modelling/convex_pieces.hpp"
#include "kccd/modelling/yaml_edit.hpp"

namespace kccd::modelling {

void checkFitRequest(const FitRequest& r) {
  const auto inRange = [](double v, double lo, double hi) { return v >= lo && v <= hi; };
  if (r.method != FitMethod::Hull && (r.points < 1 || r.points > kMaxCorePoints))
    throw FitRequestError("points", "the number of core points K must be 1 ... " + std::to_string(kMaxCorePoints) +
                                        " (got " + std::to_string(r.points) + ")");
  if (r.method == FitMethod::Tolerance && !inRange(r.tolerance, 1e-9, 1e3))
    throw FitRequestError("tolerance", "must be a length of 1e-6 ... 1e6 mm");
  if (r.max_pieces < 1 || r.max_pieces > 64)
    throw FitRequestError("pieces", "must be 1 ... 64 pieces (got " + std::to_string(r.max_pieces) + ")");
  if (r.max_pieces > 1 && !inRange(r.concavity, 1e-6, 1e3))
    throw FitRequestError("concavity", "must be a length of 1e-3 ... 1e6 mm");
  if (r.method != FitMethod::Hull && r.max_evaluations < 1)
    throw FitRequestError("max_evaluations", "must be 1 or more");
}

FittedPart fitPart(const Part& part, const FitRequest& request, const std::function<void(double)>& progress) {
  checkFitRequest(request);
  PieceSplit split;
  if (request.max_pieces > 1) {
    split = splitConcave(part, {.max_pieces = request.max_pieces, .concavity = request.concavity});
  } else {
    split.pieces.push_back(part);
    split.concavity.push_back(0.0);
  }
  FittedPart out;
  out.whole_concavity = split.whole_concavity;
  out.measured = split.measured;
  const int count = static_cast<int>(split.pieces.size());
  for (int k = 0; k < count; ++k) {
    FitOptions options{.points = request.points, .max_evaluations = request.max_evaluations, .seed = request.seed};
    if (progress) options.progress = [&](double f) { progress((k + f) / count); };
    const Part& piece = split.pieces[static_cast<std::size_t>(k)];
    FittedPiece p;
    switch (request.method) {
      case FitMethod::Hull:
        p.fit = exactHull(piece);
        break;
      case FitMethod::Tolerance:
        p.fit = fitToTolerance(piece, request.tolerance, options);
        break;
      case FitMethod::Points:
        p.fit = fit(piece, options);
        break;
    }
    p.concavity = split.concavity[static_cast<std::size_t>(k)];
    out.pieces.push_back(std::move(p));
  }
  return out;
}

std::string pieceName(const std::string& name, int k, int count) {
  return count > 1 ? name + "/" + std::to_string(k + 1) : name;
}

std::string toleranceYaml(const FitResult& fit) { return yamlNumber(std::ceil(fit.outside * 1e6) / 1e6); }

namespace {

nlohmann::json bodyJson(const FitResult& r, bool baselines) {
  nlohmann::json j;
  const double hull = r.hull_volume;
  const auto ratio = [&](double v) { return hull > 0 ? nlohmann::json(v / hull) : nlohmann::json(nullptr); };
  j["points"] = nlohmann::json::array();
  for (const Vec3& v : r.points) j["points"].push_back({v.x(), v.y(), v.z()});
  const std::string radius = yamlNumber(r.radius, true);
  j["radius"] = std::stod(radius);
  j["volume"] = r.volume;
  j["hull_volume"] = hull;
  j["volume_ratio"] = ratio(r.volume);
  if (baselines)
    j["baselines"] = {{"sphere_volume", r.sphere_volume},
                      {"sphere_ratio", ratio(r.sphere_volume)},
                      {"capsule_volume", r.capsule_volume},
                      {"capsule_ratio", ratio(r.capsule_volume)}};
  j["k"] = static_cast<int>(r.points.size());
  j["hull_vertices"] = r.hull_vertices;
  j["evaluations"] = r.evaluations;
  j["outside"] = r.outside;
  j["tolerance"] = std::stod(toleranceYaml(r));
  j["method"] = r.method;
  j["yaml"] = "{points: " + flowPoints(r.points) + ", radius: " + radius + "}";
  return j;
}

}  // namespace

std::string fitJson(const Part& part, const FitRequest& request, const FittedPart& fitted, const std::string& name) {
  const bool baselines = request.method != FitMethod::Hull;
  const int count = static_cast<int>(fitted.pieces.size());
  nlohmann::json j = count == 1 ? bodyJson(fitted.pieces.front().fit, baselines) : nlohmann::json::object();
  if (count > 1) {
    j["pieces"] = nlohmann::json::array();
    for (int k = 0; k < count; ++k) {
      nlohmann::json p = bodyJson(fitted.pieces[static_cast<std::size_t>(k)].fit, baselines);
      p["name"] = pieceName(name, k, count);
      p["concavity"] = fitted.pieces[static_cast<std::size_t>(k)].concavity;
      j["pieces"].push_back(std::move(p));
    }
  }
  if (fitted.measured) j["concavity"] = fitted.whole_concavity;
  j["exact_hull"] = request.method == FitMethod::Hull;
  j["triangles"] = part.triangles;
  j["primitives"] = part.primitives;
  return j.dump();
}

std::string bodyYaml(const BodyEntry& b, const std::string& indent) {
  const auto comment = [](const std::string& c) { return c.empty() ? std::string() : "   # " + c; };
  std::string out = indent + "- name: " + b.name + "\n";
  if (!b.link.empty()) out += indent + "  link: " + b.link + comment(b.link_comment) + "\n";
  out += indent + "  frame: " + b.frame + "\n";
  out += indent + "  points: " + flowPoints(b.fit->points) + "\n";
  out += indent + "  radius: " + yamlNumber(b.fit->radius, true) + comment(b.radius_comment) + "\n";
  out += indent + "  tolerance: " + toleranceYaml(*b.fit) + comment(b.tolerance_comment) + "\n";
  return out;
}

}  // namespace kccd::modelling

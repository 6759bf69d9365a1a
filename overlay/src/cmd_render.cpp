// `kccd render MODEL --camera CAM.yaml --state .. -o out.png`: off-screen image of the volumes
// the library checks, as the calibrated camera sees them.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include <unistd.h>

#include <opencv2/imgcodecs.hpp>

#include "cli_util.hpp"
#include "commands.hpp"
#include "kccd/checker.hpp"
#include "kccd/render/renderer.hpp"
#include "kccd/render/scene.hpp"

namespace kccd::cli {
namespace {

struct RenderArgs {
  std::string model, camera, output;
  std::string lower, upper, state;
  bool mask = false, labels = false, no_legend = false, json = false;
  double supersample = 1.0;
};

std::vector<double> stateVector(const Model& m, const std::string& text, const std::string& option) {
  std::vector<double> v = parseList(text, option);
  if (static_cast<int>(v.size()) != m.stateSize()) {
    std::string names;
    for (const std::string& n : m.stateNames()) names += (names.empty() ? "" : ", ") + n;
    throw UsageError(option + " has " + std::to_string(v.size()) + " values but model '" + m.name + "' has " +
                     std::to_string(m.stateSize()) + " state values (" + names + ")");
  }
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      throw UsageError(option + ": value " + std::to_string(i + 1) + " (" + m.stateNames()[i] + ") is not finite");
  return v;
}

// Writes the PNG under a temporary name in the same directory and renames it into place, so
// a failed run never leaves a partial file.
void writePng(const cv::Mat& image, const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  if (!fs::is_directory(dir)) throw UsageError("-o " + path + ": directory " + dir.string() + " does not exist");
  const fs::path temp = dir / ("." + target.filename().string() + ".tmp" + std::to_string(getpid()) + ".png");
  bool ok = false;
  try {
    ok = cv::imwrite(temp.string(), image);
  } catch (const cv::Exception&) {
    ok = false;
  }
  std::error_code ec;
  if (ok) fs::rename(temp, target, ec);
  if (!ok || ec) {
    fs::remove(temp, ec);
    throw UsageError("-o " + path + ": cannot write the image");
  }
}

int runRender(const RenderArgs& args) {
  const auto t0 = std::chrono::steady_clock::now();
  const Model m = loadOrExplain(args.model);
  render::Camera camera;
  try {
    camera = render::loadCamera(args.camera);
  } catch (const render::CameraError& e) {
    throw UsageError(e.what());
  }
  {
    std::string ext = std::filesystem::path(args.output).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".png") throw UsageError("-o " + args.output + ": the output must be a .png file");
    const std::filesystem::path dir = std::filesystem::path(args.output).parent_path();
    if (!dir.empty() && !std::filesystem::is_directory(dir))
      throw UsageError("-o " + args.output + ": directory " + dir.string() + " does not exist");
  }
  std::vector<double> lower, upper;
  if (!args.state.empty()) {
    if (!args.lower.empty() || !args.upper.empty()) throw UsageError("give either --state or --lower/--upper, not both");
    lower = upper = stateVector(m, args.state, "--state");
  } else {
    if (args.lower.empty() || args.upper.empty())
      throw UsageError("give the configuration with --state (static volumes) or --lower and --upper (swept volumes)");
    lower = stateVector(m, args.lower, "--lower");
    upper = stateVector(m, args.upper, "--upper");
  }
  if (m.bodies.size() > 255) throw UsageError(args.model + ": more than 255 bodies do not fit an 8-bit mask");

  Checker checker(m);
  const QueryResult& r = checker.query(lower, upper, QueryOptions{.type = QueryType::Distances});
  const Status status = r.status;
  const double margin = r.margin;
  std::vector<double> nearest(m.bodies.size(), std::numeric_limits<double>::infinity());
  for (const PairDistance& pd : r.pairs) {
    nearest[m.pairs[pd.pair].a] = std::min(nearest[m.pairs[pd.pair].a], pd.distance);
    nearest[m.pairs[pd.pair].b] = std::min(nearest[m.pairs[pd.pair].b], pd.distance);
  }
  const std::vector<render::VolumeStatus> body_status = render::bodyStatus(m, r);
  std::vector<render::Volume> volumes = args.state.empty()
                                           ? render::sceneVolumes(m, checker, body_status)
                                           : render::staticSceneVolumes(m, checker, lower, body_status);
  for (render::Volume& v : volumes)
    if (!allFinite(v.points) || !std::isfinite(v.radius)) v.points = {};  // unsafe status: nothing to draw

  render::RenderOptions options;
  options.supersample = args.supersample;
  std::unique_ptr<render::Renderer> renderer;
  try {
    renderer = std::make_unique<render::Renderer>(camera, options);
  } catch (const render::CameraError& e) {
    throw UsageError(args.camera + ": " + e.what());
  }
  render::Style style;
  style.labels = args.labels;
  style.legend = !args.no_legend;
  const auto t1 = std::chrono::steady_clock::now();
  const render::Frame frame = renderer->render(volumes, style, !args.mask, true);
  const auto t2 = std::chrono::steady_clock::now();
  writePng(args.mask ? frame.mask : frame.bgra, args.output);

  const double total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const double frame_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();
  const bool swept = lower != upper;
  if (args.json) {
    nlohmann::json j;
    j["output"] = args.output;
    j["kind"] = args.mask ? "mask" : "rgba";
    j["volumes"] = swept ? "swept" : "static";
    j["renderer"] = renderer->rendererString();
    j["width"] = camera.width;
    j["height"] = camera.height;
    j["distortion"] = camera.distorted();
    j["status"] = toString(status);
    j["margin"] = margin;
    j["bodies"] = nlohmann::json::array();
    for (std::size_t i = 0; i < m.bodies.size(); ++i)
      j["bodies"].push_back({{"name", m.bodies[i].name}, {"label", i + 1}, {"status", render::toString(body_status[i])},
                             {"min_distance", number(nearest[i])}, {"pixels", frame.pixels[i]}});
    j["stats"] = {{"frame_ms", frame_ms}, {"total_ms", total_ms}, {"triangles", frame.triangles},
                  {"meshes_built", frame.meshes_built}};
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << "wrote " << args.output << " (" << (args.mask ? "label mask" : "RGBA") << ", " << camera.width << "x"
              << camera.height << ", " << (swept ? "swept" : "static") << " volumes) in " << frame_ms << " ms\n"
              << "renderer " << renderer->rendererString() << "\n";
    for (std::size_t i = 0; i < m.bodies.size(); ++i)
      std::cout << "  " << i + 1 << " " << m.bodies[i].name << ": " << render::toString(body_status[i]) << ", "
                << frame.pixels[i] << " px\n";
  }
  if (status != Status::Ok) {
    std::cerr << "kccd: query status " << toString(status) << " (unsafe)\n";
    return 3;
  }
  return 0;
}

}  // namespace

Runner addRender(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* sub = app.add_subcommand(
      "render", "Off-screen image of the collision volumes as the camera sees them (static at --state, swept over "
                "--lower/--upper)");
  sub->add_option("model", args->model, "Model file (YAML, kccd: 1)")->required();
  sub->add_option("--camera", args->camera, "Camera file (OpenCV YAML: intrinsics, distortion, rvec/tvec)")->required();
  sub->add_option("-o,--output", args->output, "Output PNG (RGBA, straight alpha; with --mask an 8-bit label image)")
      ->required();
  sub->add_option("--state", args->state, "A configuration, comma-separated in state order (static volumes)");
  sub->add_option("--lower", args->lower, "Lower interval ends (swept volumes over the box)");
  sub->add_option("--upper", args->upper, "Upper interval ends");
  sub->add_flag("--mask", args->mask, "Write the label mask: 0 background, i + 1 for the nearest body i");
  sub->add_flag("--labels", args->labels, "Draw body names");
  sub->add_flag("--no-legend", args->no_legend, "No colour legend");
  sub->add_option("--supersample", args->supersample, "Render the pinhole image this many times larger (1..4)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 4.0));
  sub->add_flag("--json", args->json, "Machine-readable summary");
  sub->footer("Colours: green clear, amber within the safety margin, red colliding.\n"
              "Exit status: 0 written, 2 bad input, 3 unsafe query status (image still written).");
  return [args] { return runRender(*args); };
}

}  // namespace kccd::cli

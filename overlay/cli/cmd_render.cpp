// `kccd render MODEL --camera CAM.yaml --state .. -o out.png`: off-screen image of the volumes
// the library checks, as the calibrated camera sees them.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_model.hpp"
#include "cli_output.hpp"
#include "commands.hpp"
#include "kccd/render/model_view.hpp"

namespace kccd::cli {
namespace {

struct RenderArgs {
  std::string model, camera, output;
  std::string lower, upper, state;
  bool mask = false, labels = false, no_legend = false, json = false;
  double supersample = 1.0;
};

Exit runRender(const RenderArgs& args) {
  const auto t0 = std::chrono::steady_clock::now();
  const Model m = loadOrExplain(args.model);
  const calib::Camera camera = calib::loadCamera(args.camera);
  checkOutputPath(args.output, "-o", ".png");
  const StateBox box = parseStateBox(
      m, args.state, args.lower, args.upper,
      "give the configuration with --state (static volumes) or --lower and --upper (swept volumes)", true);
  const std::vector<double>& lower = box.lower;
  const std::vector<double>& upper = box.upper;
  if (m.bodies.size() > 255) throw UsageError(args.model + ": more than 255 bodies do not fit an 8-bit mask");

  render::RenderOptions options;
  options.supersample = options.mask_supersample = args.supersample;
  std::unique_ptr<render::ModelView> view;
  try {
    view = std::make_unique<render::ModelView>(m, camera, options);
  } catch (const calib::CameraError& e) {  // the projection calls the camera "camera": name its file
    throw UsageError(e.messageFrom(args.camera));
  }
  render::ModelViewRequest request;
  if (box.point) {
    request.state = lower;  // static volumes at the configuration
  } else {
    request.lower = lower;  // swept volumes over the box
    request.upper = upper;
  }
  request.colour = !args.mask;
  request.mask = true;  // also for the pixels per body
  request.style.labels = args.labels;
  request.style.legend = !args.no_legend;
  const auto t1 = std::chrono::steady_clock::now();
  const render::ModelFrame drawn = view->draw(request);  // the query and the images
  const auto t2 = std::chrono::steady_clock::now();
  const render::Frame& frame = drawn.images;
  const Status status = drawn.query->status;
  const double margin = drawn.query->margin;
  const std::vector<double>& nearest = drawn.distances;
  const std::vector<SafetyStatus>& body_status = drawn.status;
  writePngAtomically(args.output, args.mask ? frame.mask : frame.bgra, "-o");

  const double total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const double frame_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();
  const bool swept = lower != upper;
  // Volumes that are not drawn as meshes are always reported (JSON and text).
  bool not_finite = false;
  for (std::size_t i = 0; i < m.bodies.size(); ++i) not_finite |= frame.visibility[i] == render::Visibility::NotFinite;
  auto drawnNote = [&](std::size_t i) -> std::string {
    switch (frame.visibility[i]) {
      case render::Visibility::Drawn:
        return "";
      case render::Visibility::FillsView:
        return " (contains the camera: fills the view)";
      default:
        return std::string(" (not drawn: ") + render::toString(frame.visibility[i]) + ")";
    }
  };
  if (args.json) {
    nlohmann::json j;
    j["output"] = args.output;
    j["kind"] = args.mask ? "mask" : "rgba";
    j["volumes"] = swept ? "swept" : "static";
    j["renderer"] = view->renderer().rendererString();
    j["width"] = camera.width;
    j["height"] = camera.height;
    j["distortion"] = camera.distorted();
    j["status"] = toString(status);
    j["margin"] = margin;
    j["bodies"] = nlohmann::json::array();
    j["not_drawn"] = nlohmann::json::array();
    j["fills_view"] = nlohmann::json::array();
    for (std::size_t i = 0; i < m.bodies.size(); ++i) {
      const render::Visibility v = frame.visibility[i];
      if (v == render::Visibility::FillsView)
        j["fills_view"].push_back(m.bodies[i].name);
      else if (v != render::Visibility::Drawn)
        j["not_drawn"].push_back({{"body", m.bodies[i].name}, {"reason", render::toString(v)}});
    }
    for (std::size_t i = 0; i < m.bodies.size(); ++i)
      j["bodies"].push_back({{"name", m.bodies[i].name},
                             {"label", i + 1},
                             {"status", toString(body_status[i])},
                             {"min_distance", number(nearest[i])},
                             {"pixels", frame.pixels[i]}});
    // How far from its centre a mask pixel's label may come from (null: no bound).
    j["mask_edge_px"] = number(frame.mask_edge_px);
    j["stats"] = {{"frame_ms", frame_ms},
                  {"total_ms", total_ms},
                  {"triangles", frame.triangles},
                  {"meshes_built", frame.meshes_built}};
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << "wrote " << args.output << " (" << (args.mask ? "label mask" : "RGBA") << ", " << camera.width << "x"
              << camera.height << ", " << (swept ? "swept" : "static") << " volumes) in " << frame_ms << " ms\n"
              << "renderer " << view->renderer().rendererString() << "\n";
    for (std::size_t i = 0; i < m.bodies.size(); ++i)
      std::cout << "  " << i + 1 << " " << m.bodies[i].name << ": " << toString(body_status[i]) << ", "
                << frame.pixels[i] << " px" << drawnNote(i) << "\n";
  }
  if (status != Status::Ok) {
    std::cerr << "kccd: query status " << toString(status) << " (unsafe)\n";
    return Exit::Unsafe;
  }
  if (not_finite) {
    for (std::size_t i = 0; i < m.bodies.size(); ++i)
      if (frame.visibility[i] == render::Visibility::NotFinite) {
        std::cerr << "kccd: body " << m.bodies[i].name << ": volume not finite (overflow): not drawn (unsafe)\n";
        break;
      }
    return Exit::Unsafe;
  }
  return Exit::Ok;
}

}  // namespace

Runner addRender(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* sub = app.add_subcommand(
      "render",
      "Off-screen image of the collision volumes as the camera sees them (static at --state, swept over "
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
  sub->add_option("--supersample", args->supersample,
                  "Render the pinhole image (and the mask) this many times finer (1..4): thinner slivers survive the "
                  "lens warp, and mask edges lie closer to the exact labels (--json: mask_edge_px)")
      ->capture_default_str()
      ->check(finiteIn(1.0, 4.0));
  sub->add_flag("--json", args->json, "Machine-readable summary");
  sub->footer(
      "Colours: green clear, amber within the safety margin, red colliding.\n"
      "Volumes containing the camera fill the view; volumes behind the camera, farther than 1e6 m\n"
      "or not finite are not drawn and are listed (text: 'not drawn: reason'; JSON: not_drawn).\n"
      "GL: KCCD_GL=egl (EGL surfaceless, the default) or KCCD_GL=osmesa; KCCD_EGL_DEVICE=N uses EGL device N\n"
      "(e.g. a GPU); the renderer string (--json: renderer) names the one in use.\n"
      "Exit status: 0 written, 2 bad input, 3 unsafe query status or a non-finite volume (image still written).");
  return [args] { return runRender(*args); };
}

}  // namespace kccd::cli

// `kccd calib sheet`: a labelling aid. The frame's candidates (kccd::overlay::labellingCandidates:
// detected tags, strong corners, the model's points projected) drawn into a PNG, and a labels file
// to fill in from them.
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "commands.hpp"
#include "kccd/calib/image_file.hpp"
#include "kccd/overlay/calibration/calib_drawing.hpp"
#include "kccd/overlay/labelling/labelling_candidates.hpp"

namespace kccd::cli {
namespace {

struct SheetArgs {
  std::string image, tags, model, camera, state, output, labels_template;
  int candidates = 40;
};

Exit runSheet(const SheetArgs& a) {
  checkOutputPath(a.output, "-o", ".png");
  if (!a.labels_template.empty()) {
    const std::string ext = std::filesystem::path(a.labels_template).extension().string();
    if (ext != ".yaml" && ext != ".yml")
      throw UsageError("--template " + a.labels_template + ": must be a .yaml or .yml file");
    checkOutputPath(a.labels_template, "--template", ext);
  }
  if (!a.model.empty() && a.camera.empty())
    throw UsageError("--model: needs --camera (a camera file with a rough pose) to project the model's points");
  if (a.model.empty() && !a.state.empty()) throw UsageError("--state: needs --model");
  const cv::Mat bgr = calib::readImageFile(a.image, calib::ImageColour::Bgr);
  overlay::CandidateInputs in;
  in.image = a.image;
  in.corners = a.candidates;
  in.camera_name = a.camera;
  if (!a.camera.empty()) in.camera = calib::loadCamera(a.camera);
  if (!a.tags.empty()) in.tags = calib::loadTagLayout(a.tags);
  std::optional<Model> model;
  if (!a.model.empty()) {
    model = loadOrExplain(a.model);
    in.model = &*model;
    if (model->stateSize() > 0) {
      if (a.state.empty()) throw UsageError("--model: give the robot's state in the image with --state");
      in.state = parseStateBox(*model, a.state, "", "", "", true).lower;
    }
  }
  const overlay::LabellingCandidates c = overlay::labellingCandidates(bgr, in);

  const cv::Mat sheet = overlay::drawSheet(bgr, c);
  if (!a.labels_template.empty()) writeFileAtomically(a.labels_template, overlay::labelsTemplate(c, a.image, a.output));
  writePngAtomically(a.output, sheet, "-o");
  std::cout << "sheet " << a.output << ": " << c.tags.size() << " tag" << (c.tags.size() == 1 ? "" : "s")
            << " detected";
  int unknown = 0;
  for (const overlay::TagCandidate& t : c.tags) unknown += t.placed ? 0 : 1;
  if (c.layout && unknown > 0) std::cout << " (" << unknown << " not in the layout)";
  std::cout << ", " << c.corners.size() << " candidate points"
            << (model ? ", " + std::to_string(c.model_points.size()) + " model points" : "")
            << (a.labels_template.empty() ? "" : "; template " + a.labels_template) << "\n";
  return Exit::Ok;
}

}  // namespace

Runner addCalibSheet(CLI::App& calib) {
  CLI::App* sheet = calib.add_subcommand(
      "sheet",
      "A labelling aid: the frame with detected tags (ids, corner order 0..3), numbered candidate points and, with "
      "--model\n"
      "and a camera with a rough pose, the model's core points projected; --template writes a labels file to fill in.");
  auto s = std::make_shared<SheetArgs>();
  sheet->add_option("--image", s->image, "The frame")->required();
  sheet->add_option("--tags", s->tags, "Tag layout: tags it places are drawn green, others orange");
  sheet->add_option("--model", s->model, "Model whose core points are projected (needs --camera and --state)");
  sheet->add_option("--camera", s->camera, "Camera file with a rough pose (e.g. from an earlier solve)");
  sheet->add_option("--state", s->state, "The robot's state in the frame (comma-separated)");
  sheet->add_option("--candidates", s->candidates, "Most candidate points to number")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  sheet->add_option("-o,--output", s->output, "Sheet image (.png)")->required();
  sheet->add_option("--template", s->labels_template, "Labels file (.yaml) to fill in: every candidate, commented out");
  return [s] { return runSheet(*s); };
}

}  // namespace kccd::cli

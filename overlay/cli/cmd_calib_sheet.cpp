// `kccd calib sheet`: a labelling aid. The frame's candidates (kccd::overlay::labellingCandidates:
// detected tags, strong corners, the model's points projected) drawn into a PNG, and a labels file
// to fill in from them. The frame is an image file or a recording's frame (read as `kccd calib
// --video --frame` reads it: overlay::readRecordingFrames).
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_model.hpp"
#include "commands.hpp"
#include "kccd/calib/image_file.hpp"
#include "kccd/overlay/calibration/calib_drawing.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/labelling/labelling_candidates.hpp"

namespace kccd::cli {
namespace {

struct SheetArgs {
  std::string image, video, tags, model, camera, state, output, labels_template;
  int frame = -1;  // with --video
  int candidates = 40;
};

// The frame the options name: --image, or --frame N of --video; `name` is how messages and the
// labels template name it ("VIDEO#N" for a recording's frame, as kccd calib names it).
cv::Mat sheetFrame(const SheetArgs& a, std::string& name) {
  if (a.image.empty() == a.video.empty())
    throw UsageError(a.image.empty() ? "give the frame: --image FILE, or --video FILE with --frame N"
                                     : "--image and --video: give one of them");
  if (a.video.empty()) {
    if (a.frame >= 0) throw UsageError("--frame: goes with --video");
    name = a.image;
    return calib::readImageFile(a.image, calib::ImageColour::Bgr);
  }
  if (a.frame < 0) throw UsageError("--video: say which frame with --frame N");
  name = a.video + "#" + std::to_string(a.frame);
  return overlay::readRecordingFrames(a.video, {a.frame}, "--video " + a.video).frames.front();
}

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
  std::string frame_name;
  const cv::Mat bgr = sheetFrame(a, frame_name);
  overlay::CandidateInputs in;
  in.image = frame_name;
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
  if (!a.labels_template.empty())
    writeFileAtomically(a.labels_template, overlay::labelsTemplate(c, frame_name, a.output));
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
      "A labelling aid: the frame (--image, or --frame N of --video) with detected tags (ids, corner order 0..3),\n"
      "numbered candidate points and, with --model and a camera with a rough pose, the model's core points\n"
      "projected; --template writes a labels file to fill in.");
  auto s = std::make_shared<SheetArgs>();
  sheet->add_option("--image", s->image, "The frame, an image file (or give --video and --frame)");
  sheet->add_option("--video", s->video,
                    "A recording (video file or image sequence, e.g. frames/frame_%06d.png) whose --frame N is the "
                    "frame");
  sheet->add_option("--frame", s->frame, "With --video: which frame (from 0)")->check(CLI::Range(0, 100000000));
  sheet->add_option("--tags", s->tags, "Tag layout: tags it places are drawn green, others orange");
  sheet->add_option("--model", s->model, "Model whose core points are projected (needs --camera and --state)");
  sheet->add_option("--camera", s->camera, "Camera file with a rough pose (e.g. from an earlier solve)");
  sheet->add_option("--state", s->state, "The robot's state in the frame (comma-separated)");
  sheet->add_option("--candidates", s->candidates, "Most candidate points to number")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  sheet->add_option("-o,--output", s->output, "Sheet image (.png)")->required();
  sheet->add_option("--template", s->labels_template, "Labels file (.yaml) to fill in: every candidate, commented out");
  sheet->footer(
      "Give the frame as --image FILE or as --video FILE --frame N (one of them; N from 0, the frame\n"
      "kccd calib --video FILE --frame N reads, named FILE#N in the template). E.g.:\n"
      "  kccd calib sheet --image frame.png --tags tags.yaml -o sheet.png --template labels.yaml\n"
      "  kccd calib sheet --video rec/video.mkv --frame 12 --tags rec/tags.yaml -o sheet.png --template labels.yaml\n"
      "then, the template filled in: kccd calib --video rec/video.mkv --frame 12 --labels labels.yaml ...");
  return [s] { return runSheet(*s); };
}

}  // namespace kccd::cli

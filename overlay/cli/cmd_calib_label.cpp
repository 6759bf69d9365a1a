// `kccd calib label`: label calibration points in a browser. The options become a
// kccd::overlay::LabelSession (frames, labels files, tags, model, states) served by a
// kccd::overlay::LabelServer on a loopback address until Ctrl+C or the page's Quit.
#include <pthread.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

#include "calib_frames.hpp"
#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_model.hpp"
#include "commands.hpp"
#include "kccd/calib/image_file.hpp"
#include "kccd/calib/mask_refine.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/labelling/label_server.hpp"

namespace kccd::cli {
namespace {

struct LabelArgs : FrameOptions {
  std::string intrinsics, tags, model, output, host = "127.0.0.1", web_root, mask_bodies;
  std::vector<std::string> labels, masks;
  int port = 0, min_inliers = 6;
  double threshold = 8.0;
  bool open = false, no_browser = false, quiet = false;
};

bool loopback(const std::string& host) { return host == "127.0.0.1" || host == "::1" || host == "localhost"; }

Exit runLabel(LabelArgs a) {
  // Ctrl+C and SIGTERM end the server from a thread that waits for them (nothing unsafe runs in a
  // signal handler). Blocked first: every thread started from here on (the tag detector's, the
  // server's) inherits the mask, so none of them takes the signal's default action.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGUSR1);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  if (a.labels.empty()) throw UsageError("calib label: --labels LABELS.yaml is required (the file the page writes)");
  if (a.host == "localhost") a.host = "127.0.0.1";
  for (const std::string& l : a.labels) {
    const std::string ext = std::filesystem::path(l).extension().string();
    if (ext != ".yaml" && ext != ".yml") throw UsageError("--labels " + l + ": must be a .yaml or .yml file");
    checkOutputPath(l, "--labels", ext);
  }
  for (std::size_t i = 0; i < a.labels.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (a.labels[i] == a.labels[j] || sameFile(a.labels[i], a.labels[j]))
        throw UsageError("--labels " + a.labels[i] + ": given twice (each frame has its own labels file)");
  if (!a.output.empty()) {
    const std::string ext = std::filesystem::path(a.output).extension().string();
    if (ext != ".yaml" && ext != ".yml")
      throw UsageError("-o " + a.output + ": the camera file must be a .yaml or .yml file");
    checkOutputPath(a.output, "-o", ext);
  }
  std::optional<Model> model;
  if (!a.model.empty()) model = loadOrExplain(a.model);
  if (a.images.empty() && a.video.empty() && a.bag.empty())
    throw UsageError("calib label: give --image FRAME..., --video V --frame N... or --bag LOG --frame N...");
  const GivenFrames given = givenFrames(a, a.labels.size(), true, model);
  for (const std::string& w : given.warnings) std::cerr << "kccd calib label: warning: " << w << "\n";
  if (a.labels.size() != given.count)
    throw UsageError("--labels: given " + std::to_string(a.labels.size()) + " times for " +
                     std::to_string(given.count) + " frames: give one labels file per frame, in the same order");

  overlay::LabelSessionInputs in;
  in.intrinsics = overlay::intrinsicsOf(calib::loadCamera(a.intrinsics, calib::CameraPose::Optional));
  in.intrinsics_name = a.intrinsics;
  if (!a.tags.empty()) in.tags = calib::loadTagLayout(a.tags);
  in.model = model ? &*model : nullptr;
  in.pose.ransac_threshold_px = a.threshold;
  in.pose.min_inliers = a.min_inliers;
  in.camera_output = a.output;
  if (!a.masks.empty()) {
    if (!model) throw UsageError("--masks: needs --model (the robot drawn to match the masks)");
    if (a.masks.size() != given.count)
      throw UsageError("--masks: " + std::to_string(a.masks.size()) + " mask(s) for " + std::to_string(given.count) +
                       " frame(s): give one per frame, in the same order");
    for (const std::string& m : a.masks) {
      if (m == "auto")
        throw UsageError("--masks auto: only kccd calib makes masks from a recording; the page takes mask files");
      in.masks.push_back(calib::readMask(m, in.intrinsics.width, in.intrinsics.height));
      in.mask_names.push_back(m);
    }
    std::stringstream list(a.mask_bodies);
    for (std::string name; std::getline(list, name, ',');) {
      const int b = model->bodyIndex(name);
      if (b < 0)
        throw UsageError("--mask-bodies: '" + name + "' is not a body of " + a.model + " (kccd info lists them)");
      in.mask_bodies.push_back(b);
    }
  } else if (!a.mask_bodies.empty()) {
    throw UsageError("--mask-bodies: goes with --masks");
  }
  for (std::size_t f = 0; f < given.count; ++f) {
    overlay::LabelFrame frame;
    frame.name = given.names[f];
    frame.bgr =
        given.pictures.empty() ? calib::readImageFile(given.names[f], calib::ImageColour::Bgr) : given.pictures[f];
    frame.state = given.states[f];
    frame.labels_path = a.labels[f];
    in.frames.push_back(std::move(frame));
  }
  overlay::LabelSession session(std::move(in));

  if (!loopback(a.host))
    std::cerr
        << "kccd: warning: --host " << a.host
        << ": the page and its API are reachable from other machines (no password; anyone who can reach it can save)\n";
  overlay::LabelServer server(session, {.host = a.host, .port = a.port, .web_root = a.web_root});
  if (!a.quiet)
    server.onRequest([](const std::string& method, const std::string& path, int status) {
      std::cerr << method << " " << path << " " << status << "\n";
    });
  std::thread waiter([&server, signals] {
    int received = 0;
    sigwait(&signals, &received);
    server.stop();
  });
  std::cout << server.url() << std::endl;  // the first line: scripts read the address from it
  if (!a.quiet) {
    std::cerr << "kccd calib label: serving " << session.frameCount() << " frame(s); labels go to";
    for (const std::string& l : a.labels) std::cerr << " " << l;
    std::cerr << (a.output.empty() ? "" : "; camera to " + a.output) << ". Ctrl+C or Quit in the page ends it.\n";
  }
  const nlohmann::json frames = session.session()["frames"];
  for (const nlohmann::json& f : frames)
    if (f["recovered"].is_object())
      std::cerr << "kccd calib label: " << f["recovered"]["file"].get<std::string>() << " holds "
                << f["recovered"]["labels"]["labels"].size() << " label(s) autosaved after "
                << f["labels_file"].get<std::string>() << " was saved; the page offers to restore them\n";
  if (a.open && !a.no_browser) {
    const std::string command = "xdg-open '" + server.url() + "' >/dev/null 2>&1 &";
    if (std::system(command.c_str()) != 0)
      std::cerr << "kccd: could not open a browser: open " << server.url() << " yourself\n";
  }
  server.run();
  pthread_kill(waiter.native_handle(), SIGUSR1);  // ended by Quit: wake the waiter
  waiter.join();
  if (session.dirty())
    std::cerr << "kccd calib label: edits since the last save are only in the autosave (LABELS.yaml.bak); the next "
                 "session offers them\n";
  return Exit::Ok;
}

}  // namespace

Runner addCalibLabel(CLI::App& calib) {
  CLI::App* sub = calib.add_subcommand(
      "label",
      "Label calibration points in a browser: serves a page on this machine (the URL is the first line printed) that "
      "shows\n"
      "the frames, lets you click points and pick what each shows (a tag corner, a world point, a point of a model "
      "body),\n"
      "solves the pose live as kccd calib does and draws the model's volumes at the estimate. Save writes only the\n"
      "--labels files (the previous versions kept as .bak) and, when solved, the -o camera file. Exit 0 when ended.");
  auto a = std::make_shared<LabelArgs>();
  sub->add_option("--intrinsics", a->intrinsics,
                  "Camera file with the intrinsics and lens distortion (its pose is ignored); required")
      ->required();
  sub->add_option("--image", a->images, "A frame from the fixed camera (repeat for several frames)")
      ->allow_extra_args(false);
  sub->add_option("--video", a->video, "A recording (video file or image sequence) whose --frame N are the frames");
  sub->add_option("--frame", a->video_frames, "Frame index in --video or --bag (from 0; repeat for several)")
      ->allow_extra_args(false)
      ->check(CLI::Range(0, 100000000));
  addBagOptions(*sub, *a);
  sub->add_option(
         "--labels", a->labels,
         "Labels file of each frame (repeat: one per frame, same order): loaded when it exists, written by Save")
      ->allow_extra_args(false);
  sub->add_option("--tags", a->tags, "Tag layout: detected tags it places are points too");
  sub->add_option("--model", a->model, "Model file: body points to label, and its volumes drawn at the estimate");
  sub->add_option("--state", a->states, "The robot's state in the frames (once for all, or once per frame)")
      ->allow_extra_args(false);
  sub->add_option("--states", a->state_log, "State log giving each frame's state at its --time");
  sub->add_option("--time", a->times,
                  "Each frame's time in the state log's clock (s; with --video default frame / fps)")
      ->allow_extra_args(false)
      ->check(finiteIn(-1e300, 1e300));
  sub->add_option("--max-gap", a->max_gap, "No state when the log has no sample this close (s)")
      ->check(finiteIn(0, 1e300));
  sub->add_option("--ignore-columns", a->ignore_columns, "Comma-separated state log columns to skip");
  sub->add_option("-o,--output", a->output, "Camera file Save writes when the pose is solved");
  sub->add_option(
         "--masks", a->masks,
         "Robot masks, one per frame in the same order (non-zero = robot): the page's Snap to the robot refines the "
         "pose so the model's drawn robot matches them, as kccd calib --masks; needs --model and each frame's state")
      ->expected(1, -1);
  sub->add_option("--mask-bodies", a->mask_bodies,
                  "Comma-separated bodies of the model that the masks show (default: all bodies)");
  sub->add_option("--threshold", a->threshold, "RANSAC threshold (px), as kccd calib")
      ->check(finiteIn(0.1, 1000))
      ->capture_default_str();
  sub->add_option("--min-inliers", a->min_inliers, "Fewer agreeing points: not solvable, as kccd calib")
      ->check(CLI::Range(4, 1000000))
      ->capture_default_str();
  sub->add_option("--port", a->port, "Port to listen on (0: any free port)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  sub->add_option("--host", a->host,
                  "Address to listen on; anything but loopback makes the page reachable from other machines")
      ->capture_default_str();
  sub->add_flag("--open", a->open, "Open the page in the desktop's browser (xdg-open)");
  sub->add_flag("--no-browser", a->no_browser, "Open no browser (the default; overrides --open)");
  sub->add_option("--web-root", a->web_root,
                  "Serve the page's files from this folder (development) instead of the built-in ones");
  sub->add_flag("-q,--quiet", a->quiet, "Print the URL and errors only");
  return [a]() -> Exit { return runLabel(*a); };
}

}  // namespace kccd::cli

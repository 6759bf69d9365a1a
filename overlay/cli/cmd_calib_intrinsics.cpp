// `kccd calib intrinsics --image A.png B.png ... (--board LAYOUT.yaml | --grid CxR --tag-size S
// --spacing D) -o CAMERA.yaml`: camera intrinsics from several images of a planar AprilTag board.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <regex>

#include <unistd.h>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_output.hpp"
#include "cli_progress.hpp"
#include "commands.hpp"
#include "kccd/calib/board_views.hpp"
#include "kccd/calib/intrinsics.hpp"
#include "kccd/format_number.hpp"

namespace kccd::cli {
namespace {

namespace fs = std::filesystem;

struct IntrinsicsArgs {
  std::vector<std::string> images;
  std::string board, grid, output;
  double tag_size = 0.0, spacing = -1.0;
  int first_id = 0;
  bool json = false, fix_k3 = false, rational = false, quiet = false;
  CLI::Option* tag_size_opt = nullptr;
  CLI::Option* spacing_opt = nullptr;
  CLI::Option* first_id_opt = nullptr;
};

calib::Board boardFrom(const IntrinsicsArgs& args) {
  const bool grid_options =
      !args.grid.empty() || args.tag_size_opt->count() || args.spacing_opt->count() || args.first_id_opt->count();
  if (!args.board.empty() && grid_options)
    throw UsageError("--board and --grid/--tag-size/--spacing/--first-id describe the board twice: give one of them");
  if (!args.board.empty()) return calib::Board::fromLayout(calib::loadTagLayout(args.board), args.board);
  if (args.grid.empty())
    throw UsageError("give the board: --board LAYOUT.yaml, or --grid COLSxROWS --tag-size S --spacing D (metres)");
  static const std::regex size(R"(([0-9]{1,4})[xX]([0-9]{1,4}))");
  std::smatch m;
  if (!std::regex_match(args.grid, m, size))
    throw UsageError("--grid " + printable(args.grid, 40) + ": expected COLSxROWS (tags across x tags down), e.g. 6x4");
  if (!args.tag_size_opt->count() || !args.spacing_opt->count())
    throw UsageError(
        "--grid needs --tag-size S (black square edge) and --spacing D (white gap between squares), in metres");
  calib::TagGrid g;
  g.cols = std::stoi(m[1].str());
  g.rows = std::stoi(m[2].str());
  g.tag_size = args.tag_size;
  g.spacing = args.spacing;
  g.first_id = args.first_id;
  try {
    return calib::Board::grid(g);
  } catch (const InputError& e) {
    throw UsageError(e.messageFrom("--grid " + args.grid));  // the error names its source "grid"
  }
}

Exit runIntrinsics(const IntrinsicsArgs& args) {
  const calib::Board board = boardFrom(args);
  if (args.images.empty()) throw UsageError("give the images: --image A.png B.png ... (at least 3 views of the board)");
  {
    const std::string ext = fs::path(args.output).extension().string();
    if (ext != ".yaml" && ext != ".yml")
      throw UsageError("-o " + args.output + ": the camera file must be a .yaml or .yml file");
    checkOutputPath(args.output, "-o", ext);
    for (const std::string& in : args.images)
      if (sameFile(args.output, in)) throw UsageError("-o " + args.output + ": is the input image " + in);
    if (!args.board.empty() && sameFile(args.output, args.board))
      throw UsageError("-o " + args.output + ": is the board layout " + args.board);
  }
  for (std::size_t i = 0; i < args.images.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (args.images[i] == args.images[j] || sameFile(args.images[i], args.images[j]))
        throw UsageError(args.images[i] + ": image: given twice (--image " + std::to_string(j + 1) + " and " +
                         std::to_string(i + 1) + ")");

  // ---- detect the tags of every image
  calib::BoardViews seen;
  {
    Progress progress("detecting tags", args.quiet || args.json);
    seen = calib::detectBoardViews(args.images, board, [&](double f) { progress.update(f); });
  }
  const cv::Size size = seen.image_size;
  const std::vector<int>& tags_seen = seen.tags;
  const std::vector<std::vector<int>>& unknown = seen.unknown_ids;

  // ---- solve
  calib::IntrinsicsOptions options;
  options.fix_k3 = args.fix_k3;
  options.rational = args.rational;
  const calib::IntrinsicsResult r = calib::calibrateIntrinsics(seen.views, size, options);
  const bool solved = r.status == calib::IntrinsicsStatus::Solved;
  if (solved) writeFileAtomically(args.output, calib::intrinsicsCameraText(r));

  const cv::Matx33d& k = r.camera.camera_matrix;
  if (args.json) {
    nlohmann::json j;
    j["status"] = calib::toString(r.status);
    j["message"] = r.message;
    j["output"] = solved ? nlohmann::json(args.output) : nlohmann::json(nullptr);
    j["image_width"] = size.width;
    j["image_height"] = size.height;
    j["rms_px"] = number(r.rms_px);
    if (solved) {
      j["fx"] = k(0, 0);
      j["fy"] = k(1, 1);
      j["cx"] = k(0, 2);
      j["cy"] = k(1, 2);
      j["distortion"] = r.camera.distortion;
      nlohmann::json sd = nlohmann::json::array();
      for (double s : r.sigmas.distortion) sd.push_back(number(s));
      j["std_dev"] = {{"fx", number(r.sigmas.fx)},
                      {"fy", number(r.sigmas.fy)},
                      {"cx", number(r.sigmas.cx)},
                      {"cy", number(r.sigmas.cy)},
                      {"distortion", sd}};
    }
    j["views"] = nlohmann::json::array();
    for (std::size_t i = 0; i < r.views.size(); ++i) {
      const auto& v = r.views[i];
      nlohmann::json jv = {{"image", v.name},          {"tags", tags_seen[i]},       {"corners", v.points},
                           {"used", v.used},           {"rms_px", number(v.rms_px)}, {"tilt_deg", number(v.tilt_deg)},
                           {"unknown_ids", unknown[i]}};
      if (!v.note.empty()) jv["note"] = v.note;
      j["views"].push_back(jv);
    }
    j["used"] = r.used;
    j["rejected"] = r.rejected;
    std::cout << j.dump(2) << "\n";
  } else {
    for (std::size_t i = 0; i < r.views.size(); ++i) {
      const auto& v = r.views[i];
      std::cout << "  " << v.name << ": " << tags_seen[i] << " board tag" << (tags_seen[i] == 1 ? "" : "s");
      if (std::isfinite(v.tilt_deg)) std::cout << ", tilt " << formatNumber(v.tilt_deg, 3) << " deg";
      if (std::isfinite(v.rms_px)) std::cout << ", RMS " << formatNumber(v.rms_px, 3) << " px";
      if (!unknown[i].empty()) std::cout << ", " << unknown[i].size() << " tag(s) not on the board";
      if (!v.note.empty()) std::cout << " - left out: " << v.note;
      std::cout << "\n";
    }
    if (solved) {
      std::cout << "wrote " << args.output << ": " << size.width << "x" << size.height << ", fx "
                << formatNumber(k(0, 0), 7) << " +- " << formatNumber(r.sigmas.fx, 2) << ", fy "
                << formatNumber(k(1, 1), 7) << " +- " << formatNumber(r.sigmas.fy, 2) << ", cx "
                << formatNumber(k(0, 2), 6) << " +- " << formatNumber(r.sigmas.cx, 2) << ", cy "
                << formatNumber(k(1, 2), 6) << " +- " << formatNumber(r.sigmas.cy, 2) << " px\n"
                << "distortion";
      for (double d : r.camera.distortion) std::cout << " " << formatNumber(d, 5);
      std::cout << "\nRMS " << formatNumber(r.rms_px, 3) << " px from " << r.used.size() << " of " << r.views.size()
                << " images\n";
    }
  }
  if (!solved) {
    // Tags that are not on the board usually mean a wrong --grid, --first-id or --board.
    std::vector<int> foreign;
    for (const auto& ids : unknown) foreign.insert(foreign.end(), ids.begin(), ids.end());
    std::sort(foreign.begin(), foreign.end());
    foreign.erase(std::unique(foreign.begin(), foreign.end()), foreign.end());
    std::string hint;
    if (r.status == calib::IntrinsicsStatus::TooFewViews && !foreign.empty()) {
      hint = " (the images show tag";
      hint += foreign.size() == 1 ? " " : "s ";
      for (std::size_t i = 0; i < std::min<std::size_t>(foreign.size(), 8); ++i)
        hint += (i ? ", " : "") + std::to_string(foreign[i]);
      if (foreign.size() > 8) hint += ", ...";
      hint += " that the board does not have: check --grid, --first-id or --board)";
    }
    std::cerr << "kccd: intrinsics " << calib::toString(r.status) << ": " << oneLine(r.message) << hint << "\n";
    return Exit::NotSolvable;
  }
  return Exit::Ok;
}

}  // namespace

Runner addCalibIntrinsics(CLI::App& calib) {
  auto args = std::make_shared<IntrinsicsArgs>();
  CLI::App* sub = calib.add_subcommand(
      "intrinsics",
      "Camera intrinsics (focal lengths, principal point, lens distortion) from several images of a flat "
      "AprilTag board");
  sub->add_option("--image", args->images, "Images of the board (repeat --image or list several after it)")->required();
  CLI::Option* board = sub->add_option("--board", args->board, "Tag layout of the board (YAML; all tags in one plane)");
  CLI::Option* grid = sub->add_option("--grid", args->grid, "A regular board of COLSxROWS tags (e.g. 6x4)");
  args->tag_size_opt = sub->add_option("--tag-size", args->tag_size, "Grid: edge of a tag's black square (metres)")
                           ->check(finiteIn(1e-6, calib::kMaxTagSize));
  args->spacing_opt =
      sub->add_option("--spacing", args->spacing, "Grid: white gap between neighbouring black squares (metres)")
          ->check(finiteIn(0.0, calib::kMaxTagSize));
  args->first_id_opt = sub->add_option("--first-id", args->first_id, "Grid: id of the top-left tag (default 0)")
                           ->check(CLI::Range(0, calib::kMaxTagId));
  board->excludes(grid);
  sub->add_option("-o,--output", args->output, "Camera file to write (OpenCV YAML; pose zero)")->required();
  sub->add_flag("--fix-k3", args->fix_k3, "Keep k3 at 0 (lenses with little distortion, or few views)");
  sub->add_flag("--rational", args->rational, "Rational lens model k1..k6 (wide-angle lenses; needs many views)")
      ->excludes("--fix-k3");
  sub->add_flag("--json", args->json, "Machine-readable summary (rms, per-view rms, std devs, rejected views)");
  sub->add_flag("-q,--quiet", args->quiet, "No progress display");
  sub->footer(
      "The board: AprilTags (tag36h11) on a flat, rigid surface. --grid COLSxROWS --tag-size S --spacing D\n"
      "describes a regular board: ids --first-id, +1, ... row by row from the top left (as printed); or give\n"
      "its tag layout with --board (all tags in one plane, facing one way). Sizes in metres (only the\n"
      "intrinsics are written, so the unit does not matter as long as it is consistent).\n"
      "Good views: 8 or more sharp images from one camera at one resolution and fixed focus/zoom; the\n"
      "board tilted 20-45 deg towards the camera about different axes (left/right, up/down); the board\n"
      "near the image corners and edges in some views as well as in the centre; at least two whole tags\n"
      "per image. Face-on views alone cannot give the focal length.\n"
      "Output: the camera file (image size, camera_matrix, distortion_coefficients k1 k2 p1 p2 k3,\n"
      "rvec = tvec = 0, reprojection_rms_px and avg_reprojection_error): kccd calib --intrinsics reads it.\n"
      "A view that fits far worse than the others is left out and named.\n"
      "Exit status: 0 written; 2 bad input (unreadable image, images of different sizes, a board layout\n"
      "whose tags are not in one plane); 4 not solvable: too few views, face-on views only, or an\n"
      "ill-determined result - the message says what to add. Nothing is written unless solved.");
  return [args] { return runIntrinsics(*args); };
}

}  // namespace kccd::cli

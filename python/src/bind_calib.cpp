// Calibration from Python: images and recording frames as NumPy arrays, AprilTag detection, tag
// layouts and the correspondences they give, the camera pose solved from correspondences with
// the statuses and quality figures of `kccd calib`, and the pose refined to robot masks.
#include <pybind11/stl.h>

#include <opencv2/imgproc.hpp>
#include <set>

#include "arrays.hpp"
#include "bindings.hpp"
#include "kccd/calib/camera.hpp"
#include "kccd/calib/edge_refine.hpp"
#include "kccd/calib/image_file.hpp"
#include "kccd/calib/mask_refine.hpp"
#include "kccd/calib/pose.hpp"
#include "kccd/calib/silhouette.hpp"
#include "kccd/calib/tag_detect.hpp"
#include "kccd/calib/tag_layout.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/calibration/calib_refine.hpp"

namespace kccd::python {

namespace {

// A decoded 8-bit BGR picture as a fresh RGB uint8 (H, W, 3) array.
py::array_t<std::uint8_t> rgbArray(const cv::Mat& bgr) {
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return imageArray(rgb);
}

// `image` (uint8 (H, W) grey, (H, W, 3) RGB or (H, W, 4) RGBA) as an 8-bit grey cv::Mat of its own,
// converted with the weights `kccd calib` uses on its BGR frames; `name` names it in errors.
cv::Mat greyOf(const py::handle& image, const std::string& name = "image") {
  py::array a = py::array::ensure(image);
  if (!a) {
    PyErr_Clear();
    throw py::type_error(name + ": expected a NumPy array of uint8 pixels");
  }
  if (a.dtype().kind() != 'u' || a.dtype().itemsize() != 1)
    throw py::type_error(name + ": expected dtype uint8, got dtype " + py::str(a.dtype()).cast<std::string>());
  const int channels = a.ndim() == 2 ? 1 : (a.ndim() == 3 ? static_cast<int>(a.shape(2)) : 0);
  if (channels != 1 && channels != 3 && channels != 4)
    throw py::value_error(name + ": expected shape (H, W) grey, (H, W, 3) RGB or (H, W, 4) RGBA");
  if (a.shape(0) < 1 || a.shape(1) < 1) throw py::value_error(name + ": is empty");
  if (a.shape(0) > calib::kMaxImageSide || a.shape(1) > calib::kMaxImageSide)
    throw py::value_error(name + ": larger than " + std::to_string(calib::kMaxImageSide) + " pixels a side");
  const auto c = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(a);
  const cv::Mat view(static_cast<int>(c.shape(0)), static_cast<int>(c.shape(1)), CV_8UC(channels),
                     const_cast<std::uint8_t*>(c.data()));
  cv::Mat grey;
  if (channels == 1) grey = view.clone();
  if (channels == 3) cv::cvtColor(view, grey, cv::COLOR_RGB2GRAY);
  if (channels == 4) cv::cvtColor(view, grey, cv::COLOR_RGBA2GRAY);
  return grey;
}

// Mask `index` of a refinement: a path (read by calib::readMask) or a 2-D uint8 or bool array,
// non-zero = robot, of the camera's size, with both robot and background in it.
cv::Mat maskOf(const py::handle& value, std::size_t index, const calib::Camera& camera) {
  const std::string name = "masks[" + std::to_string(index) + "]";
  if (py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__"))
    return calib::readMask(py::str(py::module_::import("os").attr("fspath")(value)).cast<std::string>(), camera.width,
                           camera.height);
  py::array a = py::array::ensure(value);
  if (!a) {
    PyErr_Clear();
    throw py::type_error(name + ": expected a path or a NumPy array");
  }
  const char kind = a.dtype().kind();
  if (!((kind == 'u' && a.dtype().itemsize() == 1) || kind == 'b'))
    throw py::type_error(name + ": expected dtype uint8 or bool, got dtype " + py::str(a.dtype()).cast<std::string>());
  if (a.ndim() != 2) throw py::value_error(name + ": expected shape (H, W)");
  if (a.shape(0) != camera.height || a.shape(1) != camera.width)
    throw py::value_error(name + ": " + std::to_string(a.shape(1)) + "x" + std::to_string(a.shape(0)) +
                          " for a camera of " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  const auto c = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(a);
  const cv::Mat view(camera.height, camera.width, CV_8UC1, const_cast<std::uint8_t*>(c.data()));
  cv::Mat mask = (view != 0);
  const int robot = cv::countNonZero(mask);
  if (robot == 0) throw py::value_error(name + ": no robot in it (every pixel is 0)");
  if (robot == mask.rows * mask.cols) throw py::value_error(name + ": nothing but robot (no pixel is 0)");
  return mask;
}

// A pose covariance (of rvec, tvec) as a float64 (6, 6) array.
py::array_t<double> covarianceArray(const cv::Matx66d& c) {
  py::array_t<double> out({6, 6});
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) out.mutable_at(i, j) = c(i, j);
  return out;
}

// pictures[index] of `camera`'s size as 8-bit grey: an image file's path, or an array as greyOf
// takes it.
cv::Mat pictureOf(const py::handle& value, std::size_t index, const calib::Camera& camera) {
  const std::string name = "pictures[" + std::to_string(index) + "]";
  cv::Mat grey =
      py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__")
          ? calib::readImageFile(py::str(py::module_::import("os").attr("fspath")(value)).cast<std::string>(),
                                 calib::ImageColour::Grey)
          : greyOf(value, name);
  if (grey.cols != camera.width || grey.rows != camera.height)
    throw py::value_error(name + ": " + std::to_string(grey.cols) + "x" + std::to_string(grey.rows) +
                          " for a camera of " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  return grey;
}

// `draw` checked: what a refinement draws of the robot.
const std::string& drawOf(const std::string& draw) {
  if (draw != "auto" && draw != "visuals" && draw != "volumes")
    throw py::value_error("draw: expected 'auto', 'visuals' or 'volumes'");
  return draw;
}

// The model's body indices of `bodies` (none: all).
std::vector<int> bodyIndices(const Model& model, const std::optional<std::vector<std::string>>& bodies) {
  std::vector<int> indices;
  if (bodies)
    for (const std::string& b : *bodies) {
      const int i = model.bodyIndex(b);
      if (i < 0) throw py::value_error("bodies: the model has no body '" + b + "'");
      indices.push_back(i);
    }
  return indices;
}

// A refinement's result as refine_to_masks and refine_to_edges return it; `drawn` says what stood
// for the robot.
py::dict refinementDict(const calib::RefineResult& r, const std::string& drawn) {
  const bool edges = r.source == calib::RefineSource::Edges;
  py::list per_frame;
  for (const calib::FrameAgreement& a : r.frames) {
    py::dict d;
    if (edges) {
      d["edge_share_before"] = a.matched_before;
      d["edge_share_after"] = a.matched_after;
    } else {
      d["iou_before"] = a.iou_before;
      d["iou_after"] = a.iou_after;
    }
    d["rms_px"] = a.rms_px;
    d["outline_points"] = a.outline_points;
    per_frame.append(d);
  }
  py::dict out;
  out["improved"] = r.improved;
  out["message"] = r.message;
  out["camera"] = r.camera;
  out["frames"] = per_frame;
  out["iterations"] = r.iterations;
  out["covariance"] = r.improved ? py::object(covarianceArray(r.covariance)) : py::object(py::none());
  out["drawn"] = drawn;
  return out;
}

py::array_t<double> rows(const std::vector<std::array<double, 3>>& v, int cols) {
  py::array_t<double> out({static_cast<py::ssize_t>(v.size()), static_cast<py::ssize_t>(cols)});
  auto o = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int k = 0; k < cols; ++k) o(static_cast<py::ssize_t>(i), k) = v[i][static_cast<std::size_t>(k)];
  return out;
}

}  // namespace

namespace {

// Pictures and frames of recordings, as RGB arrays.
void bindImages(py::module_& m) {
  m.def(
      "read_image",
      [](const std::string& path) { return rgbArray(calib::readImageFile(path, calib::ImageColour::Bgr)); },
      py::arg("path"),
      "An image file (PNG, JPEG, TIFF, BMP, ...) as uint8 (H, W, 3) RGB, C-contiguous. Raises InputError naming "
      "the file.");
  m.def(
      "read_frame",
      [](const std::string& video, int index) {
        if (index < 0) throw py::value_error("index: must be >= 0");
        overlay::RecordingFrames f;
        {
          py::gil_scoped_release release;
          f = overlay::readRecordingFrames(video, {index});
        }
        return rgbArray(f.frames.at(0));
      },
      py::arg("video"), py::arg("index"),
      "Frame `index` (from 0) of a recording (a video file or an image-sequence pattern with a '%') as uint8 "
      "(H, W, 3) RGB, decoded in order up to it. Raises InputError naming the recording and the frame.");

  m.def(
      "read_frames",
      [](const std::string& video, const std::vector<int>& indices) {
        for (int i : indices)
          if (i < 0) throw py::value_error("indices: must be >= 0");
        overlay::RecordingFrames f;
        if (!indices.empty()) {
          py::gil_scoped_release release;
          f = overlay::readRecordingFrames(video, indices);
        }
        py::list out;
        for (const cv::Mat& frame : f.frames) out.append(rgbArray(frame));
        return out;
      },
      py::arg("video"), py::arg("indices"),
      "Frames `indices` (from 0, any order) of a recording as uint8 (H, W, 3) RGB arrays, in the order asked for, "
      "decoded once up to the last one. Raises InputError naming the recording and the frame.");
}

// AprilTags: detections, layouts and their correspondences.
void bindTags(py::module_& m) {
  py::class_<calib::TagDetection>(m, "TagDetection", "One detected AprilTag (family tag36h11).")
      .def_readonly("id", &calib::TagDetection::id, "The tag's id in the tag36h11 family (0 ... 586).")
      .def_property_readonly(
          "corners",
          [](const calib::TagDetection& d) {
            std::vector<std::array<double, 3>> c;
            for (const cv::Point2d& p : d.corners) c.push_back({p.x, p.y, 0.0});
            return rows(c, 2);
          },
          "float64 (4, 2): the corners in pixels (OpenCV convention: pixel centres at integers), in AprilTag's "
          "order p0..p3, counter-clockwise as seen in the image, p0 at the tag frame's (-s/2, -s/2)")
      .def_readonly("hamming", &calib::TagDetection::hamming, "bits corrected in decoding (0 ... 2)")
      .def_readonly("decision_margin", &calib::TagDetection::decision_margin, "AprilTag's decoding quality")
      .def("__repr__",
           [](const calib::TagDetection& d) { return "<kccd.TagDetection id " + std::to_string(d.id) + ">"; });

  m.def(
      "detect_tags",
      [](const py::handle& image) {
        cv::Mat grey = greyOf(image);
        py::gil_scoped_release release;
        return calib::detectTags(grey);
      },
      py::arg("image"),
      "The tag36h11 AprilTags in `image` (uint8 (H, W) grey, (H, W, 3) RGB or (H, W, 4) RGBA; converted to grey "
      "as `kccd calib` does), full resolution with refined edges, in the detector's order. The GIL is released.");

  py::class_<calib::TagLayout>(m, "TagLayout", "Where AprilTags are placed in the world (a tag layout file).")
      .def_static("load", &calib::loadTagLayout, py::arg("path"),
                  "Reads a tag layout file; raises InputError naming the file, line and field.")
      .def_static("from_yaml", &calib::parseTagLayout, py::arg("text"), py::arg("source") = "<string>",
                  "Parses tag layout text; `source` names it in errors.")
      .def_property_readonly(
          "ids",
          [](const calib::TagLayout& l) {
            std::vector<int> ids;
            for (const calib::Tag& t : l.tags) ids.push_back(t.id);
            return ids;
          },
          "The tag ids, in file order.")
      .def(
          "corners",
          [](const calib::TagLayout& l, int id) {
            const calib::Tag* t = l.find(id);
            if (!t) throw py::key_error("tag " + std::to_string(id) + " is not in the layout");
            std::vector<std::array<double, 3>> c;
            for (const cv::Point3d& p : t->corners()) c.push_back({p.x, p.y, p.z});
            return rows(c, 3);
          },
          py::arg("id"), "float64 (4, 3): tag `id`'s corners in the world (metres), in TagDetection.corners' order.")
      .def("__len__", [](const calib::TagLayout& l) { return l.tags.size(); });

  m.def(
      "tag_correspondences",
      [](const std::vector<calib::TagDetection>& detections, const calib::TagLayout& layout, const std::string& image) {
        const calib::TagCorrespondences tc = calib::tagCorrespondences(detections, layout, image);
        std::vector<std::string> names;
        std::vector<std::array<double, 3>> px, world;
        for (const calib::Correspondence& c : tc.points) {
          names.push_back(c.name);
          px.push_back({c.pixel.x, c.pixel.y, 0.0});
          world.push_back({c.world.x, c.world.y, c.world.z});
        }
        py::dict out;
        out["names"] = names;
        out["pixels"] = rows(px, 2);
        out["world"] = rows(world, 3);
        out["unknown_ids"] = tc.unknown_ids;
        return out;
      },
      py::arg("detections"), py::arg("layout"), py::arg("image") = "image",
      "Pairs each detected corner of a layout tag with its world point: a dict with 'names' ('tag3.c0' ... "
      "'tag3.c3'), 'pixels' float64 (N, 2), 'world' float64 (N, 3) (metres), in detection then corner order, and "
      "'unknown_ids' (detected ids the layout lacks). A tag detected twice raises InputError naming `image`.");
}

// The pose solve and its status.
void bindPose(py::module_& m) {
  py::list members;
  const std::pair<const char*, calib::PoseStatus> statuses[] = {{"SOLVED", calib::PoseStatus::Solved},
                                                                {"TOO_FEW_POINTS", calib::PoseStatus::TooFewPoints},
                                                                {"COLLINEAR", calib::PoseStatus::Collinear},
                                                                {"POOR_GEOMETRY", calib::PoseStatus::PoorGeometry},
                                                                {"TOO_FEW_INLIERS", calib::PoseStatus::TooFewInliers}};
  for (const auto& [name, s] : statuses) members.append(py::make_tuple(name, static_cast<int>(s)));
  py::object pose_status =
      py::module_::import("enum").attr("IntEnum")("PoseStatus", members, py::arg("module") = "kccd");
  pose_status.attr("__doc__") = "How a pose solve ended; only SOLVED comes with a camera.";
  m.attr("PoseStatus") = pose_status;

  m.def(
      "solve_pose",
      [pose_status](const calib::Camera& intrinsics, const py::handle& pixels, const py::handle& world,
                    const std::optional<std::vector<std::string>>& names, double threshold, int min_inliers) {
        const auto px = pointMatrix(pixels, "pixels", 2);
        const auto wd = pointMatrix(world, "world", 3);
        if (px.shape(0) != wd.shape(0))
          throw py::value_error("pixels, world: " + std::to_string(px.shape(0)) + " pixels but " +
                                std::to_string(wd.shape(0)) + " world points");
        if (names && static_cast<py::ssize_t>(names->size()) != px.shape(0))
          throw py::value_error("names: " + std::to_string(names->size()) + " names for " +
                                std::to_string(px.shape(0)) + " points");
        if (!(threshold > 0.0)) throw py::value_error("ransac_threshold_px: must be > 0");
        if (min_inliers < 4) throw py::value_error("min_inliers: must be >= 4");
        std::vector<calib::Correspondence> points;
        const auto p = px.unchecked<2>();
        const auto w = wd.unchecked<2>();
        for (py::ssize_t i = 0; i < px.shape(0); ++i)
          points.push_back({names ? (*names)[static_cast<std::size_t>(i)] : "p" + std::to_string(i),
                            {p(i, 0), p(i, 1)},
                            {w(i, 0), w(i, 1), w(i, 2)}});
        calib::PoseOptions options;
        options.ransac_threshold_px = threshold;
        options.min_inliers = min_inliers;
        const calib::Camera start = overlay::intrinsicsOf(intrinsics);
        calib::PoseResult r;
        {
          py::gil_scoped_release release;
          r = calib::solvePose(start, points, options);
        }
        const bool solved = r.status == calib::PoseStatus::Solved;
        py::array_t<double> residuals(static_cast<py::ssize_t>(r.residuals.size()));
        py::array_t<bool> inlier(static_cast<py::ssize_t>(r.residuals.size()));
        for (std::size_t i = 0; i < r.residuals.size(); ++i) {
          residuals.mutable_data()[i] = r.residuals[i].px;
          inlier.mutable_data()[i] = r.residuals[i].inlier;
        }
        py::dict out;
        out["status"] = pose_status(static_cast<int>(r.status));
        out["message"] = r.message;
        out["camera"] = solved ? py::cast(r.camera) : py::object(py::none());
        out["residuals_px"] = residuals;
        out["inlier"] = inlier;
        out["rejected"] = r.rejected;
        out["inliers"] = r.inliers;
        out["covariance"] = solved ? py::object(covarianceArray(r.covariance)) : py::object(py::none());
        out["reprojection_rms_px"] = solved ? py::cast(r.camera.reprojection_rms_px) : py::object(py::none());
        out["rotation_sigma_deg"] = solved ? py::cast(r.camera.rotation_sigma_deg) : py::object(py::none());
        out["position_sigma_m"] = solved ? py::cast(r.camera.position_sigma_m) : py::object(py::none());
        return out;
      },
      py::arg("intrinsics"), py::arg("pixels"), py::arg("world"), py::arg("names") = py::none(), py::kw_only(),
      py::arg("ransac_threshold_px") = 8.0, py::arg("min_inliers") = 6,
      R"doc(The camera's pose (world -> camera) from 2-D <-> 3-D correspondences, as `kccd calib`: P3P RANSAC,
SQPnP and Levenberg-Marquardt on the inliers, refusing degenerate or ill-conditioned sets. intrinsics: a Camera
(its pose and quality figures are ignored; Camera.load(path, require_pose=False) reads an intrinsics file);
pixels float64 (N, 2) (OpenCV convention: pixel centres at integers); world float64 (N, 3) (metres); names: one
per point (default 'p0', 'p1', ...), used in 'rejected' and 'message'. Returns a dict: 'status' (kccd.PoseStatus),
'message' (one line: what was found, and for a failure what to add), 'camera' (a Camera with the pose and its
quality, SOLVED only, else None), 'residuals_px' float64 (N,) and 'inlier' bool (N,) under the best pose found
(empty when none), 'rejected' (names), 'inliers', 'covariance' float64 (6, 6) of (rvec, tvec) or None, and
'reprojection_rms_px', 'rotation_sigma_deg', 'position_sigma_m' (None unless SOLVED). Raises InputError for a
non-finite coordinate, an empty or repeated name, or invalid intrinsics.)doc");
}

// The pose refined to robot masks or to the pictures' edges.
void bindRefine(py::module_& m) {
  m.def(
      "refine_to_masks",
      [](const calib::Camera& camera, const std::shared_ptr<ModelHandle>& h, const py::sequence& masks,
         const py::handle& states, const std::optional<std::vector<std::string>>& bodies,
         const std::optional<bool>& start_is_prior, const std::string& draw) {
        if (py::isinstance<py::str>(masks) || py::isinstance<py::bytes>(masks))
          throw py::type_error("masks: a list of masks (one per frame), not one path");
        const Model& model = *h->model;
        const int n = model.stateSize();
        const auto st = stateMatrix(states, "states", n);
        if (static_cast<std::size_t>(st.shape(0)) != masks.size())
          throw py::value_error("masks, states: " + std::to_string(masks.size()) + " masks but " +
                                std::to_string(st.shape(0)) + " states");
        if (masks.size() == 0) throw py::value_error("masks: give at least one");
        const overlay::RobotDrawing robot(model, bodyIndices(model, bodies), drawOf(draw));
        std::vector<calib::MaskFrame> frames;
        for (std::size_t f = 0; f < masks.size(); ++f) {
          const std::span<const double> state(st.data(static_cast<py::ssize_t>(f), 0), static_cast<std::size_t>(n));
          frames.push_back({maskOf(masks[f], f, camera), robot.volumes(state), robot.meshes(state)});
        }
        calib::RefineOptions options;
        // As kccd calib: a start with sigmas (a solve) is a prior unless told otherwise.
        options.start_is_prior = start_is_prior.value_or(camera.rotation_sigma_deg && camera.position_sigma_m);
        calib::RefineResult r;
        {
          py::gil_scoped_release release;
          r = calib::refineToMasks(camera, frames, options);
        }
        return refinementDict(r, robot.drawn());
      },
      py::arg("camera"), py::arg("model"), py::arg("masks"), py::arg("states"), py::kw_only(),
      py::arg("bodies") = py::none(), py::arg("start_is_prior") = py::none(), py::arg("draw") = "auto",
      R"doc(The camera's pose refined so that the model's volumes, drawn through the lens at each frame's state,
match robot masks of the frames, as `kccd calib --masks`: camera, a Camera with a start pose (a solve, or a rough
pose some 10 deg / 10 cm off); masks, one per frame, each a path to an image (non-zero = robot) or a uint8 or
bool (H, W) array of the camera's size; states float64 (frames, state_size); bodies, the names of the bodies
that are the robot in the masks (default all); start_is_prior: the start's sigmas are a prior, so a pose more than
3 sigma from it for a mean IoU gain below 0.02 keeps the start (default: when the camera has sigmas, i.e. a solve
such as solve_pose's, as kccd calib does). Returns a dict: 'improved' (the pose was refined; else 'camera'
is the start), 'message' (one line: what happened, or why the start was kept), 'camera' (with the refinement's
pose sigmas when improved), 'frames' (per frame 'iou_before', 'iou_after', 'rms_px', 'outline_points'),
'iterations', 'covariance' float64 (6, 6) of (rvec, tvec) or None, 'drawn' (what stood for the robot: 'visual
meshes', or 'collision volumes' with the reason when the model has visuals). draw: 'auto' (the model's visuals when
it has them and they can be read, else its collision volumes), 'visuals' or 'volumes', as kccd calib --draw. Raises InputError for an unreadable mask file (naming it), ValueError for a mask of
another size, with no robot or nothing but robot, a count that does not match the states, or an unknown body.
The GIL is released while refining.)doc");

  m.def(
      "refine_to_edges",
      [](const calib::Camera& camera, const std::shared_ptr<ModelHandle>& h, const py::sequence& pictures,
         const py::handle& states, const std::optional<std::vector<std::string>>& bodies,
         const std::optional<bool>& start_is_prior, const std::string& draw) {
        if (py::isinstance<py::str>(pictures) || py::isinstance<py::bytes>(pictures))
          throw py::type_error("pictures: a list of pictures (one per frame), not one path");
        const Model& model = *h->model;
        const int n = model.stateSize();
        const auto st = stateMatrix(states, "states", n);
        if (static_cast<std::size_t>(st.shape(0)) != pictures.size())
          throw py::value_error("pictures, states: " + std::to_string(pictures.size()) + " pictures but " +
                                std::to_string(st.shape(0)) + " states");
        if (pictures.size() == 0) throw py::value_error("pictures: give at least one");
        const overlay::RobotDrawing robot(model, bodyIndices(model, bodies), drawOf(draw));
        std::vector<calib::EdgeFrame> frames;
        for (std::size_t f = 0; f < pictures.size(); ++f) {
          const std::span<const double> state(st.data(static_cast<py::ssize_t>(f), 0), static_cast<std::size_t>(n));
          frames.push_back({pictureOf(pictures[f], f, camera), robot.volumes(state), robot.meshes(state)});
        }
        calib::EdgeOptions options;
        options.start_is_prior = start_is_prior.value_or(camera.rotation_sigma_deg && camera.position_sigma_m);
        calib::RefineResult r;
        {
          py::gil_scoped_release release;
          r = calib::refineToEdges(camera, frames, options);
        }
        return refinementDict(r, robot.drawn());
      },
      py::arg("camera"), py::arg("model"), py::arg("pictures"), py::arg("states"), py::kw_only(),
      py::arg("bodies") = py::none(), py::arg("start_is_prior") = py::none(), py::arg("draw") = "auto",
      R"doc(The camera's pose refined so that the model's volumes' outline, drawn through the lens at each frame's
state, lies on the pictures' own edges, as `kccd calib --refine edges` (no masks needed): camera, a Camera with a
start pose a few degrees off at most (e.g. a solve from 4 rough labels); pictures, one per frame, each a path to
an image or a uint8 (H, W) grey, (H, W, 3) RGB or (H, W, 4) RGBA array of the camera's size; states float64 (frames, state_size); bodies,
the bodies in view (default all); start_is_prior as refine_to_masks (for a gain below 5 points of the outline on
edges); draw as refine_to_masks. Returns the dict of refine_to_masks, with per frame 'edge_share_before' and 'edge_share_after' (the share
of the drawn outline within 2 px of an image edge of its direction) in place of the IoUs. Raises InputError for an
unreadable picture file (naming it), ValueError for a picture of another size, a count that does not match the
states, or an unknown body. The GIL is released while refining.)doc");
}

}  // namespace

void bindCalib(py::module_& m) {
  bindImages(m);
  bindTags(m);
  bindPose(m);
  bindRefine(m);
}

}  // namespace kccd::python

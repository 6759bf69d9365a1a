// kccd.Camera (a calibrated camera file) and kccd.render: the model's volumes as the camera sees
// them, off-screen, as NumPy images.
#include <pybind11/stl.h>

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "arrays.hpp"
#include "bindings.hpp"
#include "kccd/calib/camera.hpp"
#include "kccd/render/model_view.hpp"

namespace kccd::python {

namespace {

py::array_t<double> matrix3(const cv::Matx33d& k) {
  py::array_t<double> out({3, 3});
  auto o = out.mutable_unchecked<2>();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) o(r, c) = k(r, c);
  return out;
}

}  // namespace

void bindRender(py::module_& m) {
  py::class_<calib::Camera>(m, "Camera", R"doc(
A fixed camera: intrinsics, OpenCV distortion and its pose (world -> camera, Rodrigues rvec and tvec in
metres), as `kccd calib` writes it. Load with Camera.load(path).)doc")
      .def_static(
          "load",
          [](const std::string& path, bool require_pose) {
            return calib::loadCamera(path, require_pose ? calib::CameraPose::Required : calib::CameraPose::Optional);
          },
          py::arg("path"), py::arg("require_pose") = true,
          "Reads a camera file; raises InputError naming the file, line and field. require_pose=False also reads "
          "an intrinsics file without a pose (OpenCV's calibration output: rvec = tvec = 0), as solve_pose takes.")
      .def(
          "save", [](const calib::Camera& c, const std::string& path) { calib::saveCamera(c, path); }, py::arg("path"),
          "Writes the camera file (under a temporary name, renamed when complete).")
      .def_readonly("width", &calib::Camera::width, "Image width in pixels (`image_width`).")
      .def_readonly("height", &calib::Camera::height, "Image height in pixels (`image_height`).")
      .def_property_readonly(
          "camera_matrix", [](const calib::Camera& c) { return matrix3(c.camera_matrix); },
          "float64 (3, 3): fx 0 cx; 0 fy cy; 0 0 1 (pixels)")
      .def_property_readonly(
          "distortion", [](const calib::Camera& c) { return c.distortion; }, "OpenCV order: k1 k2 p1 p2 [k3 ...]")
      .def_property_readonly(
          "rvec", [](const calib::Camera& c) { return floatArray(c.rvec.val); },
          "float64 (3,): world -> camera rotation (Rodrigues vector, radians)")
      .def_property_readonly(
          "tvec", [](const calib::Camera& c) { return floatArray(c.tvec.val); },
          "float64 (3,): world -> camera translation (metres)")
      .def(
          "with_pose",
          [](const calib::Camera& c, const py::handle& rvec, const py::handle& tvec) {
            const std::vector<double> r = stateVector(rvec, "rvec", 3), t = stateVector(tvec, "tvec", 3);
            for (double v : r)
              if (!std::isfinite(v)) throw py::value_error("rvec: must be finite");
            for (double v : t)
              if (!std::isfinite(v)) throw py::value_error("tvec: must be finite");
            calib::Camera out = c;
            out.rvec = cv::Vec3d(r[0], r[1], r[2]);
            out.tvec = cv::Vec3d(t[0], t[1], t[2]);
            out.reprojection_rms_px.reset();
            out.rotation_sigma_deg.reset();
            out.position_sigma_m.reset();
            return out;
          },
          py::arg("rvec"), py::arg("tvec"),
          "A copy with the pose (world -> camera) set to rvec, tvec (float64 (3,) each; a rough start for "
          "refine_to_masks, say) and no quality figures.")
      .def_readonly("reprojection_rms_px", &calib::Camera::reprojection_rms_px,
                    "Calibration quality: RMS distance in pixels between the points seen and their projections, "
                    "or None when the file has none.")
      .def_readonly("rotation_sigma_deg", &calib::Camera::rotation_sigma_deg,
                    "Calibration quality: 1 sigma of the camera's rotation in degrees, or None when the file has none.")
      .def_readonly("position_sigma_m", &calib::Camera::position_sigma_m,
                    "Calibration quality: 1 sigma of the camera's position in metres, or None when the file has none.")
      .def("__repr__", [](const calib::Camera& c) {
        return "<kccd.Camera " + std::to_string(c.width) + "x" + std::to_string(c.height) + ">";
      });

  m.def(
      "render",
      [](const std::shared_ptr<ModelHandle>& h, const calib::Camera& camera, const py::object& state,
         const py::object& lower, const py::object& upper, bool mask, bool legend) {
        const Model& model = *h->model;
        const int n = model.stateSize();
        std::vector<double> st, lo, hi;
        if (!state.is_none()) st = stateVector(state, "state", n);
        if (lower.is_none() != upper.is_none()) throw py::value_error("lower, upper: give both (a box) or neither");
        if (!lower.is_none()) {
          lo = stateVector(lower, "lower", n);
          hi = stateVector(upper, "upper", n);
          if (st.empty())
            for (int k = 0; k < n; ++k)
              st.push_back(0.5 * (lo[static_cast<std::size_t>(k)] + hi[static_cast<std::size_t>(k)]));
        }
        cv::Mat rgba, labels;
        std::vector<SafetyStatus> status;
        std::vector<double> distances;
        {
          py::gil_scoped_release release;
          render::ModelView view(model, camera);
          render::ModelViewRequest req;
          req.state = st;
          req.lower = lo;
          req.upper = hi;
          req.mask = mask;
          req.style.legend = legend;
          const render::ModelFrame f = view.draw(req);
          cv::cvtColor(f.images.bgra, rgba, cv::COLOR_BGRA2RGBA);
          if (mask) labels = f.images.mask;
          status = f.status;
          distances = f.distances;
        }
        py::dict out;
        out["rgba"] = imageArray(rgba);
        out["labels"] = mask ? py::object(imageArray(labels)) : py::object(py::none());
        py::list sts;
        for (SafetyStatus s : status) sts.append(toString(s));
        out["status"] = sts;
        out["distances"] = distances;
        return out;
      },
      py::arg("model"), py::arg("camera"), py::kw_only(), py::arg("state") = py::none(), py::arg("lower") = py::none(),
      py::arg("upper") = py::none(), py::arg("mask") = false, py::arg("legend") = true,
      R"doc(Draws the model's volumes off-screen as `camera` sees them: static at `state`, or swept over the box
[lower, upper] (float64 (state_size,) each), coloured by a distances query (green clear, orange within the
margin, red colliding). Returns a dict: 'rgba' uint8 (H, W, 4) C-contiguous, channels R, G, B, A (straight
alpha: composite as rgb * a / 255 over the frame); 'labels' uint8 (H, W) with mask=True (body i drawn as
label i + 1, 0 nothing), else None; 'status' per body ('clear', 'within_margin', 'colliding', 'no_state');
'distances' per body, its smallest pair bound (metres). Makes a GL context per call (EGL or OSMesa);
raises GlContextError without one. The GIL is released while drawing.)doc");
}

}  // namespace kccd::python

// kccd_example_render_frame MODEL.yaml CAMERA.yaml OUT.png: the model's volumes at its zero state,
// coloured by the query's answer, rendered off-screen from the camera and written as an RGBA PNG.
// Exit 0 when something was drawn.
#include <cstdio>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include <kccd/calib/camera.hpp>
#include <kccd/model.hpp>
#include <kccd/render/model_view.hpp>

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: kccd_example_render_frame MODEL.yaml CAMERA.yaml OUT.png\n");
    return 2;
  }
  try {
    const kccd::Model model = kccd::loadModel(argv[1]);
    const kccd::calib::Camera camera = kccd::calib::loadCamera(argv[2]);
    kccd::render::ModelView view(model, camera);  // a checker and one off-screen GL context (EGL or OSMesa)
    const std::vector<double> state(model.stateSize(), 0.0);
    kccd::render::ModelViewRequest request;
    request.state = state;  // static volumes at this configuration, coloured by a query there
    const kccd::render::ModelFrame frame = view.draw(request);
    if (!cv::imwrite(argv[3], frame.images.bgra)) return 1;
    const int drawn = cv::countNonZero(frame.images.mask);
    std::printf("%s: %dx%d, %d pixels covered by %zu volumes (%s)\n", argv[3], frame.images.bgra.cols,
                frame.images.bgra.rows, drawn, model.bodies.size(), view.renderer().rendererString().c_str());
    return drawn > 0 ? 0 : 1;
  } catch (const kccd::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
}

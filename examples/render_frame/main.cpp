// kccd_example_render_frame MODEL.yaml CAMERA.yaml OUT.png: the model's volumes at its zero state,
// coloured by the query's answer, rendered off-screen from the camera and written as an RGBA PNG.
// Exit 0 when something was drawn.
#include <cstdio>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include <kccd/calib/camera.hpp>
#include <kccd/checker.hpp>
#include <kccd/model.hpp>
#include <kccd/render/renderer.hpp>
#include <kccd/render/scene.hpp>

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: kccd_example_render_frame MODEL.yaml CAMERA.yaml OUT.png\n");
    return 2;
  }
  try {
    const kccd::Model model = kccd::loadModel(argv[1]);
    const kccd::calib::Camera camera = kccd::calib::loadCamera(argv[2]);
    kccd::Checker checker(model);
    const std::vector<double> state(model.stateSize(), 0.0);
    const kccd::QueryResult& result = checker.query(state, state, kccd::QueryOptions{.type = kccd::QueryType::Distances});
    const std::vector<kccd::SafetyStatus> status = kccd::render::bodyStatus(model, result);  // the colours
    kccd::render::Renderer renderer(camera);  // one off-screen GL context (EGL or OSMesa)
    const kccd::render::Frame frame =
        renderer.render(kccd::render::staticSceneVolumes(model, checker, state, status), {}, true, true);
    if (!cv::imwrite(argv[3], frame.bgra)) return 1;
    const int drawn = cv::countNonZero(frame.mask);
    std::printf("%s: %dx%d, %d pixels covered by %zu volumes (%s)\n", argv[3], frame.bgra.cols, frame.bgra.rows, drawn,
                model.bodies.size(), renderer.rendererString().c_str());
    return drawn > 0 ? 0 : 1;
  } catch (const kccd::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
}

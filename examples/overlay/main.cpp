// kccd_example_overlay MODEL.yaml CAMERA.yaml VIDEO STATES.csv TIME_OFFSET OUT_DIR: the collision
// volumes at each frame's logged state composited onto the recording, written as
// OUT_DIR/overlay.mkv and OUT_DIR/report.json (the format of `kccd overlay --report`). Exit 0
// when every frame was checked and none is unsafe, 3 when one is, 2 for bad input.
#include <cstdio>
#include <cstdlib>
#include <string>

#include <kccd/calib/camera.hpp>
#include <kccd/model.hpp>
#include <kccd/overlay/common/staged_output.hpp>
#include <kccd/overlay/recording/overlay_recording.hpp>
#include <kccd/overlay/recording/video_sink.hpp>
#include <kccd/state_log.hpp>
#include <nlohmann/json.hpp>

int main(int argc, char** argv) {
  if (argc != 7) {
    std::fprintf(stderr, "usage: kccd_example_overlay MODEL.yaml CAMERA.yaml VIDEO STATES.csv TIME_OFFSET OUT_DIR\n");
    return 2;
  }
  try {
    const kccd::Model model = kccd::loadModel(argv[1]);
    const kccd::calib::Camera camera = kccd::calib::loadCamera(argv[2]);
    const kccd::StateLog log = kccd::loadStateLog(argv[4], model);
    const std::string out = argv[6];

    const kccd::overlay::OverlayInputs inputs{model, camera, log, argv[3]};
    kccd::overlay::OverlayOptions options;
    options.time_offset = std::strtod(argv[5], nullptr);  // log time = video time + offset
    options.contact_frames = 0;
    kccd::overlay::VideoSink video({.video = out + "/overlay.mkv"});  // lossless FFV1, staged
    const kccd::overlay::OverlayReport report =
        kccd::overlay::overlayRecording(inputs, options, &video, [](const kccd::overlay::OverlayProgress& p) {
          if (p.frames_done % 25 == 0)
            std::fprintf(stderr, "%zu frames, %.1f fps\n", p.frames_done, p.frames_per_second);
        });
    video.commit();  // the video appears whole, or not at all
    kccd::overlay::writeFileAtomically(out + "/report.json",
                                       kccd::overlay::reportJson(report, model, true).dump(1) + "\n");

    std::printf(
        "%zu frames: clear %zu, within margin %zu, colliding %zu, no state %zu (%.1f frames/s with %d threads)\n",
        report.frames.size(), report.clear, report.within_margin, report.colliding, report.no_state,
        report.frames.size() / (report.seconds > 0 ? report.seconds : 1.0), report.jobs);
    return report.firstUnsafe() ? 3 : 0;
  } catch (const kccd::InputError& e) {  // every reader's and the job's input errors: one line
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
}

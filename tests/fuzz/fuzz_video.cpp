// libFuzzer target: recordings as `kccd overlay` and `kccd calib --video` open them
// (kccd::overlay::VideoSource over FFmpeg: overlay::VideoFileReader). Any input must open and decode, or
// be rejected with kccd::InputError (overlay::VideoError) naming the recording on one line; any
// other exception, a crash, a hang or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include <opencv2/core.hpp>

#include "fuzz_support.hpp"
#include "kccd/input_error.hpp"
#include "kccd/overlay/recording/video_source.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = kccd::fuzz::writeInput("fuzz_video", "clip.mkv", data, size);
  try {
    kccd::overlay::VideoSource video(path, path);
    cv::Mat frame;
    // A few frames are enough to reach the decoders; each must be a non-empty 8-bit image.
    for (int i = 0; i < 4 && video.read(frame); ++i) {
      if (frame.empty() || frame.depth() != CV_8U) std::abort();
      if (video.nextIndex() != static_cast<std::size_t>(i) + 1) std::abort();
    }
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  return 0;
}

// AprilTag detection through libapriltag (tag36h11), corners moved to OpenCV's pixel convention.
#include "kccd/calib/tag_detect.hpp"

#include <apriltag/apriltag.h>
#include <apriltag/common/zarray.h>
#include <apriltag/tag36h11.h>

#include <algorithm>
#include <memory>
#include <stdexcept>

namespace kccd::calib {

std::vector<TagDetection> detectTags(const cv::Mat& gray) {
  if (gray.empty() || gray.type() != CV_8UC1)
    throw std::invalid_argument("detectTags: needs a non-empty 8-bit single-channel image");
  // A tag36h11 tag is 8 cells across with its black border, so an image under 8 pixels in either
  // direction holds none; libapriltag 3.3 also reads outside images under 3 rows (a crash).
  if (gray.rows < kMinTagPixels || gray.cols < kMinTagPixels) return {};
  const cv::Mat image = gray.isContinuous() ? gray : gray.clone();
  const std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> family(tag36h11_create(), tag36h11_destroy);
  const std::unique_ptr<apriltag_detector_t, void (*)(apriltag_detector_t*)> detector(apriltag_detector_create(),
                                                                                      apriltag_detector_destroy);
  if (!family || !detector) throw std::bad_alloc();
  apriltag_detector_add_family(detector.get(), family.get());
  detector->quad_decimate = 1.0f;  // full resolution: corner accuracy over speed
  detector->quad_sigma = 0.0f;
  detector->refine_edges = 1;
  detector->nthreads = 1;
  image_u8_t im{.width = image.cols,
                .height = image.rows,
                .stride = static_cast<int32_t>(image.step[0]),
                .buf = const_cast<uint8_t*>(image.ptr<uint8_t>())};
  const std::unique_ptr<zarray_t, void (*)(zarray_t*)> found(apriltag_detector_detect(detector.get(), &im),
                                                             apriltag_detections_destroy);
  std::vector<TagDetection> out;
  for (int i = 0; found && i < zarray_size(found.get()); ++i) {
    apriltag_detection_t* d = nullptr;
    zarray_get(found.get(), i, &d);
    TagDetection t;
    t.id = d->id;
    for (int k = 0; k < 4; ++k)
      t.corners[static_cast<std::size_t>(k)] = cv::Point2d(d->p[k][0] - 0.5, d->p[k][1] - 0.5);
    t.hamming = d->hamming;
    t.decision_margin = d->decision_margin;
    out.push_back(t);
  }
  return out;
}

TagCorrespondences tagCorrespondences(std::span<const TagDetection> detections, const TagLayout& layout,
                                      const std::string& image) {
  TagCorrespondences out;
  std::vector<int> seen;
  for (const TagDetection& d : detections) {
    if (std::find(seen.begin(), seen.end(), d.id) != seen.end())
      throw TagDetectionError(image + ": tags: tag " + std::to_string(d.id) +
                              " is detected twice (each id may appear once: is it printed twice?)");
    seen.push_back(d.id);
    const Tag* tag = layout.find(d.id);
    if (!tag) {
      out.unknown_ids.push_back(d.id);
      continue;
    }
    const auto world = tag->corners();
    for (std::size_t k = 0; k < 4; ++k)
      out.points.push_back({"tag" + std::to_string(d.id) + ".c" + std::to_string(k), d.corners[k], world[k]});
  }
  std::sort(out.unknown_ids.begin(), out.unknown_ids.end());
  return out;
}

}  // namespace kccd::calib

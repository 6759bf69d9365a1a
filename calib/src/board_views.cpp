#include "kccd/calib/board_views.hpp"

#include "kccd/calib/image_file.hpp"
#include "kccd/calib/tag_detect.hpp"

namespace kccd::calib {

BoardViews detectBoardViews(const std::vector<std::string>& images, const Board& board,
                            const std::function<void(double)>& progress) {
  BoardViews out;
  for (std::size_t i = 0; i < images.size(); ++i) {
    const std::string& path = images[i];
    const cv::Mat gray = readImageFile(path, ImageColour::Grey);
    if (i == 0) {
      out.image_size = gray.size();
    } else if (gray.size() != out.image_size) {
      throw ImageError(path + ": image: " + std::to_string(gray.cols) + "x" + std::to_string(gray.rows) +
                       " differs from " + images[0] + " (" + std::to_string(out.image_size.width) + "x" +
                       std::to_string(out.image_size.height) +
                       "): all images must come from one camera at one resolution");
    }
    const TagCorrespondences tc = tagCorrespondences(detectTags(gray), board.layout, path);
    out.views.push_back({path, tc.points});
    out.tags.push_back(static_cast<int>(tc.points.size() / 4));
    out.unknown_ids.push_back(tc.unknown_ids);
    if (progress) progress(static_cast<double>(i + 1) / static_cast<double>(images.size()));
  }
  return out;
}

}  // namespace kccd::calib

// Frame-times files (kccd/overlay/recording/frame_times.hpp): the table, and one exact message per mistake.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

#include "kccd/overlay/recording/frame_times.hpp"

namespace kccd::overlay {
namespace {

std::string errorOf(const std::string& text) {
  try {
    parseFrameTimes(text, "t.csv");
  } catch (const FrameTimesError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(FrameTimes, ReadsTheTable) {
  EXPECT_EQ(parseFrameTimes("frame,time\n0,0\n1,0.04\n2,0.09\n", "t.csv"), (std::vector<double>{0.0, 0.04, 0.09}));
  // BOM, CRLF, no final newline, signed and exponent forms.
  EXPECT_EQ(parseFrameTimes("\xEF\xBB\xBF"
                            "frame,time\r\n0,-1.5e-3\r\n1,2e0",
                            "t.csv"),
            (std::vector<double>{-1.5e-3, 2.0}));
}

TEST(FrameTimes, EveryMistakeNamesItsLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "t.csv: no rows"},
      {"frame,time\n", "t.csv: no rows"},
      {"time,frame\n0,0\n", "t.csv:1:1: the header must be 'frame,time' (found 'time,frame')"},
      {"frame,time\n0,0\n\n1,1\n", "t.csv:3:1: empty line"},
      {"frame,time\n0;0\n", "t.csv:2:1: expected two fields: frame,time"},
      {"frame,time\n0,0,0\n", "t.csv:2:1: expected two fields: frame,time"},
      {"frame,time\n-1,0\n", "t.csv:2:1: column 'frame': not a frame number: '-1'"},
      {"frame,time\n0,abc\n", "t.csv:2:3: column 'time': not a finite number: 'abc'"},
      {"frame,time\n0,nan\n", "t.csv:2:3: column 'time': not a finite number: 'nan'"},
      {"frame,time\n0,1e301\n", "t.csv:2:3: column 'time': not a finite number: '1e301'"},
      {"frame,time\n0,0\n2,1\n",
       "t.csv:3:1: column 'frame': expected frame 1, found 2 (one row per frame, from 0, in order)"},
      {"frame,time\n0,0\n0,1\n",
       "t.csv:3:1: column 'frame': expected frame 1, found 0 (one row per frame, from 0, in order)"},
      {"frame,time\n0,1\n1,1\n", "t.csv:3:3: column 'time': times must increase strictly"},
      {"frame,time\n0,0\n1,\x1b[31m\n", "t.csv:3:3: column 'time': not a finite number: '\\x1b[31m'"},
  };
  for (const auto& [text, message] : cases) EXPECT_EQ(errorOf(text), message) << text;
}

TEST(FrameTimes, FilesAreRegularAndBounded) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("kccd_frame_times_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "times.csv").string();
  std::ofstream(file) << "frame,time\n0,0.5\n";
  EXPECT_EQ(loadFrameTimes(file), std::vector<double>{0.5});
  auto error = [](const std::string& path) {
    try {
      loadFrameTimes(path);
    } catch (const FrameTimesError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(error((dir / "missing.csv").string()),
            (dir / "missing.csv").string() + ": cannot open the frame-times file (no such file)");
  EXPECT_EQ(error(dir.string()), dir.string() + ": a folder, not a frame-times file");
  const std::string fifo = (dir / "fifo").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(error(fifo), fifo + ": not a regular file (a device, FIFO or socket)");  // refused without blocking
  std::filesystem::remove_all(dir);
}

// The frame-times reader fills the error's location as data (line, column, field), as every table reader does.
TEST(FrameTimesFile, ErrorsCarryLineColumnAndField) {
  try {
    (void)parseFrameTimes("frame,time\n0,0\n1,x\n", "t.csv");
    ADD_FAILURE();
  } catch (const FrameTimesError& e) {
    EXPECT_STREQ(e.what(), "t.csv:3:3: column 'time': not a finite number: 'x'");
    EXPECT_EQ(e.location().line, 3u);
    EXPECT_EQ(e.location().column, 3u);
    EXPECT_EQ(e.location().field, "column 'time'");
  }
}

}  // namespace
}  // namespace kccd::overlay

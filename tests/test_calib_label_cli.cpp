// `kccd calib label` as a person or a script starts it: the address on the first line of stdout,
// Ctrl+C (SIGINT) or SIGTERM ends it with exit 0, a warning when it listens beyond this machine,
// and the mistakes of its command line or inputs as one line naming the file and place, exit 2,
// before anything is served or written.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "support/run_program.hpp"

namespace {

namespace fs = std::filesystem;
using kccd::testing::Outcome;
const std::string kData = KCCD_DATA_DIR;
const std::string kCli = KCCD_CLI;

class CalibLabelCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("kccd_label_cli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    frame_ = (dir_ / "frame.png").string();
    cv::imwrite(frame_, cv::Mat(720, 1280, CV_8UC3, cv::Scalar(80, 90, 100)));
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string base() const {
    return kCli + " calib label --intrinsics " + kData + "/demo_camera.yaml --image " + frame_ + " --model " + kData +
           "/demo_arm.yaml --state 0.3,0.4,0.6";
  }

  // Starts the server in the background, waits for its first line, sends `signal`, and returns
  // its stdout, then "rc=N", then its stderr after a line "--".
  Outcome serveAndStop(const std::string& args, const char* signal) {
    const std::string out = (dir_ / "out.txt").string(), err = (dir_ / "err.txt").string();
    const std::string script = base() + " " + args + " > " + out + " 2> " + err +
                               " & p=$!; for i in $(seq 300); do [ -s " + out +
                               " ] && break; sleep 0.05; done; kill -" + signal + " $p; wait $p; echo rc=$? >> " + out +
                               "; cat " + out + "; echo --; cat " + err;
    return kccd::testing::runProgram(script);
  }

  fs::path dir_;
  std::string frame_;
};

TEST_F(CalibLabelCli, PrintsItsAddressFirstAndEndsOnSignals) {
  for (const char* signal : {"INT", "TERM"}) {
    const std::string labels = (dir_ / "labels.yaml").string();
    const Outcome o = serveAndStop("--labels " + labels, signal);
    EXPECT_TRUE(std::regex_search(o.out, std::regex("^http://127\\.0\\.0\\.1:[0-9]+/\nrc=0\n--\n"))) << o.out;
    EXPECT_NE(o.out.find("rc=0"), std::string::npos) << signal << ": " << o.out;
    EXPECT_NE(o.out.find("serving 1 frame(s); labels go to " + labels), std::string::npos) << o.out;
    EXPECT_FALSE(fs::exists(labels)) << "nothing labelled, nothing saved: no file";
  }
}

TEST_F(CalibLabelCli, WarnsWhenReachableFromOtherMachines) {
  const Outcome o = serveAndStop("--labels " + (dir_ / "l.yaml").string() + " --host 0.0.0.0 -q", "TERM");
  EXPECT_NE(o.out.find("warning: --host 0.0.0.0: the page and its API are reachable from other machines"),
            std::string::npos)
      << o.out;
  EXPECT_TRUE(std::regex_search(o.out, std::regex("http://0\\.0\\.0\\.0:[0-9]+/"))) << o.out;
  EXPECT_NE(o.out.find("rc=0"), std::string::npos) << o.out;
}

TEST_F(CalibLabelCli, MistakesAreOneLineAndExit2) {
  const std::string labels = (dir_ / "labels.yaml").string();
  struct Case {
    std::string args, expected;
  };
  std::ofstream(dir_ / "bad.yaml") << "labels:\n  - {name: a, pixel: [1, 2], world: [0, 0]}\n";
  cv::imwrite((dir_ / "small.png").string(), cv::Mat(10, 10, CV_8UC3, cv::Scalar(0, 0, 0)));
  const Case cases[] = {
      {"", "--labels LABELS.yaml is required"},
      {"--labels " + (dir_ / "l.txt").string(), "must be a .yaml or .yml file"},
      {"--labels " + labels + " -o " + (dir_ / "cam.txt").string(), "the camera file must be a .yaml or .yml file"},
      {"--labels " + (dir_ / "bad.yaml").string(), (dir_ / "bad.yaml").string() + ":2:"},
      {"--labels " + labels + " --image " + (dir_ / "small.png").string(), "--labels: given 1 times for 2"},
      {"--labels " + labels + " --web-root " + (dir_ / "nothing").string(),
       "--web-root " + (dir_ / "nothing").string() + ": not a folder"},
      // Snap to the robot: a mask per frame, of the camera's size, with robot in it.
      {"--labels " + labels + " --masks " + (dir_ / "small.png").string(), "small.png: mask: 10x10, but the camera"},
      {"--labels " + labels + " --masks " + frame_ + " " + frame_, "--masks: 2 mask(s) for 1 frame(s)"},
      {"--labels " + labels + " --mask-bodies arm", "--mask-bodies: goes with --masks"},
  };
  for (const Case& c : cases) {
    const Outcome o = kccd::testing::runProgram(base() + " " + c.args + " -q");
    EXPECT_EQ(o.code, 2) << c.args << "\n" << o.err;
    EXPECT_NE(o.err.find(c.expected), std::string::npos) << c.args << "\n" << o.err;
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
    EXPECT_TRUE(o.out.empty()) << "no address printed: " << o.out;
  }
  // A frame of another size than the camera.
  const Outcome o =
      kccd::testing::runProgram(kCli + " calib label --intrinsics " + kData + "/demo_camera.yaml --image " +
                                (dir_ / "small.png").string() + " --labels " + labels + " -q");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("small.png"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(labels));
}

}  // namespace

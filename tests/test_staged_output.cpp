// Staged outputs: nothing appears under the target's name until commit(), what was not committed
// is removed, and a committed output has the permissions a plain create would give (checked
// against open(2)/mkdir(2) themselves under two umasks).
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "kccd/overlay/common/staged_output.hpp"
#include "support/files.hpp"

namespace fs = std::filesystem;
using kccd::overlay::OutputError;
using kccd::overlay::StagedOutput;
using kccd::testing::readText;

namespace {

class StagedOutputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("kccd_staged_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    old_mask_ = ::umask(022);
  }
  void TearDown() override {
    ::umask(old_mask_);
    fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // Everything in the test folder, sorted (temporary names included).
  std::string listing() const {
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.insert(e.path().filename().string());
    std::string out;
    for (const auto& n : names) out += n + " ";
    return out;
  }
  static unsigned modeOf(const std::string& p) {
    struct stat st {};
    EXPECT_EQ(::stat(p.c_str(), &st), 0) << p;
    return st.st_mode & 07777;
  }

  fs::path dir_;
  mode_t old_mask_ = 022;
};

TEST_F(StagedOutputTest, NewFilesAndFoldersGetWhatAPlainCreateGives) {
  for (const mode_t mask : {mode_t{022}, mode_t{077}, mode_t{002}}) {
    ::umask(mask);
    const std::string plain_file = path("plain_" + std::to_string(mask)), plain_dir = plain_file + "_dir";
    const int fd = ::open(plain_file.c_str(), O_CREAT | O_WRONLY, 0666);
    ASSERT_GE(fd, 0);
    ::close(fd);
    ASSERT_EQ(::mkdir(plain_dir.c_str(), 0777), 0);
    EXPECT_EQ(kccd::overlay::plainCreateMode(false), modeOf(plain_file));
    EXPECT_EQ(kccd::overlay::plainCreateMode(true), modeOf(plain_dir));

    const std::string report = path("report_" + std::to_string(mask) + ".json");
    kccd::overlay::writeFileAtomically(report, "{}\n");
    EXPECT_EQ(readText(report), "{}\n");
    EXPECT_EQ(modeOf(report), modeOf(plain_file)) << "umask " << mask;

    // A file a writer fills by its own name (a video), and a folder of frames.
    StagedOutput video(path("out_" + std::to_string(mask) + ".mp4"), StagedOutput::Kind::File, "-o out.mp4");
    EXPECT_EQ(video.path().extension(), ".mp4");  // the writer picks the container by it
    std::ofstream(video.path()) << "frames";
    video.commit();
    EXPECT_EQ(modeOf(video.target().string()), modeOf(plain_file)) << "umask " << mask;
    StagedOutput frames(path("pngs_" + std::to_string(mask)), StagedOutput::Kind::Folder, "--png-dir pngs");
    std::ofstream(frames.path() / "frame_000000.png") << "png";
    frames.commit();
    EXPECT_EQ(modeOf(frames.target().string()), modeOf(plain_dir)) << "umask " << mask;
    EXPECT_EQ(readText(frames.target().string() + "/frame_000000.png"), "png");
  }
}

TEST_F(StagedOutputTest, NothingUnderTheTargetNameBeforeCommitNothingLeftWithout) {
  {
    StagedOutput video(path("out.mkv"), StagedOutput::Kind::File, "-o out.mkv");
    std::ofstream(video.path()) << "half a video";
    EXPECT_FALSE(fs::exists(path("out.mkv")));
  }  // abandoned: a killed run leaves nothing that looks complete
  EXPECT_EQ(listing(), "");
  {
    StagedOutput frames(path("pngs"), StagedOutput::Kind::Folder, "--png-dir pngs");
    std::ofstream(frames.path() / "frame_000000.png") << "png";
  }
  EXPECT_EQ(listing(), "");
  // An existing file is untouched until commit, then replaced whole and keeps its mode.
  kccd::overlay::writeFileAtomically(path("model.yaml"), "old\n");
  ASSERT_EQ(::chmod(path("model.yaml").c_str(), 0640), 0);
  {
    StagedOutput edit(path("model.yaml"), StagedOutput::Kind::File, "model.yaml");
    std::ofstream(edit.path()) << "new\n";
    EXPECT_EQ(readText(path("model.yaml")), "old\n");
    edit.commit();
  }
  EXPECT_EQ(readText(path("model.yaml")), "new\n");
  EXPECT_EQ(modeOf(path("model.yaml")), 0640u);
  EXPECT_EQ(listing(), "model.yaml ");
}

TEST_F(StagedOutputTest, SymbolicLinksStayLinks) {
  fs::create_directory(path("real"));
  kccd::overlay::writeFileAtomically(path("real/camera.yaml"), "a\n");
  fs::create_symlink("real/camera.yaml", path("camera.yaml"));
  kccd::overlay::writeFileAtomically(path("camera.yaml"), "b\n");
  EXPECT_TRUE(fs::is_symlink(path("camera.yaml")));
  EXPECT_EQ(readText(path("real/camera.yaml")), "b\n");
}

TEST_F(StagedOutputTest, FoldersAreNotMixedUnlessReplaced) {
  fs::create_directory(path("run"));
  std::ofstream(path("run/old.txt")) << "old";
  try {
    StagedOutput frames(path("run"), StagedOutput::Kind::Folder, "--png-dir run");
    FAIL() << "a non-empty folder was accepted";
  } catch (const OutputError& e) {
    EXPECT_EQ(std::string(e.what()), "--png-dir run: the folder is not empty (kccd does not mix runs)");
  }
  {
    StagedOutput synth(path("run/"), StagedOutput::Kind::Folder, "-o run", StagedOutput::Existing::ReplaceFolder);
    std::ofstream(synth.path() / "new.txt") << "new";
    EXPECT_TRUE(fs::exists(path("run/old.txt")));  // the old run stays until the new one is whole
    synth.commit();
  }
  EXPECT_FALSE(fs::exists(path("run/old.txt")));
  EXPECT_EQ(readText(path("run/new.txt")), "new");
  EXPECT_EQ(listing(), "run ");  // the old folder moved aside is gone
  // An empty folder is simply taken.
  fs::create_directory(path("empty"));
  StagedOutput frames(path("empty"), StagedOutput::Kind::Folder, "--png-dir empty");
  frames.commit();
  EXPECT_TRUE(fs::is_directory(path("empty")));
}

TEST_F(StagedOutputTest, ErrorsNameTheOutputAsGiven) {
  try {
    StagedOutput video(path("missing/out.mp4"), StagedOutput::Kind::File, "-o missing/out.mp4");
    FAIL() << "a missing folder was accepted";
  } catch (const OutputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("-o missing/out.mp4: folder ", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
  kccd::overlay::writeFileAtomically(path("file"), "x");
  EXPECT_THROW(StagedOutput(path("file"), StagedOutput::Kind::Folder, "-o file"), OutputError);
  if (::geteuid() != 0) {  // root writes anywhere
    fs::create_directory(path("locked"));
    fs::permissions(path("locked"), fs::perms::owner_read | fs::perms::owner_exec);
    EXPECT_THROW(kccd::overlay::writeFileAtomically(path("locked/r.json"), "{}"), OutputError);
    fs::permissions(path("locked"), fs::perms::owner_all);
  }
}

}  // namespace

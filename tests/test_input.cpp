// The input foundation: the bounded regular-file reader, InputError's location as data, the YAML
// reader's places, and the one number formatter.
#include <gtest/gtest.h>

#include <cerrno>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <sys/stat.h>
#include <unistd.h>

#include "kccd/file_reader.hpp"
#include "kccd/format_number.hpp"
#include "kccd/input_error.hpp"
#include "kccd/model.hpp"
#include "kccd/state_log.hpp"
#include "kccd/yaml_reader.hpp"

namespace kccd {
namespace {

namespace fs = std::filesystem;

class FileReader : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) / ("kccd_file_reader_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& bytes) const {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }

  // The FileError of reading `path` with `max_bytes` (fails the test when the read succeeds).
  static FileError errorOf(const std::string& path, std::uintmax_t max_bytes = 1000,
                           const std::string& label = "file") {
    try {
      (void)readRegularFile(path, max_bytes, label);
    } catch (const FileError& e) {
      return e;
    }
    ADD_FAILURE() << path << " was read";
    return FileError(path, label, FileProblem::CannotRead, 0, 0, max_bytes);
  }

  fs::path dir_;
};

TEST_F(FileReader, ReadsEveryByteUpToTheBound) {
  const std::string bytes = std::string("a\0b\r\n", 5) + std::string(995, 'x');
  EXPECT_EQ(readRegularFile(write("exact.bin", bytes), 1000), bytes);  // exactly the bound
  EXPECT_EQ(readRegularFile(write("empty.txt", ""), 0), "");
}

TEST_F(FileReader, RefusesAFileOverTheBound) {
  const std::string path = write("big.txt", std::string(1001, 'x'));
  const FileError e = errorOf(path, 1000);
  EXPECT_EQ(e.kind(), FileProblem::TooLarge);
  EXPECT_EQ(e.size(), 1001u);
  EXPECT_EQ(e.maxBytes(), 1000u);
  const FileError kib = errorOf(write("big2.txt", std::string(3000, 'x')), 2048, "tag layout");
  EXPECT_EQ(std::string(kib.what()), (dir_ / "big2.txt").string() + ": larger than 2 KiB");
}

TEST_F(FileReader, RefusesFoldersDevicesAndFifosWithoutBlocking) {
  const FileError folder = errorOf(dir_.string());
  EXPECT_EQ(folder.kind(), FileProblem::Directory);
  EXPECT_EQ(std::string(folder.what()), dir_.string() + ": a folder, not a file");
  EXPECT_EQ(errorOf("/dev/zero").kind(), FileProblem::NotRegular);  // would never end if read
  const std::string fifo = (dir_ / "fifo").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(errorOf(fifo).kind(), FileProblem::NotRegular);  // would block if opened for reading
}

TEST_F(FileReader, NamesAMissingFileAndItsSource) {
  const std::string missing = (dir_ / "missing.yaml").string();
  const FileError e = errorOf(missing, 1000, "camera file");
  EXPECT_EQ(e.kind(), FileProblem::Missing);
  EXPECT_EQ(e.systemError(), ENOENT);
  EXPECT_EQ(e.systemReason(), "no such file");
  EXPECT_EQ(std::string(e.what()), missing + ": cannot open the camera file (no such file)");
  EXPECT_EQ(e.location().source, missing);
  EXPECT_EQ(e.location().field, "");
  EXPECT_EQ(e.location().line, 0u);
  EXPECT_EQ(e.problem(), "cannot open the camera file (no such file)");
  // A part of the path that is not a folder: no such file either way.
  const std::string under_file = write("plain.txt", "x") + "/inside.yaml";
  EXPECT_EQ(errorOf(under_file).kind(), FileProblem::Missing);
}

TEST_F(FileReader, NamesAFileItCannotOpen) {
  if (::geteuid() == 0) GTEST_SKIP() << "root opens any file";
  const std::string path = write("locked.txt", "x");
  fs::permissions(path, fs::perms::none);
  const FileError e = errorOf(path);
  EXPECT_EQ(e.kind(), FileProblem::CannotOpen);
  EXPECT_EQ(e.systemError(), EACCES);
}

TEST(InputErrorLocation, BuildsTheOneLineMessageFromItsParts) {
  const InputError full({"cell.yaml", 3, 7, "joints[0].axis"}, "zero axis");
  EXPECT_STREQ(full.what(), "cell.yaml:3:7: joints[0].axis: zero axis");
  EXPECT_EQ(full.location().line, 3u);
  EXPECT_EQ(full.location().column, 7u);
  EXPECT_EQ(full.problem(), "zero axis");
  EXPECT_STREQ(InputError({"log.csv", 4, 0, {}}, "empty line").what(), "log.csv:4: empty line");
  EXPECT_STREQ(InputError({"cam.yaml", 0, 0, "rvec"}, "non-finite value").what(), "cam.yaml: rvec: non-finite value");
  // A message given whole: no location, the problem is the message.
  const InputError plain("something: wrong");
  EXPECT_STREQ(plain.what(), "something: wrong");
  EXPECT_TRUE(plain.location().source.empty());
  EXPECT_EQ(plain.problem(), "something: wrong");
}

TEST(InputErrorLocation, ShowsAnotherSourceWithoutParsingTheMessage) {
  const InputError e({"camera", 0, 0, "supersample"}, "must be in 1..4");
  EXPECT_EQ(e.messageFrom("studio.yaml"), "studio.yaml: supersample: must be in 1..4");
  EXPECT_STREQ(e.what(), "camera: supersample: must be in 1..4");  // unchanged
  EXPECT_EQ(InputError({"grid", 0, 0, "cols"}, "0 is not in 1..587").messageFrom("--grid 0x4"),
            "--grid 0x4: cols: 0 is not in 1..587");
  EXPECT_EQ(InputError("no place known").messageFrom("x.yaml"), "x.yaml: no place known");
  // A subclass keeps the data it is rebuilt from.
  const ModelError m(e.location(), e.problem());
  EXPECT_STREQ(m.what(), e.what());
  EXPECT_EQ(m.location().field, "supersample");
}

// The error of parsing `text` as a model named cell.yaml.
ModelError modelError(const std::string& text) {
  try {
    (void)parseModel(text, "cell.yaml");
  } catch (const ModelError& e) {
    return e;
  }
  ADD_FAILURE() << "the model loaded";
  return ModelError("none");
}

TEST(InputErrorLocation, TheModelReaderFillsLineColumnAndField) {
  const std::string text =
      "kccd: 1\n"
      "joints:\n"
      "  - {name: j, parent: world, type: revolute, axis: [0, 0, 0]}\n"
      "bodies:\n"
      "  - {name: b, frame: j, points: [[0, 0, 0]], radius: 0.1}\n";
  const ModelError e = modelError(text);
  EXPECT_STREQ(e.what(), "cell.yaml:3:52: joint 'j'.axis: zero axis");
  EXPECT_EQ(e.location().source, "cell.yaml");
  EXPECT_EQ(e.location().line, 3u);
  EXPECT_EQ(e.location().column, 52u);
  EXPECT_EQ(e.location().field, "joint 'j'.axis");
  EXPECT_EQ(e.problem(), "zero axis");
  // From the structural pre-check: a repeated key.
  const ModelError dup = modelError("kccd: 1\nkccd: 1\n");
  EXPECT_EQ(dup.location().line, 2u);
  EXPECT_EQ(dup.location().column, 1u);
  EXPECT_EQ(dup.location().field, "kccd");
  // A missing field is placed at its mapping.
  const ModelError missing = modelError("kccd: 1\nbodies:\n  - {name: b, frame: world, points: [[0, 0, 0]]}\n");
  EXPECT_EQ(missing.location().line, 3u);
  EXPECT_EQ(missing.location().field, "body 'b'.radius");
  EXPECT_EQ(missing.problem(), "required field is missing");
}

TEST(InputErrorLocation, TheYamlReaderPlacesEveryCheck) {
  const YamlReader r("t.yaml", 40);
  const YAML::Node root = r.load("a: [1, x, 3]\nb: \"\"\n");
  try {
    (void)r.vec<3>(root["a"], "a", 10.0, "10");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "t.yaml:1:8: a[1]: expected a number, got 'x'");
    EXPECT_EQ(e.location().column, 8u);
  }
  try {
    (void)r.text(root["b"], "b");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "t.yaml:2:4: b: must not be empty");
  }
  try {
    (void)r.load("a: 1\n---\nb: 2\n");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(e.location().line, 2u);
    EXPECT_EQ(e.location().field, "document");
  }
  EXPECT_EQ(r.where(root["a"]), "t.yaml:1:4");
  EXPECT_EQ(r.where(root["none"]), "t.yaml");  // no place: the source alone
}

// Anchors and aliases share a node: a reader walking the document visits it once per alias.
// Sharing a little is fine; aliases of aliases that multiply a few hundred bytes into billions of
// values are refused at the alias that passes the bound, with its place.
TEST(InputErrorLocation, AliasesThatMultiplyAreRefused) {
  const YamlReader r("t.yaml", 40);
  const YAML::Node ok = r.load("a: &p [1, 2, 3]\nb: *p\nc: *p\n");
  EXPECT_EQ(ok["c"].size(), 3u);
  std::string bomb = "a0: &a0 [1, 2, 3, 4, 5, 6, 7, 8]\n";
  for (int i = 1; i < 40; ++i)
    bomb += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [*a" + std::to_string(i - 1) + ", *a" +
            std::to_string(i - 1) + ", *a" + std::to_string(i - 1) + ", *a" + std::to_string(i - 1) + "]\n";
  try {
    (void)r.load(bomb);
    ADD_FAILURE() << "4^39 values accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("aliases expand the document to more than 4194304 values"), std::string::npos)
        << e.what();
    // The values through a9 number 3.3 million; a10's first alias (line 11) adds 2.4 million more.
    EXPECT_EQ(e.location().line, 11u) << e.what();
  }
  // The bound is a limit: a lower one refuses the small document above.
  YamlLimits small;
  small.max_expanded_nodes = 8;
  EXPECT_THROW((void)r.load("a: &p [1, 2, 3]\nb: *p\nc: *p\n", small), InputError);
}

TEST(InputErrorLocation, TheTableReadersFillLineColumnAndField) {
  Model m = parseModel(
      "kccd: 1\njoints:\n  - {name: q, parent: world, type: prismatic, axis: [1, 0, 0]}\n"
      "bodies:\n  - {name: b, frame: q, points: [[0, 0, 0]], radius: 0.1}\n",
      "m.yaml");
  try {
    (void)parseStateLog("time,q\n0,0\n1,1e999\n", "s.csv", m);
    ADD_FAILURE();
  } catch (const StateLogError& e) {
    EXPECT_EQ(e.location().source, "s.csv");
    EXPECT_EQ(e.location().line, 3u);
    EXPECT_EQ(e.location().column, 3u);
    EXPECT_EQ(e.location().field, "column 'q'");
    EXPECT_EQ(e.problem(), "'1e999' is out of the range of a double");
  }
}

TEST(FormatNumber, PrintsSignificantDigitsAsPrintfDoes) {
  EXPECT_EQ(formatNumber(0.137, 10), "0.137");
  EXPECT_EQ(formatNumber(-2.5, 3), "-2.5");
  EXPECT_EQ(formatNumber(1.0 / 3.0, 3), "0.333");
  EXPECT_EQ(formatNumber(123456789.0, 4), "1.235e+08");
  EXPECT_EQ(formatNumber(1e300, 10), "1e+300");
  EXPECT_EQ(formatNumber(-1.5e-300, 6), "-1.5e-300");
  EXPECT_EQ(formatNumber(std::numeric_limits<double>::denorm_min(), 3), "4.94e-324");
  EXPECT_EQ(formatNumber(std::numeric_limits<double>::max(), 17), "1.7976931348623157e+308");
  EXPECT_EQ(formatNumber(0.1, 17), "0.10000000000000001");  // 17 digits read back exactly
  EXPECT_EQ(formatNumber(-0.0, 6), "-0");
  EXPECT_EQ(formatNumber(HUGE_VAL, 6), "inf");
  EXPECT_EQ(formatNumber(-HUGE_VAL, 6), "-inf");
  EXPECT_EQ(formatNumber(std::numeric_limits<double>::quiet_NaN(), 6), "nan");
  EXPECT_EQ(formatNumber(1.0 / 7.0, 40).size(), 42u);  // more digits than a small buffer holds
}

TEST(FormatNumber, ShortestReadsBackExactly) {
  EXPECT_EQ(shortestNumber(0.1), "0.1");
  EXPECT_EQ(shortestNumber(-2.5), "-2.5");
  EXPECT_EQ(shortestNumber(1e300), "1e+300");
  EXPECT_EQ(shortestNumber(std::numeric_limits<double>::denorm_min()), "5e-324");
  EXPECT_EQ(shortestNumber(-std::numeric_limits<double>::max()), "-1.7976931348623157e+308");
  EXPECT_EQ(shortestNumber(HUGE_VAL), "inf");
  EXPECT_EQ(shortestNumber(std::numeric_limits<double>::quiet_NaN()), "nan");
  for (const double v : {0.137, 1.0 / 3.0, 6.02214076e23, -2.2250738585072014e-308})
    EXPECT_EQ(std::stod(shortestNumber(v)), v) << shortestNumber(v);
}

}  // namespace
}  // namespace kccd

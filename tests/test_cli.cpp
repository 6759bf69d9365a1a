// End-to-end: the kccd program as scripts use it (JSON contract, exit codes, one-line errors).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "kccd/query.hpp"
#include "support/files.hpp"
#include "support/run_program.hpp"
#include "support/sanitized.hpp"

namespace {

using kccd::testing::Outcome;

Outcome runKccd(const std::string& args, bool merge_stderr = false) {
  return kccd::testing::runProgram(std::string(KCCD_CLI) + " " + args, merge_stderr);
}

const std::string kDemo = std::string(KCCD_DATA_DIR) + "/demo_arm.yaml";

TEST(Cli, InfoListsStateNamesAndPairs) {
  const Outcome r = runKccd("info " + kDemo + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["state"], nlohmann::json({"shoulder_yaw", "shoulder_pitch", "elbow"}));
  EXPECT_EQ(j["totals"]["bodies"], 7);
  EXPECT_EQ(j["pairs"].size(), j["totals"]["pairs"].get<std::size_t>());
  EXPECT_EQ(runKccd("info " + kDemo).code, 0);
}

TEST(Cli, QueryJsonContract) {
  const Outcome r = runKccd("query " + kDemo + " --lower 0.1,0.2,0.3 --upper 0.2,0.4,0.6 --type distances --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["type"], "distances");
  EXPECT_EQ(j["status"], "ok");
  ASSERT_TRUE(j["collision"].is_boolean());
  ASSERT_TRUE(j["min_distance"].is_number());
  const auto info = nlohmann::json::parse(runKccd("info " + kDemo + " --json").out);
  ASSERT_EQ(j["pairs"].size(), info["pairs"].size());  // every checked pair
  double min_d = 1e9;
  std::size_t witnesses = 0;
  for (const auto& p : j["pairs"]) {
    for (const char* key : {"a", "b", "frame"}) EXPECT_TRUE(p[key].is_string()) << key;
    EXPECT_GE(p["distance"].get<double>(), 0.0);
    if (p.contains("witness_a")) {
      ++witnesses;
      EXPECT_EQ(p["witness_a"].size(), 3u);
      EXPECT_EQ(p["witness_b"].size(), 3u);
    }
    min_d = std::min(min_d, p["distance"].get<double>());
  }
  EXPECT_EQ(witnesses, j["pairs"].size());  // a distances query runs GJK on every pair
  EXPECT_DOUBLE_EQ(j["min_distance"].get<double>(), min_d);
  EXPECT_EQ(j["collision"].get<bool>(), min_d <= j["margin"].get<double>());
  for (const char* key : {"time_us", "pairs_checked", "gjk_calls"}) EXPECT_TRUE(j["stats"][key].is_number()) << key;
}

TEST(Cli, QueryExactStageChoices) {
  // A wide swing of the demo arm: the exact stage tightens every pair it refines, never loosens.
  const std::string box = "query " + kDemo + " --lower -0.6,0.1,0.2 --upper 0.6,0.5,0.8 --type distances --json";
  std::map<std::string, nlohmann::json> runs;
  for (const char* exact : {"off", "margin", "band", "all", "0.25"}) {
    const Outcome r = runKccd(box + " --exact " + exact);
    ASSERT_EQ(r.code, 0) << exact << ": " << r.err;
    runs[exact] = nlohmann::json::parse(r.out);
  }
  EXPECT_EQ(runs["off"]["stats"]["exact_calls"], 0);
  EXPECT_GT(runs["all"]["stats"]["exact_calls"].get<int>(), runs["off"]["stats"]["exact_calls"].get<int>());
  ASSERT_EQ(runs["off"]["pairs"].size(), runs["all"]["pairs"].size());
  int tighter = 0;
  for (std::size_t k = 0; k < runs["off"]["pairs"].size(); ++k) {
    const double off = runs["off"]["pairs"][k]["distance"], all = runs["all"]["pairs"][k]["distance"];
    const double margin = runs["margin"]["pairs"][k]["distance"], quarter = runs["0.25"]["pairs"][k]["distance"];
    const double band = runs["band"]["pairs"][k]["distance"];
    EXPECT_GE(all, off);
    EXPECT_GE(margin, off);
    EXPECT_GE(quarter, margin - 1e-12);
    EXPECT_GE(band, margin);  // the band refines more pairs: never looser
    tighter += all > off + 1e-6;
  }
  EXPECT_GT(tighter, 0);
  // The default is the band (0.2 m above the margin for distance queries), which here refines
  // pairs the margin alone leaves to the point volumes.
  const auto plain = nlohmann::json::parse(runKccd(box).out);
  EXPECT_EQ(plain["pairs"], runs["band"]["pairs"]);
  EXPECT_GT(runs["band"]["stats"]["exact_calls"].get<int>(), runs["margin"]["stats"]["exact_calls"].get<int>());
  const auto narrow_band = nlohmann::json::parse(runKccd(box + " --exact-band 0").out);
  EXPECT_EQ(narrow_band["pairs"], runs["margin"]["pairs"]);
  // Splitting (on by default) only ever raises a bound; 0 turns it off.
  const auto unsplit = nlohmann::json::parse(runKccd(box + " --exact-splits 0").out);
  EXPECT_EQ(unsplit["stats"]["split_pairs"], 0);
  for (std::size_t k = 0; k < unsplit["pairs"].size(); ++k)
    EXPECT_GE(runs["band"]["pairs"][k]["distance"].get<double>(), unsplit["pairs"][k]["distance"].get<double>());
  for (const char* bad : {"-1", "33", "two"}) {
    const Outcome r = runKccd(box + " --exact-splits " + bad, true);
    EXPECT_EQ(r.code, 2) << bad;
    EXPECT_NE(r.out.find("--exact-splits"), std::string::npos) << r.out;
  }
  // A split gap of 0 splits whenever a split could gain: never looser, at least as many splits.
  const auto fine = nlohmann::json::parse(runKccd(box + " --exact-split-gap 0").out);
  EXPECT_GE(fine["stats"]["split_pairs"].get<int>(), runs["band"]["stats"]["split_pairs"].get<int>());
  for (std::size_t k = 0; k < fine["pairs"].size(); ++k) {
    const double d = runs["band"]["pairs"][k]["distance"].get<double>();
    EXPECT_GE(fine["pairs"][k]["distance"].get<double>(), d - 2.0 * kccd::kExactDistanceTolerance - 1e-3 * d);
  }
  for (const char* bad : {"-1", "nan", "1e9", "wide"}) {
    const Outcome r = runKccd(box + " --exact-split-gap " + bad, true);
    EXPECT_EQ(r.code, 2) << bad;
    EXPECT_NE(r.out.find("--exact-split-gap"), std::string::npos) << r.out;
  }
  for (const char* bad : {"sometimes", "-1", "nan", "2e6"}) {
    const Outcome r = runKccd(box + " --exact " + bad, true);
    EXPECT_EQ(r.code, 2) << bad;
    EXPECT_NE(r.out.find("--exact: expected band, margin, all, off or a distance"), std::string::npos) << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  }
}

TEST(Cli, QueryTypesAndState) {
  for (const char* type : {"collision", "closest", "nclosest --n 3"}) {
    const Outcome r = runKccd("query " + kDemo + " --state 0.1,0.3,0.4 --json --type " + type);
    ASSERT_EQ(r.code, 0) << type << ": " << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["status"], "ok");
  }
  const auto n =
      nlohmann::json::parse(runKccd("query " + kDemo + " --state 0.1,0.3,0.4 --json --type nclosest --n 3").out);
  EXPECT_EQ(n["pairs"].size(), 3u);
  EXPECT_LE(n["pairs"][0]["distance"].get<double>(), n["pairs"][1]["distance"].get<double>());
}

TEST(Cli, BadInputGivesOneLineAndNonZeroExit) {
  struct Case {
    std::string args;
    int code;
    std::string text;
  };
  const std::vector<Case> cases = {
      {"query /nonexistent/m.yaml --state 0", 2, "/nonexistent/m.yaml: cannot open"},
      {"query " + kDemo + " --state 0.1,0.2", 2, "--state has 2 values but model 'demo_arm' has 3"},
      {"query " + kDemo + " --state 0.1,abc,0.3", 2, "--state: value 2 ('abc') is not a number"},
      {"query " + kDemo + " --lower 0.1,0.2,0.3", 2, "needs --lower and --upper"},
      {"query " + kDemo + " --state 0,0,0 --type fastest", 2, "unknown query type 'fastest'"},
      {"query " + kDemo + " --lower 0.3,0,0 --upper 0.1,0,0", 3, "lower_above_upper"},
      {"query " + kDemo + " --state nan,0,0", 3, "non_finite_state"},
  };
  for (const Case& c : cases) {
    const Outcome r = runKccd(c.args);
    EXPECT_EQ(r.code, c.code) << c.args;
    EXPECT_NE(r.err.find(c.text), std::string::npos) << c.args << " -> " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << c.args << " -> " << r.err;
  }
  // A bad model file: the message names file, line and field.
  const std::string bad = ::testing::TempDir() + "/bad_model.yaml";
  FILE* f = fopen(bad.c_str(), "w");
  fputs("kccd: 1\nbodies:\n  - {name: a, frame: world, points: [[0, 0]], radius: 0.1}\n", f);
  fclose(f);
  const Outcome r = runKccd("info " + bad);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("bad_model.yaml:3:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("body 'a'.points[0]"), std::string::npos) << r.err;
}

TEST(Cli, HelpExplainsEverySubcommand) {
  const Outcome r = runKccd("--help", true);
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("query"), std::string::npos);
  EXPECT_NE(r.out.find("info"), std::string::npos);
  const Outcome q = runKccd("query --help", true);
  EXPECT_EQ(q.code, 0);
  for (const char* flag : {"--lower", "--upper", "--state", "--type", "--n", "--margin", "--budget-us", "--json"})
    EXPECT_NE(q.out.find(flag), std::string::npos) << flag;
  EXPECT_NE(runKccd("").code, 0);  // a subcommand is required
}

// `kccd` runs --version, info and query itself, loading only the checker's libraries, and hands
// every other subcommand to kccd-all: both must print the same bytes and exit the same way.
TEST(Cli, LightCommandsRunWithoutTheWholeProgramAndAgreeWithIt) {
  const Outcome libs = kccd::testing::runProgram(std::string("ldd ") + KCCD_CLI);
  ASSERT_EQ(libs.code, 0) << libs.err;
  for (const char* heavy : {"opencv", "gdal", "avcodec", "OSMesa", "Coin", "assimp", "gstreamer"})
    EXPECT_EQ(libs.out.find(heavy), std::string::npos) << heavy << " is loaded by kccd:\n" << libs.out;
  const auto whole = [](const std::string& args) {  // kccd-all under the launcher's name (argv[0])
    return kccd::testing::runProgram(std::string("bash -c 'exec -a ") + KCCD_CLI + " " + KCCD_ALL + " " + args + "'",
                                     true);
  };
  const std::string box = " --lower -0.5,0,0 --upper 0.5,0,0";
  for (const std::string& args :
       {std::string("--version"), std::string("info --help"), std::string("query --help"), "info " + kDemo,
        "info " + kDemo + " --json", "query " + kDemo + box + " --type distances --json",
        "query " + kDemo + box + " --explain", "query " + kDemo + " --state 1", "query " + kDemo + " --bogus",
        std::string("info /nonexistent.yaml"), std::string("info"), std::string("render --help"),
        std::string("nosuch")}) {
    Outcome light = runKccd(args, true), all = whole(args);
    for (Outcome* o : {&light, &all}) {  // the query's own time differs from run to run
      auto& s = o->out;
      for (const std::string key : {"\"time_us\": ", "time "})
        for (std::size_t at = s.find(key); at != std::string::npos; at = s.find(key, at + 1)) {
          const std::size_t end = s.find_first_of(",\n ", at + key.size());
          s.erase(at + key.size(), end - at - key.size());
        }
    }
    EXPECT_EQ(light.code, all.code) << args;
    EXPECT_EQ(light.out, all.out) << args;
  }
  // Without kccd-all beside it (nor in ../libexec/kccd), only the light subcommands remain.
  const std::filesystem::path dir = kccd::testing::scratchFolder("kccd_launcher_alone");
  std::filesystem::copy_file(KCCD_CLI, dir / "kccd");
  EXPECT_EQ(kccd::testing::runProgram((dir / "kccd").string() + " info " + kDemo).code, 0);
  const Outcome alone = kccd::testing::runProgram((dir / "kccd").string() + " render --help");
  EXPECT_EQ(alone.code, 1);
  EXPECT_NE(alone.err.find("kccd-all"), std::string::npos) << alone.err;
  std::filesystem::remove_all(dir);
}

// kccd-all loads FFmpeg's libraries (with ~120 codec libraries behind them) only when a command
// opens a video: not linked, and not loaded by a command that reads no video. (Opening one loads
// them: every VideoFileTest does.)
TEST(Cli, TheWholeProgramLoadsFfmpegOnlyForAVideo) {
  const Outcome libs = kccd::testing::runProgram(std::string("ldd ") + KCCD_ALL);
  ASSERT_EQ(libs.code, 0) << libs.err;
  for (const char* video : {"libavcodec", "libavformat", "libswscale", "libavutil"})
    EXPECT_EQ(libs.out.find(video), std::string::npos) << video << " is linked by kccd-all:\n" << libs.out;
  const Outcome run =
      kccd::testing::runProgram(std::string("env LD_DEBUG=files ") + KCCD_ALL + " render " + kDemo + " --help", true);
  EXPECT_EQ(run.code, 0) << run.out;
  EXPECT_NE(run.out.find("libEGL"), std::string::npos) << "LD_DEBUG=files lists no library:\n"
                                                       << run.out.substr(0, 400);
  EXPECT_EQ(run.out.find("libavcodec"), std::string::npos) << "render --help loaded FFmpeg";
}

}  // namespace

namespace {

// Every scratch file and folder of this process (TempDir()/PID_*) is removed when its tests end.
class ScratchFiles : public ::testing::Environment {
 public:
  void TearDown() override {
    const std::string prefix = std::to_string(getpid()) + "_";
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(::testing::TempDir(), ec))
      if (e.path().filename().string().rfind(prefix, 0) == 0) std::filesystem::remove_all(e.path(), ec);
  }
};
[[maybe_unused]] ::testing::Environment* const kScratchFiles = ::testing::AddGlobalTestEnvironment(new ScratchFiles);

const std::string kModels = "/usr/share/inventor/data/models/";

std::string scratchCopy(const std::string& from, const std::string& name) {
  const std::string to = ::testing::TempDir() + "/" + std::to_string(getpid()) + "_" + name;
  std::ifstream in(from, std::ios::binary);
  std::ofstream out(to, std::ios::binary);
  out << in.rdbuf();
  return to;
}

}  // namespace

TEST(Cli, FitJsonContractAndErrors) {
  const Outcome r = runKccd("fit " + kModels + "simple/cube.iv --points 8 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["points"].size(), 8u);
  EXPECT_GE(j["radius"].get<double>(), 0.0);
  EXPECT_NEAR(j["hull_volume"].get<double>(), 8.0, 1e-6);  // Coin's default cube: 2 x 2 x 2
  EXPECT_NEAR(j["volume"].get<double>(), 8.0, 1e-3);
  EXPECT_GT(j["baselines"]["sphere_ratio"].get<double>(), 2.0);

  Outcome e = runKccd("fit " + kModels + "simple/cube.iv --points 17");
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.err.find("--points: the number of core points K must be 1 ... 16 (got 17)"), std::string::npos) << e.err;
  const std::string two = ::testing::TempDir() + "/" + std::to_string(getpid()) + "_two_parts.iv";
  std::ofstream(two) << "#Inventor V2.1 ascii\nDEF a Separator { Cube {} }\nDEF b Separator { Sphere {} }\n";
  e = runKccd("fit " + two + " -q");
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.err.find("top-level parts"), std::string::npos) << e.err;
  EXPECT_EQ(e.out, "");  // nothing half-printed
  // A coordinate beyond what a model may hold (1e6 m), or not a number, in an ASCII STL: the line
  // and the vertex, exit 2 (the fit's distances used to overflow into an internal error).
  const std::string huge = ::testing::TempDir() + "/" + std::to_string(getpid()) + "_huge.stl";
  for (const std::string value : {"1e308", "inf", "nan", "2e6"}) {
    std::ofstream(huge) << "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 " << value
                        << " 0\nendloop\nendfacet\nendsolid s\n";
    e = runKccd("fit " + huge + " -k 8 --merge");
    EXPECT_EQ(e.code, 2) << value << ": " << e.err;
    EXPECT_EQ(std::count(e.err.begin(), e.err.end(), '\n'), 1) << e.err;
    EXPECT_NE(e.err.find("_huge.stl:6: vertex 3: "), std::string::npos) << value << ": " << e.err;
  }
  // --scale and --seed: a factor of 0, two factors, a negative seed (never wrapped to 2^64 - 1).
  for (const auto& [args, says] :
       {std::pair<std::string, std::string>{"--scale 0", "--scale: each factor must be a finite number other than 0"},
        {"--scale 1,2", "--scale: give one factor or three (X,Y,Z)"},
        {"--seed -1", "--seed: expected a whole number 0 ... "}}) {
    e = runKccd("fit " + kModels + "simple/cube.iv -q " + args);
    EXPECT_EQ(e.code, 2) << args << ": " << e.err;
    EXPECT_EQ(std::count(e.err.begin(), e.err.end(), '\n'), 1) << e.err;
    EXPECT_NE(e.err.find(says), std::string::npos) << args << ": " << e.err;
    EXPECT_EQ(e.out, "");
  }
  // Scaled per axis in the file's frame: the 2 x 2 x 2 cube becomes 1 x 1 x 4, or 1 x 1 x 1.
  for (const auto& [scale, volume] : {std::pair<std::string, double>{"0.5,0.5,2", 4.0}, {"0.5", 1.0}}) {
    const Outcome scaled = runKccd("fit " + kModels + "simple/cube.iv --points 8 --json --scale " + scale);
    ASSERT_EQ(scaled.code, 0) << scaled.err;
    EXPECT_NEAR(nlohmann::json::parse(scaled.out)["hull_volume"].get<double>(), volume, 1e-6) << scale;
  }
  e = runKccd("fit /nonexistent/part.iv");
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.err.find("/nonexistent/part.iv: cannot open the file"), std::string::npos) << e.err;
  // --hull: no fit, the exact hull (a cylinder's rims as circumscribed polygons); no K with it.
  const Outcome h = runKccd("fit " + kModels + "simple/cylinder.iv --hull --json");
  ASSERT_EQ(h.code, 0) << h.err;
  const auto jh = nlohmann::json::parse(h.out);
  EXPECT_TRUE(jh["exact_hull"].get<bool>());
  EXPECT_GT(jh["points"].size(), 16u);
  EXPECT_EQ(jh["k"].get<std::size_t>(), jh["points"].size());
  EXPECT_LT(jh["radius"].get<double>(), 1e-4);
  EXPECT_NEAR(jh["volume_ratio"].get<double>(), 1.0, 1e-3);
  EXPECT_FALSE(jh.contains("baselines"));
  e = runKccd("fit " + kModels + "simple/cylinder.iv --hull -k 4");
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.err.find("--points excludes --hull"), std::string::npos) << e.err;
}

// Every option error, whatever the parser finds, is one line starting "kccd: " and exit 2.
TEST(Cli, OptionErrorsFollowTheOneLineContract) {
  struct Case {
    std::string args;
    std::string text;
  };
  const std::vector<Case> cases = {
      {"query " + kDemo + " --state 0,0,0 --n 0", "--n: expected a whole number from 1 to 1000000, got '0'"},
      {"query " + kDemo + " --state 0,0,0 --n abc", "--n: expected a whole number"},
      {"query " + kDemo + " --state 0,0,0 --bogus", "unknown option or extra argument: --bogus"},
      {"query", "model is required"},
      {"frobnicate", "unknown subcommand 'frobnicate'"},
      {"query " + kDemo + " --state=", "--state: needs a value"},
      {"query " + kDemo + " --state 0,0,0 --margin nan", "--margin: must be a finite number, got 'nan'"},
      {"query " + kDemo + " --state 0,0,0 --budget-us nan", "--budget-us: must be a finite number"},
      {"query " + kDemo + " --state 0,0,0 --budget-us 9.2e15", "--budget-us: must be in [0, 1e+12]"},
      {"query " + kDemo + " --state 0,0,0 --margin -1", "--margin: must be in [0, 1e+06]"},
      {"pairs " + kDemo + " --max-boxes 0", "--max-boxes: expected a whole number"},
      {"query " + kDemo + " --state \"$(printf '0,\\033[31m,0')\"", "\\x1b[31m"},
      {"fit " + std::string(KCCD_DATA_DIR) + "/parts/gripper.iv --tolerance 0",
       "--tolerance: must be in [1e-06, 1e+06]"},
      {"fit " + std::string(KCCD_DATA_DIR) + "/parts/gripper.iv --pieces many", "--pieces: expected auto or a number"},
      {"fit " + std::string(KCCD_DATA_DIR) + "/parts/gripper.iv --tolerance 1 --hull", "excludes"},
      {"import x.urdf --pieces 0", "--pieces: expected auto or a number of pieces 1 ... 64, got '0'"},
      {"import x.urdf -k 8 --tolerance 1", "excludes"},
      {"import x.urdf --concavity nan", "--concavity: must be a finite number"},
  };
  for (const Case& c : cases) {
    const Outcome r = runKccd(c.args);
    EXPECT_EQ(r.code, 2) << c.args << " -> " << r.err;
    EXPECT_EQ(r.err.rfind("kccd: ", 0), 0u) << c.args << " -> " << r.err;
    EXPECT_NE(r.err.find(c.text), std::string::npos) << c.args << " -> " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << c.args << " -> " << r.err;
    EXPECT_EQ(r.err.find('\x1b'), std::string::npos) << c.args << ": raw escape byte echoed";
    EXPECT_LT(r.err.size(), 300u) << c.args << " -> " << r.err;  // no 309-digit numbers
  }
  for (const char* ok : {"--help", "--version", "query --help"}) EXPECT_EQ(runKccd(ok).code, 0) << ok;
}

// Huge but finite inputs the loader accepts never turn a colliding box into "clear".
TEST(Cli, HugeAnglesAndAxesStaySafe) {
  const std::string model = ::testing::TempDir() + "/huge_angles.yaml";
  for (const char* axis : {"[0, 0, 1]", "[1e200, 1e200, 0]"}) {
    {
      std::ofstream f(model);
      f << "kccd: 1\nsafety_margin: 0.02\njoints: [{name: r, parent: world, type: revolute, axis: " << axis
        << ", limits: [-2e16, 2e16]}]\nbodies:\n  - {name: b, frame: world, points: [[1, 0, 0]], radius: 0.1}\n"
        << "  - {name: c, frame: r, points: [[0, 1.1, 0]], radius: 0.1}\n";
    }
    for (const char* box :
         {"--lower=-1e17 --upper=1e17", "--lower=1e17 --upper=1.00000000001e17", "--lower=-3.4e38 --upper=3.4e38"}) {
      const Outcome r = runKccd("query " + model + " " + box + " --json");
      ASSERT_EQ(r.code, 0) << r.err;
      EXPECT_TRUE(nlohmann::json::parse(r.out)["collision"].get<bool>()) << axis << " " << box << ": " << r.out;
    }
    const Outcome p = runKccd("pairs " + model + " --json -q");
    ASSERT_EQ(p.code, 0) << p.err;
    const auto proofs = nlohmann::json::parse(p.out);
    for (const auto& pair : proofs["pairs"]) EXPECT_NE(pair["verdict"], "never") << p.out;
  }
}

// A model with only fixed joints (no state values) is queried with no values at all.
TEST(Cli, ModelWithoutStateValuesCanBeQueried) {
  const std::string model = ::testing::TempDir() + "/fixed_only.yaml";
  {
    std::ofstream f(model);
    f << "kccd: 1\njoints: [{name: f, parent: world, type: fixed, origin: {xyz: [1, 0, 0]}}]\nbodies:\n"
         "  - {name: a, frame: world, points: [[0, 0, 0]], radius: 0.1}\n"
         "  - {name: b, frame: f, points: [[0, 0, 0]], radius: 0.1}\n";
  }
  for (const char* args : {""}) {
    const Outcome r = runKccd("query " + model + args + " --type closest --json");
    ASSERT_EQ(r.code, 0) << args << ": " << r.err;
    EXPECT_NEAR(nlohmann::json::parse(r.out)["min_distance"].get<double>(), 0.8, 1e-9);
  }
  EXPECT_EQ(runKccd("query " + model + " --state 1").code, 2);
  EXPECT_EQ(runKccd("query " + model + " --state=").code, 2);  // CLI11 wants a value after '='; omit --state
}

TEST(Cli, FitWritesIntoAModel) {
  const std::string model = scratchCopy(kDemo, "fit_model.yaml");
  const Outcome r = runKccd("fit " + kModels + "simple/cone.iv --points 4 -q --model " + model + " --body forearm");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string text = kccd::testing::readText(model);
  EXPECT_NE(text.find("# A small, readable example"), std::string::npos);  // comments kept
  const Outcome info = runKccd("info " + model + " --json");
  ASSERT_EQ(info.code, 0) << info.err;
  const auto j = nlohmann::json::parse(info.out);
  for (const auto& b : j["bodies"])
    if (b["name"] == "forearm") {
      EXPECT_EQ(b["points"], 4);
    }
  const Outcome bad = runKccd("fit " + kModels + "simple/cone.iv -q --model " + model + " --body nobody");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("no body named 'nobody'"), std::string::npos) << bad.err;
}

// The body's tolerance is the new fit's bound, never the old geometry's (kccd info prints it).
TEST(Cli, FitIntoAModelReplacesTheBodysTolerance) {
  const std::string model = scratchCopy(kDemo, "fit_tolerance.yaml");
  std::string text = kccd::testing::readText(model);
  const std::string radius = "    radius: 0.045\n";
  ASSERT_NE(text.find(radius), std::string::npos);
  text.replace(text.find(radius), radius.size(), radius + "    tolerance: 0.123\n");  // a stale bound
  std::ofstream(model, std::ios::binary) << text;
  const Outcome fit =
      runKccd("fit " + kModels + "simple/cone.iv --tolerance 2 --json --model " + model + " --body forearm");
  ASSERT_EQ(fit.code, 0) << fit.err;
  const double bound = nlohmann::json::parse(fit.out)["tolerance"].get<double>();
  EXPECT_LE(bound, 0.002);
  const Outcome info = runKccd("info " + model + " --json");
  ASSERT_EQ(info.code, 0) << info.err;
  bool seen = false;
  const auto j = nlohmann::json::parse(info.out);
  for (const auto& b : j["bodies"])
    if (b["name"] == "forearm") {
      seen = true;
      EXPECT_EQ(b["tolerance"].get<double>(), bound) << info.out;
    }
  EXPECT_TRUE(seen) << info.out;
}

// Edits of one model by concurrent runs all land (a lock serialises them); a symbolic link stays
// a link, the file keeps its mode, and no temporary file is left behind.
TEST(Cli, ConcurrentEditsOfOneModelAreNotLost) {
  const std::string dir = ::testing::TempDir() + "/concurrent_edit";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string real = dir + "/real.yaml", link = dir + "/link.yaml";
  std::filesystem::copy_file(kDemo, real);
  std::filesystem::permissions(real, std::filesystem::perms(0640));
  std::filesystem::create_symlink("real.yaml", link);
  const std::vector<std::string> bodies = {"upper_arm", "forearm", "post", "table", "gripper"};
  std::string script;
  for (const std::string& b : bodies)
    script += std::string(KCCD_CLI) + " fit " + kModels + "simple/cone.iv --points 3 --evaluations 300 -q --model " +
              link + " --body " + b + " >/dev/null & ";
  script += "wait";
  ASSERT_EQ(kccd::testing::runProgram(script).code, 0);
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  EXPECT_EQ(std::filesystem::status(real).permissions() & std::filesystem::perms::all, std::filesystem::perms(0640));
  const Outcome info = runKccd("info " + real + " --json");
  ASSERT_EQ(info.code, 0) << info.err;
  int edited = 0;
  const auto j = nlohmann::json::parse(info.out);
  for (const auto& b : j["bodies"])
    if (std::find(bodies.begin(), bodies.end(), b["name"].get<std::string>()) != bodies.end())
      edited += b["points"] == 3;
  EXPECT_EQ(edited, static_cast<int>(bodies.size())) << info.out;  // every edit landed
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 2);
}

TEST(Cli, PairsProvesAndWrites) {
  const std::string model = scratchCopy(kDemo, "pairs_model.yaml");
  const Outcome r = runKccd("pairs " + model + " --json -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  int never = 0;
  for (const auto& p : j["pairs"]) never += p["verdict"] == "never";
  EXPECT_GT(never, 0);
  const Outcome w = runKccd("pairs " + model + " --write -q");
  ASSERT_EQ(w.code, 0) << w.err;
  const auto after = nlohmann::json::parse(runKccd("info " + model + " --json").out);
  // Every pair left to check is one the proof could not rule out.
  EXPECT_EQ(after["pairs"].size(), j["pairs"].size() - j["ignore"].size());
  EXPECT_EQ(runKccd("pairs /nonexistent.yaml").code, 2);
}

TEST(Cli, ImportWritesALoadableModel) {
  const std::string dir = std::string(KCCD_TEST_DATA_DIR) + "/urdf";
  const std::string out = ::testing::TempDir() + "/" + std::to_string(getpid()) + "_imported.yaml";
  const Outcome r = runKccd("import " + dir + "/two_link.urdf --srdf " + dir +
                            "/two_link.srdf --package-path kccd_test=" + dir + " -k 4 -q -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  const Outcome info = runKccd("info " + out + " --json");
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["state"], nlohmann::json({"yaw", "lift", "spin"}));
  const Outcome e = runKccd("import " + dir + "/two_link.urdf -q");
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.err.find("unknown package 'kccd_test'"), std::string::npos) << e.err;
  EXPECT_EQ(runKccd("import " + dir + "/two_link.urdf --package-path nonsense -q").code, 2);
  // --pairs: the proofs of `kccd pairs` written into the ignore list, next to the SRDF's pairs.
  const std::string proven = ::testing::TempDir() + "/" + std::to_string(getpid()) + "_proven.yaml";
  const Outcome p = runKccd("import " + dir + "/two_link.urdf --srdf " + dir +
                            "/two_link.srdf --package-path kccd_test=" + dir + " -k 4 --pairs -o " + proven);
  ASSERT_EQ(p.code, 0) << p.err;
  EXPECT_NE(p.err.find("pairs: "), std::string::npos) << p.err;
  const Outcome again = runKccd("pairs " + proven + " --json");
  ASSERT_EQ(again.code, 0) << again.err;
  const nlohmann::json proofs = nlohmann::json::parse(again.out);
  int ignored = 0;
  for (const auto& pair : proofs.at("pairs")) {
    // Every pair proven never or always touching is now ignored; the SRDF's stay ignored.
    if (pair.at("verdict") == "never" || pair.at("verdict") == "always_touching") {
      EXPECT_FALSE(pair.at("checked")) << pair;
    }
    ignored += pair.at("checked") ? 0 : 1;
  }
  EXPECT_GE(ignored, 2);  // at least the SRDF's two pairs
  const Outcome plain = runKccd("pairs " + out + " --json");
  ASSERT_EQ(plain.code, 0) << plain.err;
  int ignored_plain = 0;
  const nlohmann::json plain_proofs = nlohmann::json::parse(plain.out);
  for (const auto& pair : plain_proofs.at("pairs")) ignored_plain += pair.at("checked") ? 0 : 1;
  EXPECT_GE(ignored, ignored_plain);
}

namespace {

// A state log CSV with a header and the rows given (time first).
std::string writeLog(const std::string& name, const std::string& header, const std::vector<std::string>& rows) {
  const std::string path = ::testing::TempDir() + "/" + std::to_string(getpid()) + "_" + name;
  std::ofstream f(path);
  f << header << "\n";
  for (const std::string& row : rows) f << row << "\n";
  return path;
}

}  // namespace

// A real robot out of the box: a Panda-like arm imported from its URDF (hand on fixed joints,
// prismatic fingers) ignores its rigid and adjacent pairs with reasons, and a recording of it that
// never touches anything (kccd synth's trajectory search, near-misses only) has no colliding
// frame in kccd overlay; the survey of its log names the pair that comes within the margin.
TEST(Cli, ImportedGripperArmRecordingHasNoCollidingFrame) {
  const std::string dir = ::testing::TempDir() + "/" + std::to_string(getpid()) + "_gripper";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string model = dir + "/arm.yaml";
  const Outcome imp = runKccd("import " + std::string(KCCD_TEST_DATA_DIR) + "/urdf/gripper_arm.urdf -k " +
                              std::to_string(kccd::testing::casesFor(8, 4)) + " --pairs -q -o " +
                              model);  // the fit: 44 s at 8 under ASan
  ASSERT_EQ(imp.code, 0) << imp.err;
  const auto info = nlohmann::json::parse(runKccd("info " + model + " --json").out);
  std::map<std::string, std::string> reason;
  for (const auto& p : info.at("ignored"))
    reason[p.at("a").get<std::string>() + "-" + p.at("b").get<std::string>()] = p.at("reason");
  EXPECT_EQ(reason["link3-hand"], "rigid");
  EXPECT_EQ(reason["hand-left_finger"], "adjacent");
  // link3 lies between link2 and the hand: checked, or ignored only by a proof.
  EXPECT_TRUE(reason.count("link2-hand") == 0 || reason.at("link2-hand") == "never") << reason["link2-hand"];
  const Outcome text = runKccd("info " + model);
  EXPECT_NE(text.out.find("ignored pairs (pairs: ignore) and why:"), std::string::npos) << text.out;

  const Outcome synth = runKccd("synth " + model + " -o " + dir +
                                "/rec --seconds 4 --fps 10 --width 640 --height 480 "
                                "--no-collision -q");
  ASSERT_EQ(synth.code, 0) << synth.err;
  const auto truth = nlohmann::json::parse(std::ifstream(dir + "/rec/synth.json"));
  ASSERT_FALSE(truth.at("near_collision_frames").empty());  // it does come close
  const Outcome ov = runKccd("overlay " + model + " --camera " + dir + "/rec/camera_true.yaml --video " + dir +
                             "/rec/video.mkv --states " + dir + "/rec/states.csv --time-offset 0.137 -o " + dir +
                             "/out.mkv --report " + dir + "/report.json -q");
  ASSERT_EQ(ov.code, 0) << ov.err;
  const auto report = nlohmann::json::parse(std::ifstream(dir + "/report.json"));
  int colliding = 0, within = 0;
  for (const auto& f : report.at("frames")) {
    colliding += f.at("status") == "colliding";
    within += f.at("status") == "within_margin";
  }
  EXPECT_EQ(colliding, 0);
  EXPECT_GT(within, 0);

  // The survey of the same log: the rows within the margin, the pair responsible, video times.
  const Outcome sv = runKccd("pairs " + model + " --states " + dir + "/rec/states.csv --time-offset 0.137 --json -q");
  ASSERT_EQ(sv.code, 0) << sv.err;
  const auto survey = nlohmann::json::parse(sv.out);
  EXPECT_GT(survey.at("samples_within").get<int>(), 0);
  const auto& top = survey.at("pairs").at(0);
  EXPECT_GT(top.at("within").get<int>(), 0);
  EXPECT_EQ(top.at("overlapping"), 0);
  EXPECT_GE(top.at("min_distance").get<double>(), 0.3 * 0.01);  // synth's near misses: about half the margin
  EXPECT_LE(top.at("first_within").get<double>(), top.at("last_within").get<double>());
  // --ignored also surveys the ignored pairs: the rigid hand overlaps link3 in every state.
  const auto all =
      nlohmann::json::parse(runKccd("pairs " + model + " --states " + dir + "/rec/states.csv --ignored --json -q").out);
  bool rigid_seen = false;
  for (const auto& p : all.at("pairs"))
    if (p.at("a") == "link3" && p.at("b") == "hand") {
      rigid_seen = true;
      EXPECT_EQ(p.at("ignored"), "rigid");
      EXPECT_EQ(p.at("within"), all.at("samples"));
    }
  EXPECT_TRUE(rigid_seen);
  // --random: configurations drawn inside the limits instead of a recording, the same report.
  const Outcome rnd = runKccd("pairs " + model + " --random 300 --seed 4 --ignored --json -q");
  ASSERT_EQ(rnd.code, 0) << rnd.err;
  const auto drawn = nlohmann::json::parse(rnd.out);
  EXPECT_EQ(drawn.at("samples"), 300);
  EXPECT_EQ(drawn.at("states"), "random");
  for (const auto& p : drawn.at("pairs"))
    if (p.at("a") == "link3" && p.at("b") == "hand") {
      EXPECT_EQ(p.at("within"), 300);  // rigid, touching
    }
  EXPECT_EQ(runKccd("pairs " + model + " --random 300 --seed 4 --ignored --json -q").out, rnd.out);  // repeatable
  std::filesystem::remove_all(dir);
}

// Survey input errors: one line naming the log and place, exit 2; options that need --states.
TEST(Cli, PairsSurveyBadInput) {
  const std::string bad =
      writeLog("survey_bad.csv", "time,shoulder_yaw,shoulder_pitch,elbow", {"0,0,0,0", "0.1,0,x,0"});
  const Outcome r = runKccd("pairs " + kDemo + " --states " + bad);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("survey_bad.csv:3:"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(runKccd("pairs " + kDemo + " --time-offset 1").code, 2);
  EXPECT_EQ(runKccd("pairs " + kDemo + " --states " + bad + " --write").code, 2);
  EXPECT_EQ(runKccd("pairs " + kDemo + " --ignored").code, 2);
  EXPECT_EQ(runKccd("pairs " + kDemo + " --random 0").code, 2);
  EXPECT_EQ(runKccd("pairs " + kDemo + " --random 5 --states " + bad).code, 2);
  EXPECT_EQ(runKccd("pairs " + kDemo + " --seed 3").code, 2);
  const std::string good =
      writeLog("survey_good.csv", "time,shoulder_yaw,shoulder_pitch,elbow", {"0,-0.5,0,0", "0.1,0.5,0,0", "0.2,0,0,0"});
  const Outcome ok = runKccd("pairs " + kDemo + " --states " + good + " --all");
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_NE(ok.out.find("3 recorded states"), std::string::npos) << ok.out;
}

// Robot logs (kccd::logs) against files other projects' writers made: tests/bags/write_mcap.mjs
// writes the same recording (200 JointState at 1 kHz with shuffled joint order, 10 RGB images at
// 30 Hz, header stamps 2 and 35 ms behind the log times) as MCAP with @mcap/core, unchunked and in
// chunks stored plain, zstd and lz4, with the messages serialised by @foxglove/rosmsg2-serialization,
// and lists what it wrote in truth.json. Also: every cut of a file reads a prefix with a warning,
// damaged bytes give one-line errors, and the CDR / ROS 1 decoders against a byte encoder of this
// file's own, in both byte orders.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/input_error.hpp"
#include "kccd/logs/bag_summary.hpp"
#include "kccd/logs/decode.hpp"
#include "kccd/logs/log_reader.hpp"
#include "kccd/logs/mcap_reader.hpp"
#include "kccd/logs/message_definition.hpp"
#include "kccd/overlay/bags/bag_export.hpp"
#include "support/files.hpp"
#include "support/run_program.hpp"

namespace {

namespace fs = std::filesystem;
using namespace kccd::logs;
using kccd::testing::readText;
using kccd::testing::runProgram;

const char* const kFiles[] = {"joint_plain.mcap", "joint_zstd.mcap", "joint_lz4.mcap", "joint_chunked_none.mcap"};

class McapFixtures : public ::testing::Test {
 protected:
  // The writer runs once per process (node and tests/bags/node_modules: scripts/install-deps.sh --tests).
  static void SetUpTestSuite() {
    dir_ = kccd::testing::scratchFolder("test_logs") / "bags";
    fs::create_directories(dir_);
    const auto r = runProgram(
        std::string(KCCD_NODE) + " " + KCCD_SOURCE_DIR + "/tests/bags/write_mcap.mjs " + dir_.string(), true);
    ASSERT_EQ(r.code, 0) << "the fixture writer failed (npm ci in tests/bags?): " << r.out;
    const auto db = runProgram(
        std::string(KCCD_PYTHON) + " " + KCCD_SOURCE_DIR + "/tests/bags/write_db3.py " + dir_.string(), true);
    ASSERT_EQ(db.code, 0) << "the sqlite3 fixture writer failed: " << db.out;
    const auto ros1 = runProgram(
        std::string(KCCD_PYTHON) + " " + KCCD_SOURCE_DIR + "/tests/bags/write_ros1.py " + dir_.string(), true);
    ASSERT_EQ(ros1.code, 0) << "the ROS 1 fixture writer failed (python3-rosbag, python3-sensor-msgs?): " << ros1.out;
    truth_ = nlohmann::json::parse(readText((dir_ / "truth.json").string()));
  }
  static std::string file(const std::string& name) { return (dir_ / name).string(); }
  static std::vector<LogMessage> all(McapReader& r, std::vector<std::vector<std::uint8_t>>* bytes = nullptr) {
    std::vector<LogMessage> out;
    LogMessage m;
    while (r.next(m)) {
      out.push_back(m);
      if (bytes) bytes->emplace_back(m.data.begin(), m.data.end());
    }
    return out;
  }
  // `kccd bag export` of `bag` into a folder named by `tag`: the state log, frame times and camera file.
  static std::vector<std::string> exportOf(const std::string& bag, const std::string& tag) {
    const fs::path out = dir_ / ("export_" + tag);
    fs::create_directories(out);
    const auto r = runProgram(std::string(KCCD_CLI) + " bag export " + bag + " -q --states " +
                              (out / "s.csv").string() + " --video " + (out / "v.mkv").string() + " --frame-times " +
                              (out / "t.csv").string() + " --camera-info " + (out / "c.yaml").string());
    EXPECT_EQ(r.code, 0) << r.err;
    return std::vector<std::string>{readText((out / "s.csv").string()), readText((out / "t.csv").string()),
                                    readText((out / "c.yaml").string())};
  }
  static inline fs::path dir_;
  static inline nlohmann::json truth_;
};

std::uint64_t ns(const nlohmann::json& s) { return std::stoull(s.get<std::string>()); }

// A 64x48 pinhole camera 2 m in front of the fixtures' seven-joint arms, looking along +y: written
// to the scratch folder as `name`, its path returned.
std::string camera64(const std::string& name) {
  return kccd::testing::writeScratch(
      "test_logs", name,
      "%YAML:1.0\n---\nimage_width: 64\nimage_height: 48\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   "
      "dt: d\n"
      "   data: [ 40, 0, 31.5, 0, 40, 23.5, 0, 0, 1 ]\ndistortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: "
      "5\n   dt: d\n"
      "   data: [ 0, 0, 0, 0, 0 ]\nrvec: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [ "
      "1.5707963267948966, 0, 0 ]\n"
      "tvec: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [ 0, 0.5, 2 ]\n");
}

TEST_F(McapFixtures, EveryFileReadsAsWritten) {
  for (const char* name : kFiles) {
    SCOPED_TRACE(name);
    McapReader r(file(name));
    std::vector<std::vector<std::uint8_t>> bytes;
    const std::vector<LogMessage> msgs = all(r, &bytes);
    EXPECT_TRUE(r.damage().empty()) << r.damage();
    EXPECT_EQ(r.profile(), truth_["profile"]);
    EXPECT_EQ(r.library(), truth_["library"]);
    const nlohmann::json& t = truth_["files"][name];
    if (t["compression"].is_null()) {
      EXPECT_TRUE(r.chunks().empty());
    } else {
      EXPECT_GT(
          r.chunks().at(t["compression"].get<std::string>().empty() ? "none" : t["compression"].get<std::string>()), 3);
    }
    // Per topic, the definitions the file stores decode every message to what was written.
    const MessageDefinitions joint =
        MessageDefinitions::parse("sensor_msgs/msg/JointState", msgs.front().schema->data, Dialect::Ros2);
    std::size_t j = 0, i = 0;
    std::uint64_t last = 0;
    for (std::size_t k = 0; k < msgs.size(); ++k) {
      const LogMessage& m = msgs[k];
      EXPECT_GE(m.log_time, last);  // the writer's order is log-time order
      last = m.log_time;
      EXPECT_EQ(m.publish_time, m.log_time);
      const std::span<const std::uint8_t> data(bytes[k]);
      if (m.channel->topic == "/joint_states") {
        ASSERT_LT(j, truth_["joint_states"].size());
        const nlohmann::json& w = truth_["joint_states"][j++];
        EXPECT_EQ(m.log_time, ns(w["log_time_ns"]));
        EXPECT_EQ(m.schema->name, "sensor_msgs/msg/JointState");
        const Value v = decodeCdr(joint, data);
        EXPECT_EQ(v.field("header")->field("stamp")->field("sec")->i, w["stamp_sec"].get<std::int64_t>());
        EXPECT_EQ(v.field("header")->field("stamp")->field("nanosec")->u, w["stamp_nanosec"].get<std::uint64_t>());
        const Value& names = *v.field("name");
        ASSERT_EQ(names.items.size(), w["name"].size());
        for (std::size_t q = 0; q < names.items.size(); ++q) {
          EXPECT_EQ(names.items[q].s, w["name"][q].get<std::string>());
          EXPECT_EQ(v.field("position")->items[q].f, w["position"][q].get<double>());
          EXPECT_EQ(v.field("velocity")->items[q].f, w["velocity"][q].get<double>());
        }
        ASSERT_EQ(v.field("effort")->items.size(), w["effort"].size());
        for (std::size_t q = 0; q < w["effort"].size(); ++q)
          EXPECT_EQ(v.field("effort")->items[q].f, w["effort"][q].get<double>());
      } else if (m.channel->topic == "/camera/camera_info") {
        const nlohmann::json& w = truth_["camera_infos"][0];
        const MessageDefinitions info = MessageDefinitions::parse(m.schema->name, m.schema->data, Dialect::Ros2);
        const Value v = decodeCdr(info, data);
        EXPECT_EQ(v.field("distortion_model")->s, w["distortion_model"].get<std::string>());
        ASSERT_EQ(v.field("k")->items.size(), 9u);
        for (std::size_t q = 0; q < 9; ++q) EXPECT_EQ(v.field("k")->items[q].f, w["k"][q].get<double>());
        EXPECT_EQ(v.field("roi")->field("do_rectify")->kind, Value::Kind::Bool);
      } else {
        ASSERT_EQ(m.channel->topic, "/camera/image_raw");
        ASSERT_LT(i, truth_["images"].size());
        const nlohmann::json& w = truth_["images"][i++];
        EXPECT_EQ(m.log_time, ns(w["log_time_ns"]));
        const MessageDefinitions image = MessageDefinitions::parse(m.schema->name, m.schema->data, Dialect::Ros2);
        const Value v = decodeCdr(image, data);
        EXPECT_EQ(v.field("height")->u, w["height"].get<std::uint64_t>());
        EXPECT_EQ(v.field("width")->u, w["width"].get<std::uint64_t>());
        EXPECT_EQ(v.field("encoding")->s, w["encoding"].get<std::string>());
        EXPECT_EQ(v.field("step")->u, w["step"].get<std::uint64_t>());
        const Value& px = *v.field("data");
        ASSERT_EQ(px.kind, Value::Kind::Bytes);
        EXPECT_EQ(std::accumulate(px.bytes.begin(), px.bytes.end(), 0), w["data_sum"].get<int>());
        for (std::size_t q = 0; q < 8; ++q) EXPECT_EQ(px.bytes[q], w["data_first8"][q].get<int>());
      }
    }
    EXPECT_EQ(j, truth_["joint_states"].size());
    EXPECT_EQ(i, truth_["images"].size());
  }
}

TEST_F(McapFixtures, BagInfoMatchesTheWriter) {
  for (const char* name : kFiles) {
    SCOPED_TRACE(name);
    const auto r = runProgram(std::string(KCCD_CLI) + " bag info " + file(name) + " --json");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err, "");
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["messages"], truth_["joint_states"].size() + truth_["images"].size() + truth_["camera_infos"].size());
    EXPECT_TRUE(j["damage"].is_null());
    const nlohmann::json& topics = truth_["files"][name]["topics"];
    ASSERT_EQ(j["topics"].size(), topics.size());
    for (const nlohmann::json& w : topics) {
      const auto it = std::find_if(j["topics"].begin(), j["topics"].end(),
                                   [&](const nlohmann::json& t) { return t["topic"] == w["topic"]; });
      ASSERT_NE(it, j["topics"].end()) << w["topic"];
      const nlohmann::json& t = *it;
      EXPECT_EQ(t["type"], w["schema_name"]);
      EXPECT_EQ(t["schema_encoding"], w["schema_encoding"]);
      EXPECT_EQ(t["message_encoding"], w["message_encoding"]);
      EXPECT_EQ(t["count"], w["count"]);
      EXPECT_EQ(t["first_log_time_ns"], w["first_log_time_ns"]);
      EXPECT_EQ(t["last_log_time_ns"], w["last_log_time_ns"]);
      const double span = 1e-9 * static_cast<double>(ns(w["last_log_time_ns"]) - ns(w["first_log_time_ns"]));
      if (w["count"] > 1) {
        EXPECT_NEAR(t["rate_hz"].get<double>(), (w["count"].get<double>() - 1) / span, 1e-6);
      } else {
        EXPECT_EQ(t["rate_hz"], 0.0);
      }
      // The stamps the writer set: 2 ms (joints) and 35 ms (images, camera info) behind the log times.
      const double skew = w["topic"] == "/joint_states" ? 0.002 : 0.035;
      EXPECT_EQ(t["stamped"], w["count"]);
      EXPECT_EQ(t["zero_stamps"], 0);
      for (const char* k : {"min", "median", "max"}) EXPECT_NEAR(t["skew_s"][k].get<double>(), skew, 1e-6) << k;
      // One channel, one publisher: its row is the topic's.
      ASSERT_EQ(t["publishers"].size(), 1u);
      for (const char* k : {"type", "count", "first_log_time_ns", "last_log_time_ns", "rate_hz", "stamped", "skew_s"})
        EXPECT_EQ(t["publishers"][0][k], t[k]) << k;
      EXPECT_EQ(t["publishers"][0]["metadata"], nlohmann::json::object());
    }
  }
  // The text form names both topics with their types and the skews in milliseconds.
  const auto text = runProgram(std::string(KCCD_CLI) + " bag info " + file("joint_zstd.mcap"));
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("/joint_states  sensor_msgs/msg/JointState  200 messages from 0.000 to 0.199 s, 1000.0 Hz, "
                          "skew 2.000 / 2.000 / 2.000 ms"),
            std::string::npos)
      << text.out;
  EXPECT_NE(text.out.find("/camera/image_raw  sensor_msgs/msg/Image  10 messages"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find(" zstd\n"), std::string::npos) << text.out;
}

TEST_F(McapFixtures, ACutFileReadsAPrefixWithAWarning) {
  for (const char* name : kFiles) {
    SCOPED_TRACE(name);
    const std::string bytes = readText(file(name));
    McapReader whole(file(name));
    std::vector<std::vector<std::uint8_t>> all_bytes;
    const std::vector<LogMessage> full = all(whole, &all_bytes);
    std::size_t cuts = 0, shorter = 0;
    for (std::size_t cut = 8; cut < bytes.size(); cut += 1 + cut % 97) {
      const std::string path = kccd::testing::writeScratch("test_logs", "cut.mcap", bytes.substr(0, cut));
      McapReader r(path);
      std::vector<std::vector<std::uint8_t>> got_bytes;
      std::vector<LogMessage> got;
      ASSERT_NO_THROW(got = all(r, &got_bytes)) << "cut at " << cut;
      ++cuts;
      EXPECT_FALSE(r.damage().empty()) << "cut at " << cut;
      EXPECT_NE(r.damage().find("cut short at byte"), std::string::npos) << r.damage();
      ASSERT_LE(got.size(), full.size());
      shorter += got.size() < full.size();
      for (std::size_t k = 0; k < got.size(); ++k) {  // a prefix of the whole file's messages
        EXPECT_EQ(got[k].log_time, full[k].log_time);
        EXPECT_EQ(got[k].channel->topic, full[k].channel->topic);
        EXPECT_EQ(got_bytes[k], all_bytes[k]);
      }
    }
    EXPECT_GT(cuts, 50u);
    EXPECT_GT(shorter, cuts / 2);
  }
  // The command: a bag cut at 60 % of its bytes is summarised with one warning naming the byte.
  const std::string bytes = readText(file("joint_lz4.mcap"));
  const std::string path =
      kccd::testing::writeScratch("test_logs", "sixty.mcap", bytes.substr(0, bytes.size() * 6 / 10));
  const auto r = runProgram(std::string(KCCD_CLI) + " bag info " + path + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: " + path + ": cut short at byte "), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["messages"].get<int>(), 50);
  EXPECT_LT(j["messages"].get<int>(), 211);
  EXPECT_TRUE(j["damage"].is_string());
}

TEST_F(McapFixtures, DamagedBytesGiveOneLineErrorsOrStillRead) {
  int errors = 0, read = 0;
  for (const char* name : {"joint_zstd.mcap", "joint_plain.mcap", "joint_lz4.mcap"}) {
    const std::string bytes = readText(file(name));
    for (std::size_t at = 0; at < bytes.size(); at += 1 + at % 211) {
      std::string damaged = bytes;
      damaged[at] = static_cast<char>(damaged[at] ^ (1 + at % 255));
      const std::string path = kccd::testing::writeScratch("test_logs", "damaged.mcap", damaged);
      try {
        const BagSummary b = summarizeBag(path);
        ++read;
        EXPECT_LE(b.messages, 211u);
      } catch (const kccd::InputError& e) {
        ++errors;
        const std::string what = e.what();
        EXPECT_EQ(what.rfind(path + ": byte ", 0), 0u) << what;
        EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      }
    }
  }
  // CRCs and structure catch most damage; bytes inside message payloads may decode to other values.
  EXPECT_GT(errors, read);
  std::cout << "damaged files: " << errors << " rejected, " << read << " read\n";
}

// A type of two fields of a type of two fields ... of an empty type holds 2^64 values in no bytes:
// decoding stops at a bound on the messages made per byte, with an error, at once.
TEST(MessageDecoding, TypesThatTakeNoBytesCannotMultiply) {
  std::string text = "T1 a\nT1 b\n";
  for (int k = 1; k < 64; ++k)
    text += std::string(80, '=') + "\nMSG: fuzz_msgs/T" + std::to_string(k) + "\nT" + std::to_string(k + 1) + " a\nT" +
            std::to_string(k + 1) + " b\n";
  text += std::string(80, '=') + "\nMSG: fuzz_msgs/T64\n";
  for (const Dialect dialect : {Dialect::Ros2, Dialect::Ros1}) {
    const MessageDefinitions types = MessageDefinitions::parse("fuzz_msgs/Root", text, dialect);
    const std::vector<std::uint8_t> bytes = {0, 1, 0, 0, 0, 0, 0, 0};
    const auto start = std::chrono::steady_clock::now();
    try {
      (void)(dialect == Dialect::Ros2 ? decodeCdr(types, bytes) : decodeRos1(types, bytes));
      ADD_FAILURE() << "2^64 values decoded";
    } catch (const DecodeError& e) {
      EXPECT_NE(std::string(e.what()).find("types that take no bytes"), std::string::npos) << e.what();
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  }
  // An empty type a few times over is still read.
  const MessageDefinitions few = MessageDefinitions::parse(
      "fuzz_msgs/Root", "E[4] e\n" + std::string(80, '=') + "\nMSG: fuzz_msgs/E\n", Dialect::Ros2);
  EXPECT_EQ(decodeCdr(few, std::vector<std::uint8_t>{0, 1, 0, 0}).items.front().items.size(), 4u);
}

TEST(McapReader, NotAnMcapFileOrNoFile) {
  const std::string text = kccd::testing::writeScratch("test_logs", "text.mcap", "hello, not a log\n");
  try {
    McapReader r(text);
    FAIL() << "read a text file";
  } catch (const kccd::InputError& e) {
    EXPECT_EQ(std::string(e.what()), text + ": byte 0: not an MCAP file (its first 8 bytes are not the MCAP magic)");
  }
  EXPECT_THROW(McapReader("/nonexistent/x.mcap"), kccd::InputError);
  const auto r = runProgram(std::string(KCCD_CLI) + " bag info " + text);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(
      r.err,
      "kccd: " + text +
          ": byte 0: not a robot log kccd reads: its first bytes are those of no MCAP file, rosbag2 sqlite3 (.db3) "
          "file or ROS 1 bag (a rosbag2 folder is given as the folder)\n");
  const std::string empty = kccd::testing::writeScratch("test_logs", "empty.db3", "");
  EXPECT_EQ(runProgram(std::string(KCCD_CLI) + " bag info " + empty).err,
            "kccd: " + empty + ": byte 0: an empty file, not a robot log\n");
  EXPECT_EQ(runProgram(std::string(KCCD_CLI) + " bag info /nonexistent/x.db3").err,
            "kccd: /nonexistent/x.db3: file: cannot be opened (no such file)\n");
}

// An encoder of this file's own (it shares nothing with the decoder): CDR aligned to each
// primitive's size from after the 4-byte header, either byte order; ROS 1 packed little-endian.
class Encoder {
 public:
  Encoder(bool cdr, bool big) : cdr_(cdr), big_(big) {
    if (cdr) out_ = {0, static_cast<std::uint8_t>(big ? 0 : 1), 0, 0};
  }
  template <class T>
  void put(T v) {
    if (cdr_)
      while ((out_.size() - 4) % sizeof(T) != 0) out_.push_back(0xEE);  // padding need not be zero
    std::uint8_t b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (big_) std::reverse(b, b + sizeof(T));
    out_.insert(out_.end(), b, b + sizeof(T));
  }
  void str(const std::string& s) {
    put<std::uint32_t>(static_cast<std::uint32_t>(s.size() + (cdr_ ? 1 : 0)));
    out_.insert(out_.end(), s.begin(), s.end());
    if (cdr_) out_.push_back(0);
  }
  std::vector<std::uint8_t> out_;

 private:
  bool cdr_, big_;
};

const char* const kJointState2 =
    "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n"
    "================================================================================\nMSG: std_msgs/Header\n"
    "builtin_interfaces/Time stamp\nstring frame_id\n"
    "================================================================================\nMSG: builtin_interfaces/Time\n"
    "int32 sec\nuint32 nanosec\n";

TEST(RosMessages, CdrInBothByteOrdersAndRos1) {
  const MessageDefinitions ros2 = MessageDefinitions::parse("sensor_msgs/msg/JointState", kJointState2, Dialect::Ros2);
  for (const bool big : {false, true}) {
    Encoder e(true, big);
    e.put<std::int32_t>(-7), e.put<std::uint32_t>(123456789), e.str("base");
    e.put<std::uint32_t>(2), e.str("a"), e.str("bb");
    e.put<std::uint32_t>(2), e.put<double>(1.5), e.put<double>(-2.25);
    e.put<std::uint32_t>(1), e.put<double>(0.125);
    e.put<std::uint32_t>(0);
    const Value v = decodeCdr(ros2, e.out_);
    EXPECT_EQ(v.field("header")->field("stamp")->field("sec")->i, -7);
    EXPECT_EQ(v.field("header")->field("stamp")->field("nanosec")->u, 123456789u);
    EXPECT_EQ(v.field("header")->field("frame_id")->s, "base");
    EXPECT_EQ(v.field("name")->items.at(1).s, "bb");
    EXPECT_EQ(v.field("position")->items.at(1).f, -2.25);
    EXPECT_EQ(v.field("velocity")->items.at(0).f, 0.125);
    EXPECT_TRUE(v.field("effort")->items.empty());
    // Every shorter message is refused at an offset inside it.
    for (std::size_t n = 0; n < e.out_.size(); ++n) {
      try {
        decodeCdr(ros2, std::span(e.out_.data(), n));
        ADD_FAILURE() << "decoded " << n << " of " << e.out_.size() << " bytes";
      } catch (const DecodeError& err) {
        EXPECT_LE(err.offset(), n);
      }
    }
  }
  // ROS 1: Header has seq and a time; packed, strings without NUL.
  const std::string def1 =
      "Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n"
      "================================================================================\nMSG: std_msgs/Header\n"
      "uint32 seq\ntime stamp\nstring frame_id\n";
  const MessageDefinitions ros1 = MessageDefinitions::parse("sensor_msgs/JointState", def1, Dialect::Ros1);
  Encoder e(false, false);
  e.put<std::uint32_t>(9), e.put<std::uint32_t>(100), e.put<std::uint32_t>(5), e.str("world");
  e.put<std::uint32_t>(1), e.str("j");
  e.put<std::uint32_t>(1), e.put<double>(3.0);
  e.put<std::uint32_t>(0), e.put<std::uint32_t>(0);
  const Value v = decodeRos1(ros1, e.out_);
  EXPECT_EQ(v.field("header")->field("seq")->u, 9u);
  EXPECT_EQ(v.field("header")->field("stamp")->items.at(0).u, 100u);
  EXPECT_EQ(v.field("header")->field("stamp")->items.at(1).u, 5u);
  EXPECT_EQ(v.field("header")->field("frame_id")->s, "world");
  EXPECT_EQ(v.field("position")->items.at(0).f, 3.0);
  // A count larger than the bytes left is refused before anything is made for it.
  Encoder huge(true, false);
  huge.put<std::int32_t>(0), huge.put<std::uint32_t>(0), huge.str("");
  huge.put<std::uint32_t>(0x7fffffff);
  try {
    decodeCdr(ros2, huge.out_);
    ADD_FAILURE() << "decoded a sequence of 2^31 strings from 20 bytes";
  } catch (const DecodeError& err) {
    EXPECT_NE(std::string(err.what()).find("more than the"), std::string::npos) << err.what();
  }
  // Other encapsulations are named.
  std::vector<std::uint8_t> xcdr2{0x00, 0x07, 0, 0, 1, 2, 3, 4};
  try {
    decodeCdr(ros2, xcdr2);
    ADD_FAILURE();
  } catch (const DecodeError& err) {
    EXPECT_NE(std::string(err.what()).find("0x0007 is not plain CDR"), std::string::npos) << err.what();
  }
}

TEST(RosMessages, DefinitionsParseTheirSyntaxAndNameTheLineOfAMistake) {
  // Constants, defaults, comments, bounded and fixed arrays, "pkg/msg/Type" and same-package names.
  const MessageDefinitions d = MessageDefinitions::parse(
      "my_pkg/msg/Thing",
      "# a comment\nint32 LIMIT=5 # a constant\nstring NAME=a#b\nfloat64 x 0.5  # with a default\n"
      "uint8[4] fixed\nint16[<=3] bounded\nstring<=10 label\nOther[] others\nstd_msgs/msg/Empty e\n"
      "================================================================================\nMSG: my_pkg/Other\nbool ok\n"
      "================================================================================\nMSG: std_msgs/msg/Empty\n",
      Dialect::Ros2);
  const MessageType& t = d.root();
  EXPECT_EQ(t.name, "my_pkg/Thing");
  ASSERT_EQ(t.fields.size(), 6u);
  EXPECT_EQ(t.fields[0].name, "x");
  EXPECT_EQ(t.fields[1].array, Field::Array::Fixed);
  EXPECT_EQ(t.fields[1].length, 4u);
  EXPECT_EQ(t.fields[2].array, Field::Array::Dynamic);
  EXPECT_EQ(t.fields[3].primitive, Primitive::String);
  EXPECT_EQ(t.fields[4].type_name, "my_pkg/Other");
  EXPECT_EQ(t.fields[5].type_name, "std_msgs/Empty");
  EXPECT_NE(d.find("std_msgs/Empty"), nullptr);
  struct Case {
    std::string text;
    std::size_t line;
    std::string problem;
  };
  const Case cases[] = {
      {"int32 a\nfloat64[x] b\n", 2, "'x': not an array length"},
      {"int32 a\nint32\n", 2, "'int32': expected TYPE NAME"},
      {"Missing m\n", 0, "the type p/Missing is used but not defined"},
      {"int32 1bad\n", 1, "'1bad' is not a field name"},
      {"p/Root r\n", 0, "the type p/Root contains itself"},
      {"int32 a\n====\nnot a MSG line\n", 3, "expected a 'MSG: pkg/Type' line"},
  };
  for (const Case& c : cases) {
    try {
      MessageDefinitions::parse("p/Root", c.text, Dialect::Ros2);
      ADD_FAILURE() << "parsed: " << c.text;
    } catch (const DefinitionError& e) {
      EXPECT_EQ(e.line(), c.line) << c.text;
      EXPECT_NE(std::string(e.what()).find(c.problem), std::string::npos) << e.what();
    }
  }
  // ROS 1: time and duration are primitives, Header is std_msgs/Header.
  const MessageDefinitions r1 = MessageDefinitions::parse(
      "p/T", "Header h\ntime t\nduration d\n====\nMSG: std_msgs/Header\nuint32 seq\n", Dialect::Ros1);
  EXPECT_EQ(r1.root().fields[0].type_name, "std_msgs/Header");
  EXPECT_EQ(r1.root().fields[1].primitive, Primitive::Time);
  EXPECT_EQ(r1.root().fields[2].primitive, Primitive::Duration);
  // ROS 2 has no time primitive: a type of that name must be defined.
  EXPECT_THROW(MessageDefinitions::parse("p/T", "time t\n", Dialect::Ros2), DefinitionError);
}

// rosbag2 sqlite3: the same messages, written with Python's sqlite3 in rosbag2's layouts (Humble:
// no definitions stored, Jazzy: message_definitions, a split folder), rows not in time order.
TEST_F(McapFixtures, Db3BagsReadAsTheSameMessages) {
  McapReader mcap(file("joint_plain.mcap"));
  std::vector<std::vector<std::uint8_t>> want_bytes;
  const std::vector<LogMessage> want = all(mcap, &want_bytes);
  std::vector<std::string> topics;
  for (const LogMessage& m : want) topics.push_back(m.channel->topic);
  const std::string mcap_info =
      runProgram(std::string(KCCD_CLI) + " bag info " + file("joint_plain.mcap") + " --json").out;
  for (const char* name : {"humble.db3", "jazzy.db3", "split"}) {
    SCOPED_TRACE(name);
    const std::unique_ptr<LogReader> r = openLog(file(name));
    EXPECT_EQ(r->format(), "rosbag2 sqlite3");
    std::vector<std::vector<std::uint8_t>> got_bytes;
    std::vector<std::string> got_topics;
    std::vector<std::uint64_t> got_times;
    LogMessage m;
    while (r->next(m)) {
      got_bytes.emplace_back(m.data.begin(), m.data.end());
      got_topics.push_back(m.channel->topic);
      got_times.push_back(m.log_time);
      ASSERT_NE(m.schema, nullptr);  // stored or built in
    }
    EXPECT_TRUE(r->damage().empty()) << r->damage();
    EXPECT_EQ(got_topics, topics);
    EXPECT_EQ(got_bytes, want_bytes);
    for (std::size_t k = 0; k < want.size() && k < got_times.size(); ++k)
      EXPECT_EQ(got_times[k], want[k].log_time) << k;
    // bag info: the same topics, counts, times and skews as the MCAP file's; where the definitions came from.
    const auto info = runProgram(std::string(KCCD_CLI) + " bag info " + file(name) + " --json");
    ASSERT_EQ(info.code, 0) << info.err;
    nlohmann::json a = nlohmann::json::parse(info.out), b = nlohmann::json::parse(mcap_info);
    for (nlohmann::json& t : a["topics"]) {
      EXPECT_EQ(t["definition"], std::string(name) == "jazzy.db3" ? "stored" : "built in");
      t.erase("definition");
    }
    for (nlohmann::json& t : b["topics"]) t.erase("definition");
    EXPECT_EQ(a["topics"], b["topics"]);
    EXPECT_EQ(a["messages"], b["messages"]);
    EXPECT_EQ(a["format"], "rosbag2 sqlite3");
  }
  // The export of a .db3 is the export of the MCAP file, byte for byte.
  EXPECT_EQ(exportOf(file("humble.db3"), "humble"), exportOf(file("joint_zstd.mcap"), "mcap"));
  EXPECT_EQ(exportOf(file("split"), "split"), exportOf(file("joint_zstd.mcap"), "mcap"));
  // A database cut short: the message rows it still holds, in time order, each as in the whole
  // file, with a warning naming the cut; the more it holds, the more is read.
  const std::string bytes = readText(file("humble.db3"));
  std::vector<std::size_t> counts;
  for (const int percent : {30, 60, 90}) {
    SCOPED_TRACE(percent);
    const std::string cut = kccd::testing::writeScratch("test_logs", "cut" + std::to_string(percent) + ".db3",
                                                        bytes.substr(0, bytes.size() * percent / 100));
    std::unique_ptr<LogReader> r;
    try {
      r = openLog(cut);
    } catch (const kccd::InputError& e) {  // nothing left to read: said so
      EXPECT_NE(
          std::string(e.what()).find("cut short at byte " + std::to_string(bytes.size() * percent / 100) + " of the "),
          std::string::npos)
          << e.what();
      counts.push_back(0);
      continue;
    }
    LogMessage m;
    std::size_t n = 0, k = 0;
    std::uint64_t last = 0;
    while (r->next(m)) {
      while (k < want.size() && !(want[k].log_time == m.log_time && want[k].channel->topic == m.channel->topic &&
                                  want_bytes[k] == std::vector<std::uint8_t>(m.data.begin(), m.data.end())))
        ++k;
      ASSERT_LT(k, want.size()) << "message " << n << " is not one of the file's, in order";
      EXPECT_GE(m.log_time, last);
      last = m.log_time;
      ++n, ++k;
    }
    EXPECT_NE(r->damage().find("cut short at byte " + std::to_string(bytes.size() * percent / 100) + " of the "),
              std::string::npos)
        << r->damage();
    counts.push_back(n);
    const auto info = runProgram(std::string(KCCD_CLI) + " bag info " + cut);
    EXPECT_EQ(info.code, n > 0 ? 0 : 2) << info.err;
  }
  EXPECT_GT(counts[1], 0u);
  EXPECT_LT(counts[2], want.size());
  EXPECT_LE(counts[0], counts[1]);
  EXPECT_LE(counts[1], counts[2]);
  // A damaged schema (not cut): one line that names the file and says what may help.
  std::string broken = bytes;
  for (std::size_t i = 100; i < 160; ++i) broken[i] = '\xff';
  const std::string damaged = kccd::testing::writeScratch("test_logs", "damaged.db3", broken);
  const auto r = runProgram(std::string(KCCD_CLI) + " bag info " + damaged);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err.rfind("kccd: " + damaged + ": sqlite3: ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  // A folder without metadata.yaml: named.
  const fs::path empty = dir_ / "empty_folder";
  fs::create_directories(empty);
  EXPECT_THROW(openLog(empty.string()), kccd::InputError);
}

// ROS 1 bags written by ROS 1's rosbag (chunks plain, bz2, lz4) from the same list: the same
// topics, counts, times and stamps; every cut a prefix with a warning; the same exported bytes.
TEST_F(McapFixtures, Ros1BagsReadAsTheSameRecording) {
  const nlohmann::json mcap = nlohmann::json::parse(
      runProgram(std::string(KCCD_CLI) + " bag info " + file("joint_plain.mcap") + " --json").out);
  for (const char* name : {"ros1_none.bag", "ros1_bz2.bag", "ros1_lz4.bag"}) {
    SCOPED_TRACE(name);
    const auto info = runProgram(std::string(KCCD_CLI) + " bag info " + file(name) + " --json");
    ASSERT_EQ(info.code, 0) << info.err;
    nlohmann::json a = nlohmann::json::parse(info.out), b = mcap;
    EXPECT_EQ(a["format"], "ROS 1 bag");
    const std::string comp = std::string(name).substr(5, std::string(name).find('.') - 5);
    EXPECT_GT(a["chunks"][comp].get<int>(), 3);
    for (nlohmann::json* j : {&a, &b})
      for (nlohmann::json& t : (*j)["topics"]) {
        EXPECT_EQ(t["definition"], "stored");
        t["type"] = kccd::logs::normalTypeName(t["type"].get<std::string>());  // ROS 1 names have no "/msg/"
        t.erase("schema_encoding"), t.erase("message_encoding");
        EXPECT_EQ(t["publishers"].size(), 1u);  // a connection per topic: the publisher's row is the topic's
        t.erase("publishers");
      }
    EXPECT_EQ(a["topics"], b["topics"]);
    // Every cut reads a prefix of the messages (by topic and time) with the warning.
    const std::string bytes = readText(file(name));
    const std::unique_ptr<LogReader> whole = openLog(file(name));
    std::vector<std::pair<std::string, std::uint64_t>> full;
    LogMessage m;
    while (whole->next(m)) full.emplace_back(m.channel->topic, m.log_time);
    EXPECT_EQ(full.size(), 211u);
    std::size_t cuts = 0;
    for (std::size_t cut = 13; cut < bytes.size(); cut += 1 + cut % 173) {
      const std::string path = kccd::testing::writeScratch("test_logs", "cut.bag", bytes.substr(0, cut));
      const std::unique_ptr<LogReader> r = openLog(path);
      std::size_t k = 0;
      ASSERT_NO_THROW({
        while (r->next(m)) {
          ASSERT_LT(k, full.size());
          EXPECT_EQ(std::make_pair(m.channel->topic, m.log_time), full[k]) << "cut at " << cut;
          ++k;
        }
      }) << "cut at "
         << cut;
      EXPECT_NE(r->damage().find("cut short at byte"), std::string::npos) << "cut at " << cut;
      ++cuts;
    }
    EXPECT_GT(cuts, 50u);
  }
  EXPECT_EQ(exportOf(file("ros1_bz2.bag"), "ros1"), exportOf(file("joint_zstd.mcap"), "mcap1"));
}

// Nanoseconds as the decimal text of seconds ("3.3335"): what an exported time must read back as.
double decimalSeconds(std::uint64_t ns) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%llu.%09llu", static_cast<unsigned long long>(ns / 1000000000),
                static_cast<unsigned long long>(ns % 1000000000));
  return std::stod(buf);
}

// Splits a CSV file into rows of fields.
std::vector<std::vector<std::string>> csv(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(readText(path));
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> f;
    std::istringstream l(line);
    for (std::string x; std::getline(l, x, ',');) f.push_back(x);
    rows.push_back(f);
  }
  return rows;
}

TEST_F(McapFixtures, ExportWritesTheSuitesOwnFiles) {
  const fs::path out = dir_ / "export";
  fs::create_directories(out);
  for (const char* clock : {"header", "log"}) {
    SCOPED_TRACE(clock);
    const std::string s = (out / "states.csv").string(), v = (out / "video.mkv").string(),
                      t = (out / "times.csv").string(), c = (out / "camera.yaml").string();
    const auto r =
        runProgram(std::string(KCCD_CLI) + " bag export " + file("joint_lz4.mcap") + " --states " + s + " --video " +
                   v + " --frame-times " + t + " --camera-info " + c + " --time-source " + clock);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err, "");
    // Time 0: the earliest exported time on that clock (the first image's: its stamp is 35 ms behind).
    const bool header = std::string(clock) == "header";
    const std::uint64_t origin = ns(truth_["images"][0]["log_time_ns"]) - (header ? 35000000 : 0);
    EXPECT_NE(r.out.find("time 0 of the files: " + std::to_string(origin) + " ns"), std::string::npos) << r.out;
    // The state log: the first message's joint order, velocities, every message in its own order mapped by name.
    const auto rows = csv(s);
    ASSERT_EQ(rows.size(), 201u);
    ASSERT_EQ(rows[0].size(), 15u);
    EXPECT_EQ(rows[0][0], "time");
    EXPECT_EQ(rows[0][1], "joint1");
    EXPECT_EQ(rows[0][14], "joint7.vel");
    for (std::size_t i = 0; i < 200; ++i) {
      const nlohmann::json& w = truth_["joint_states"][i];
      const std::uint64_t when = header ? std::uint64_t(w["stamp_sec"].get<std::int64_t>()) * 1000000000 +
                                              w["stamp_nanosec"].get<std::uint64_t>()
                                        : ns(w["log_time_ns"]);
      EXPECT_EQ(std::stod(rows[i + 1][0]), decimalSeconds(when - origin))
          << i;  // exactly the decimal, not a product with 1e-9
      for (std::size_t q = 0; q < 7; ++q) {
        const std::string name = w["name"][q];
        const std::size_t col =
            static_cast<std::size_t>(std::find(rows[0].begin(), rows[0].end(), name) - rows[0].begin());
        ASSERT_LT(col, 8u) << name;
        EXPECT_EQ(std::stod(rows[i + 1][col]), w["position"][q].get<double>()) << i << " " << name;
        EXPECT_EQ(std::stod(rows[i + 1][col + 7]), w["velocity"][q].get<double>()) << i << " " << name;
      }
    }
    // The frames: the video (lossless) holds the images as BGR, the frame-times file their times.
    const auto times = csv(t);
    ASSERT_EQ(times.size(), 11u);
    EXPECT_EQ(times[0], (std::vector<std::string>{"frame", "time"}));
    cv::VideoCapture cap(v);
    ASSERT_TRUE(cap.isOpened());
    for (int i = 0; i < 10; ++i) {
      const nlohmann::json& w = truth_["images"][i];
      const std::uint64_t when = ns(w["log_time_ns"]) - (header ? 35000000 : 0);
      EXPECT_EQ(std::stod(times[i + 1][1]), decimalSeconds(when - origin)) << i;
      cv::Mat frame;
      ASSERT_TRUE(cap.read(frame)) << i;
      ASSERT_EQ(frame.size(), cv::Size(64, 48));
      // Byte j of the RGB data is (7 i + j) mod 256: pixel (0, 0) is R = 7i, G = 7i + 1, B = 7i + 2.
      const cv::Vec3b px = frame.at<cv::Vec3b>(0, 0);
      EXPECT_EQ(px, cv::Vec3b((7 * i + 2) % 256, (7 * i + 1) % 256, (7 * i) % 256)) << i;
      long sum = 0;
      for (int y = 0; y < frame.rows; ++y)
        for (int x = 0; x < frame.cols; ++x)
          for (int k = 0; k < 3; ++k) sum += frame.at<cv::Vec3b>(y, x)[k];
      EXPECT_EQ(sum, w["data_sum"].get<long>()) << i;
    }
    // The camera info: an intrinsics file kccd reads.
    const kccd::calib::Camera cam = kccd::calib::loadCamera(c, kccd::calib::CameraPose::Optional);
    const nlohmann::json& w = truth_["camera_infos"][0];
    EXPECT_EQ(cam.width, 64);
    EXPECT_EQ(cam.height, 48);
    for (int q = 0; q < 9; ++q) EXPECT_EQ(cam.camera_matrix(q / 3, q % 3), w["k"][q].get<double>());
    ASSERT_EQ(cam.distortion.size(), 5u);
    for (std::size_t q = 0; q < 5; ++q) EXPECT_EQ(cam.distortion[q], w["d"][q].get<double>());
  }
  // Mistakes: one line naming the option or the bag, nothing written.
  const std::string s = (out / "bad.csv").string();
  struct Case {
    std::string args, message;
  };
  const Case cases[] = {
      {" --states " + s + " --joint-topic /nope",
       "--joint-topic /nope: " + file("joint_zstd.mcap") +
           " has no sensor_msgs/JointState topic of that name (it has: /joint_states)"},
      {" --video " + (out / "v.mkv").string(), "needs --frame-times"},
      {"", "nothing to write"},
      {" --states " + (out / "bad.txt").string(), ".csv"},
  };
  for (const Case& k : cases) {
    const auto r = runProgram(std::string(KCCD_CLI) + " bag export " + file("joint_zstd.mcap") + k.args);
    EXPECT_EQ(r.code, 2) << k.args;
    EXPECT_NE(r.err.find(k.message), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_FALSE(fs::exists(s));
}

TEST(BagImages, EveryEncodingBecomesTheSameBgrFrame) {
  // A 5x3 BGR image, and the same pixels in every encoding the export reads.
  cv::Mat bgr(3, 5, CV_8UC3);
  cv::randu(bgr, 0, 256);
  const std::string def =
      "uint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n";
  const MessageDefinitions types = MessageDefinitions::parse("sensor_msgs/Image", def, Dialect::Ros1);
  auto message = [&](const cv::Mat& m, const std::string& enc, std::vector<std::uint8_t>& bytes, int padding) {
    Encoder e(false, false);
    const std::size_t step = m.cols * m.elemSize() + static_cast<std::size_t>(padding);
    e.put<std::uint32_t>(static_cast<std::uint32_t>(m.rows)), e.put<std::uint32_t>(static_cast<std::uint32_t>(m.cols)),
        e.str(enc);
    e.put<std::uint8_t>(0), e.put<std::uint32_t>(static_cast<std::uint32_t>(step)),
        e.put<std::uint32_t>(static_cast<std::uint32_t>(step * m.rows));
    for (int y = 0; y < m.rows; ++y) {
      e.out_.insert(e.out_.end(), m.ptr<std::uint8_t>(y), m.ptr<std::uint8_t>(y) + m.cols * m.elemSize());
      e.out_.insert(e.out_.end(), static_cast<std::size_t>(padding), 0xAB);
    }
    bytes = e.out_;
    return decodeRos1(types, bytes);
  };
  cv::Mat rgb, bgra, rgba, grey, grey_bgr;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  cv::cvtColor(bgr, bgra, cv::COLOR_BGR2BGRA);
  cv::cvtColor(bgr, rgba, cv::COLOR_BGR2RGBA);
  for (const auto& [m, enc] :
       std::vector<std::pair<cv::Mat, std::string>>{{bgr, "bgr8"}, {rgb, "rgb8"}, {bgra, "bgra8"}, {rgba, "rgba8"}})
    for (const int padding : {0, 3}) {
      std::vector<std::uint8_t> bytes;
      const Value v = message(m, enc, bytes, padding);
      const cv::Mat got = kccd::overlay::imageOf(v, false, "test");
      cv::Mat diff;
      cv::absdiff(got, bgr, diff);
      EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0) << enc << " padding " << padding;
    }
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(grey, grey_bgr, cv::COLOR_GRAY2BGR);
  std::vector<std::uint8_t> bytes;
  EXPECT_EQ(cv::norm(kccd::overlay::imageOf(message(grey, "mono8", bytes, 0), false, "test"), grey_bgr, cv::NORM_INF),
            0);
  cv::Mat grey16;
  grey.convertTo(grey16, CV_16U, 256.0);
  EXPECT_EQ(
      cv::norm(kccd::overlay::imageOf(message(grey16, "mono16", bytes, 0), false, "test"), grey_bgr, cv::NORM_INF), 0);
  // Data shorter than its rows, an unknown encoding: one line naming the place.
  try {
    Value v = message(bgr, "bgr8", bytes, 0);
    v.items[5].bytes = v.items[5].bytes.first(10);
    kccd::overlay::imageOf(v, false, "bag.mcap: byte 7: topic /cam: message 3");
    ADD_FAILURE();
  } catch (const kccd::InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("bag.mcap: byte 7: topic /cam: message 3: the image's data (10 bytes)", 0),
              0u)
        << e.what();
  }
  EXPECT_THROW(kccd::overlay::imageOf(message(bgr, "yuv422", bytes, 0), false, "x"), kccd::InputError);
  // Compressed: PNG and JPEG as OpenCV encodes them.
  const MessageDefinitions ctypes =
      MessageDefinitions::parse("sensor_msgs/CompressedImage", "string format\nuint8[] data\n", Dialect::Ros1);
  for (const char* ext : {".png", ".jpg"}) {
    std::vector<std::uint8_t> enc;
    cv::imencode(ext, bgr, enc);
    Encoder e(false, false);
    e.str(ext + 1), e.put<std::uint32_t>(static_cast<std::uint32_t>(enc.size()));
    e.out_.insert(e.out_.end(), enc.begin(), enc.end());
    const Value v = decodeRos1(ctypes, e.out_);
    const cv::Mat got = kccd::overlay::imageOf(v, true, "x");
    ASSERT_EQ(got.size(), bgr.size());
    if (std::string(ext) == ".png") {
      EXPECT_EQ(cv::norm(got, bgr, cv::NORM_INF), 0);
    }
  }
}

// `kccd overlay --bag`: the same frames (PNG bytes) and report as the overlay of the bag's exported
// files, for a log of each format; the model's joints matched by name; mistakes named.
TEST_F(McapFixtures, OverlayOfABagIsTheOverlayOfItsExportedFiles) {
  const fs::path out = dir_ / "overlay";
  fs::create_directories(out);
  // Seven revolute joints named as the log names them, each with a capsule; a 64x48 camera 2 m away.
  std::string model = "kccd: 1\nname: seven\nsafety_margin: 0.02\njoints:\n";
  for (int k = 1; k <= 7; ++k)
    model += "  - {name: joint" + std::to_string(k) +
             ", parent: " + (k == 1 ? std::string("world") : "joint" + std::to_string(k - 1)) +
             ", type: revolute, origin: {xyz: [0, 0, " + (k == 1 ? "0" : "0.12") + "]}, axis: [" +
             (k % 2 ? "0, 0, 1" : "0, 1, 0") + "], limits: [-3, 3]}\n";
  model += "bodies:\n  - {name: base, frame: world, points: [[0.3, 0, 0], [0.3, 0, 0.5]], radius: 0.05}\n";
  for (int k = 1; k <= 7; ++k)
    model += "  - {name: link" + std::to_string(k) + ", frame: joint" + std::to_string(k) +
             ", points: [[0, 0, 0], [0.05, 0, 0.1]], radius: 0.03}\n";
  const std::string model_path = kccd::testing::writeScratch("test_logs", "seven.yaml", model);
  const std::string camera_path = camera64("cam64.yaml");
  const std::string base = std::string(KCCD_CLI) + " overlay " + model_path + " --camera " + camera_path + " --quiet";
  auto frames = [&](const fs::path& dir) {
    std::vector<std::string> v;
    for (int i = 0; i < 10; ++i)
      v.push_back(readText(
          (dir / ("frame_" + std::string(6 - std::to_string(i).size(), '0') + std::to_string(i) + ".png")).string()));
    return v;
  };
  auto reportFrames = [&](const fs::path& report) {
    nlohmann::json f = nlohmann::json::parse(readText(report.string())).at("frames");
    for (nlohmann::json& x : f) x.erase("written");
    return f;
  };
  for (const char* name : {"joint_zstd.mcap", "humble.db3", "ros1_lz4.bag"}) {
    SCOPED_TRACE(name);
    const fs::path d = out / name;
    fs::create_directories(d);
    const auto ex =
        runProgram(std::string(KCCD_CLI) + " bag export " + file(name) + " -q --states " + (d / "s.csv").string() +
                   " --video " + (d / "v.mkv").string() + " --frame-times " + (d / "t.csv").string());
    ASSERT_EQ(ex.code, 0) << ex.err;
    const auto files = runProgram(base + " --video " + (d / "v.mkv").string() + " --states " + (d / "s.csv").string() +
                                  " --frame-times " + (d / "t.csv").string() + " --png-dir " + (d / "files").string() +
                                  " --report " + (d / "files.json").string());
    ASSERT_EQ(files.code, 0) << files.err;
    const auto direct = runProgram(base + " --bag " + file(name) + " --png-dir " + (d / "bag").string() + " --report " +
                                   (d / "bag.json").string() + " --timeline " + (d / "timeline.png").string());
    ASSERT_EQ(direct.code, 0) << direct.err;
    EXPECT_EQ(direct.err, "");
    const cv::Mat timeline = cv::imread((d / "timeline.png").string());
    EXPECT_EQ(timeline.cols, 1600);
    EXPECT_EQ(nlohmann::json::parse(readText((d / "bag.json").string())).at("timeline"), (d / "timeline.png").string());
    EXPECT_EQ(frames(d / "bag"), frames(d / "files"));
    const nlohmann::json a = reportFrames(d / "bag.json"), b = reportFrames(d / "files.json");
    EXPECT_EQ(a, b);
    ASSERT_EQ(a.size(), 10u);
  }
  // The clocks: the images were logged 35 ms after their stamps, the joints 2 ms after theirs. On the
  // stamps the first image (35 ms before the first log time) precedes every joint state; on the log
  // times it has the first one exactly. Joint 1 moves 0.001 rad per ms: each frame meets states 33 ms
  // later on the log clock.
  const auto header = runProgram(base + " --bag " + file("joint_zstd.mcap") + " --report " + (out / "h.json").string());
  const auto log = runProgram(base + " --bag " + file("joint_zstd.mcap") + " --time-source log --report " +
                              (out / "l.json").string());
  ASSERT_EQ(header.code, 0) << header.err;
  ASSERT_EQ(log.code, 0) << log.err;
  const nlohmann::json h = reportFrames(out / "h.json"), l = reportFrames(out / "l.json");
  const nlohmann::json source = nlohmann::json::parse(readText((out / "l.json").string())).at("source");
  EXPECT_EQ(source.at("time_source"), "log");
  EXPECT_EQ(source.at("image_topic"), "/camera/image_raw");
  EXPECT_EQ(source.at("bag"), file("joint_zstd.mcap"));
  ASSERT_EQ(h.size(), 10u);
  ASSERT_EQ(l.size(), 10u);
  EXPECT_EQ(h.at(0).at("state"), "none");
  EXPECT_EQ(l.at(0).at("state"), "exact");
  EXPECT_EQ(l.at(0).at("state_values").at(0).get<double>(), 0.1);
  for (std::size_t i = 0; i < 10; ++i)
    EXPECT_EQ(h.at(i).at("time"), l.at(i).at("time")) << i;  // the frames' own times: 1/30 s apart
  // Joint states cover 200 ms: frames 1-5 have one on both clocks (the stamps' runs out after frame 6, the log's after
  // 5).
  EXPECT_NE(h.at(6).at("state"), "none");
  EXPECT_EQ(l.at(6).at("state"), "none");
  for (std::size_t i = 1; i <= 5; ++i) {
    EXPECT_NEAR(l.at(i).at("state_values").at(0).get<double>() - h.at(i).at("state_values").at(0).get<double>(), 0.033,
                1e-9)
        << i;
  }
  // Mistakes: one line each.
  struct Case {
    std::string args, message;
  };
  std::string renamed = model;  // joint7 renamed elbow, which the log does not name
  for (std::size_t at; (at = renamed.find("joint7")) != std::string::npos;) renamed.replace(at, 6, "elbow");
  const std::string other = kccd::testing::writeScratch("test_logs", "elbow.yaml", renamed);
  const Case cases[] = {
      {base + " --bag " + file("joint_zstd.mcap") + " --video x.mkv --report r.json", "--video: not with --bag"},
      {base + " --report r.json", "give --video and --states, --bag (a robot log) or --lerobot"},
      {std::string(KCCD_CLI) + " overlay " + other + " --camera " + camera_path + " --bag " + file("joint_zstd.mcap") +
           " --report " + (out / "e.json").string(),
       "the joint states do not name the model's state value 'elbow' (they name: joint1, joint2, joint3, joint4, "
       "joint5, joint6, joint7)"},
      {base + " --bag " + file("joint_zstd.mcap") + " --image-topic /nope --report " + (out / "e.json").string(),
       "--image-topic /nope: "},
  };
  for (const Case& c : cases) {
    const auto r = runProgram(c.args);
    EXPECT_EQ(r.code, 2) << c.args;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

// A joint map: a state value read from a logged joint of another name, scaled and offset, one in
// degrees, one constant; every frame's state values follow from the plain run's. Its mistakes are
// placed at their line.
TEST_F(McapFixtures, AJointMapRenamesScalesAndFixesStateValues) {
  const fs::path out = dir_ / "joint_map";
  fs::create_directories(out);
  auto modelText = [](const std::string& j3, const std::string& j7) {
    std::string model = "kccd: 1\nname: seven\nsafety_margin: 0.02\njoints:\n";
    for (int k = 1; k <= 7; ++k) {
      const std::string name = k == 3 ? j3 : k == 7 ? j7 : "joint" + std::to_string(k);
      model += "  - {name: " + name + ", parent: " +
               (k == 1   ? std::string("world")
                : k == 4 ? j3
                         : "joint" + std::to_string(k - 1)) +
               ", type: revolute, origin: {xyz: [0, 0, " + (k == 1 ? "0" : "0.12") +
               "]}, axis: [0, 0, 1], limits: [-300, 300]}\n";
    }
    model += "bodies:\n  - {name: base, frame: world, points: [[0.3, 0, 0], [0.3, 0, 0.5]], radius: 0.05}\n";
    model += "  - {name: tip, frame: " + j7 + ", points: [[0, 0, 0], [0.05, 0, 0.1]], radius: 0.03}\n";
    return model;
  };
  const std::string plain = kccd::testing::writeScratch("test_logs", "map_plain.yaml", modelText("joint3", "joint7"));
  const std::string renamed = kccd::testing::writeScratch("test_logs", "map_renamed.yaml", modelText("rail", "wrist"));
  const std::string camera = camera64("map_cam.yaml");
  const std::string map = kccd::testing::writeScratch("test_logs", "map.yaml",
                                                      "kccd_joint_map: 1\njoints:\n"
                                                      "  wrist: {from: joint7, scale: -2.5, offset: 0.25}\n"
                                                      "  rail: {constant: 0.125}\n"
                                                      "  joint2: {from: joint2, degrees: true}\n"
                                                      "  joint5: joint1\n");
  const std::string bag = file("joint_lz4.mcap");
  auto run = [&](const std::string& model, const std::string& extra, const std::string& tag) {
    const fs::path report = out / (tag + ".json");
    const auto r = runProgram(std::string(KCCD_CLI) + " overlay " + model + " --camera " + camera + " --bag " + bag +
                              " --report " + report.string() + " --quiet " + extra);
    EXPECT_EQ(r.code, 0) << r.err;
    return std::make_pair(
        r, r.code == 0 ? nlohmann::json::parse(readText(report.string())).at("frames") : nlohmann::json());
  };
  const auto [plain_run, a] = run(plain, "", "plain");
  const auto [mapped_run, b] = run(renamed, "--joint-map " + map, "mapped");
  ASSERT_EQ(a.size(), 10u);
  ASSERT_EQ(b.size(), 10u);
  EXPECT_EQ(plain_run.err, "");
  EXPECT_NE(mapped_run.err.find("logged joints the model does not read, left out: joint3, joint5\n"), std::string::npos)
      << mapped_run.err;
  int compared = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].at("state"), b[i].at("state")) << i;
    if (a[i].at("state") == "none") continue;
    std::vector<double> p = a[i].at("state_values").get<std::vector<double>>(),
                        q = b[i].at("state_values").get<std::vector<double>>();
    ASSERT_EQ(p.size(), 7u);
    ASSERT_EQ(q.size(), 7u);
    EXPECT_EQ(q[0], p[0]);
    EXPECT_DOUBLE_EQ(q[1], p[1] * M_PI / 180.0);
    EXPECT_EQ(q[2], 0.125);
    EXPECT_EQ(q[3], p[3]);
    EXPECT_EQ(q[4], p[0]);  // joint5 read from joint1
    EXPECT_EQ(q[5], p[5]);
    EXPECT_DOUBLE_EQ(q[6], -2.5 * p[6] + 0.25);
    ++compared;
  }
  EXPECT_GE(compared, 5);
  // Without the map the renamed model's values are missing; with a map of mistakes, each is placed.
  struct Case {
    std::string map, message;
  };
  const Case cases[] = {
      {"", "the joint states do not name the model's state value 'rail' (they name: "},
      {"kccd_joint_map: 1\njoints:\n  wrist: joint7\n  elbow: joint3\n",
       "map.yaml:4:3: joints.elbow: the model has no state value of that name"},
      {"kccd_joint_map: 1\njoints:\n  wrist: joint7\n  rail: {from: joint3, constant: 1}\n", "map.yaml:4:"},
      {"kccd_joint_map: 1\njoints:\n  wrist: joint7\n  rail: {from: joint3, scale: 0}\n",
       "joints.rail.scale: 0 would ignore the log"},
      {"kccd_joint_map: 1\njoints:\n  wrist: joint7\n  rail: {from: joint3, gain: 2}\n", "joints.rail"},
      {"kccd_joint_map: 2\njoints: {}\n", "kccd_joint_map: expected 1"},
      {"kccd_joint_map: 1\njoints:\n  wrist: joint7\n  rail: {from: joint9}\n",
       "the joint states do not name 'joint9', which "},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.map);
    std::string extra;
    if (!c.map.empty()) extra = " --joint-map " + kccd::testing::writeScratch("test_logs", "bad_map.yaml", c.map);
    const auto r = runProgram(std::string(KCCD_CLI) + " overlay " + renamed + " --camera " + camera + " --bag " + bag +
                              " --report " + (out / "bad.json").string() + extra);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out / "bad.json"));
  }
  const auto no_bag =
      runProgram(std::string(KCCD_CLI) + " overlay " + plain + " --camera " + camera +
                 " --video v.mkv --states s.csv --joint-map " + map + " --report " + (out / "bad.json").string());
  EXPECT_EQ(no_bag.code, 2);
  EXPECT_NE(no_bag.err.find("--joint-map: goes with --bag"), std::string::npos) << no_bag.err;
}

// A golden case on a frame of a robot log: its picture is the image topic's frame and its state the
// joint states' at that frame's time, so the overlay golden is the frame `overlay --bag` draws,
// pixel for pixel, whichever format holds the log; golden.json names the bag, topics and clock.
TEST_F(McapFixtures, AGoldenCaseOnABagFrameIsTheOverlaysFrame) {
  const fs::path out = dir_ / "golden";
  fs::remove_all(out);
  fs::create_directories(out);
  const std::string model = kccd::testing::writeScratch(
      "test_logs", "golden_seven.yaml",
      "kccd: 1\nname: seven\nsafety_margin: 0.02\njoints:\n"
      "  - {name: joint1, parent: world, type: revolute, axis: [0, 0, 1], limits: [-3, 3]}\n"
      "  - {name: joint2, parent: joint1, type: revolute, origin: {xyz: [0, 0, 0.12]}, axis: [0, 1, 0], limits: [-3, "
      "3]}\n"
      "  - {name: joint3, parent: joint2, type: revolute, origin: {xyz: [0, 0, 0.12]}, axis: [0, 0, 1], limits: [-3, "
      "3]}\n"
      "  - {name: joint4, parent: joint3, type: revolute, origin: {xyz: [0, 0, 0.12]}, axis: [0, 1, 0], limits: [-3, "
      "3]}\n"
      "  - {name: joint5, parent: joint4, type: revolute, origin: {xyz: [0, 0, 0.12]}, axis: [0, 0, 1], limits: [-3, "
      "3]}\n"
      "  - {name: joint6, parent: joint5, type: revolute, origin: {xyz: [0, 0, 0.12]}, axis: [0, 1, 0], limits: [-3, "
      "3]}\n"
      "  - {name: joint7, parent: joint6, type: revolute, origin: {xyz: [0, 0, 0.12]}, axis: [0, 0, 1], limits: [-3, "
      "3]}\n"
      "bodies:\n  - {name: base, frame: world, points: [[0.3, 0, 0], [0.3, 0, 0.5]], radius: 0.05}\n"
      "  - {name: arm, frame: joint4, points: [[0, 0, 0], [0.3, 0, 0.1]], radius: 0.04}\n");
  const std::string camera = camera64("golden_cam.yaml");
  const std::string manifest = (out / "manifest.yaml").string();
  std::ofstream(manifest)
      << "kccd_golden: 1\ndefaults: {model: " << model << ", camera: " << camera << ", bag: " << file("joint_zstd.mcap")
      << ", outputs: [mask, overlay]}\ncases:\n  - {id: mcap-f2, frame: 2}\n  - {id: mcap-f5, frame: 5}\n"
      << "  - {id: db3-f5, frame: 5, bag: " << file("jazzy.db3")
      << "}\n  - {id: ros1-f5, frame: 5, bag: " << file("ros1_bz2.bag") << "}\n";
  const auto update = runProgram(std::string(KCCD_CLI) + " golden update " + manifest + " -q");
  ASSERT_EQ(update.code, 0) << update.err;
  const auto run =
      runProgram(std::string(KCCD_CLI) + " golden run " + manifest + " --out " + (out / "results").string() + " -q");
  EXPECT_EQ(run.code, 0) << run.out << run.err;
  const auto overlay = runProgram(std::string(KCCD_CLI) + " overlay " + model + " --camera " + camera + " --bag " +
                                  file("joint_zstd.mcap") + " --png-dir " + (out / "overlay").string() + " -q");
  ASSERT_EQ(overlay.code, 0) << overlay.err;
  auto same = [](const cv::Mat& a, const cv::Mat& b) {
    return a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0;
  };
  const cv::Mat drawn2 = cv::imread((out / "overlay" / "frame_000002.png").string()),
                drawn5 = cv::imread((out / "overlay" / "frame_000005.png").string());
  ASSERT_FALSE(drawn5.empty());
  EXPECT_TRUE(same(cv::imread((out / "goldens" / "mcap-f2" / "overlay.png").string()), drawn2));
  for (const char* id : {"mcap-f5", "db3-f5", "ros1-f5"}) {
    SCOPED_TRACE(id);
    EXPECT_TRUE(same(cv::imread((out / "goldens" / id / "overlay.png").string()), drawn5));
  }
  EXPECT_FALSE(same(drawn2, drawn5));  // another frame, another state: the comparison can fail
  const nlohmann::json g =
      nlohmann::json::parse(readText((out / "goldens" / "mcap-f5" / "golden.json").string())).at("inputs").at("bag");
  EXPECT_EQ(g.at("frame"), 5);
  EXPECT_EQ(g.at("image_topic"), "/camera/image_raw");
  EXPECT_EQ(g.at("joint_topic"), "/joint_states");
  EXPECT_EQ(g.at("time_source"), "header");
  // Mistakes: a frame the bag does not have; a bag and a video in one case.
  std::ofstream(manifest) << "kccd_golden: 1\ndefaults: {model: " << model << ", camera: " << camera
                          << ", bag: " << file("joint_zstd.mcap") << "}\ncases:\n  - {id: far, frame: 10}\n";
  const auto far =
      runProgram(std::string(KCCD_CLI) + " golden run " + manifest + " --out " + (out / "r2").string() + " -q");
  EXPECT_EQ(far.code, 2);
  EXPECT_NE(far.err.find("case 'far'.frame: 10: " + file("joint_zstd.mcap") + " has 10 images on /camera/image_raw"),
            std::string::npos)
      << far.err;
  std::ofstream(manifest) << "kccd_golden: 1\ndefaults: {model: " << model << ", camera: " << camera
                          << "}\ncases:\n  - {id: both, frame: 1, bag: " << file("joint_zstd.mcap")
                          << ", video: v.mkv, states: s.csv}\n";
  const auto both =
      runProgram(std::string(KCCD_CLI) + " golden run " + manifest + " --out " + (out / "r3").string() + " -q");
  EXPECT_EQ(both.code, 2);
  EXPECT_NE(both.err.find("manifest.yaml:4:"), std::string::npos) << both.err;
  EXPECT_NE(both.err.find("give video and states, a bag, or a lerobot dataset, one of them"), std::string::npos)
      << both.err;
}

// The same messages written topic by topic (tests/bags/write_mcap.mjs: joint_overlap.mcap, zstd
// chunks whose time ranges overlap): read in log-time order from the chunk index, as the file
// written in time order reads, message for message; and the summary, export and overlay agree.
TEST_F(McapFixtures, ChunksThatOverlapInTimeAreMergedByLogTime) {
  McapReader ordered(file("joint_zstd.mcap")), overlapping(file("joint_overlap.mcap"));
  EXPECT_FALSE(ordered.merging());
  EXPECT_TRUE(overlapping.merging());
  std::vector<std::vector<std::uint8_t>> a_bytes, b_bytes;
  const std::vector<LogMessage> a = all(ordered, &a_bytes), b = all(overlapping, &b_bytes);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), 211u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].log_time, b[i].log_time) << i;
    EXPECT_EQ(a[i].channel->topic, b[i].channel->topic) << i;
    EXPECT_EQ(a[i].sequence, b[i].sequence) << i;
    EXPECT_EQ(a_bytes[i], b_bytes[i]) << i;
  }
  EXPECT_TRUE(overlapping.damage().empty());
  EXPECT_GT(overlapping.chunks().at("zstd"), 2);
  const auto info_a = runProgram(std::string(KCCD_CLI) + " bag info " + file("joint_zstd.mcap") + " --json");
  const auto info_b = runProgram(std::string(KCCD_CLI) + " bag info " + file("joint_overlap.mcap") + " --json");
  EXPECT_EQ(nlohmann::json::parse(info_a.out)["topics"], nlohmann::json::parse(info_b.out)["topics"]);
  EXPECT_EQ(exportOf(file("joint_overlap.mcap"), "overlap"), exportOf(file("joint_zstd.mcap"), "mcap"));
}

// What a reader streams, copied out of its views (which last until its next message).
struct Read {
  std::string topic;
  std::uint16_t channel = 0;
  std::uint64_t log_time = 0, offset = 0;
  std::vector<std::uint8_t> bytes;
};

std::vector<Read> readAll(LogReader& r) {
  std::vector<Read> out;
  LogMessage m;
  while (r.next(m))
    out.push_back(Read{m.channel->topic, m.channel->id, m.log_time, m.offset, {m.data.begin(), m.data.end()}});
  return out;
}

nlohmann::json infoJson(const std::string& bag) {
  const auto r = runProgram(std::string(KCCD_CLI) + " bag info " + bag + " --json");
  EXPECT_EQ(r.code, 0) << r.err;
  return r.code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
}

// A topic several nodes publish (a ROS 1 connection each, as `rosbag record` writes a PR2's /tf;
// an MCAP channel each) is one row of bag info with its publishers' rows under it: the topics'
// rows are those of the same log with one publisher per topic, each publisher's those of its own
// messages (joint state k came from publisher k mod 3).
TEST_F(McapFixtures, ATopicOfSeveralPublishersIsOneRow) {
  const char* const callers[] = {"/arm_controller", "/gripper_controller", "/joint_state_publisher"};
  const nlohmann::json& joints = truth_["joint_states"];
  for (const auto& [name, single] :
       {std::pair{"ros1_publishers.bag", "ros1_none.bag"}, std::pair{"joint_publishers.mcap", "joint_zstd.mcap"}}) {
    SCOPED_TRACE(name);
    nlohmann::json a = infoJson(file(name)), b = infoJson(file(single));
    ASSERT_EQ(a["topics"].size(), 3u);
    for (const nlohmann::json& t : a["topics"]) {
      if (t["topic"] != "/joint_states") {
        EXPECT_EQ(t["publishers"].size(), 1u) << t["topic"];
        continue;
      }
      const nlohmann::json& pubs = t["publishers"];
      ASSERT_EQ(pubs.size(), 3u);
      for (std::size_t p = 0; p < 3; ++p) {
        SCOPED_TRACE(callers[p]);
        const std::size_t n = (joints.size() + 2 - p) / 3;
        EXPECT_EQ(pubs[p]["metadata"]["callerid"], callers[p]);
        EXPECT_EQ(pubs[p]["type"], t["type"]);
        EXPECT_EQ(pubs[p]["count"], n);
        EXPECT_EQ(pubs[p]["first_log_time_ns"], joints[p]["log_time_ns"]);
        EXPECT_EQ(pubs[p]["last_log_time_ns"], joints[p + 3 * (n - 1)]["log_time_ns"]);
        EXPECT_NEAR(pubs[p]["rate_hz"].get<double>(), 1000.0 / 3, 1e-6);  // 3 ms apart
        EXPECT_EQ(pubs[p]["stamped"], n);
        EXPECT_NEAR(pubs[p]["skew_s"]["median"].get<double>(), 0.002, 1e-6);
      }
    }
    for (nlohmann::json* j : {&a, &b})
      for (nlohmann::json& t : (*j)["topics"]) t.erase("publishers");
    EXPECT_EQ(a["topics"], b["topics"]);
    EXPECT_EQ(a["messages"], b["messages"]);
    // The text: one line for the topic, with its publisher count.
    const auto text = runProgram(std::string(KCCD_CLI) + " bag info " + file(name));
    ASSERT_EQ(text.code, 0) << text.err;
    std::size_t lines = 0;
    for (std::size_t at = 0; (at = text.out.find("\n  /joint_states  ", at)) != std::string::npos; ++at) ++lines;
    EXPECT_EQ(lines, 1u) << text.out;
    EXPECT_NE(text.out.find("  200 messages (3 publishers) from 0.000 to 0.199 s, 1000.0 Hz, skew 2.000 / 2.000 / "
                            "2.000 ms\n"),
              std::string::npos)
        << text.out;
    EXPECT_EQ(text.out.find("publisher)"), std::string::npos) << text.out;  // one publisher: no count
  }
}

// A rosbag2 bag split into MCAP files (11, listed in its metadata.yaml, each giving the topics other
// channel ids) reads as one log: the messages of the one-file log in the same order, one channel
// per topic, places naming the file; bag info and the export as the one file's. A file cut short
// loses its own tail only; a file missing, or files of two storages, are errors naming them.
TEST_F(McapFixtures, ABagSplitIntoMcapFilesReadsAsOneLog) {
  McapReader one(file("joint_zstd.mcap"));
  const std::vector<Read> want = readAll(one);
  const std::unique_ptr<LogReader> r = openLog(file("split_mcap"));
  EXPECT_EQ(r->format(), "MCAP");
  const std::vector<Read> got = readAll(*r);
  EXPECT_TRUE(r->damage().empty()) << r->damage();
  EXPECT_EQ(r->profile(), truth_["profile"]);
  EXPECT_EQ(r->library(), truth_["library"]);
  ASSERT_EQ(got.size(), want.size());
  std::map<std::string, std::uint16_t> channel_of;
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(got[k].topic, want[k].topic) << k;
    EXPECT_EQ(got[k].log_time, want[k].log_time) << k;
    EXPECT_EQ(got[k].bytes, want[k].bytes) << k;
    const auto [it, fresh] = channel_of.try_emplace(got[k].topic, got[k].channel);
    EXPECT_EQ(it->second, got[k].channel) << k << " " << got[k].topic;
  }
  std::set<std::uint16_t> ids;
  for (const auto& [topic, id] : channel_of) ids.insert(id);
  EXPECT_EQ(ids.size(), 3u);
  const std::size_t first3 = 3 * want.size() / 11;  // the writer's division
  EXPECT_EQ(r->place(got[first3].offset).rfind("rec_3.mcap byte ", 0), 0u) << r->place(got[first3].offset);
  EXPECT_EQ(r->place(got[first3 - 1].offset).rfind("rec_2.mcap byte ", 0), 0u) << r->place(got[first3 - 1].offset);
  int chunks = 0;
  for (int k = 0; k < 11; ++k) {
    McapReader part(file("split_mcap/rec_" + std::to_string(k) + ".mcap"));
    all(part);
    chunks += part.chunks().at("zstd");
  }
  EXPECT_EQ(r->chunks().at("zstd"), chunks);
  // bag info: the one file's topics; the chunks of all files.
  const nlohmann::json a = infoJson(file("split_mcap")), b = infoJson(file("joint_zstd.mcap"));
  EXPECT_EQ(a["format"], "MCAP");
  EXPECT_EQ(a["topics"], b["topics"]);
  EXPECT_EQ(a["messages"], b["messages"]);
  EXPECT_EQ(a["chunks"]["zstd"], chunks);
  EXPECT_EQ(exportOf(file("split_mcap"), "split_mcap"), exportOf(file("joint_zstd.mcap"), "mcap"));

  // rec_5 cut at half: rec_0 to rec_4 whole, a prefix of rec_5, rec_6 on whole, with a warning.
  const fs::path cut = dir_ / "split_mcap_cut";
  fs::create_directories(cut);
  fs::copy(dir_ / "split_mcap", cut, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  const std::string five = readText((cut / "rec_5.mcap").string());
  std::ofstream((cut / "rec_5.mcap").string(), std::ios::binary) << five.substr(0, five.size() / 2);
  const std::unique_ptr<LogReader> c = openLog(cut.string());
  const std::vector<Read> part = readAll(*c);
  EXPECT_EQ(c->damage().rfind("rec_5.mcap: cut short at byte ", 0), 0u) << c->damage();
  const std::size_t first5 = 5 * want.size() / 11, first6 = 6 * want.size() / 11;
  ASSERT_LT(part.size(), want.size());
  const std::size_t lost = want.size() - part.size();
  EXPECT_LE(lost, first6 - first5);
  for (std::size_t k = 0; k < part.size(); ++k) {
    const std::size_t w = k < first6 - lost ? k : k + lost;
    EXPECT_EQ(part[k].log_time, want[w].log_time) << k;
    EXPECT_EQ(part[k].bytes, want[w].bytes) << k;
  }
  const auto warned = runProgram(std::string(KCCD_CLI) + " bag info " + cut.string());
  EXPECT_EQ(warned.code, 0) << warned.err;
  EXPECT_NE(warned.err.find("warning: " + cut.string() + ": rec_5.mcap: cut short at byte "), std::string::npos)
      << warned.err;

  // A file the metadata lists that is not there; an MCAP file listed with a .db3 file.
  const auto folder = [&](const std::string& name, const std::vector<std::string>& files) {
    const fs::path d = dir_ / name;
    fs::create_directories(d);
    std::string meta =
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  relative_file_paths:\n";
    for (const std::string& f : files) {
      meta += "    - " + f + "\n";
      for (const fs::path& from : {dir_ / "split_mcap" / f, dir_ / "split" / f})
        if (fs::exists(from)) fs::copy_file(from, d / f, fs::copy_options::overwrite_existing);
    }
    std::ofstream((d / "metadata.yaml").string()) << meta;
    return d.string();
  };
  const std::string missing = folder("split_missing", {"rec_0.mcap", "rec_99.mcap"});
  try {
    openLog(missing);
    ADD_FAILURE() << "a missing file read";
  } catch (const kccd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("rec_99.mcap: file: listed in the folder's metadata.yaml, but not a file"),
              std::string::npos)
        << e.what();
  }
  const std::string mixed = folder("split_mixed", {"rec_0.mcap", "split_1.db3"});
  try {
    openLog(mixed);
    ADD_FAILURE() << "MCAP and sqlite3 files read as one log";
  } catch (const kccd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("MCAP files and files of another kind"), std::string::npos) << e.what();
  }
}

// A ROS 1 bag cut inside an uncompressed chunk: a 100 Hz log of 4 MB in rosbag's default chunks of
// 768 KiB, cut at points inside its first chunk (at 300 kB, as a copy stopped early, it read no
// message before): exactly the messages whose records end before the cut (the writer found each
// record's end by its bytes), in order, each as in the whole bag; the damage names the cut chunk.
TEST_F(McapFixtures, ARos1BagCutInsideAnUncompressedChunkKeepsItsWholeRecords) {
  const nlohmann::json big = nlohmann::json::parse(readText(file("big_truth.json")));
  const std::unique_ptr<LogReader> whole = openLog(file("ros1_big_none.bag"));
  const std::vector<Read> full = readAll(*whole);
  EXPECT_TRUE(whole->damage().empty()) << whole->damage();
  ASSERT_EQ(full.size(), big["messages"].size());
  std::vector<std::uint64_t> ends;
  for (std::size_t k = 0; k < full.size(); ++k) {
    EXPECT_EQ(full[k].log_time, ns(big["messages"][k]["log_time_ns"])) << k;
    ends.push_back(big["messages"][k]["record_end"].get<std::uint64_t>());
  }
  const nlohmann::json& bag = big["bags"]["ros1_big_none.bag"];
  const std::uint64_t chunk = bag["chunks"][0], next_chunk = bag["chunks"][1];
  ASSERT_GT(next_chunk - chunk, 768u * 1024);
  const std::string bytes = readText(file("ros1_big_none.bag"));
  // The first chunk's record ends with its last message's (index records follow it).
  const auto in_first = static_cast<std::size_t>(
      std::count_if(ends.begin(), ends.end(), [&](std::uint64_t e) { return e < next_chunk; }));
  const std::uint64_t chunk_end = ends[in_first - 1];
  std::vector<std::uint64_t> cuts = {chunk + 100, ends[0] - 1,   ends[0],   ends[0] + 1,
                                     300000,      ends[400] - 1, ends[400], chunk_end - 1};
  for (std::uint64_t c = chunk + 50000; c < chunk_end; c += 97003) cuts.push_back(c);
  for (const std::uint64_t cut : cuts) {
    SCOPED_TRACE("cut at " + std::to_string(cut));
    const auto want =
        static_cast<std::size_t>(std::count_if(ends.begin(), ends.end(), [&](auto e) { return e <= cut; }));
    const std::string path = kccd::testing::writeScratch("test_logs", "cut_big.bag", bytes.substr(0, cut));
    const std::unique_ptr<LogReader> r = openLog(path);
    std::vector<Read> got;
    ASSERT_NO_THROW(got = readAll(*r));
    ASSERT_EQ(got.size(), want);
    for (std::size_t k = 0; k < got.size(); ++k) {
      EXPECT_EQ(got[k].log_time, full[k].log_time) << k;
      EXPECT_EQ(got[k].bytes, full[k].bytes) << k;
    }
    EXPECT_NE(r->damage().find("cut short at byte " + std::to_string(chunk) + " of " + std::to_string(cut) +
                               " (inside a record's "),
              std::string::npos)
        << r->damage();
    EXPECT_NE(r->damage().find(": an uncompressed chunk: its records whole before the cut are read)"),
              std::string::npos)
        << r->damage();
  }
  // At 300 kB of the 4 MB: hundreds of messages, and bag info says so with one warning.
  const auto at300k =
      static_cast<std::size_t>(std::count_if(ends.begin(), ends.end(), [](auto e) { return e <= 300000; }));
  EXPECT_GT(at300k, 250u);
  const std::string path = kccd::testing::writeScratch("test_logs", "cut_300k.bag", bytes.substr(0, 300000));
  const auto info = runProgram(std::string(KCCD_CLI) + " bag info " + path + " --json");
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["messages"], at300k);
  EXPECT_EQ(std::count(info.err.begin(), info.err.end(), '\n'), 1) << info.err;
  EXPECT_NE(info.err.find("warning: " + path + ": cut short at byte " + std::to_string(chunk)), std::string::npos)
      << info.err;
}

// A ROS 1 bag cut inside a compressed chunk (bz2, lz4; 2 MiB chunks of random image bytes, so
// several compressed blocks each): what the bytes before the cut decompress to is read, the
// messages whose records are whole in it, exactly as Python's streaming decoders make of the same
// bytes (the writer's figures); where nothing decompresses (a cut inside the first block), no
// message, and the damage says which.
TEST_F(McapFixtures, ARos1BagCutInsideACompressedChunkKeepsWhatDecompresses) {
  const nlohmann::json big = nlohmann::json::parse(readText(file("big_truth.json")));
  for (const char* name : {"ros1_big_bz2.bag", "ros1_big_lz4.bag"}) {
    SCOPED_TRACE(name);
    const std::string compression = std::string(name).substr(9, 3);
    const std::unique_ptr<LogReader> whole = openLog(file(name));
    const std::vector<Read> full = readAll(*whole);
    ASSERT_EQ(full.size(), big["messages"].size());
    const std::string bytes = readText(file(name));
    const std::string chunk = std::to_string(big["bags"][name]["chunks"][0].get<std::uint64_t>());
    std::size_t kept = 0;
    for (const nlohmann::json& c : big["bags"][name]["cuts"]) {
      const auto cut = c["cut"].get<std::size_t>();
      SCOPED_TRACE("cut at " + std::to_string(cut));
      const std::string path = kccd::testing::writeScratch("test_logs", "cut_big." + compression, bytes.substr(0, cut));
      const std::unique_ptr<LogReader> r = openLog(path);
      std::vector<Read> got;
      ASSERT_NO_THROW(got = readAll(*r));
      ASSERT_EQ(got.size(), c["messages"].get<std::size_t>());
      for (std::size_t k = 0; k < got.size(); ++k) {
        EXPECT_EQ(got[k].log_time, full[k].log_time) << k;
        EXPECT_EQ(got[k].bytes, full[k].bytes) << k;
      }
      const std::string& d = r->damage();
      EXPECT_EQ(d.rfind("cut short at byte " + chunk + " of " + std::to_string(cut) + " (inside a record's ", 0), 0u)
          << d;
      if (c["decompressed"] == 0) {
        EXPECT_NE(d.find(": a chunk compressed with " + compression + " of which nothing decompresses before the cut"),
                  std::string::npos)
            << d;
      } else {
        EXPECT_NE(d.find(": a chunk compressed with " + compression + " whose first " + c["decompressed"].dump() +
                         " of " + c["chunk_size"].dump() + " bytes decompress before the cut"),
                  std::string::npos)
            << d;
      }
      kept = std::max(kept, got.size());
    }
    EXPECT_GT(kept, 800u);  // a whole block's messages at least
  }
}

}  // namespace

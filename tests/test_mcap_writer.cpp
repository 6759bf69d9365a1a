// Writing robot logs: kccd::logs::McapWriter read back by the suite's McapReader and walked record by
// record as the MCAP spec lays them out (magic, opcodes, lengths, the summary's groups, the
// footer), its CRCs checked by damaging bytes; JointState's and CompressedImage's CDR bytes decoded
// by the suite's CDR decoder with the definitions written beside them; and a state log written as a
// bag (kccd::overlay::writeStateLogBag, StateLogBagWriter with frames) read back by `overlay --bag`'s
// reader as the same samples and frames. Other projects' readers (@mcap/core) check a written bag
// in test_synth.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "kccd/input_error.hpp"
#include "kccd/logs/decode.hpp"
#include "kccd/logs/joint_state_cdr.hpp"
#include "kccd/logs/log_reader.hpp"
#include "kccd/logs/mcap_reader.hpp"
#include "kccd/logs/mcap_writer.hpp"
#include "kccd/logs/message_definition.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/bags/bag_recording.hpp"
#include "kccd/overlay/bags/state_log_bag.hpp"
#include "kccd/overlay/common/staged_output.hpp"
#include "kccd/overlay/recording/frame_source.hpp"
#include "kccd/state_log.hpp"
#include "support/files.hpp"

namespace {

namespace fs = std::filesystem;
using namespace kccd::logs;

const std::string kTag = "test_mcap_writer";

std::vector<std::uint8_t> bytesOf(const std::string& s) { return {s.begin(), s.end()}; }

std::uint64_t le(const std::string& b, std::size_t at, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v |= static_cast<std::uint64_t>(static_cast<unsigned char>(b[at + i])) << (8 * i);
  return v;
}

// A file of two schemas, three channels (one without a schema, one with metadata) and interleaved
// messages; finished unless `finish` is false.
std::string sampleFile(bool finish = true) {
  std::ostringstream out;
  McapWriter w(out, "ros2", "kccd test");
  const std::uint16_t a = w.addSchema("pkg/msg/A", "ros2msg", "int32 x\n");
  const std::uint16_t b = w.addSchema("pkg/msg/B", "ros2msg", "string s\n");
  EXPECT_EQ(a, 1);
  EXPECT_EQ(b, 2);
  const std::uint16_t ca = w.addChannel(a, "/a", "cdr");
  const std::uint16_t cb = w.addChannel(b, "/b", "cdr", {{"offered_qos_profiles", ""}, {"k", "v"}});
  const std::uint16_t cn = w.addChannel(0, "/raw", "json");
  EXPECT_EQ(ca, 0);
  EXPECT_EQ(cb, 1);
  EXPECT_EQ(cn, 2);
  w.write(ca, 1000, 990, bytesOf("a0"));
  w.write(cb, 2000, 2000, bytesOf("b0-longer"));
  w.write(ca, 3000, 3000, bytesOf(""));
  w.write(cn, 2500, 2400, bytesOf("{}"));
  if (finish) w.finish();
  return out.str();
}

TEST(McapWriter, ReadsBackRecordForRecord) {
  const std::string path = kccd::testing::writeScratch(kTag, "sample.mcap", sampleFile());
  McapReader r(path);
  struct Seen {
    std::string topic, encoding, schema;
    std::uint32_t sequence;
    std::uint64_t log, publish;
    std::string data;
  };
  std::vector<Seen> seen;
  LogMessage m;
  while (r.next(m))
    seen.push_back({m.channel->topic, m.channel->message_encoding, m.schema ? m.schema->name : "", m.sequence,
                    m.log_time, m.publish_time, std::string(m.data.begin(), m.data.end())});
  EXPECT_EQ(r.damage(), "");
  EXPECT_EQ(r.profile(), "ros2");
  EXPECT_EQ(r.library(), "kccd test");
  EXPECT_TRUE(r.chunks().empty());
  ASSERT_EQ(seen.size(), 4u);  // in file order: one data section, no chunks
  const Seen want[] = {{"/a", "cdr", "pkg/msg/A", 0, 1000, 990, "a0"},
                       {"/b", "cdr", "pkg/msg/B", 0, 2000, 2000, "b0-longer"},
                       {"/a", "cdr", "pkg/msg/A", 1, 3000, 3000, ""},
                       {"/raw", "json", "", 0, 2500, 2400, "{}"}};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(seen[i].topic, want[i].topic) << i;
    EXPECT_EQ(seen[i].encoding, want[i].encoding) << i;
    EXPECT_EQ(seen[i].schema, want[i].schema) << i;
    EXPECT_EQ(seen[i].sequence, want[i].sequence) << i;
    EXPECT_EQ(seen[i].log, want[i].log) << i;
    EXPECT_EQ(seen[i].publish, want[i].publish) << i;
    EXPECT_EQ(seen[i].data, want[i].data) << i;
  }
  EXPECT_EQ(r.schemas().at(2).data, "string s\n");
  EXPECT_EQ(r.schemas().at(2).encoding, "ros2msg");
  const std::vector<std::pair<std::string, std::string>> metadata{{"offered_qos_profiles", ""}, {"k", "v"}};
  EXPECT_EQ(r.channels().at(1).metadata, metadata);
  EXPECT_EQ(openLog(path)->format(), "MCAP");
}

// The records as the spec lays them out: magic, then opcode (1 byte) and length (8 bytes) per
// record, the data section (Header first, Data End last), the summary (schemas, channels,
// statistics, then the summary offsets naming each group), the Footer and the closing magic.
TEST(McapWriter, LayoutFollowsTheSpec) {
  const std::string f = sampleFile();
  const std::string magic("\x89MCAP0\r\n", 8);
  ASSERT_GT(f.size(), 16u + 29u);
  EXPECT_EQ(f.substr(0, 8), magic);
  EXPECT_EQ(f.substr(f.size() - 8), magic);
  struct Rec {
    int op;
    std::size_t at, length;
  };
  std::vector<Rec> recs;
  for (std::size_t p = 8; p < f.size() - 8;) {
    ASSERT_LE(p + 9, f.size() - 8);
    const std::size_t len = le(f, p + 1, 8);
    ASSERT_LE(p + 9 + len, f.size() - 8) << "record at " << p;
    recs.push_back({static_cast<unsigned char>(f[p]), p, len});
    p += 9 + len;
  }
  std::string ops;
  for (const Rec& r : recs) ops += std::to_string(r.op) + " ";
  // Header, schema, schema, channel x3, message x4, Data End | schema x2, channel x3, statistics,
  // summary offset x3, Footer.
  EXPECT_EQ(ops, "1 3 3 4 4 4 5 5 5 5 15 3 3 4 4 4 11 14 14 14 2 ");
  ASSERT_EQ(recs.size(), 21u);
  const Rec& footer = recs.back();
  ASSERT_EQ(footer.length, 20u);
  EXPECT_EQ(le(f, footer.at + 9, 8), recs[11].at) << "summary_start: the first record after Data End";
  EXPECT_EQ(le(f, footer.at + 17, 8), recs[17].at) << "summary_offset_start: the first Summary Offset";
  EXPECT_NE(le(f, footer.at + 25, 4), 0u) << "summary CRC";
  EXPECT_NE(le(f, recs[10].at + 9, 4), 0u) << "data section CRC";
  // Statistics: 4 messages, 2 schemas, 3 channels, no attachments, metadata or chunks, times
  // 1000 ... 3000, per channel 2, 1, 1.
  const std::size_t s = recs[16].at + 9;
  EXPECT_EQ(le(f, s, 8), 4u);
  EXPECT_EQ(le(f, s + 8, 2), 2u);
  EXPECT_EQ(le(f, s + 10, 4), 3u);
  EXPECT_EQ(le(f, s + 14, 4) + le(f, s + 18, 4) + le(f, s + 22, 4), 0u);
  EXPECT_EQ(le(f, s + 26, 8), 1000u);
  EXPECT_EQ(le(f, s + 34, 8), 3000u);
  ASSERT_EQ(le(f, s + 42, 4), 30u);
  std::map<std::uint64_t, std::uint64_t> counts;
  for (std::size_t k = 0; k < 3; ++k) counts[le(f, s + 46 + 10 * k, 2)] = le(f, s + 48 + 10 * k, 8);
  EXPECT_EQ(counts, (std::map<std::uint64_t, std::uint64_t>{{0, 2}, {1, 1}, {2, 1}}));
  // Each summary offset: the group's opcode, where it starts and its length in bytes.
  const std::size_t want_start[] = {recs[11].at, recs[13].at, recs[16].at};
  const std::size_t want_end[] = {recs[13].at, recs[16].at, recs[17].at};
  const int want_op[] = {3, 4, 11};
  for (std::size_t k = 0; k < 3; ++k) {
    const std::size_t o = recs[17 + k].at + 9;
    EXPECT_EQ(recs[17 + k].length, 17u);
    EXPECT_EQ(static_cast<unsigned char>(f[o]), want_op[k]) << k;
    EXPECT_EQ(le(f, o + 1, 8), want_start[k]) << k;
    EXPECT_EQ(le(f, o + 9, 8), want_end[k] - want_start[k]) << k;
  }
}

// A damaged byte in the data section or in the summary is caught by the CRCs the writer filled in.
TEST(McapWriter, CrcsCatchDamage) {
  const std::string f = sampleFile();
  const auto read = [](const std::string& bytes) {
    McapReader r(kccd::testing::writeScratch(kTag, "damaged.mcap", bytes));
    LogMessage m;
    while (r.next(m)) {
    }
  };
  std::string data = f;
  const std::size_t message = data.find("b0-longer");
  ASSERT_NE(message, std::string::npos);
  data[message] = 'c';
  EXPECT_THROW(
      try { read(data); } catch (const kccd::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("the data section's CRC does not match"), std::string::npos) << e.what();
        throw;
      },
      kccd::InputError);
  // The statistics' last byte: the top byte of the last channel's message count, just before the
  // first summary offset (the footer's summary_offset_start).
  std::string summary = f;
  const std::size_t offsets = le(f, f.size() - 8 - 29 + 17, 8);
  ASSERT_GT(offsets, message);
  summary[offsets - 1] ^= 1;
  EXPECT_THROW(
      try { read(summary); } catch (const kccd::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("CRC does not match"), std::string::npos) << e.what();
        throw;
      },
      kccd::InputError);
}

TEST(McapWriter, AFileNotFinishedReadsAsCutShort) {
  McapReader r(kccd::testing::writeScratch(kTag, "unfinished.mcap", sampleFile(false)));
  LogMessage m;
  int n = 0;
  while (r.next(m)) ++n;
  EXPECT_EQ(n, 4);
  EXPECT_NE(r.damage().find("no Footer record"), std::string::npos) << r.damage();
}

TEST(McapWriter, MisuseIsRefused) {
  std::ostringstream out;
  McapWriter w(out, "", "");
  EXPECT_THROW(w.addChannel(1, "/x", "cdr"), std::invalid_argument);
  EXPECT_THROW(w.write(0, 0, 0, {}), std::invalid_argument);
  w.addChannel(0, "/x", "json");
  w.finish();
  EXPECT_THROW(w.write(0, 0, 0, {}), std::invalid_argument);
  EXPECT_THROW(w.finish(), std::invalid_argument);
}

// JointState's bytes decoded with the definition written beside them: every field, alignment after
// strings of every length modulo 4, stamps before and after the epoch.
TEST(JointStateCdr, DecodesAsWritten) {
  const MessageDefinitions types =
      MessageDefinitions::parse(kJointStateSchemaName, jointStateDefinition(), Dialect::Ros2);
  EXPECT_EQ(types.root().name, "sensor_msgs/JointState");
  for (const std::int64_t stamp : {std::int64_t{1'700'000'000'123'456'789}, std::int64_t{-1}, std::int64_t{0}}) {
    JointState s;
    s.stamp_ns = stamp;
    s.frame_id = "cam";
    s.name = {"a", "bb", "ccc", "dddd"};
    s.position = {0.1, -2.5, 1e-300, 3.0};
    s.velocity = {1, 2, 3, 4};
    const std::vector<std::uint8_t> bytes = encodeJointStateCdr(s);
    EXPECT_EQ(bytes[0], 0x00);
    EXPECT_EQ(bytes[1], 0x01);  // CDR little-endian
    const Value v = decodeCdr(types, bytes);
    EXPECT_EQ(headerStamp(v), stamp);
    const Value& st = *v.field("header")->field("stamp");
    EXPECT_GE(st.field("nanosec")->u, 0u);
    EXPECT_LT(st.field("nanosec")->u, 1'000'000'000u);
    EXPECT_EQ(v.field("header")->field("frame_id")->s, "cam");
    std::vector<std::string> names;
    for (const Value& n : v.field("name")->items) names.push_back(n.s);
    EXPECT_EQ(names, s.name);
    const auto numbers = [&](const char* field) {
      std::vector<double> out;
      for (const Value& x : v.field(field)->items) out.push_back(x.number());
      return out;
    };
    EXPECT_EQ(numbers("position"), s.position);
    EXPECT_EQ(numbers("velocity"), s.velocity);
    EXPECT_TRUE(numbers("effort").empty());
  }
  JointState far;
  far.stamp_ns = (std::int64_t{1} << 31) * 1'000'000'000;  // 2038-01-19 03:14:08: past int32 seconds
  EXPECT_THROW(encodeJointStateCdr(far), std::invalid_argument);
  JointState nul;
  nul.name = {std::string("a\0b", 3)};
  EXPECT_THROW(encodeJointStateCdr(nul), std::invalid_argument);
}

// CompressedImage's bytes decoded with the definition written beside them: header, format and
// data of every length modulo 4 (the data's count follows a string, so its alignment varies).
TEST(CompressedImageCdr, DecodesAsWritten) {
  const MessageDefinitions types =
      MessageDefinitions::parse(kCompressedImageSchemaName, compressedImageDefinition(), Dialect::Ros2);
  EXPECT_EQ(types.root().name, "sensor_msgs/CompressedImage");
  const std::vector<std::uint8_t> jpeg = {0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0x10, 0xFF, 0xD9};
  for (std::size_t n = 0; n <= jpeg.size(); ++n) {
    CompressedImage image;
    image.stamp_ns = 1'700'000'000'137'000'000 + static_cast<std::int64_t>(n);
    image.frame_id = std::string(n % 5, 'c');
    image.format = n % 2 ? "jpeg" : "bgr8; jpeg compressed bgr8";
    image.data = std::span<const std::uint8_t>(jpeg).first(n);
    const std::vector<std::uint8_t> bytes = encodeCompressedImageCdr(image);
    EXPECT_EQ(bytes[1], 0x01);  // CDR little-endian
    const Value v = decodeCdr(types, bytes);
    EXPECT_EQ(headerStamp(v), image.stamp_ns) << n;
    EXPECT_EQ(v.field("header")->field("frame_id")->s, image.frame_id) << n;
    EXPECT_EQ(v.field("format")->s, image.format) << n;
    const Value& data = *v.field("data");
    ASSERT_EQ(data.kind, Value::Kind::Bytes) << n;
    EXPECT_EQ(std::vector<std::uint8_t>(data.bytes.begin(), data.bytes.end()),
              std::vector<std::uint8_t>(jpeg.begin(), jpeg.begin() + static_cast<std::ptrdiff_t>(n)))
        << n;
  }
  CompressedImage nul;
  nul.format = std::string("jp\0eg", 5);
  EXPECT_THROW(encodeCompressedImageCdr(nul), std::invalid_argument);
  CompressedImage far;
  far.stamp_ns = (std::int64_t{1} << 31) * 1'000'000'000;
  EXPECT_THROW(encodeCompressedImageCdr(far), std::invalid_argument);
}

// A state log as a bag, read back by `overlay --bag`'s and `check --bag`'s reader: the same times
// (to the nanosecond), values and velocities.
TEST(StateLogBag, ReadsBackAsTheLog) {
  const kccd::Model model = kccd::loadModel(std::string(KCCD_DATA_DIR) + "/demo_arm.yaml");
  const std::string text =
      "time,shoulder_yaw,shoulder_pitch,elbow,elbow.vel,shoulder_yaw.vel,shoulder_pitch.vel\n"
      "0,0.1,0.2,0.3,1,2,3\n"
      "0.008,-0.1,0.25,1e-7,-1,0,0.5\n"
      "0.333333333333,3.141592653589793,0,-2,0,0,0\n";
  const kccd::StateLog log = kccd::parseStateLog(text, "log.csv", model);
  const fs::path path = kccd::testing::scratchFolder(kTag) / "log.mcap";
  kccd::overlay::writeStateLogBag(log, path);
  const kccd::overlay::BagRecording rec =
      kccd::overlay::readBagRecording({.bag = path.string(), .frames = false}, model);
  EXPECT_TRUE(rec.warnings.empty());
  EXPECT_EQ(rec.joint_topic, "/joint_states");
  EXPECT_EQ(rec.origin_ns, 1'700'000'000'000'000'000u);
  ASSERT_EQ(rec.log.rows(), 3u);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(rec.log.times[i], log.times[i], 0.5e-9) << i;
  EXPECT_EQ(rec.log.values, log.values);
  EXPECT_EQ(rec.log.velocities, log.velocities);
  // Without every velocity column, none is written.
  const kccd::StateLog some =
      kccd::parseStateLog("time,shoulder_yaw,shoulder_pitch,elbow,elbow.vel\n0,1,2,3,4\n", "some.csv", model);
  kccd::overlay::writeStateLogBag(some, path);
  EXPECT_FALSE(kccd::overlay::readBagRecording({.bag = path.string(), .frames = false}, model).log.hasVelocities());
}

// A BGR test card: a gradient with a bright square at (x, x), so that frames differ.
cv::Mat testCard(int x) {
  cv::Mat m(48, 64, CV_8UC3);
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < m.cols; ++c) m.at<cv::Vec3b>(r, c) = cv::Vec3b(static_cast<uchar>(4 * c), 128, 255 - 5 * r);
  m(cv::Rect(x, x, 16, 16)).setTo(cv::Scalar(250, 250, 250));
  return m;
}

// Frames added as they come, between the samples: the file holds both topics in log-time order
// (a sample before a frame of the same nanosecond, the samples after the last frame at the end),
// the frames' header stamps, log and publish times at their log times, JPEG in the format
// image_transport names; `overlay --bag`'s reader pairs each frame with the samples at its time
// and decodes the test cards it was given.
TEST(StateLogBag, FramesInterleaveInLogTimeOrder) {
  const kccd::Model model = kccd::loadModel(std::string(KCCD_DATA_DIR) + "/demo_arm.yaml");
  const kccd::StateLog log = kccd::parseStateLog(
      "time,shoulder_yaw,shoulder_pitch,elbow\n0,0,0,0\n0.01,0.1,0,0\n0.02,0.2,0,0\n0.03,0.3,0,0\n", "log.csv", model);
  const fs::path path = kccd::testing::scratchFolder(kTag) / "frames.mcap";
  const std::vector<double> times = {0.005, 0.02, 0.035};
  {
    kccd::overlay::StateLogBagWriter w(log, path);
    for (std::size_t k = 0; k < times.size(); ++k) w.addImage(times[k], testCard(8 * static_cast<int>(k)));
    EXPECT_EQ(w.images(), 3u);
    EXPECT_FALSE(fs::exists(path));  // staged until finish()
    w.finish();
  }
  McapReader r(path.string());
  std::vector<std::pair<std::string, std::uint64_t>> order;
  LogMessage m;
  const std::uint64_t origin = 1'700'000'000'000'000'000;
  while (r.next(m)) {
    order.emplace_back(m.channel->topic, m.log_time - origin);
    EXPECT_EQ(m.publish_time, m.log_time);
    if (m.channel->topic != "/camera/image_raw/compressed") continue;
    EXPECT_EQ(m.schema->name, "sensor_msgs/msg/CompressedImage");
    const MessageDefinitions types = MessageDefinitions::parse(m.schema->name, m.schema->data, Dialect::Ros2);
    const Value v = decodeCdr(types, m.data);  // its field names are the definitions
    EXPECT_EQ(headerStamp(v), static_cast<std::int64_t>(m.log_time));
    EXPECT_EQ(v.field("header")->field("frame_id")->s, "camera");
    EXPECT_EQ(v.field("format")->s, "bgr8; jpeg compressed bgr8");
    const std::span<const std::uint8_t> jpeg = v.field("data")->bytes;
    ASSERT_GE(jpeg.size(), 4u);
    EXPECT_EQ(jpeg[0], 0xFF);
    EXPECT_EQ(jpeg[1], 0xD8);  // a JPEG's start of image
  }
  EXPECT_EQ(r.damage(), "");
  const std::string j = "/joint_states", c = "/camera/image_raw/compressed";
  const std::vector<std::pair<std::string, std::uint64_t>> want = {
      {j, 0}, {c, 5'000'000}, {j, 10'000'000}, {j, 20'000'000}, {c, 20'000'000}, {j, 30'000'000}, {c, 35'000'000}};
  EXPECT_EQ(order, want);
  // overlay --bag's reader: the samples and the frames on one clock, the cards decoded.
  const kccd::overlay::BagRecording rec = kccd::overlay::readBagRecording({.bag = path.string()}, model);
  EXPECT_TRUE(rec.warnings.empty());
  EXPECT_EQ(rec.image_topic, c);
  EXPECT_EQ(rec.origin_ns, origin);
  EXPECT_EQ(rec.frame_times, times);
  EXPECT_EQ(rec.log.rows(), 4u);
  const std::unique_ptr<kccd::overlay::FrameSource> frames = rec.open_frames();
  cv::Mat f;
  for (std::size_t k = 0; k < times.size(); ++k) {
    ASSERT_TRUE(frames->read(f)) << k;
    const cv::Mat card = testCard(8 * static_cast<int>(k));
    ASSERT_EQ(f.size(), card.size());
    EXPECT_LT(cv::norm(f, card, cv::NORM_L1) / static_cast<double>(card.total() * 3), 3.0) << k;
  }
  EXPECT_FALSE(frames->read(f));
}

TEST(StateLogBag, BadFramesAreRefusedAndAnUnfinishedBagIsNotLeft) {
  const kccd::Model model = kccd::loadModel(std::string(KCCD_DATA_DIR) + "/demo_arm.yaml");
  const kccd::StateLog log =
      kccd::parseStateLog("time,shoulder_yaw,shoulder_pitch,elbow\n0,0,0,0\n1,0,0,0\n", "log.csv", model);
  const fs::path dir = kccd::testing::scratchFolder(kTag) / "bad_frames";
  fs::create_directories(dir);
  {
    kccd::overlay::StateLogBagWriter w(log, dir / "x.mcap", {.label = "x.mcap"});
    w.addImage(0.5, testCard(0));
    try {
      w.addImage(0.5 + 1e-10, testCard(0));
      ADD_FAILURE() << "a frame at the previous one's nanosecond was taken";
    } catch (const kccd::InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("x.mcap: the frame at log time 0.5", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(" s is not after the previous frame"), std::string::npos) << e.what();
    }
    try {
      w.addImage(-1e10, testCard(0));
      ADD_FAILURE() << "a frame before 1970 was taken";
    } catch (const kccd::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("x.mcap: the frame at log time"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("(1970 ... 2038)"), std::string::npos) << e.what();
    }
    EXPECT_THROW(w.addImage(0.7, cv::Mat()), std::invalid_argument);
    EXPECT_THROW(w.addImage(0.7, cv::Mat(4, 4, CV_8UC1, cv::Scalar(0))), std::invalid_argument);
  }  // not finished: nothing left
  EXPECT_TRUE(fs::is_empty(dir));
  EXPECT_THROW(kccd::overlay::StateLogBagWriter(log, dir / "q.mcap", {.jpeg_quality = 0}), std::invalid_argument);
  EXPECT_TRUE(fs::is_empty(dir));
  kccd::overlay::StateLogBagWriter done(log, dir / "y.mcap");
  done.finish();
  EXPECT_THROW(done.addImage(0.5, testCard(0)), std::invalid_argument);
  EXPECT_THROW(done.finish(), std::invalid_argument);
}

TEST(StateLogBag, BadInputIsOneLineAndWritesNothing) {
  const kccd::Model model = kccd::loadModel(std::string(KCCD_DATA_DIR) + "/demo_arm.yaml");
  const fs::path dir = kccd::testing::scratchFolder(kTag) / "bad";
  fs::create_directories(dir);
  const auto problem = [&](const std::string& csv, const kccd::overlay::StateLogBagOptions& o) -> std::string {
    try {
      kccd::overlay::writeStateLogBag(kccd::parseStateLog(csv, "x.csv", model), dir / "x.mcap", o);
    } catch (const kccd::InputError& e) {
      return e.what();
    }
    return "";
  };
  const std::string head = "time,shoulder_yaw,shoulder_pitch,elbow\n";
  EXPECT_NE(problem(head + "0,0,0,0\n", {.origin_ns = 0, .label = "x.mcap"})
                .find("x.mcap: the sample at log time 0 s would be stamped at 0 s since 1970"),
            std::string::npos);
  EXPECT_NE(problem(head + "1,0,0,0\n", {.origin_ns = std::int64_t{2'200'000'000} * 1'000'000'000}).find("2038"),
            std::string::npos);
  EXPECT_NE(problem(head + "0,0,0,0\n1e-10,0,0,0\n", {}).find("round to the same nanosecond"), std::string::npos);
  EXPECT_TRUE(fs::is_empty(dir));
  EXPECT_THROW(kccd::overlay::writeStateLogBag(kccd::parseStateLog(head + "0,0,0,0\n", "x.csv", model),
                                               dir / "no_folder" / "x.mcap"),
               kccd::overlay::OutputError);
}

}  // namespace

// State logs: the CSV dialect (every mistake one line naming file, line and column), and the
// state at a time (exact, interpolated along the shorter arc, gaps, velocities).
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "kccd/state_log.hpp"

namespace kccd {
namespace {

constexpr double kPi = std::numbers::pi;

// State values: base (revolute, no limits: unwrapped), arm (revolute with limits), slide
// (prismatic), pose.x, pose.y, pose.z (translation3d).
const Model& model() {
  static const Model m = parseModel(R"(kccd: 1
joints:
  - {name: base, parent: world, type: revolute, axis: [0, 0, 1]}
  - {name: arm, parent: base, type: revolute, axis: [0, 1, 0], limits: [-3, 3]}
  - {name: slide, parent: arm, type: prismatic, axis: [1, 0, 0]}
  - {name: pose, parent: world, type: translation3d}
bodies:
  - {name: floor, frame: world, points: [[0, 0, 0]], radius: 0.1}
  - {name: tool, frame: slide, points: [[0, 0, 0]], radius: 0.1}
  - {name: box, frame: pose, points: [[0, 0, 0]], radius: 0.1}
)",
                                    "test.yaml");
  return m;
}

const std::string kHeader = "time,base,arm,slide,pose.x,pose.y,pose.z";

std::string parseError(const std::string& text, std::vector<std::string> ignore = {}) {
  try {
    parseStateLog(text, "log.csv", model(), ignore);
  } catch (const StateLogError& e) {
    return e.what();
  }
  return "(parsed)";
}

// One data row of kHeader with every value `v` at time `t`.
std::string row(double t, double v = 0.0) {
  std::string s = std::to_string(t);
  for (int i = 0; i < 6; ++i) s += "," + std::to_string(v);
  return s + "\n";
}

TEST(StateLog, ParsesColumnsInAnyOrder) {
  const std::string text =
      "pose.z,time,slide,note,arm,pose.x,base,pose.y\n"
      "6,0.5,3,first,2,4,1,5\n"
      "-6,1.25,-3,second row,-2,-4,-1,-5\n";
  const std::vector<std::string> ignore{"note"};
  const StateLog log = parseStateLog(text, "log.csv", model(), ignore);
  EXPECT_EQ(log.names, model().stateNames());
  ASSERT_EQ(log.rows(), 2u);
  ASSERT_EQ(log.stateSize(), 6u);
  EXPECT_EQ(log.times, (std::vector<double>{0.5, 1.25}));
  EXPECT_EQ(log.values, (std::vector<double>{1, 2, 3, 4, 5, 6, -1, -2, -3, -4, -5, -6}));
  EXPECT_EQ(std::vector<double>(log.row(1).begin(), log.row(1).end()), (std::vector<double>{-1, -2, -3, -4, -5, -6}));
  EXPECT_FALSE(log.hasVelocities());
  EXPECT_TRUE(log.velocities.empty());
  EXPECT_EQ(log.ignored, std::vector<std::string>{"note"});
  EXPECT_EQ(log.circular, (std::vector<std::uint8_t>{1, 0, 0, 0, 0, 0}));  // only the joint without limits
  EXPECT_DOUBLE_EQ(log.medianPeriod(), 0.75);
}

TEST(StateLog, AcceptsBomCrlfAndTheNumberForms) {
  const std::string crlf = "\xEF\xBB\xBF" + kHeader + "\r\n0,.5,5.,-0,1E+3,1e-320,-12.25e-1\r\n1,0,0,0,0,0,0\r\n";
  const StateLog a = parseStateLog(crlf, "log.csv", model());
  ASSERT_EQ(a.rows(), 2u);
  EXPECT_EQ(a.values[0], 0.5);
  EXPECT_EQ(a.values[1], 5.0);
  EXPECT_EQ(a.values[2], 0.0);
  EXPECT_TRUE(std::signbit(a.values[2]));
  EXPECT_EQ(a.values[3], 1000.0);
  EXPECT_EQ(a.values[4], 1e-320);
  EXPECT_EQ(a.values[5], -1.225);
  // The same as LF, without a final line end, and with one empty line at the very end.
  const std::string lf = kHeader + "\n0,.5,5.,-0,1E+3,1e-320,-12.25e-1\n1,0,0,0,0,0,0";
  EXPECT_EQ(parseStateLog(lf, "log.csv", model()).values, a.values);
  EXPECT_EQ(parseStateLog(lf + "\n\n", "log.csv", model()).values, a.values);
  EXPECT_EQ(parseStateLog(lf + "\r\n\r\n", "log.csv", model()).values, a.values);
  EXPECT_EQ(parseStateLog(lf + "\n", "log.csv", model()).rows(), 2u);
  // Boundary magnitudes.
  const StateLog big = parseStateLog(kHeader + "\n-1e300,1e300,-1e300,0,0,0,0\n", "log.csv", model());
  EXPECT_EQ(big.times[0], -1e300);
  EXPECT_EQ(big.values[0], 1e300);
}

TEST(StateLog, IgnoredColumnsAreNotParsed) {
  const std::vector<std::string> ignore{"comment", "arm.vel", "absent"};
  const StateLog log = parseStateLog(kHeader + ",comment,arm.vel\n0,1,2,3,4,5,6,,nan\n1,1,2,3,4,5,6,any text; here,x\n",
                                     "log.csv", model(), ignore);
  EXPECT_EQ(log.rows(), 2u);
  EXPECT_FALSE(log.hasVelocities());  // arm.vel was skipped
  EXPECT_EQ(log.ignored, (std::vector<std::string>{"comment", "arm.vel"}));
}

struct Bad {
  std::string text;
  std::string message;
};

TEST(StateLog, EveryMistakeIsOneLineWithItsPlace) {
  const std::string h = kHeader + "\n";
  const std::string ok = "0,0,0,0,0,0,0\n";
  const std::vector<Bad> cases = {
      {"", "log.csv:1: empty file (expected a header line: time and the model's state value names)"},
      {"\xEF\xBB\xBF", "log.csv:1: empty file (expected a header line: time and the model's state value names)"},
      {"\n" + ok, "log.csv:1: empty header line (expected time and the model's state value names)"},
      {h, "log.csv:1: no data rows after the header (a log needs at least one sample)"},
      {kHeader, "log.csv:1: no data rows after the header (a log needs at least one sample)"},
      {h + "\n", "log.csv:1: no data rows after the header (a log needs at least one sample)"},
      // Header.
      {"time,\"base\",arm,slide,pose.x,pose.y,pose.z\n" + ok,
       "log.csv:1:6: a '\"': quoting is not part of the dialect"},
      {"# time,base\n" + h + ok, "log.csv:1:1: a comment line (the dialect has none)"},
      {"base,arm,slide,pose.x,pose.y,pose.z\n0,0,0,0,0,0\n",
       "log.csv:1: column 'time': missing (the sample times in seconds)"},
      {"time,base,arm,slide,pose.x,pose.z\n0,0,0,0,0,0\n",
       "log.csv:1: column 'pose.y': missing (a state value of the model: every one needs a column)"},
      {"time,base,arm,slide,pose.x,pose.y,pose.z,arm\n", "log.csv:1:42: column 'arm': named twice (also at 1:11)"},
      {"time,base,time\n", "log.csv:1:11: column 'time': named twice (also at 1:1)"},
      {"time,base,arm,slide,pose.x,pose.y,pose.z,elbow\n",
       "log.csv:1:42: column 'elbow': unknown column (a state value of the model? see kccd info; a column to skip is "
       "listed as "
       "ignored)"},
      {"time,base,arm,slide,pose.x,pose.y,pose.z,elbow.vel\n",
       "log.csv:1:42: column 'elbow.vel': unknown column (a state value of the model? see kccd info; a column to skip "
       "is "
       "listed as ignored)"},
      {"time,base,arm,slide,pose.x,pose.y,pose.z,time.vel\n",
       "log.csv:1:42: column 'time.vel': unknown column (a state value of the model? see kccd info; a column to skip "
       "is "
       "listed as ignored)"},
      {"time,base, arm,slide,pose.x,pose.y,pose.z\n",
       "log.csv:1:11: column ' arm': space around the name (the dialect has no padding)"},
      {"time,,base\n", "log.csv:1:6: empty column name (field 2 of the header)"},
      {"time,base,\x01x\x7f\n",
       "log.csv:1:11: column '\\x01x\\x7f': unknown column (a state value of the model? see kccd info; a column to "
       "skip is "
       "listed as ignored)"},
      {"time,base,arm\rslide\n",
       "log.csv:1:14: a carriage return not followed by a line feed (line ends are LF or CRLF)"},
      {h + "0,0,0,0,0,0,0\r", "log.csv:2:14: a carriage return not followed by a line feed (line ends are LF or CRLF)"},
      // Rows.
      {h + ok + "1,0,0,0,0,0\n", "log.csv:3: 6 fields, but the header has 7 columns"},
      {h + ok + "1,0,0,0,0,0,0,0\n", "log.csv:3: 8 fields, but the header has 7 columns"},
      {h + "0,0,0,0,0,0,1,5\n", "log.csv:2: 8 fields, but the header has 7 columns"},  // decimal comma
      {h + "0,0,\"1\",0,0,0,0\n", "log.csv:2:5: a '\"': quoting is not part of the dialect"},
      {h + ok + "# pause\n", "log.csv:3:1: a comment line (the dialect has none)"},
      {h + ok + "\n" + "1,0,0,0,0,0,0\n", "log.csv:3: empty line (the dialect has none between rows)"},
      {h + ok + "\n\n", "log.csv:3: empty line (the dialect has none between rows)"},
      {h + "0,0,,0,0,0,0\n", "log.csv:2:5: column 'arm': empty field (every field of a row needs a number)"},
      {h + "0,0,0,0,0,0,\n", "log.csv:2:13: column 'pose.z': empty field (every field of a row needs a number)"},
      {h + "0,+1,0,0,0,0,0\n", "log.csv:2:3: column 'base': a leading '+' is not part of the dialect: '+1'"},
      {h + "0,nan,0,0,0,0,0\n", "log.csv:2:3: column 'base': must be a finite number, got 'nan'"},
      {h + "0,0,NaN,0,0,0,0\n", "log.csv:2:5: column 'arm': must be a finite number, got 'NaN'"},
      {h + "inf,0,0,0,0,0,0\n", "log.csv:2:1: column 'time': must be a finite number, got 'inf'"},
      {h + "0,-Infinity,0,0,0,0,0\n", "log.csv:2:3: column 'base': must be a finite number, got '-Infinity'"},
      {h + "0,0x1p3,0,0,0,0,0\n", "log.csv:2:3: column 'base': not a decimal number: '0x1p3'"},
      {h + "0,1.5abc,0,0,0,0,0\n", "log.csv:2:3: column 'base': not a decimal number: '1.5abc'"},
      {h + "0,1e,0,0,0,0,0\n", "log.csv:2:3: column 'base': not a decimal number: '1e'"},
      {h + "0,-,0,0,0,0,0\n", "log.csv:2:3: column 'base': not a decimal number: '-'"},
      {h + "0,.,0,0,0,0,0\n", "log.csv:2:3: column 'base': not a decimal number: '.'"},
      {h + "0,1\x01,0,0,0,0,0\n", "log.csv:2:3: column 'base': not a decimal number: '1\\x01'"},
      {h + "0, 1.5,0,0,0,0,0\n",
       "log.csv:2:3: column 'base': space around the number ' 1.5' (the dialect has no padding)"},
      {h + "0,1.5 ,0,0,0,0,0\n",
       "log.csv:2:3: column 'base': space around the number '1.5 ' (the dialect has no padding)"},
      {h + "0,1e400,0,0,0,0,0\n", "log.csv:2:3: column 'base': '1e400' is out of the range of a double"},
      {h + "0,0,0,0,0,0,-2e300\n",
       "log.csv:2:13: column 'pose.z': '-2e300' is beyond the largest magnitude accepted (1e300)"},
      {h + "0.5,0,0,0,0,0,0\n0.5,0,0,0,0,0,0\n",
       "log.csv:3:1: column 'time': 0.5 is not after the previous row's 0.5 (time must increase strictly)"},
      {h + "0.5,0,0,0,0,0,0\n0.6,0,0,0,0,0,0\n0.25,0,0,0,0,0,0\n",
       "log.csv:4:1: column 'time': 0.25 is not after the previous row's 0.6 (time must increase strictly)"},
      // Places on CRLF lines and after a BOM count from the first byte of the line after the BOM.
      {"\xEF\xBB\xBF" + kHeader + "\r\n0,0,abc,0,0,0,0\r\n", "log.csv:2:5: column 'arm': not a decimal number: 'abc'"},
      {"\xEF\xBB\xBFtime,base,base\r\n", "log.csv:1:11: column 'base': named twice (also at 1:6)"},
  };
  for (const Bad& c : cases) {
    EXPECT_EQ(parseError(c.text), c.message) << "input: " << printable(c.text, 200);
  }
}

TEST(StateLog, RequiredColumnsCannotBeIgnored) {
  EXPECT_EQ(parseError(kHeader + "\n" + row(0), {"arm"}),
            "log.csv:1:11: column 'arm': listed as ignored, but time and every state value of the model are required");
  EXPECT_EQ(parseError(kHeader + "\n" + row(0), {"time"}),
            "log.csv:1:1: column 'time': listed as ignored, but time and every state value of the model are required");
  // Listing a column the file does not have changes nothing.
  EXPECT_EQ(parseError(kHeader + "\n" + row(0), {"absent"}), "(parsed)");
}

TEST(StateLog, AModelStateNamedTimeCannotBeLogged) {
  const Model m = parseModel(
      "kccd: 1\njoints:\n  - {name: time, parent: world, type: prismatic, axis: [1, 0, 0]}\n"
      "bodies:\n  - {name: b, frame: time, points: [[0, 0, 0]], radius: 0.1}\n",
      "m.yaml");
  try {
    parseStateLog("time\n0\n", "log.csv", m);
    FAIL() << "parsed";
  } catch (const StateLogError& e) {
    EXPECT_EQ(
        std::string(e.what()),
        "log.csv:1: column 'time': the model has a state value named 'time', which a log cannot tell from its time "
        "column");
  }
}

TEST(StateLog, MessagesQuoteOnlyPrintableText) {
  const std::string long_name(300, 'q');
  const std::string message = parseError("time,base,arm,slide,pose.x,pose.y,pose.z," + long_name + "\n");
  EXPECT_LT(message.size(), 250u);
  EXPECT_NE(message.find("column 'qqq"), std::string::npos);
  EXPECT_NE(message.find("...'"), std::string::npos);
  const std::string newline = parseError(kHeader + "\n0,\xff\n,0,0,0,0,0\n");  // the LF splits the row
  EXPECT_EQ(newline, "log.csv:2: 2 fields, but the header has 7 columns");
  EXPECT_EQ(parseError(kHeader + "\n0,\xff,0,0,0,0,0\n"), "log.csv:2:3: column 'base': not a decimal number: '\\xff'");
}

// --- stateAt -----------------------------------------------------------------------------------

StateLog logOf(const std::string& text) { return parseStateLog(text, "log.csv", model()); }

TEST(StateAt, LinearInterpolationIsExactForLinearMotion) {
  // Each value moves linearly (a + b t), sampled at irregular times: every time in between gets
  // exactly a + b t back. The limited joint and the prismatic one never unwrap.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> step(0.001, 0.02);
  const double a[6] = {0.3, -1.0, 0.25, 1.0, -2.0, 0.5};
  const double b[6] = {0.5, 1.5, -0.75, 2.0, 0.125, -3.0};
  std::string text = kHeader + "\n";
  std::vector<double> times;
  for (double t = 0.0; t < 1.0; t += step(rng)) times.push_back(t);
  char buffer[64];
  for (const double t : times) {
    std::snprintf(buffer, sizeof buffer, "%.17g", t);
    text += buffer;
    for (int i = 0; i < 6; ++i) {
      std::snprintf(buffer, sizeof buffer, ",%.17g", a[i] + b[i] * t);
      text += buffer;
    }
    text += "\n";
  }
  const StateLog log = logOf(text);
  ASSERT_EQ(log.rows(), times.size());
  std::uniform_real_distribution<double> when(times.front(), times.back());
  std::vector<double> state(6), velocity(6);
  for (int k = 0; k < 2000; ++k) {
    const double t = when(rng);
    const StateMatch m = stateAt(log, t, 0.05, state, velocity);
    ASSERT_NE(m, StateMatch::None) << t;
    for (int i = 0; i < 6; ++i) {
      EXPECT_NEAR(state[i], a[i] + b[i] * t, 1e-12) << "value " << i << " at " << t;
      EXPECT_NEAR(velocity[i], b[i], 1e-9) << "rate " << i << " at " << t;
    }
  }
}

TEST(StateAt, InterpolatesTheChordOfCurvedMotion) {
  // q(t) = t^2 sampled at 0, 0.5, 2: between samples the state is the chord, worked out by hand.
  const StateLog log = logOf(kHeader + "\n0,0,0,0,0,0,0\n0.5,0,0.25,0,0,0,0\n2,0,4,0,0,0,0\n");
  std::vector<double> state(6), velocity(6);
  EXPECT_EQ(stateAt(log, 0.2, 10.0, state, velocity), StateMatch::Interpolated);
  EXPECT_DOUBLE_EQ(state[1], 0.1);  // 0 + 0.2 * (0.25 / 0.5)
  EXPECT_DOUBLE_EQ(velocity[1], 0.5);
  EXPECT_EQ(stateAt(log, 1.5, 10.0, state, velocity), StateMatch::Interpolated);
  EXPECT_DOUBLE_EQ(state[1], 2.75);  // 0.25 + 1.0 * (3.75 / 1.5)
  EXPECT_DOUBLE_EQ(velocity[1], 2.5);
}

TEST(StateAt, UnlimitedRevoluteJointsTakeTheShorterArc) {
  // base (no limits) goes 3.1 -> -3.1: through pi. arm (limits [-3, 3]) goes 2.9 -> -2.9: through 0.
  const StateLog log = logOf(kHeader + "\n0,3.1,2.9,0,0,0,0\n1,-3.1,-2.9,0,0,0,0\n");
  const double arc = 2 * kPi - 6.2;  // the short way from 3.1 to -3.1 (positive)
  std::vector<double> state(6), velocity(6);
  for (const double t : {0.1, 0.25, 0.5, 0.75, 0.9}) {
    ASSERT_EQ(stateAt(log, t, 2.0, state, velocity), StateMatch::Interpolated);
    const double expected = 3.1 + t * arc;  // as an angle
    EXPECT_NEAR(std::cos(state[0]), std::cos(expected), 1e-12) << t;
    EXPECT_NEAR(std::sin(state[0]), std::sin(expected), 1e-12) << t;
    EXPECT_NEAR(std::abs(std::abs(state[0]) - kPi), std::abs(kPi - expected), 1e-12) << t;  // near pi, never near 0
    EXPECT_NEAR(velocity[0], arc, 1e-12);
    EXPECT_NEAR(state[1], 2.9 - 5.8 * t, 1e-12) << t;  // the limited joint moves through 0
    EXPECT_NEAR(velocity[1], -5.8, 1e-12);
  }
  // Next to each sample the value stays next to the logged one (not wrapped to the other side).
  ASSERT_EQ(stateAt(log, 0.5, 2.0, state), StateMatch::Interpolated);
  EXPECT_NEAR(state[0], kPi, 1e-12);
  ASSERT_EQ(stateAt(log, 0.9, 2.0, state), StateMatch::Interpolated);
  EXPECT_NEAR(state[0], -3.1 - 0.1 * arc, 1e-12);
  // Many turns between samples: still the short way.
  const StateLog turns = logOf(kHeader + "\n0,100.1,0,0,0,0,0\n1,-100.1,0,0,0,0,0\n");
  ASSERT_EQ(stateAt(turns, 0.5, 2.0, state, velocity), StateMatch::Interpolated);
  const double d = std::remainder(-200.2, 2 * kPi);
  EXPECT_LE(std::abs(d), kPi);
  EXPECT_NEAR(state[0], 100.1 + 0.5 * d, 1e-9);
  EXPECT_NEAR(velocity[0], d, 1e-9);
}

TEST(StateAt, ExactTimesGiveTheSampleItself) {
  const StateLog log =
      logOf(kHeader + "\n0,0.1,0.2,0.3,0.4,0.5,0.6\n0.1,1.1,1.2,1.3,1.4,1.5,1.6\n0.3,3.1,-3.2,3.3,3.4,3.5,3.6\n");
  std::vector<double> state(6), velocity(6);
  for (const double dt : {0.0, 0.9e-9, -0.9e-9}) {
    ASSERT_EQ(stateAt(log, 0.1 + dt, 0.0, state), StateMatch::Exact) << dt;  // no gap allowed: only samples
    EXPECT_EQ(std::vector<double>(state.begin(), state.end()),
              std::vector<double>(log.row(1).begin(), log.row(1).end()));
  }
  EXPECT_EQ(stateAt(log, 0.1 + 2e-9, 0.0, state), StateMatch::None);
  EXPECT_EQ(stateAt(log, -0.5e-9, 0.0, state), StateMatch::Exact);       // just before the first sample
  EXPECT_EQ(stateAt(log, 0.3 + 0.5e-9, 0.0, state), StateMatch::Exact);  // just after the last
  EXPECT_EQ(state[1], -3.2);
  // The velocity at a sample: the central difference of its neighbours, one-sided at the ends.
  ASSERT_EQ(stateAt(log, 0.1, 1.0, state, velocity), StateMatch::Exact);
  EXPECT_NEAR(velocity[2], (3.3 - 0.3) / 0.3, 1e-12);
  ASSERT_EQ(stateAt(log, 0.0, 1.0, state, velocity), StateMatch::Exact);
  EXPECT_NEAR(velocity[2], (1.3 - 0.3) / 0.1, 1e-12);
  ASSERT_EQ(stateAt(log, 0.3, 1.0, state, velocity), StateMatch::Exact);
  EXPECT_NEAR(velocity[2], (3.3 - 1.3) / 0.2, 1e-12);
  // Only the neighbour within max_gap counts.
  ASSERT_EQ(stateAt(log, 0.1, 0.15, state, velocity), StateMatch::Exact);
  EXPECT_NEAR(velocity[2], (1.3 - 0.3) / 0.1, 1e-12);
  // Unwrapped at a sample too: 1.1 -> 3.1 is 2.0, 0.1 -> 1.1 is 1.0 (both short arcs).
  ASSERT_EQ(stateAt(log, 0.1, 1.0, state, velocity), StateMatch::Exact);
  EXPECT_NEAR(velocity[0], 3.0 / 0.3, 1e-12);
  // A sample without a neighbour within max_gap has no rate: None when one is asked for.
  const std::vector<double> before(state);
  EXPECT_EQ(stateAt(log, 0.1, 0.05, state, velocity), StateMatch::None);
  EXPECT_EQ(state, before);
  EXPECT_EQ(stateAt(log, 0.1, 0.05, state), StateMatch::Exact);
}

TEST(StateAt, GapsAndTheEndsOfTheLogGiveNoState) {
  const StateLog log = logOf(kHeader + "\n" + row(0, 0) + row(0.1, 1) + row(0.2, 2) + row(1.0, 10) + row(1.1, 11));
  std::vector<double> state(6, -7.0);
  EXPECT_EQ(stateAt(log, 0.05, 0.15, state), StateMatch::Interpolated);
  EXPECT_NEAR(state[3], 0.5, 1e-12);
  EXPECT_EQ(stateAt(log, 0.5, 0.15, state), StateMatch::None);            // a 0.8 s gap
  EXPECT_NEAR(state[3], 0.5, 1e-12);                                      // left unchanged
  EXPECT_EQ(stateAt(log, 0.5, 0.8001, state), StateMatch::Interpolated);  // the gap allowed
  EXPECT_NEAR(state[3], 5.0, 1e-12);
  EXPECT_EQ(stateAt(log, 0.5, 0.7999, state), StateMatch::None);
  EXPECT_EQ(stateAt(log, -0.01, 100.0, state), StateMatch::None);       // before the first sample
  EXPECT_EQ(stateAt(log, 1.1 + 1e-6, 100.0, state), StateMatch::None);  // after the last
  EXPECT_EQ(stateAt(log, 1.0, 0.0, state), StateMatch::Exact);
  EXPECT_EQ(stateAt(log, std::nan(""), 100.0, state), StateMatch::None);
  EXPECT_EQ(stateAt(log, INFINITY, 100.0, state), StateMatch::None);
  EXPECT_EQ(stateAt(log, 0.05, std::nan(""), state), StateMatch::None);
  EXPECT_EQ(stateAt(log, 0.05, -1.0, state), StateMatch::None);
  EXPECT_EQ(stateAt(log, 0.05, INFINITY, state), StateMatch::Interpolated);
}

TEST(StateAt, VelocityColumnsAndFiniteDifferences) {
  // base.vel and slide.vel are logged (deliberately not the slopes); the others come from the samples.
  const StateLog log = logOf(
      "time,base,arm,slide,pose.x,pose.y,pose.z,slide.vel,base.vel\n"
      "0,0,0,0,0,0,0,10,-1\n"
      "1,1,2,3,4,5,6,20,-3\n"
      "3,2,4,6,8,10,12,40,-5\n");
  ASSERT_TRUE(log.hasVelocities());
  EXPECT_EQ(log.logged_velocity, (std::vector<std::uint8_t>{1, 0, 1, 0, 0, 0}));
  EXPECT_TRUE(std::isnan(log.velocities[1]));  // no arm.vel column
  EXPECT_EQ(log.velocities[0], -1.0);
  EXPECT_EQ(log.velocities[2], 10.0);
  std::vector<double> state(6), velocity(6);
  ASSERT_EQ(stateAt(log, 0.25, 1.0, state, velocity), StateMatch::Interpolated);
  EXPECT_DOUBLE_EQ(velocity[0], -1.5);  // logged: -1 + 0.25 * (-3 - -1)
  EXPECT_DOUBLE_EQ(velocity[2], 12.5);  // logged: 10 + 0.25 * (20 - 10)
  EXPECT_DOUBLE_EQ(velocity[1], 2.0);   // slope
  EXPECT_DOUBLE_EQ(velocity[5], 6.0);
  EXPECT_DOUBLE_EQ(state[5], 1.5);
  ASSERT_EQ(stateAt(log, 2.0, 2.0, state, velocity), StateMatch::Interpolated);
  EXPECT_DOUBLE_EQ(velocity[2], 30.0);
  EXPECT_DOUBLE_EQ(velocity[1], 1.0);
  // At a sample: the logged rate, the central difference for the rest.
  ASSERT_EQ(stateAt(log, 1.0, 2.0, state, velocity), StateMatch::Exact);
  EXPECT_EQ(velocity[0], -3.0);
  EXPECT_EQ(velocity[2], 20.0);
  EXPECT_DOUBLE_EQ(velocity[1], 4.0 / 3.0);
  // A sample with no neighbour within max_gap: fine only when every value has its column.
  EXPECT_EQ(stateAt(log, 1.0, 0.5, state, velocity), StateMatch::None);
  const StateLog all = logOf(
      "time,base,arm,slide,pose.x,pose.y,pose.z,base.vel,arm.vel,slide.vel,pose.x.vel,pose.y.vel,pose.z.vel\n"
      "0,0,0,0,0,0,0,1,2,3,4,5,6\n");
  ASSERT_EQ(stateAt(all, 0.0, 0.0, state, velocity), StateMatch::Exact);
  EXPECT_EQ(velocity, (std::vector<double>{1, 2, 3, 4, 5, 6}));
}

TEST(StateAt, SingleSampleLog) {
  const StateLog log = logOf(kHeader + "\n" + row(2.0, 0.5));
  std::vector<double> state(6), velocity(6);
  EXPECT_EQ(stateAt(log, 2.0, 1.0, state), StateMatch::Exact);
  EXPECT_EQ(state[4], 0.5);
  EXPECT_EQ(stateAt(log, 2.0, 1.0, state, velocity), StateMatch::None);  // no rate to give
  EXPECT_EQ(stateAt(log, 2.1, 1.0, state), StateMatch::None);
  EXPECT_EQ(log.medianPeriod(), 0.0);
}

TEST(StateAt, WrongSpanSizesAreCallerErrors) {
  const StateLog log = logOf(kHeader + "\n" + row(0) + row(1));
  std::vector<double> five(5), six(6), seven(7);
  EXPECT_THROW(stateAt(log, 0.5, 1.0, five), std::invalid_argument);
  EXPECT_THROW(stateAt(log, 0.5, 1.0, six, seven), std::invalid_argument);
  EXPECT_EQ(stateAt(log, 0.5, 1.0, six, {}), StateMatch::Interpolated);
}

TEST(StateLog, MedianPeriod) {
  EXPECT_NEAR(logOf(kHeader + "\n" + row(0) + row(0.1) + row(0.3) + row(0.4) + row(2.0) + row(2.1)).medianPeriod(), 0.1,
              1e-12);
  EXPECT_DOUBLE_EQ(logOf(kHeader + "\n" + row(0) + row(1) + row(3)).medianPeriod(), 1.5);
}

TEST(StateLog, LargeLogParsesQuickly) {
  std::string text = kHeader + "\n";
  text.reserve(100000 * 70);
  char buffer[160];
  for (int i = 0; i < 100000; ++i) {
    const double t = i * 0.001;
    std::snprintf(buffer, sizeof buffer, "%.3f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", t, std::sin(t), std::cos(t), t * 0.5,
                  -t, 2 * t, 1.0);
    text += buffer;
  }
  const auto start = std::chrono::steady_clock::now();
  const StateLog log = logOf(text);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(log.rows(), 100000u);
  EXPECT_NEAR(log.times.back(), 99.999, 1e-12);
  EXPECT_NEAR(log.values[99999 * 6 + 1], std::cos(99.999), 1e-6);
  EXPECT_NEAR(log.medianPeriod(), 0.001, 1e-9);
  EXPECT_LT(seconds, 1.0) << "100k rows took " << seconds << " s";
  std::printf("100k rows parsed in %.1f ms\n", seconds * 1e3);
  std::vector<double> state(6);
  ASSERT_EQ(stateAt(log, 50.0005, 0.002, state), StateMatch::Interpolated);
  EXPECT_NEAR(state[0], std::sin(50.0005), 1e-5);
}

// --- files -------------------------------------------------------------------------------------

class StateLogFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("kccd_state_log_test_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  std::string loadError(const std::string& path) {
    try {
      loadStateLog(path, model());
    } catch (const StateLogError& e) {
      return e.what();
    }
    return "(loaded)";
  }

  std::filesystem::path dir_;
};

TEST_F(StateLogFile, LoadsAndNamesTheFile) {
  const std::string path = write("good.csv", kHeader + "\r\n" + row(0) + row(1));
  EXPECT_EQ(loadStateLog(path, model()).rows(), 2u);
  const std::string bad = write("bad.csv", kHeader + "\n0,0,0,0,0,0,x\n");
  EXPECT_EQ(loadError(bad), bad + ":2:13: column 'pose.z': not a decimal number: 'x'");
}

TEST_F(StateLogFile, OnlyRegularFiles) {
  const std::string missing = (dir_ / "missing.csv").string();
  EXPECT_EQ(loadError(missing), missing + ": cannot open the state log (no such file)");
  EXPECT_EQ(loadError(dir_.string()), dir_.string() + ": a folder, not a state log");
  const std::string fifo = (dir_ / "fifo.csv").string();
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(loadError(fifo), fifo + ": not a regular file (a device, FIFO or socket)");  // without blocking
  EXPECT_EQ(loadError("/dev/null"), "/dev/null: not a regular file (a device, FIFO or socket)");
}

}  // namespace
}  // namespace kccd

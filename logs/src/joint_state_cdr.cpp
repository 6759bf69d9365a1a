#include "kccd/logs/joint_state_cdr.hpp"

#include <bit>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>

namespace kccd::logs {
namespace {

// CDR little-endian (encapsulation 0x0001): each primitive aligned to its size, counted from the
// byte after the 4-byte encapsulation header; a string is its length with the closing NUL, then
// its bytes and the NUL; a sequence its element count, then the elements. `type` names the
// message in errors.
class CdrWriter {
 public:
  explicit CdrWriter(const char* type) : type_(type), b_{0x00, 0x01, 0x00, 0x00} {}
  template <class T>
  void num(T v) {
    while ((b_.size() - 4) % sizeof(T) != 0) b_.push_back(0);
    const auto bits = std::bit_cast<std::conditional_t<sizeof(T) == 8, std::uint64_t, std::uint32_t>>(v);
    for (std::size_t i = 0; i < sizeof(T); ++i) b_.push_back(static_cast<std::uint8_t>(bits >> (8 * i)));
  }
  void count(std::size_t n) {
    if (n > std::numeric_limits<std::uint32_t>::max())
      throw std::invalid_argument(std::string(type_) + ": more than 2^32 - 1 values in one field");
    num(static_cast<std::uint32_t>(n));
  }
  void str(const std::string& s) {
    if (s.find('\0') != std::string::npos)
      throw std::invalid_argument(std::string(type_) + ": a string with a NUL byte cannot be written as CDR");
    count(s.size() + 1);
    b_.insert(b_.end(), s.begin(), s.end());
    b_.push_back(0);
  }
  void doubles(const std::vector<double>& v) {
    count(v.size());
    for (const double x : v) num(x);
  }
  void bytes(std::span<const std::uint8_t> v) {
    count(v.size());
    b_.insert(b_.end(), v.begin(), v.end());
  }
  // std_msgs/Header: builtin_interfaces/Time (seconds rounded down, so that nanosec is in
  // [0, 1e9) for stamps before the epoch too), then frame_id.
  void header(std::int64_t stamp_ns, const std::string& frame_id) {
    constexpr std::int64_t kNs = 1'000'000'000;
    const std::int64_t sec = stamp_ns >= 0 ? stamp_ns / kNs : -((-(stamp_ns + 1)) / kNs) - 1;
    if (sec < std::numeric_limits<std::int32_t>::min() || sec > std::numeric_limits<std::int32_t>::max())
      throw std::invalid_argument(std::string(type_) + ": stamp " + std::to_string(stamp_ns) +
                                  " ns: its seconds do not fit the header's int32");
    num(static_cast<std::int32_t>(sec));
    num(static_cast<std::uint32_t>(stamp_ns - sec * kNs));
    str(frame_id);
  }
  std::vector<std::uint8_t> take() { return std::move(b_); }

 private:
  const char* type_;
  std::vector<std::uint8_t> b_;
};

// The definitions of the types a message's header uses, after its own (the "=" rule, then MSG: NAME).
std::string headerDependencies() {
  const std::string rule(80, '=');
  return rule +
         "\n"
         "MSG: std_msgs/Header\n"
         "builtin_interfaces/Time stamp\n"
         "string frame_id\n" +
         rule +
         "\n"
         "MSG: builtin_interfaces/Time\n"
         "int32 sec\n"
         "uint32 nanosec\n";
}

}  // namespace

const std::string& jointStateDefinition() {
  static const std::string text =
      "std_msgs/Header header\n"
      "string[] name\n"
      "float64[] position\n"
      "float64[] velocity\n"
      "float64[] effort\n" +
      headerDependencies();
  return text;
}

std::vector<std::uint8_t> encodeJointStateCdr(const JointState& s) {
  CdrWriter w("JointState");
  w.header(s.stamp_ns, s.frame_id);
  w.count(s.name.size());
  for (const std::string& n : s.name) w.str(n);
  w.doubles(s.position);
  w.doubles(s.velocity);
  w.doubles(s.effort);
  return w.take();
}

const std::string& compressedImageDefinition() {
  static const std::string text =
      "std_msgs/Header header\n"
      "string format\n"
      "uint8[] data\n" +
      headerDependencies();
  return text;
}

std::vector<std::uint8_t> encodeCompressedImageCdr(const CompressedImage& image) {
  CdrWriter w("CompressedImage");
  w.header(image.stamp_ns, image.frame_id);
  w.str(image.format);
  w.bytes(image.data);
  return w.take();
}

}  // namespace kccd::logs

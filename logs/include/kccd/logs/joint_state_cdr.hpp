// sensor_msgs/msg/JointState and sensor_msgs/msg/CompressedImage as ROS 2 records them: the
// definition a bag stores as the channel's "ros2msg" schema (with the types it uses after it) and a
// message's CDR bytes (the 4-byte encapsulation header, then little-endian fields aligned to their
// size), so the suite writes joint states and camera frames that its own decoder and every ROS 2
// reader decode.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace kccd::logs {

/// One joint state: the header and the joints' names and values.
struct JointState {
  std::int64_t stamp_ns = 0;  ///< header.stamp in nanoseconds since the epoch (sec fits an int32)
  std::string frame_id;       ///< header.frame_id
  std::vector<std::string> name;
  std::vector<double> position, velocity, effort;  ///< each empty or one value per name
};

/// The schema name of a JointState channel.
inline constexpr char kJointStateSchemaName[] = "sensor_msgs/msg/JointState";

/// The ros2msg definition of JointState, std_msgs/Header and builtin_interfaces/Time after it.
const std::string& jointStateDefinition();

/// The CDR bytes of `state`. Throws std::invalid_argument for a stamp whose seconds do not fit
/// an int32, a name with a NUL byte, or arrays of more than 2^32 - 1 values.
std::vector<std::uint8_t> encodeJointStateCdr(const JointState& state);

/// One compressed camera frame: the header, the format and the encoded bytes (not owned).
struct CompressedImage {
  std::int64_t stamp_ns = 0;  ///< header.stamp in nanoseconds since the epoch (sec fits an int32)
  std::string frame_id;       ///< header.frame_id: the camera's optical frame
  /// How the bytes are encoded; image_transport's compressed plugin writes e.g. "bgr8; jpeg compressed bgr8".
  std::string format;
  std::span<const std::uint8_t> data;  ///< the JPEG (or PNG) file's bytes
};

/// The schema name of a CompressedImage channel.
inline constexpr char kCompressedImageSchemaName[] = "sensor_msgs/msg/CompressedImage";

/// The ros2msg definition of CompressedImage, std_msgs/Header and builtin_interfaces/Time after it.
const std::string& compressedImageDefinition();

/// The CDR bytes of `image`. Throws std::invalid_argument as encodeJointStateCdr does (a stamp, a
/// NUL byte in frame_id or format, 2^32 or more bytes of data).
std::vector<std::uint8_t> encodeCompressedImageCdr(const CompressedImage& image);

}  // namespace kccd::logs

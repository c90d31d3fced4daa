// ROS 2 messages, as a run's MCAP log (log.mcap) and the Foxglove live stream
// carry them, so that Foxglove, Lichtblick and ROS 2 tools decode them with no
// vlab-specific code:
//   schema   ros2msg text (schema encoding "ros2msg"): the type's fields, then
//            each type it uses after a line of 80 '=' and "MSG: pkg/Type"
//   message  CDR (message encoding "cdr"): the 4-byte encapsulation header
//            00 01 00 00 (plain CDR, little-endian), then the fields in order,
//            each aligned to its own size counted from the end of that header;
//            a string is a uint32 length counting its terminating NUL, its
//            bytes and the NUL; a sequence is a uint32 count, then its items
// Three kinds of message:
//   signals  one device's log columns at one period: vlab_msgs/msg/<Device>
//            (builtin_interfaces/Time stamp, then one float64 per column), on
//            topic /<device> (SignalChannels)
//   poses    tf2_msgs/msg/TFMessage: a geometry_msgs/TransformStamped per body
//            (parent frame "world", child frame the body's name)
//   images   sensor_msgs/msg/CompressedImage: a camera's frame as PNG or JPEG
//            bytes ("png" or "jpeg"), frame_id the camera's name
//   scene    foxglove_msgs/msg/SceneUpdate: the visual geometry (SceneGeometry)
//            as primitives, one entity per body, locked to the body's frame,
//            and one for the world's geoms; sent once, it holds for the run
// A message's stamp is the simulated time of its period. Little-endian hosts
// only. Encoding writes into a string it resizes: no allocation once the
// string has the capacity.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <nlohmann/json_fwd.hpp>

namespace vlab::scene {

inline constexpr char kSchemaEncoding[] = "ros2msg";
inline constexpr char kMessageEncoding[] = "cdr";

struct MessageSchema {
  std::string name;  ///< ROS 2 type name: "tf2_msgs/msg/TFMessage"
  std::string text;  ///< ros2msg definition, with the types it uses
};

/// One device's log columns as one channel's messages: the columns whose name
/// starts with "DEVICE." ("pa10.q.S1", "jr3.Fx"); a column without a '.' other
/// than "time" is a device of its own, whose one field is "value".
struct SignalChannel {
  std::string device;               ///< "pa10"
  std::string topic;                ///< "/pa10"
  MessageSchema schema;             ///< vlab_msgs/msg/Pa10: stamp, then fields
  std::vector<int> columns;         ///< indices in the log's columns, field order
  std::vector<std::string> fields;  ///< "q_s1" for "pa10.q.S1" (FieldName)
};

/// The channels of a log's `columns`, in order of each device's first column;
/// "time" is every message's stamp, not a field. Distinct devices get distinct
/// type names, and a device's fields distinct names (a clash gets "_2", ...).
std::vector<SignalChannel> SignalChannels(const std::vector<std::string>& columns);

/// A ROS 2 field name for a column's part after its device ("q.S1" -> "q_s1",
/// "Fx" -> "fx", "p_des.x" -> "p_des_x"): lower case, every run of characters
/// other than letters and digits one '_', none at either end, "f" before a
/// leading digit; "value" when nothing is left.
std::string FieldName(const std::string& part);

/// The stamp's seconds and nanoseconds of a time t >= 0 (s), to the nearest ns.
void StampOf(double t, std::int32_t* sec, std::uint32_t* nanosec);

/// A signals message of `channel` at time t from one log row (`row`: the
/// values of all the log's columns, in its order).
void EncodeSignals(double t, const SignalChannel& channel, const double* row, std::string* out);

MessageSchema TfMessageSchema();

/// One body's pose in its parent's frame.
struct FrameTransform {
  std::string parent;       ///< "world"
  std::string child;        ///< the body's frame (BodyFrames)
  double translation[3];    ///< m
  double rotation_wxyz[4];  ///< unit quaternion, w first (MuJoCo's order)
};

/// A tf2_msgs/msg/TFMessage at time t of `count` transforms, each stamped t.
void EncodeTfMessage(double t, const FrameTransform* transforms, std::size_t count, std::string* out);

MessageSchema CompressedImageSchema();

/// A sensor_msgs/msg/CompressedImage at time t: `format` "png" or "jpeg",
/// `frame_id` the camera's name, `size` bytes of the encoded image.
void EncodeCompressedImage(double t, const std::string& frame_id, const std::string& format, const std::uint8_t* data,
                           std::size_t size, std::string* out);

/// The frame of every body of a scene's geometry (SceneGeometry's "bodies",
/// in order): its name, or "body_N" (N its index there) when it has none or
/// its name is taken or is "world". The frames of TFMessages and SceneUpdates.
std::vector<std::string> BodyFrames(const nlohmann::json& geometry);

MessageSchema SceneUpdateSchema();

/// A foxglove_msgs/msg/SceneUpdate at time t of a scene's visual geometry
/// (SceneGeometry): an entity per body with a geom (frame and id BodyFrames',
/// frame locked) and one for the world's geoms ("world"), each geom a
/// primitive in its body's frame with its rgba: box -> cube, sphere and
/// ellipsoid -> sphere, cylinder -> cylinder, capsule -> a cylinder and two
/// spheres, plane -> a 1 mm thick cube under its surface (an infinite plane
/// drawn 10 m square), mesh -> a triangle list of its vertices and faces from
/// `model` (the MJCF the geometry came from; null: meshes are left out, the
/// geometry does not hold their vertices). Textures are not carried:
/// Foxglove's primitives have colours only. Throws nlohmann::json's
/// exceptions for a geometry without the fields SceneGeometry writes.
void EncodeSceneUpdate(double t, const nlohmann::json& geometry, const mjModel* model, std::string* out);

}  // namespace vlab::scene

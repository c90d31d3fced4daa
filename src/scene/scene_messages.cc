#include "scene/scene_messages.h"

#include <cctype>
#include <cmath>
#include <cstring>

namespace vlab::scene {

namespace {

const std::string kSeparator = std::string(80, '=') + "\n";

const char kTimeText[] = "int32 sec\nuint32 nanosec\n";
const char kHeaderText[] = "builtin_interfaces/Time stamp\nstring frame_id\n";

// the definition of a type used by another: the separator, "MSG: NAME", its fields
std::string Dependency(const char* name, const char* text) { return kSeparator + "MSG: " + name + "\n" + text; }

// CDR writer: fields aligned to their size from the end of the encapsulation header
class Cdr {
 public:
  explicit Cdr(std::string* out) : out_(out) {
    out_->clear();
    out_->append("\x00\x01\x00\x00", 4);
  }
  void Align(std::size_t size) {
    const std::size_t offset = out_->size() - 4;
    if (offset % size) out_->append(size - offset % size, '\0');
  }
  template <typename T>
  void Put(T value) {
    Align(sizeof(T));
    const std::size_t at = out_->size();
    out_->resize(at + sizeof(T));
    std::memcpy(out_->data() + at, &value, sizeof(T));
  }
  void String(const std::string& s) {
    Put<std::uint32_t>(static_cast<std::uint32_t>(s.size() + 1));
    out_->append(s);
    out_->push_back('\0');
  }
  void Bytes(const std::uint8_t* data, std::size_t size) {
    Put<std::uint32_t>(static_cast<std::uint32_t>(size));
    out_->append(reinterpret_cast<const char*>(data), size);
  }
  void Stamp(double t) {
    std::int32_t sec = 0;
    std::uint32_t nanosec = 0;
    StampOf(t, &sec, &nanosec);
    Put(sec);
    Put(nanosec);
  }

 private:
  std::string* out_;
};

// "pa10" -> "Pa10", "cube_a" -> "CubeA": a ROS 2 type name (a letter first, letters and digits)
std::string TypeName(const std::string& device) {
  std::string name;
  bool upper = true;
  for (char c : device) {
    if (!std::isalnum(static_cast<unsigned char>(c))) {
      upper = true;
      continue;
    }
    name.push_back(upper ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c);
    upper = false;
  }
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) name = "D" + name;
  return name;
}

// `name`, or name_2, name_3, ... : the first not in `taken`
std::string Unique(const std::string& name, const std::vector<std::string>& taken) {
  auto used = [&](const std::string& n) {
    for (const std::string& t : taken) {
      if (t == n) return true;
    }
    return false;
  };
  std::string candidate = name;
  for (int i = 2; used(candidate); ++i) candidate = name + "_" + std::to_string(i);
  return candidate;
}

}  // namespace

std::string FieldName(const std::string& part) {
  std::string name;
  bool gap = false;
  for (char c : part) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      if (gap && !name.empty()) name.push_back('_');
      name.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
      gap = false;
    } else {
      gap = true;
    }
  }
  if (name.empty()) return "value";
  if (std::isdigit(static_cast<unsigned char>(name[0]))) name = "f" + name;
  return name;
}

void StampOf(double t, std::int32_t* sec, std::uint32_t* nanosec) {
  const long long ns = std::llround(t * 1e9);
  *sec = static_cast<std::int32_t>(ns / 1000000000LL);
  *nanosec = static_cast<std::uint32_t>(ns % 1000000000LL);
}

std::vector<SignalChannel> SignalChannels(const std::vector<std::string>& columns) {
  std::vector<SignalChannel> channels;
  std::vector<std::string> types;
  for (std::size_t i = 0; i < columns.size(); ++i) {
    const std::string& column = columns[i];
    if (column == "time") continue;
    const std::size_t dot = column.find('.');
    const std::string device = column.substr(0, dot);
    SignalChannel* channel = nullptr;
    for (SignalChannel& c : channels) {
      if (c.device == device) channel = &c;
    }
    if (!channel) {
      channel = &channels.emplace_back();
      channel->device = device;
      channel->topic = "/" + device;
      channel->schema.name = "vlab_msgs/msg/" + Unique(TypeName(device), types);
      types.push_back(channel->schema.name.substr(std::strlen("vlab_msgs/msg/")));
    }
    channel->columns.push_back(static_cast<int>(i));
    channel->fields.push_back(
        Unique(FieldName(dot == std::string::npos ? std::string() : column.substr(dot + 1)), channel->fields));
  }
  for (SignalChannel& channel : channels) {
    std::string text = "# " + channel.device + "'s log columns at one control period (vlab run log)\n";
    text += "builtin_interfaces/Time stamp\n";
    for (std::size_t f = 0; f < channel.fields.size(); ++f) {
      text += "float64 " + channel.fields[f] + "  # " + columns[channel.columns[f]] + "\n";
    }
    channel.schema.text = text + Dependency("builtin_interfaces/Time", kTimeText);
  }
  return channels;
}

void EncodeSignals(double t, const SignalChannel& channel, const double* row, std::string* out) {
  Cdr cdr(out);
  cdr.Stamp(t);
  for (int column : channel.columns) cdr.Put(row[column]);
}

MessageSchema TfMessageSchema() {
  return {"tf2_msgs/msg/TFMessage",
          std::string("geometry_msgs/TransformStamped[] transforms\n") +
              Dependency("geometry_msgs/TransformStamped",
                         "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n") +
              Dependency("std_msgs/Header", kHeaderText) + Dependency("builtin_interfaces/Time", kTimeText) +
              Dependency("geometry_msgs/Transform",
                         "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n") +
              Dependency("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n") +
              Dependency("geometry_msgs/Quaternion", "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n")};
}

void EncodeTfMessage(double t, const FrameTransform* transforms, std::size_t count, std::string* out) {
  Cdr cdr(out);
  cdr.Put<std::uint32_t>(static_cast<std::uint32_t>(count));
  for (std::size_t i = 0; i < count; ++i) {
    const FrameTransform& tf = transforms[i];
    cdr.Stamp(t);
    cdr.String(tf.parent);
    cdr.String(tf.child);
    for (double v : tf.translation) cdr.Put(v);
    cdr.Put(tf.rotation_wxyz[1]);
    cdr.Put(tf.rotation_wxyz[2]);
    cdr.Put(tf.rotation_wxyz[3]);
    cdr.Put(tf.rotation_wxyz[0]);
  }
}

MessageSchema CompressedImageSchema() {
  return {"sensor_msgs/msg/CompressedImage", std::string("std_msgs/Header header\nstring format\nuint8[] data\n") +
                                                 Dependency("std_msgs/Header", kHeaderText) +
                                                 Dependency("builtin_interfaces/Time", kTimeText)};
}

void EncodeCompressedImage(double t, const std::string& frame_id, const std::string& format, const std::uint8_t* data,
                           std::size_t size, std::string* out) {
  Cdr cdr(out);
  cdr.Stamp(t);
  cdr.String(frame_id);
  cdr.String(format);
  cdr.Bytes(data, size);
}

}  // namespace vlab::scene

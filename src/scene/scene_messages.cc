#include "scene/scene_messages.h"

#include <cctype>
#include <cmath>
#include <cstring>

#include <nlohmann/json.hpp>

namespace vlab::scene {

namespace {

const std::string kSeparator = std::string(80, '=') + "\n";

const char kTimeText[] = "int32 sec\nuint32 nanosec\n";
const char kPoseText[] = "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n";
const char kXyzText[] = "float64 x\nfloat64 y\nfloat64 z\n";
const char kQuaternionText[] = "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";
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
  void Count(std::size_t n) { Put<std::uint32_t>(static_cast<std::uint32_t>(n)); }
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

std::vector<std::string> BodyFrames(const nlohmann::json& geometry) {
  std::vector<std::string> frames;
  const nlohmann::json& bodies = geometry.at("bodies");
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    std::string name = bodies[i].get<std::string>();
    bool taken = name.empty() || name == "world";
    for (const std::string& f : frames) taken = taken || f == name;
    frames.push_back(taken ? "body_" + std::to_string(i) : name);
  }
  return frames;
}

MessageSchema SceneUpdateSchema() {
  const char* pose_size_color = "geometry_msgs/Pose pose\ngeometry_msgs/Vector3 size\nfoxglove_msgs/Color color\n";
  return {
      "foxglove_msgs/msg/SceneUpdate",
      std::string("foxglove_msgs/SceneEntityDeletion[] deletions\nfoxglove_msgs/SceneEntity[] entities\n") +
          Dependency("foxglove_msgs/SceneEntityDeletion",
                     "builtin_interfaces/Time timestamp\nuint8 MATCHING_ID=0\nuint8 ALL=1\nuint8 type\nstring id\n") +
          Dependency("builtin_interfaces/Time", kTimeText) +
          Dependency("foxglove_msgs/SceneEntity",
                     "builtin_interfaces/Time timestamp\nstring frame_id\nstring id\n"
                     "builtin_interfaces/Duration lifetime\nbool frame_locked\n"
                     "foxglove_msgs/KeyValuePair[] metadata\nfoxglove_msgs/ArrowPrimitive[] arrows\n"
                     "foxglove_msgs/CubePrimitive[] cubes\nfoxglove_msgs/SpherePrimitive[] spheres\n"
                     "foxglove_msgs/CylinderPrimitive[] cylinders\nfoxglove_msgs/LinePrimitive[] lines\n"
                     "foxglove_msgs/TriangleListPrimitive[] triangles\nfoxglove_msgs/TextPrimitive[] texts\n"
                     "foxglove_msgs/ModelPrimitive[] models\n") +
          Dependency("builtin_interfaces/Duration", kTimeText) +
          Dependency("foxglove_msgs/KeyValuePair", "string key\nstring value\n") +
          Dependency("foxglove_msgs/ArrowPrimitive",
                     "geometry_msgs/Pose pose\nfloat64 shaft_length\nfloat64 shaft_diameter\n"
                     "float64 head_length\nfloat64 head_diameter\nfoxglove_msgs/Color color\n") +
          Dependency("geometry_msgs/Pose", kPoseText) + Dependency("geometry_msgs/Point", kXyzText) +
          Dependency("geometry_msgs/Quaternion", kQuaternionText) +
          Dependency("foxglove_msgs/Color", "float64 r\nfloat64 g\nfloat64 b\nfloat64 a\n") +
          Dependency("foxglove_msgs/CubePrimitive", pose_size_color) + Dependency("geometry_msgs/Vector3", kXyzText) +
          Dependency("foxglove_msgs/SpherePrimitive", pose_size_color) +
          Dependency("foxglove_msgs/CylinderPrimitive",
                     "geometry_msgs/Pose pose\ngeometry_msgs/Vector3 size\nfloat64 bottom_scale\n"
                     "float64 top_scale\nfoxglove_msgs/Color color\n") +
          Dependency("foxglove_msgs/LinePrimitive",
                     "uint8 LINE_STRIP=0\nuint8 LINE_LOOP=1\nuint8 LINE_LIST=2\nuint8 type\n"
                     "geometry_msgs/Pose pose\nfloat64 thickness\nbool scale_invariant\n"
                     "geometry_msgs/Point[] points\nfoxglove_msgs/Color color\nfoxglove_msgs/Color[] colors\n"
                     "uint32[] indices\n") +
          Dependency("foxglove_msgs/TriangleListPrimitive",
                     "geometry_msgs/Pose pose\ngeometry_msgs/Point[] points\nfoxglove_msgs/Color color\n"
                     "foxglove_msgs/Color[] colors\nuint32[] indices\n") +
          Dependency("foxglove_msgs/TextPrimitive",
                     "geometry_msgs/Pose pose\nbool billboard\nfloat64 font_size\nbool scale_invariant\n"
                     "foxglove_msgs/Color color\nstring text\n") +
          Dependency("foxglove_msgs/ModelPrimitive",
                     "geometry_msgs/Pose pose\ngeometry_msgs/Vector3 scale\nfoxglove_msgs/Color color\n"
                     "bool override_color\nstring url\nstring media_type\nuint8[] data\n")};
}

namespace {

// one primitive: a pose in the body's frame (x, y, z; qw, qx, qy, qz), a size, rgba
struct Primitive {
  double pos[3];
  double quat[4];
  double size[3];
  double rgba[4];
  int mesh = -1;  // triangles: the mesh's id
};

struct Entity {
  std::string frame;
  std::vector<Primitive> cubes, spheres, cylinders, triangles;
};

// q * (0, v) * q^-1 added to p: a point v of a geom's frame in its body's
void Offset(const Primitive& geom, double along_z, double* out) {
  const double w = geom.quat[0], x = geom.quat[1], y = geom.quat[2], z = geom.quat[3];
  // the geom's z axis in its body's frame: the third column of the rotation matrix
  out[0] = geom.pos[0] + along_z * 2 * (x * z + w * y);
  out[1] = geom.pos[1] + along_z * 2 * (y * z - w * x);
  out[2] = geom.pos[2] + along_z * (1 - 2 * (x * x + y * y));
}

void PutPose(Cdr& cdr, const Primitive& p) {
  for (double v : p.pos) cdr.Put(v);
  cdr.Put(p.quat[1]);
  cdr.Put(p.quat[2]);
  cdr.Put(p.quat[3]);
  cdr.Put(p.quat[0]);
}

void PutColor(Cdr& cdr, const Primitive& p) {
  for (double v : p.rgba) cdr.Put(v);
}

}  // namespace

void EncodeSceneUpdate(double t, const nlohmann::json& geometry, const mjModel* model, std::string* out) {
  const std::vector<std::string> frames = BodyFrames(geometry);
  std::vector<Entity> entities(frames.size() + 1);
  entities[0].frame = "world";
  for (std::size_t i = 0; i < frames.size(); ++i) entities[i + 1].frame = frames[i];
  constexpr double kInfinitePlaneHalf_m = 5, kPlaneThickness_m = 0.001;
  for (const nlohmann::json& g : geometry.at("geoms")) {
    Primitive p{};
    for (int i = 0; i < 3; ++i) p.pos[i] = g.at("pos").at(i).get<double>();
    for (int i = 0; i < 4; ++i) p.quat[i] = g.at("quat").at(i).get<double>();
    for (int i = 0; i < 4; ++i) p.rgba[i] = g.at("rgba").at(i).get<double>();
    double size[3];
    for (int i = 0; i < 3; ++i) size[i] = g.at("size").at(i).get<double>();
    Entity& e = entities.at(static_cast<std::size_t>(g.at("body").get<int>() + 1));
    const std::string type = g.at("type").get<std::string>();
    if (type == "box") {
      for (int i = 0; i < 3; ++i) p.size[i] = 2 * size[i];
      e.cubes.push_back(p);
    } else if (type == "sphere") {
      p.size[0] = p.size[1] = p.size[2] = 2 * size[0];
      e.spheres.push_back(p);
    } else if (type == "ellipsoid") {
      for (int i = 0; i < 3; ++i) p.size[i] = 2 * size[i];
      e.spheres.push_back(p);
    } else if (type == "cylinder" || type == "capsule") {
      p.size[0] = p.size[1] = 2 * size[0];
      p.size[2] = 2 * size[1];
      e.cylinders.push_back(p);
      if (type == "capsule") {
        Primitive cap = p;
        cap.size[2] = cap.size[0];
        for (double end : {-size[1], size[1]}) {
          Offset(p, end, cap.pos);
          e.spheres.push_back(cap);
        }
      }
    } else if (type == "plane") {
      p.size[0] = 2 * (size[0] > 0 ? size[0] : kInfinitePlaneHalf_m);
      p.size[1] = 2 * (size[1] > 0 ? size[1] : kInfinitePlaneHalf_m);
      p.size[2] = kPlaneThickness_m;
      Primitive moved = p;
      Offset(p, -kPlaneThickness_m / 2, moved.pos);
      e.cubes.push_back(moved);
    } else if (type == "mesh" && model) {
      p.mesh = g.at("mesh").get<int>();
      if (p.mesh >= 0 && p.mesh < model->nmesh) e.triangles.push_back(p);
    }
  }

  Cdr cdr(out);
  cdr.Count(0);  // deletions
  std::size_t count = 0;
  for (const Entity& e : entities) {
    count += !(e.cubes.empty() && e.spheres.empty() && e.cylinders.empty() && e.triangles.empty());
  }
  cdr.Count(count);
  for (const Entity& e : entities) {
    if (e.cubes.empty() && e.spheres.empty() && e.cylinders.empty() && e.triangles.empty()) continue;
    cdr.Stamp(t);
    cdr.String(e.frame);
    cdr.String(e.frame);        // id
    cdr.Put<std::int32_t>(0);   // lifetime: 0, for ever
    cdr.Put<std::uint32_t>(0);  //
    cdr.Put<std::uint8_t>(1);   // frame_locked
    cdr.Count(0);               // metadata
    cdr.Count(0);               // arrows
    for (const auto* list : {&e.cubes, &e.spheres}) {
      cdr.Count(list->size());
      for (const Primitive& p : *list) {
        PutPose(cdr, p);
        for (double v : p.size) cdr.Put(v);
        PutColor(cdr, p);
      }
    }
    cdr.Count(e.cylinders.size());
    for (const Primitive& p : e.cylinders) {
      PutPose(cdr, p);
      for (double v : p.size) cdr.Put(v);
      cdr.Put(1.0);  // bottom_scale
      cdr.Put(1.0);  // top_scale
      PutColor(cdr, p);
    }
    cdr.Count(0);  // lines
    cdr.Count(e.triangles.size());
    for (const Primitive& p : e.triangles) {
      PutPose(cdr, p);
      const int vert = model->mesh_vertadr[p.mesh], nvert = model->mesh_vertnum[p.mesh];
      cdr.Count(static_cast<std::size_t>(nvert));
      for (int v = 0; v < 3 * nvert; ++v) cdr.Put(static_cast<double>(model->mesh_vert[3 * vert + v]));
      PutColor(cdr, p);
      cdr.Count(0);  // colors
      const int face = model->mesh_faceadr[p.mesh], nface = model->mesh_facenum[p.mesh];
      cdr.Count(3 * static_cast<std::size_t>(nface));
      for (int f = 0; f < 3 * nface; ++f) cdr.Put(static_cast<std::uint32_t>(model->mesh_face[3 * face + f]));
    }
    cdr.Count(0);  // texts
    cdr.Count(0);  // models
  }
}

}  // namespace vlab::scene

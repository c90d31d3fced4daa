// scene/scene_messages.h: the ROS 2 schemas and CDR bytes of MCAP logs and the
// Foxglove live stream. The bytes are checked against layouts worked out by
// hand from the CDR rules (alignment counted after the 4-byte header); the MCAP
// and live-stream tests decode them with Foxglove's own ROS 2 decoder.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <nlohmann/json.hpp>

#include "scene/scene_geometry.h"
#include "scene/scene_messages.h"

namespace vlab::lab::messages_test {
namespace {

using scene::FieldName;
using scene::SignalChannels;

template <typename T>
T At(const std::string& bytes, std::size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}

TEST(SceneMessages, FieldNamesAreRos2Names) {
  EXPECT_EQ(FieldName("q.S1"), "q_s1");
  EXPECT_EQ(FieldName("Fx"), "fx");
  EXPECT_EQ(FieldName("p_des.x"), "p_des_x");
  EXPECT_EQ(FieldName("__a..B__"), "a_b");
  EXPECT_EQ(FieldName("3d"), "f3d");
  EXPECT_EQ(FieldName("..."), "value");
  EXPECT_EQ(FieldName(""), "value");
}

TEST(SceneMessages, ChannelsAreDevicesAndTimeIsTheStamp) {
  const std::vector<std::string> columns = {"time",      "pa10.q.S1", "jr3.Fx",   "pa10.q.S2",
                                            "pa10.q.s1", "flag",      "cube-a.x", "cube_a.x"};
  const auto channels = SignalChannels(columns);
  ASSERT_EQ(channels.size(), 5u);
  EXPECT_EQ(channels[0].topic, "/pa10");
  EXPECT_EQ(channels[0].schema.name, "vlab_msgs/msg/Pa10");
  EXPECT_EQ(channels[0].columns, (std::vector<int>{1, 3, 4}));
  EXPECT_EQ(channels[0].fields, (std::vector<std::string>{"q_s1", "q_s2", "q_s1_2"}));
  EXPECT_EQ(channels[1].fields, (std::vector<std::string>{"fx"}));
  EXPECT_EQ(channels[2].device, "flag");
  EXPECT_EQ(channels[2].fields, (std::vector<std::string>{"value"}));
  // two devices whose type names would be alike get distinct ones
  EXPECT_EQ(channels[3].schema.name, "vlab_msgs/msg/CubeA");
  EXPECT_EQ(channels[4].schema.name, "vlab_msgs/msg/CubeA_2");
  EXPECT_EQ(channels[0].schema.text.rfind("# pa10's log columns", 0), 0u);
  EXPECT_NE(channels[0].schema.text.find("builtin_interfaces/Time stamp\nfloat64 q_s1  # pa10.q.S1\n"
                                         "float64 q_s2  # pa10.q.S2\nfloat64 q_s1_2  # pa10.q.s1\n"),
            std::string::npos);
  EXPECT_NE(channels[0].schema.text.find(std::string(80, '=') + "\nMSG: builtin_interfaces/Time\n"
                                                                "int32 sec\nuint32 nanosec\n"),
            std::string::npos);
}

TEST(SceneMessages, SignalsAreTheStampThenTheColumnsAsFloat64) {
  const std::vector<std::string> columns = {"time", "pa10.q.S1", "jr3.Fx", "pa10.q.S2"};
  const auto channels = SignalChannels(columns);
  const double row[] = {1.25, -0.5, 7.0, 3.0e-300};
  std::string bytes;
  scene::EncodeSignals(row[0], channels[0], row, &bytes);
  ASSERT_EQ(bytes.size(), 4u + 8 + 16);
  EXPECT_EQ(bytes.substr(0, 4), std::string("\x00\x01\x00\x00", 4));
  EXPECT_EQ(At<std::int32_t>(bytes, 4), 1);
  EXPECT_EQ(At<std::uint32_t>(bytes, 8), 250000000u);
  EXPECT_EQ(At<double>(bytes, 12), -0.5);
  EXPECT_EQ(At<double>(bytes, 20), 3.0e-300);
}

TEST(SceneMessages, StampsRoundToTheNanosecondAndCarry) {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  scene::StampOf(0.001, &sec, &nanosec);
  EXPECT_EQ(sec, 0);
  EXPECT_EQ(nanosec, 1000000u);
  scene::StampOf(2.9999999999, &sec, &nanosec);
  EXPECT_EQ(sec, 3);
  EXPECT_EQ(nanosec, 0u);
}

TEST(SceneMessages, TfMessageLaysOutEachTransformAligned) {
  const scene::FrameTransform tf[] = {{"world", "hand", {1, 2, 3}, {0.5, 0.1, 0.2, 0.3}},
                                      {"world", "ab", {4, 5, 6}, {1, 0, 0, 0}}};
  std::string bytes;
  scene::EncodeTfMessage(0.5, tf, 2, &bytes);
  // count; stamp (0, 5e8); "world" (4 + 6); "hand" (4 + 5), padding to 8; 7 float64
  std::size_t at = 4;
  EXPECT_EQ(At<std::uint32_t>(bytes, at), 2u);
  EXPECT_EQ(At<std::int32_t>(bytes, at + 4), 0);
  EXPECT_EQ(At<std::uint32_t>(bytes, at + 8), 500000000u);
  EXPECT_EQ(At<std::uint32_t>(bytes, at + 12), 6u);
  EXPECT_EQ(std::string(bytes.data() + at + 16, 6), std::string("world\0", 6));
  // the child's length at body offset 24 (22 rounded up to 4), its 5 bytes to 33, doubles from 40
  EXPECT_EQ(At<std::uint32_t>(bytes, at + 24), 5u);
  EXPECT_EQ(std::string(bytes.data() + at + 28, 5), std::string("hand\0", 5));
  EXPECT_EQ(At<double>(bytes, at + 40), 1.0);
  EXPECT_EQ(At<double>(bytes, at + 56), 3.0);
  EXPECT_EQ(At<double>(bytes, at + 64), 0.1);  // x, y, z, then w
  EXPECT_EQ(At<double>(bytes, at + 88), 0.5);
  // the second transform starts at 96: its stamp, then its strings and doubles
  EXPECT_EQ(At<std::uint32_t>(bytes, at + 100), 500000000u);
  // its frame "world" at 104 (4 + 6 to 114), the child's length at 116, "ab" to 123, doubles from 128
  EXPECT_EQ(At<std::uint32_t>(bytes, at + 116), 3u);
  EXPECT_EQ(std::string(bytes.data() + at + 120, 3), std::string("ab\0", 3));
  EXPECT_EQ(At<double>(bytes, at + 128), 4.0);
  EXPECT_EQ(bytes.size(), at + 128 + 56);
  EXPECT_EQ(scene::TfMessageSchema().name, "tf2_msgs/msg/TFMessage");
}

TEST(SceneMessages, CompressedImageCarriesFormatAndBytes) {
  const std::uint8_t png[] = {0x89, 'P', 'N', 'G', 1, 2, 3};
  std::string bytes;
  scene::EncodeCompressedImage(1.0, "webcam", "png", png, sizeof png, &bytes);
  // stamp 8; "webcam" 4 + 7 to 19; pad to 20; "png" 4 + 4 to 28; count 4 to 32; data
  EXPECT_EQ(At<std::uint32_t>(bytes, 4 + 8), 7u);
  EXPECT_EQ(At<std::uint32_t>(bytes, 4 + 20), 4u);
  EXPECT_EQ(std::string(bytes.data() + 4 + 24, 4), std::string("png\0", 4));
  EXPECT_EQ(At<std::uint32_t>(bytes, 4 + 28), 7u);
  EXPECT_EQ(bytes.substr(4 + 32), std::string(reinterpret_cast<const char*>(png), sizeof png));
  EXPECT_EQ(scene::CompressedImageSchema().name, "sensor_msgs/msg/CompressedImage");
}

// reads CDR back as the rules say (alignment from the end of the 4-byte header)
class CdrReader {
 public:
  explicit CdrReader(const std::string& bytes) : bytes_(bytes) {}
  template <typename T>
  T Get() {
    if ((at_ - 4) % sizeof(T)) at_ += sizeof(T) - (at_ - 4) % sizeof(T);
    EXPECT_LE(at_ + sizeof(T), bytes_.size());
    T value{};
    if (at_ + sizeof(T) <= bytes_.size()) std::memcpy(&value, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }
  std::string String() {
    const auto n = Get<std::uint32_t>();
    std::string s = bytes_.substr(at_, n ? n - 1 : 0);
    at_ += n;
    return s;
  }
  std::vector<double> Doubles(int n) {
    std::vector<double> v;
    for (int i = 0; i < n; ++i) v.push_back(Get<double>());
    return v;
  }
  bool AtEnd() const { return at_ == bytes_.size(); }

 private:
  const std::string& bytes_;
  std::size_t at_ = 4;
};

// a world plane, a body with a box, a capsule and a tetrahedron mesh, a body without a name
constexpr char kSceneXml[] = R"(<mujoco>
  <asset><mesh name="tet" vertex="0 0 0  1 0 0  0 1 0  0 0 1"/></asset>
  <worldbody>
    <geom type="plane" size="2 3 0.1" rgba="0.5 0.5 0.5 1"/>
    <body name="hand" pos="0 0 1">
      <freejoint/>
      <geom type="box" size="0.1 0.2 0.3" pos="1 2 3" rgba="1 0 0 1"/>
      <geom type="capsule" size="0.05 0.2" rgba="0 1 0 1"/>
      <geom type="mesh" mesh="tet" rgba="0 0 1 0.5"/>
    </body>
    <body pos="1 0 0"><freejoint/><geom type="sphere" size="0.1"/></body>
  </worldbody>
</mujoco>)";

TEST(SceneMessages, SceneUpdateCarriesEveryGeomInItsBodysFrame) {
  char error[1000] = "";
  mjVFS vfs;
  mj_defaultVFS(&vfs);
  ASSERT_EQ(mj_makeEmptyFileVFS(&vfs, "scene.xml", sizeof kSceneXml), 0);
  std::memcpy(vfs.filedata[vfs.nfile - 1], kSceneXml, sizeof kSceneXml);
  mjModel* m = mj_loadXML("scene.xml", &vfs, error, sizeof error);
  mj_deleteVFS(&vfs);
  ASSERT_NE(m, nullptr) << error;
  const nlohmann::json geometry = scene::SceneGeometry(m, scene::SceneBodies(m));
  EXPECT_EQ(scene::BodyFrames(geometry), (std::vector<std::string>{"hand", "body_1"}));
  std::string bytes;
  scene::EncodeSceneUpdate(2.5, geometry, m, &bytes);
  const int mesh_vertices = m->mesh_vertnum[0], mesh_faces = m->mesh_facenum[0];
  const std::vector<float> vertices(m->mesh_vert, m->mesh_vert + 3 * mesh_vertices);
  const std::vector<int> faces(m->mesh_face, m->mesh_face + 3 * mesh_faces);
  mj_deleteModel(m);

  CdrReader r(bytes);
  EXPECT_EQ(r.Get<std::uint32_t>(), 0u);  // deletions
  ASSERT_EQ(r.Get<std::uint32_t>(), 3u);  // world, hand, body_1
  struct Counts {
    std::string frame;
    std::uint32_t cubes, spheres, cylinders, triangles;
  };
  const Counts expected[] = {{"world", 1, 0, 0, 0}, {"hand", 1, 2, 1, 1}, {"body_1", 0, 1, 0, 0}};
  for (const Counts& e : expected) {
    SCOPED_TRACE(e.frame);
    EXPECT_EQ(r.Get<std::int32_t>(), 2);
    EXPECT_EQ(r.Get<std::uint32_t>(), 500000000u);
    EXPECT_EQ(r.String(), e.frame);
    EXPECT_EQ(r.String(), e.frame);
    EXPECT_EQ(r.Get<std::int32_t>(), 0);  // lifetime
    EXPECT_EQ(r.Get<std::uint32_t>(), 0u);
    EXPECT_EQ(r.Get<std::uint8_t>(), 1);    // frame locked
    EXPECT_EQ(r.Get<std::uint32_t>(), 0u);  // metadata
    EXPECT_EQ(r.Get<std::uint32_t>(), 0u);  // arrows
    ASSERT_EQ(r.Get<std::uint32_t>(), e.cubes);
    for (std::uint32_t i = 0; i < e.cubes; ++i) {
      const auto pose = r.Doubles(7), size = r.Doubles(3), rgba = r.Doubles(4);
      if (e.frame == "world") {  // the plane: 1 mm thick, its top at z = 0
        EXPECT_EQ(pose, (std::vector<double>{0, 0, -0.0005, 0, 0, 0, 1}));
        EXPECT_EQ(size, (std::vector<double>{4, 6, 0.001}));
        EXPECT_FLOAT_EQ(rgba[0], 0.5);
      } else {
        EXPECT_EQ(pose, (std::vector<double>{1, 2, 3, 0, 0, 0, 1}));
        EXPECT_FLOAT_EQ(size[0], 0.2);
        EXPECT_FLOAT_EQ(size[1], 0.4);
        EXPECT_FLOAT_EQ(size[2], 0.6);
        EXPECT_EQ(rgba, (std::vector<double>{1, 0, 0, 1}));
      }
    }
    ASSERT_EQ(r.Get<std::uint32_t>(), e.spheres);
    for (std::uint32_t i = 0; i < e.spheres; ++i) {
      const auto pose = r.Doubles(7), size = r.Doubles(3);
      r.Doubles(4);
      if (e.frame == "hand") {  // the capsule's ends
        EXPECT_NEAR(pose[2], i == 0 ? -0.2 : 0.2, 1e-12);
        EXPECT_FLOAT_EQ(size[0], 0.1);
      }
    }
    ASSERT_EQ(r.Get<std::uint32_t>(), e.cylinders);
    for (std::uint32_t i = 0; i < e.cylinders; ++i) {
      r.Doubles(7);
      const auto size = r.Doubles(3);
      EXPECT_FLOAT_EQ(size[2], 0.4);
      EXPECT_EQ(r.Doubles(2), (std::vector<double>{1, 1}));
      r.Doubles(4);
    }
    EXPECT_EQ(r.Get<std::uint32_t>(), 0u);  // lines
    ASSERT_EQ(r.Get<std::uint32_t>(), e.triangles);
    for (std::uint32_t i = 0; i < e.triangles; ++i) {
      r.Doubles(7);
      ASSERT_EQ(r.Get<std::uint32_t>(), static_cast<std::uint32_t>(mesh_vertices));
      for (int v = 0; v < 3 * mesh_vertices; ++v) EXPECT_EQ(r.Get<double>(), vertices[v]);
      EXPECT_DOUBLE_EQ(r.Doubles(4)[3], 0.5);
      EXPECT_EQ(r.Get<std::uint32_t>(), 0u);  // colors
      ASSERT_EQ(r.Get<std::uint32_t>(), static_cast<std::uint32_t>(3 * mesh_faces));
      for (int f = 0; f < 3 * mesh_faces; ++f) EXPECT_EQ(r.Get<std::uint32_t>(), static_cast<std::uint32_t>(faces[f]));
    }
    EXPECT_EQ(r.Get<std::uint32_t>(), 0u);  // texts
    EXPECT_EQ(r.Get<std::uint32_t>(), 0u);  // models
  }
  EXPECT_TRUE(r.AtEnd());
  EXPECT_EQ(mesh_faces, 4);
}

}  // namespace
}  // namespace vlab::lab::messages_test

// Tests `vlab export` (src/view/view_gltf.cc): a passive pendulum run with
// outputs: {poses: {rate: 50}} for 1 s (51 frames, t = 0 ... 1 s) exported as
// a .glb that
//   - is a valid GLB (magic, version 2, lengths, a JSON and a BIN chunk, every
//     bufferView inside the buffer and every accessor inside its view);
//   - has one node per body with its geoms as children, the world's geom at
//     the root, and one animation with a translation and a rotation channel
//     for the body, whose input has 51 times from 0 to 1 s and whose outputs
//     have 51 keys each, the last key equal to the recording's last frame;
//   - round-trips through three.js r111's GLTFLoader (headless Chromium): one
//     clip of 1 s with 2 tracks, a node "bob" whose pose at t = 1 s is the
//     last frame's;
// and that it refuses to overwrite a file and a folder without a recording.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cdp_client.h"
#include "test_util.h"

namespace vlab {
namespace {

using nlohmann::json;
using testing::ReadFile;
using testing::RunVlab;
using testing::TempDir;
using testing::WriteFile;

constexpr int kFrames = 51;  // 1 s at 50 Hz, both ends

constexpr const char* kXml = R"(<mujoco>
  <option timestep="0.001"/>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="bob" pos="0 0 1">
      <joint name="swing" type="hinge" axis="0 1 0"/>
      <geom name="rod" type="capsule" fromto="0 0 0 0.5 0 0" size="0.02" rgba="1 0 0 1"/>
      <geom name="ball" type="sphere" pos="0.5 0 0" size="0.05" rgba="0 0 1 0.5"/>
    </body>
  </worldbody>
</mujoco>
)";

std::uint32_t U32(const std::string& s, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, s.data() + at, 4);
  return v;
}
float F32(const std::string& s, std::size_t at) {
  float v = 0;
  std::memcpy(&v, s.data() + at, 4);
  return v;
}

class GltfTest : public ::testing::Test {
 protected:
  void SetUp() override {
    WriteFile(dir_ / "pendulum.xml", kXml);
    WriteFile(dir_ / "rec.yaml",
              "name: rec\nscene: pendulum.xml\nduration: 1.0\ncontrol_period: 0.002\n"
              "outputs: {poses: {rate: 50}}\n");
    const testing::ProcessResult run = RunVlab("run " + (dir_ / "rec.yaml") + " --out " + (dir_ / "run"));
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const testing::ProcessResult exported = RunVlab("export " + (dir_ / "run") + " " + (dir_ / "run.glb"));
    ASSERT_EQ(exported.exit_code, 0) << exported.err;
    glb_ = ReadFile(dir_ / "run.glb");
    poses_ = ReadFile(dir_ / "run/poses.bin");
  }
  // the last recorded frame's bob: x, y, z, qw, qx, qy, qz
  std::vector<float> LastFrame() const {
    std::vector<float> p;
    for (int i = 0; i < 7; ++i) p.push_back(F32(poses_, (kFrames - 1) * 44 + 16 + 4 * i));
    return p;
  }
  TempDir dir_;
  std::string glb_, poses_;
};

TEST_F(GltfTest, TheGlbIsValidAndCarriesTheRecordedMotion) {
  ASSERT_EQ(poses_.size(), static_cast<std::size_t>(kFrames) * 44);
  ASSERT_GE(glb_.size(), 28u);
  EXPECT_EQ(U32(glb_, 0), 0x46546C67u);  // "glTF"
  EXPECT_EQ(U32(glb_, 4), 2u);
  EXPECT_EQ(U32(glb_, 8), glb_.size());
  const std::uint32_t json_length = U32(glb_, 12);
  EXPECT_EQ(U32(glb_, 16), 0x4E4F534Au);  // "JSON"
  EXPECT_EQ(json_length % 4, 0u);
  const json g = json::parse(glb_.substr(20, json_length));
  const std::size_t bin_at = 20 + json_length;
  const std::uint32_t bin_length = U32(glb_, bin_at);
  EXPECT_EQ(U32(glb_, bin_at + 4), 0x004E4942u);  // "BIN"
  EXPECT_EQ(bin_at + 8 + bin_length, glb_.size());
  EXPECT_EQ(g["asset"]["version"], "2.0");
  EXPECT_EQ(g["buffers"][0]["byteLength"], bin_length);

  // every view inside the buffer, every accessor inside its view
  for (const json& a : g["accessors"]) {
    const json& v = g["bufferViews"][a["bufferView"].get<int>()];
    const std::string type = a["type"];
    const int n = type == "SCALAR" ? 1 : type == "VEC3" ? 3 : 4;
    EXPECT_LE(v["byteOffset"].get<std::size_t>() + v["byteLength"].get<std::size_t>(), bin_length);
    EXPECT_EQ(v["byteLength"].get<std::size_t>(), a["count"].get<std::size_t>() * n * 4);
  }
  // nodes: bob (with rod and ball), then the geoms; the floor at the root
  ASSERT_EQ(g["nodes"].size(), 4u);
  EXPECT_EQ(g["nodes"][0]["name"], "bob");
  EXPECT_EQ(g["nodes"][0]["children"].size(), 2u);
  EXPECT_EQ(g["scenes"][0]["nodes"], json::array({0, 1}));
  EXPECT_EQ(g["nodes"][1]["name"], "floor");
  EXPECT_EQ(g["materials"][2]["alphaMode"], "BLEND");  // the half-transparent ball
  // the animation: 2 channels on node 0, 51 keys from 0 to 1 s
  ASSERT_EQ(g["animations"].size(), 1u);
  const json& anim = g["animations"][0];
  ASSERT_EQ(anim["channels"].size(), 2u);
  for (const json& c : anim["channels"]) EXPECT_EQ(c["target"]["node"], 0);
  const json& input = g["accessors"][anim["samplers"][0]["input"].get<int>()];
  EXPECT_EQ(input["count"], kFrames);
  EXPECT_FLOAT_EQ(input["min"][0].get<float>(), 0.0f);
  EXPECT_FLOAT_EQ(input["max"][0].get<float>(), 1.0f);
  for (const json& s : anim["samplers"]) EXPECT_EQ(g["accessors"][s["output"].get<int>()]["count"], kFrames);
  // the last keys are the last frame (glTF rotation x, y, z, w)
  const std::vector<float> last = LastFrame();
  const json& tr = g["accessors"][anim["samplers"][0]["output"].get<int>()];
  const json& ro = g["accessors"][anim["samplers"][1]["output"].get<int>()];
  const std::size_t tr_at = bin_at + 8 + g["bufferViews"][tr["bufferView"].get<int>()]["byteOffset"].get<std::size_t>();
  const std::size_t ro_at = bin_at + 8 + g["bufferViews"][ro["bufferView"].get<int>()]["byteOffset"].get<std::size_t>();
  for (int i = 0; i < 3; ++i) EXPECT_EQ(F32(glb_, tr_at + 12 * (kFrames - 1) + 4 * i), last[i]);
  const int xyzw[4] = {4, 5, 6, 3};
  for (int i = 0; i < 4; ++i) EXPECT_EQ(F32(glb_, ro_at + 16 * (kFrames - 1) + 4 * i), last[xyzw[i]]);
  EXPECT_GT(std::abs(last[3] - 1.0f), 0.01f) << "the pendulum must have swung";
}

TEST_F(GltfTest, ThreeJsGltfLoaderReadsIt) {
  testing::Chromium chromium(dir_ / "profile", 320, 240);
  for (const char* script : {"three.min.js", "GLTFLoader.js"}) {
    chromium.Evaluate(ReadFile(std::string(VLAB_BINARY_DIR "/view_web/") + script) + "\n;0");
  }
  std::string hex;
  for (unsigned char c : glb_) {
    static const char* digits = "0123456789abcdef";
    hex += digits[c >> 4];
    hex += digits[c & 15];
  }
  const json r = json::parse(
      chromium
          .Evaluate("new Promise((ok, fail) => { const h = '" + hex +
                    "'; const b = new Uint8Array(h.length / 2);"
                    " for (let i = 0; i < b.length; ++i) b[i] = parseInt(h.substr(2 * i, 2), 16);"
                    " new THREE.GLTFLoader().parse(b.buffer, '', g => {"
                    "  const clip = g.animations[0], bob = g.scene.getObjectByName('bob');"
                    "  const mixer = new THREE.AnimationMixer(g.scene);"
                    "  mixer.clipAction(clip).play(); mixer.setTime(clip.duration - 1e-6);"
                    "  ok(JSON.stringify({clips: g.animations.length, duration: clip.duration,"
                    "   tracks: clip.tracks.length, p: bob.position.toArray(), q: bob.quaternion.toArray()}));"
                    " }, e => fail(String(e))); })")
          .get<std::string>());
  EXPECT_EQ(r["clips"], 1);
  EXPECT_NEAR(r["duration"].get<double>(), 1.0, 1e-6);
  EXPECT_EQ(r["tracks"], 2);
  // the pose at the clip's end: the last frame, to float precision (the mixer
  // interpolates 1e-6 s before the last key: |dx| < 1e-6 s x a few m/s)
  const std::vector<float> last = LastFrame();
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(r["p"][i].get<double>(), last[i], 1e-5);
  const int xyzw[4] = {4, 5, 6, 3};
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(r["q"][i].get<double>(), last[xyzw[i]], 1e-5);
}

TEST_F(GltfTest, RefusesToOverwriteAndNeedsARecording) {
  testing::ProcessResult r = RunVlab("export " + (dir_ / "run") + " " + (dir_ / "run.glb"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("exists"), std::string::npos) << r.err;
  EXPECT_EQ(ReadFile(dir_ / "run.glb"), glb_);
  r = RunVlab("export " + dir_.path() + " " + (dir_ / "other.glb"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("scene.json"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace vlab

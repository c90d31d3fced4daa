// Tests the textures, cameras and lights of `vlab export`
// (src/view/view_gltf.cc, view_gltf_texture.cc, view_gltf_lights.cc): three
// lettered cubes of mjcf/cubes (cube textures: a letter and an ArUco marker on
// each face) on a checkered floor (a 2-D texture, texrepeat 4 4), each cube
// turned another way so that five different faces face the camera, a camera
// "close" and two lights, recorded for 0.1 s and exported.
//   - Khronos' glTF-Validator (tests/node/validate_gltf.mjs) finds 0 errors
//     (and 0 warnings) in the .glb;
//   - the .glb has 19 PNG images (the floor's, six faces a cube), a repeating
//     and a clamping sampler, the camera (yfov 40 deg, the MJCF's pose) and
//     the lights (a spot with the MJCF's cutoff, a directional one);
//   - the letters and markers are where MuJoCo draws them: three.js r111's
//     GLTFLoader in headless Chromium renders the .glb through its camera
//     "close" at 400 x 300, OSMesa renders the MJCF's camera at the first
//     recorded instant (the cubes at rest at qpos0, the glb's animation at
//     t = 0); on the cubes' pixels (OSMesa's segmentation, 2 px in from their
//     outlines) the dark-print masks (grey under half the 90th percentile of
//     the cubes' grey, per image) have IoU >= kMinIoU (0.6). Measured 0.907
//     (13,941 dark pixels in OSMesa's render); the same render with the
//     textures taken off the materials, which the test also makes and
//     requires under the bound, gives 0.318 (the shaded faces): the test fails
//     when the textures are left out.
// It fails, never skips, without Chromium or node (tools/setup.sh installs
// both for tests).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <nlohmann/json.hpp>

#include "cdp_client.h"
#include "render/image_codec.h"
#include "render/renderer.h"
#include "test_util.h"

namespace vlab {
namespace {

using nlohmann::json;
using testing::ReadFile;
using testing::RunVlab;
using testing::TempDir;
using testing::WriteFile;

constexpr int kWidth = 400, kHeight = 300;
constexpr double kMinIoU = 0.6;  // measured 0.907 with the textures, 0.318 without

// `dir`: the scene file's folder (MuJoCo reads includes relative to it, even absolute ones)
std::string Scene(const std::string& dir) {
  const std::string cubes = std::filesystem::relative(VLAB_SOURCE_DIR "/mjcf/cubes", dir).string() + "/";
  return R"(<mujoco model="lettered cubes">
  <compiler texturedir=")" +
         cubes + R"("/>
  <include file=")" +
         cubes + R"(cubes_assets.xml"/>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.32 0.34 0.36" rgb2="0.6 0.62 0.64" width="64" height="64"/>
    <material name="floor" texture="grid" texrepeat="4 4"/>
  </asset>
  <worldbody>
    <light name="key" pos="0.3 -0.4 1.2" dir="-0.2 0.35 -1" diffuse="0.7 0.7 0.7" cutoff="40"/>
    <light name="sun" directional="true" pos="0 0 2" dir="0 0 -1" diffuse="0.3 0.3 0.3"/>
    <geom name="floor" type="plane" size="0.5 0.5 0.01" material="floor"/>
    <camera name="close" pos="0.18 -0.11 0.185" xyaxes="0.68 0.73 0 -0.45 0.42 0.79" fovy="40"/>
    <body name="cube_A" pos="0 0 0.025">
      <include file=")" +
         cubes + R"(cube_A.xml"/>
    </body>
    <body name="cube_B" pos="0.09 0.02 0.025" euler="90 0 30">
      <include file=")" +
         cubes + R"(cube_B.xml"/>
    </body>
    <body name="cube_C" pos="-0.02 0.1 0.025" euler="0 90 -20">
      <include file=")" +
         cubes + R"(cube_C.xml"/>
    </body>
  </worldbody>
</mujoco>
)";
}

std::string Hex(const std::string& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string hex;
  for (unsigned char c : bytes) {
    hex += digits[c >> 4];
    hex += digits[c & 15];
  }
  return hex;
}

using Mask = std::vector<char>;

double IoU(const Mask& a, const Mask& b) {
  long both = 0, either = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    both += a[i] && b[i];
    either += a[i] || b[i];
  }
  return either > 0 ? static_cast<double>(both) / static_cast<double>(either) : 0.0;
}

// dark print on the cubes: grey under half the 90th percentile of the cubes' grey
Mask DarkPrint(const std::vector<std::uint8_t>& grey, const Mask& cubes) {
  std::vector<std::uint8_t> values;
  for (std::size_t i = 0; i < grey.size(); ++i) {
    if (cubes[i]) values.push_back(grey[i]);
  }
  Mask dark(grey.size(), 0);
  if (values.empty()) return dark;
  std::nth_element(values.begin(), values.begin() + values.size() * 9 / 10, values.end());
  const double threshold = 0.5 * values[values.size() * 9 / 10];
  for (std::size_t i = 0; i < grey.size(); ++i) dark[i] = cubes[i] && grey[i] < threshold;
  return dark;
}

std::vector<std::uint8_t> Grey(const std::string& png) {
  render::Image image;
  render::DecodeImage(reinterpret_cast<const std::uint8_t*>(png.data()), png.size(), render::DecodeMode::kGray, &image);
  if (image.width != kWidth || image.height != kHeight) return {};
  return image.bytes;
}

class GltfTextureTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    WriteFile(*dir_ / "cubes.xml", Scene(dir_->path()));
    WriteFile(*dir_ / "rec.yaml",
              "name: rec\nscene: cubes.xml\nduration: 0.1\ncontrol_period: 0.002\noutputs: {poses: {rate: 50}}\n");
    const testing::ProcessResult run = RunVlab("run " + (*dir_ / "rec.yaml") + " --out " + (*dir_ / "run") + " -q");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const testing::ProcessResult exported = RunVlab("export " + (*dir_ / "run") + " " + (*dir_ / "run.glb"));
    ASSERT_EQ(exported.exit_code, 0) << exported.err;
    EXPECT_NE(exported.out.find("19 textures, 1 cameras, 2 lights"), std::string::npos) << exported.out;
    glb_ = new std::string(ReadFile(*dir_ / "run.glb"));
  }
  static void TearDownTestSuite() {
    delete glb_;
    delete dir_;
  }
  static json Json() {
    std::uint32_t length = 0;
    std::memcpy(&length, glb_->data() + 12, 4);
    return json::parse(glb_->substr(20, length));
  }
  static TempDir* dir_;
  static std::string* glb_;
};
TempDir* GltfTextureTest::dir_ = nullptr;
std::string* GltfTextureTest::glb_ = nullptr;

TEST_F(GltfTextureTest, KhronosValidatorFindsNoErrors) {
  const std::string out = *dir_ / "validator.txt";
  const std::string cmd = "cd '" VLAB_SOURCE_DIR "/tests/node' && timeout 60 node validate_gltf.mjs '" +
                          (*dir_ / "run.glb") + "' >'" + out + "' 2>&1";
  const int status = std::system(cmd.c_str());
  const std::string report = ReadFile(out);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << report;
  EXPECT_NE(report.find(": 0 errors, 0 warnings"), std::string::npos) << report;
  EXPECT_NE(report.find("19 images"), std::string::npos) << report;
}

TEST_F(GltfTextureTest, CarriesTexturesCamerasAndLights) {
  const json g = Json();
  ASSERT_EQ(g["images"].size(), 19u);
  for (const json& image : g["images"]) EXPECT_EQ(image["mimeType"], "image/png");
  EXPECT_EQ(g["images"][0]["name"], "grid");
  EXPECT_EQ(g["images"][1]["name"], "cube_A +x");
  ASSERT_EQ(g["samplers"].size(), 2u);
  EXPECT_EQ(g["samplers"][0]["wrapS"], 10497);  // the floor's: REPEAT
  EXPECT_EQ(g["samplers"][1]["wrapS"], 33071);  // the faces': CLAMP_TO_EDGE
  // a cube: one primitive per face, each with its face's texture
  const json& cube = g["meshes"][1];
  EXPECT_EQ(cube["name"], "cube_A");
  ASSERT_EQ(cube["primitives"].size(), 6u);
  for (int f = 0; f < 6; ++f) {
    const int material = cube["primitives"][f]["material"];
    const int texture = g["materials"][material]["pbrMetallicRoughness"]["baseColorTexture"]["index"];
    EXPECT_EQ(g["textures"][texture]["source"], 1 + f);
  }
  // the camera: yfov 40 deg, at the MJCF's pose in the world
  ASSERT_EQ(g["cameras"].size(), 1u);
  EXPECT_NEAR(g["cameras"][0]["perspective"]["yfov"].get<double>(), 40 * M_PI / 180, 1e-9);
  const json* camera = nullptr;
  for (const json& n : g["nodes"]) {
    if (n.contains("camera")) camera = &n;
  }
  ASSERT_NE(camera, nullptr);
  EXPECT_EQ((*camera)["name"], "close");
  EXPECT_NEAR((*camera)["translation"][0].get<double>(), 0.18, 1e-9);
  // the lights: the spot's cone is its cutoff; the sun shines down (-z unturned)
  const json& lights = g["extensions"]["KHR_lights_punctual"]["lights"];
  ASSERT_EQ(lights.size(), 2u);
  EXPECT_EQ(lights[0]["type"], "spot");
  EXPECT_NEAR(lights[0]["spot"]["outerConeAngle"].get<double>(), 40 * M_PI / 180, 1e-6);
  EXPECT_NEAR(lights[0]["intensity"].get<double>(), 0.7, 1e-6);
  EXPECT_EQ(lights[1]["type"], "directional");
  EXPECT_EQ(g["extensionsUsed"], json::array({"KHR_lights_punctual"}));
}

TEST_F(GltfTextureTest, LettersAreWhereOsmesaDrawsThem) {
  // OSMesa: the cubes' pixels (2 px in from their outlines) and the grey image, camera "close", qpos0
  char error[1000] = "";
  mjModel* m = mj_loadXML((*dir_ / "cubes.xml").c_str(), nullptr, error, sizeof(error));
  ASSERT_NE(m, nullptr) << error;
  mjData* d = mj_makeData(m);
  mj_forward(m, d);
  render::Renderer::Options options;
  options.width = kWidth;
  options.height = kHeight;
  options.log_renderer = false;
  Mask cubes(kWidth * kHeight, 0);
  std::vector<std::uint8_t> reference(kWidth * kHeight);
  {
    auto renderer = render::Renderer::Create(m, options);
    render::SegmentationImage seg;
    render::RgbImage rgb;
    renderer->RenderSegmentation(d, render::CameraId(m, "close"), &seg);
    renderer->Render(d, render::CameraId(m, "close"), &rgb);
    std::vector<std::int32_t> bodies;
    render::GeomsToBodies(m, seg, &bodies);
    for (int y = 2; y < kHeight - 2; ++y) {
      for (int x = 2; x < kWidth - 2; ++x) {
        bool inside = true;
        for (int dy = -2; dy <= 2; ++dy) {
          for (int dx = -2; dx <= 2; ++dx) inside = inside && bodies[(y + dy) * kWidth + x + dx] > 0;
        }
        cubes[y * kWidth + x] = inside;
      }
    }
    for (int i = 0; i < kWidth * kHeight; ++i) {
      const std::uint8_t* p = &rgb.pixels[3 * i];
      reference[i] = static_cast<std::uint8_t>(std::lround(0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]));
    }
  }
  mj_deleteData(d);
  mj_deleteModel(m);
  ASSERT_GT(std::count(cubes.begin(), cubes.end(), 1), 5000) << "the cubes must fill the picture";

  // Chromium: the .glb through its camera, MuJoCo's headlight (ambient 0.1, diffuse 0.4 along
  // the view) added as the viewer's light, once with the textures and once without
  testing::Chromium chromium(*dir_ / "profile", kWidth, kHeight);
  chromium.Call("Emulation.setDeviceMetricsOverride",
                {{"width", kWidth}, {"height", kHeight}, {"deviceScaleFactor", 1}, {"mobile", false}});
  // the page loads three.js and the .glb (as a script: a file:// page may not fetch) from files
  // (sent through DevTools, three.min.js alone took 4 s to evaluate)
  std::string page = "<!DOCTYPE html><html><body style=\"margin: 0\">";
  for (const char* script : {"three.min.js", "GLTFLoader.js"}) {
    page += std::string("<script src=\"file://" VLAB_BINARY_DIR "/view_web/") + script + "\"></script>";
  }
  WriteFile(*dir_ / "glb.js", "window.glbHex = '" + Hex(*glb_) + "';\n");
  page += "<script src=\"glb.js\"></script></body></html>";
  WriteFile(*dir_ / "page.html", page);
  chromium.Call("Page.navigate", {{"url", "file://" + (*dir_ / "page.html")}});
  chromium.Evaluate(
      "new Promise(r => { const ready = () => window.glbHex && window.THREE && THREE.GLTFLoader;"
      " if (ready()) r(0); else window.addEventListener('load', () => r(0)); })");
  const std::string loaded =
      chromium
          .Evaluate(
              "new Promise((ok, fail) => { const h = window.glbHex; const b = new Uint8Array(h.length / 2);"
              " for (let i = 0; i < b.length; ++i) b[i] = parseInt(h.substr(2 * i, 2), 16);"
              " new THREE.GLTFLoader().parse(b.buffer, '', g => {"
              "  document.body.style.margin = '0';"
              "  const r = window.r = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});"
              "  r.setPixelRatio(1); r.setSize(" +
              std::to_string(kWidth) + ", " + std::to_string(kHeight) +
              "); document.body.appendChild(r.domElement);"
              "  const scene = window.scene = g.scene, mixer = new THREE.AnimationMixer(scene);"
              "  mixer.clipAction(g.animations[0]).play(); mixer.setTime(0);"
              "  const cam = window.cam = g.cameras.find(c => c.name === 'close');"
              "  cam.aspect = " +
              std::to_string(kWidth) + " / " + std::to_string(kHeight) +
              "; cam.updateProjectionMatrix();"
              "  scene.add(new THREE.AmbientLight(0xffffff, 0.1));"
              "  const head = new THREE.DirectionalLight(0xffffff, 0.4); head.position.set(0, 0, 1);"
              "  cam.add(head); cam.add(head.target); head.target.position.set(0, 0, -1);"
              "  scene.updateMatrixWorld(true); const t = performance.now(); r.render(scene, cam); window.renderMs = "
              "performance.now() - t;"
              "  ok(String(g.cameras.length) + ' ' + String(scene.children.length)); }, e => fail(String(e))); })")
          .get<std::string>();
  ASSERT_FALSE(loaded.empty());
  const std::vector<std::uint8_t> textured = Grey(chromium.Screenshot());
  chromium.Evaluate(
      "scene.traverse(o => { if (o.material) { o.material.map = null; o.material.needsUpdate = true; } });"
      " r.render(scene, cam); 0");
  const std::vector<std::uint8_t> plain = Grey(chromium.Screenshot());
  ASSERT_EQ(textured.size(), reference.size());
  ASSERT_EQ(plain.size(), reference.size());

  const Mask want = DarkPrint(reference, cubes);
  const double iou = IoU(DarkPrint(textured, cubes), want), iou_plain = IoU(DarkPrint(plain, cubes), want);
  std::printf("dark print on the cubes: %ld px in OSMesa's render; IoU %.3f textured, %.3f without textures\n",
              static_cast<long>(std::count(want.begin(), want.end(), 1)), iou, iou_plain);
  EXPECT_GE(iou, kMinIoU);
  EXPECT_LT(iou_plain, kMinIoU) << "without its textures the export must fail this test";
  if (::testing::Test::HasFailure()) {
    if (const char* keep = std::getenv("VLAB_VIEW_FAILED")) {  // where to keep the images of a failure
      render::ImageView view{kWidth, kHeight, 1, 8, textured.data(), 0};
      std::vector<std::uint8_t> png;
      render::EncodePng(view, -1, &png);
      testing::WriteFile(std::string(keep) + "_gltf.png", std::string(png.begin(), png.end()));
      view.pixels = reference.data();
      render::EncodePng(view, -1, &png);
      testing::WriteFile(std::string(keep) + "_osmesa.png", std::string(png.begin(), png.end()));
    }
  }
}

}  // namespace
}  // namespace vlab

// vlab cubes --out DIR: writes the lettered cubes (face PNGs, MJCF fragments,
// README) into DIR, one letter per cube (--letters) or alphabet blocks with a
// letter per face (--faces); with --scene FILE, also the cube scene: the PA10 scene
// with --count cubes at poses drawn from --seed and a webcam above the table.
// The output is deterministic: the same options give the same bytes.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "bridge/bridge_markers.h"
#include "cli/cli_commands.h"
#include "core/core_errors.h"
#include "lab/scenario/lab_yaml.h"
#include "vision/vision_cubes.h"
#include "vision/vision_scene.h"

namespace vlab::cli {

namespace {

namespace fs = std::filesystem;

struct CubesArgs {
  std::string out_dir;
  std::string letters = "ABCDEF";
  std::string faces;
  double size_m = 0.05;
  std::string dictionary = "4X4_50";
  int first_id = 0;
  std::string scene;
  int count = 6;
  long long seed = 1;
  std::string pa10_dir = "mjcf/pa10";
  bool quiet = false;
};

// `to` as the scene file must name it: relative to the scene's folder, '/' separators
std::string RelativeTo(const fs::path& scene, const fs::path& to) {
  const fs::path from = fs::absolute(scene).parent_path().lexically_normal();
  return fs::absolute(to).lexically_normal().lexically_relative(from).generic_string();
}

int Cubes(const CubesArgs& a, const CLI::App& cmd) {
  vision::CubeSetConfig cubes;
  const bridge::MarkerDictionary* dictionary = bridge::FindMarkerDictionary(a.dictionary);
  if (dictionary == nullptr) {
    std::string known;
    for (const auto& d : bridge::MarkerDictionaries()) known += std::string(known.empty() ? "" : ", ") + d.name;
    throw vlab::InputError("cubes: --dictionary '" + a.dictionary + "' is not one of " + known);
  }
  cubes.letters = a.letters;
  if (cmd.count("--faces") > 0) {
    if (cmd.count("--letters") > 0) throw vlab::InputError("cubes: --letters and --faces exclude each other");
    std::size_t from = 0;
    while (from <= a.faces.size()) {
      const std::size_t comma = std::min(a.faces.find(',', from), a.faces.size());
      cubes.faces.push_back(a.faces.substr(from, comma - from));
      from = comma + 1;
    }
  }
  cubes.size_m = a.size_m;
  cubes.dictionary = dictionary->code;
  cubes.first_id = a.first_id;
  vision::CheckCubeSet(cubes);

  // everything is checked and generated before anything is written
  const bool with_scene = !a.scene.empty();
  if (!with_scene && (cmd.count("--count") > 0 || cmd.count("--seed") > 0)) {
    throw vlab::InputError("cubes: --count and --seed need --scene FILE");
  }
  std::string scene_xml;
  if (with_scene) {
    if (a.seed < 0) throw vlab::InputError("cubes: --seed must be >= 0");
    if (!fs::is_regular_file(fs::path(a.pa10_dir) / "pa10.xml")) {
      throw vlab::InputError("cubes: --pa10 '" + a.pa10_dir + "' has no pa10.xml (the PA10 model folder, mjcf/pa10)");
    }
    vision::CubeSceneConfig scene;
    scene.count = a.count;
    scene.seed = static_cast<std::uint64_t>(a.seed);
    const auto placements = vision::PlaceCubes(cubes, scene);
    scene_xml =
        vision::CubeSceneXml(cubes, scene, placements, RelativeTo(a.scene, a.out_dir), RelativeTo(a.scene, a.pa10_dir));
  }
  const std::vector<vision::GeneratedFile> files = vision::CubeSetFiles(cubes);

  vision::WriteGeneratedFiles(a.out_dir, files);
  if (!a.quiet) {
    std::printf("vlab cubes: %d cubes (%s), %s markers %d-%d of %s mm, %zu files in %s\n", vision::CubeCount(cubes),
                vision::CubeSetOption(cubes).c_str(), dictionary->name, vision::CubeMarkerId(cubes, 0, 0),
                vision::CubeMarkerId(cubes, vision::CubeCount(cubes) - 1, vision::kCubeFaces - 1),
                vision::MjcfNumber(vision::CubeMarkerSide(cubes) * 1000).c_str(), files.size(), a.out_dir.c_str());
  }
  if (with_scene) {
    const fs::path scene(a.scene);
    const std::string folder = scene.parent_path().empty() ? std::string(".") : scene.parent_path().string();
    vision::WriteGeneratedFiles(folder, {{scene.filename().string(), scene_xml}});
    if (!a.quiet) std::printf("vlab cubes: scene %s: %d cubes, seed %lld\n", a.scene.c_str(), a.count, a.seed);
  }
  return 0;
}

}  // namespace

Subcommand AddCubesCommand(CLI::App& app) {
  auto args = std::make_shared<CubesArgs>();
  CLI::App* cmd = app.add_subcommand(
      "cubes", "Write the lettered cubes (face PNGs with ArUco markers, MJCF) and optionally their scene");
  cmd->add_option("--out", args->out_dir, "Folder for the cube files (e.g. mjcf/cubes)")->required();
  cmd->add_option("--letters", args->letters, "One cube per letter, A-Z or 0-9, on all its faces (default ABCDEF)");
  cmd->add_option("--faces", args->faces,
                  "Alphabet blocks instead: one block per comma-separated entry, its six face letters in the order "
                  "right left up down front back (e.g. AGMSY4,BHNTZ5)");
  cmd->add_option("--size", args->size_m, "Cube edge, m (default 0.05)");
  cmd->add_option("--dictionary", args->dictionary, "ArUco dictionary, e.g. 4X4_50 (default), 5X5_100, APRILTAG_36h11");
  cmd->add_option("--first-id", args->first_id, "Marker id of the first cube's first face (default 0)");
  cmd->add_option("--scene", args->scene, "Also write the cube scene (MJCF) to this file, e.g. scenes/pa10_cubes.xml");
  cmd->add_option("--count", args->count, "Cubes in the scene: the first N letters or blocks (default 6)");
  cmd->add_option("--seed", args->seed, "Seed of the cubes' poses, an integer from 0 to 2^53 (default 1)")
      ->check(CLI::Validator(lab::CheckSeedText, ""));
  cmd->add_option("--pa10", args->pa10_dir, "The PA10 model folder the scene includes (default mjcf/pa10)");
  cmd->add_flag("-q,--quiet", args->quiet, "No summary lines");
  return {cmd, [args, cmd] { return WithErrorReport([&] { return Cubes(*args, *cmd); }); }};
}

}  // namespace vlab::cli

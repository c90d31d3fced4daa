// Ground-truth scoring of a spelled word (kind word, lab only): for each
// letter of the word, how far its cube is from its slot, how its letter reads
// against the slot's reading direction, how level its top face is, how fast
// it moves, and whether the face on top carries the letter at all; `spelled`
// when every letter is within the bounds. For checks and logs of the lettered
// cubes case study (what a vision pipeline should make true).
//
// Ports
//   input   none
//   output  [spelled, then per letter of the word, in order: pos_error,
//           yaw_error, tilt, speed, on_top]:
//           spelled    1 when every letter is within every bound and on top, else 0
//           pos_error  xy distance of the cube's centre to its slot's origin, m
//           yaw_error  angle between the reading direction ("up" of the
//                      letter) of the face now on top and the slot's y axis,
//                      both projected onto the world's xy plane, deg (0 .. 180)
//           tilt       angle between the top face's outward normal and the
//                      world z axis, deg (0 .. 54.7: the top face is the one
//                      whose normal points most upwards)
//           speed      the cube's centre's speed, m/s
//           on_top     1 when the face on top carries the letter, else 0
//   rate    sampled at the end of every control period from the free joints'
//           positions and velocities (the state after the last physics step)
//   log     NAME.spelled; NAME.<L>.pos_error, .yaw_error, .tilt, .speed, .on_top
// Faces and letters come from the cube generator's definition
// (vision/vision_cube_faces.h): face f's letter reads along CubeFaceUp(f); a
// body whose model has the custom text "<body>.faces" (an alphabet block,
// `vlab cubes --faces`) carries those six letters on faces 0-5, any other
// body carries its letter on all six faces (`vlab cubes --letters`).
#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"
#include "core/core_errors.h"
#include "lab/devices/device_word.h"
#include "lab/scenario/lab_yaml.h"
#include "vision/vision_cube_faces.h"

namespace vlab::lab {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr int kValuesPerLetter = 5;
constexpr const char* kLetterValues[kValuesPerLetter] = {"pos_error", "yaw_error", "tilt", "speed", "on_top"};

bool IsLetter(char c) { return (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9'); }

// one letter: its cube's free joint, its slot, the letters on its faces
struct Letter {
  char letter = 'A';
  int qpos = 0, dof = 0;  // addresses of the free joint
  int slot = -1;          // site id
  char faces[vision::kCubeFaces] = {};
  // last sample
  double pos_error = 0, yaw_error = 0, tilt = 0, speed = 0;
  bool on_top = false;
};

class SimWord final : public Device {
 public:
  SimWord(const mjModel* m, const DeviceConfig& c) : Device(c), config_(c.ParamsAs<WordParams>()) {
    if (config_.word.empty() || config_.slots.size() != config_.word.size() ||
        config_.bodies.size() != config_.word.size()) {
      throw InputError(who() + ": word '" + config_.word + "' needs one slot and one body per letter (" +
                       std::to_string(config_.slots.size()) + " slots, " + std::to_string(config_.bodies.size()) +
                       " bodies)");
    }
    for (std::size_t i = 0; i < config_.word.size(); ++i) letters_.push_back(Bind(m, i));
  }

  void Reset(const mjData& d) override { Sample(d, d.time); }

  void Sample(const mjData& d, double) override {
    spelled_ = true;
    for (Letter& l : letters_) {
      Score(d, &l);
      const WordBounds& b = config_.bounds;
      spelled_ = spelled_ && l.on_top && l.pos_error <= b.position_m && l.yaw_error <= b.angle_deg &&
                 l.tilt <= b.tilt_deg && l.speed <= b.speed_m_s;
    }
  }

  void State(std::vector<double>* p) const override {
    p->resize(static_cast<std::size_t>(ColumnCount()));
    Values(p->data());
  }
  std::vector<std::string> Columns() const override {
    std::vector<std::string> out = {name() + ".spelled"};
    for (const std::string& v : ValueNames()) out.push_back(name() + "." + v);
    return out;
  }
  int ColumnCount() const override { return 1 + kValuesPerLetter * static_cast<int>(letters_.size()); }
  void Row(const mjData&, double* out) const override { Values(out); }

  std::string DescribeFacts() const override {
    nlohmann::json j;
    j["layout"] = bridge::LayoutJson(kind(), ValueNames());
    j["units"] = {{"spelled", "1 or 0"}, {"pos_error", "m"}, {"yaw_error", "deg"},
                  {"tilt", "deg"},       {"speed", "m/s"},   {"on_top", "1 or 0"}};
    j["word"] = config_.word;
    j["slots"] = config_.slots;
    j["bodies"] = config_.bodies;
    j["bounds"] = {{"position", config_.bounds.position_m},
                   {"angle_deg", config_.bounds.angle_deg},
                   {"tilt_deg", config_.bounds.tilt_deg},
                   {"speed", config_.bounds.speed_m_s}};
    j["frame"] = "world";
    j["ground_truth"] = true;
    return j.dump();
  }

 private:
  // letter i: its body's free joint, its slot site, its face letters
  Letter Bind(const mjModel* m, std::size_t i) {
    Letter l;
    l.letter = config_.word[i];
    const std::string& body_name = config_.bodies[i];
    const std::string what = "letter '" + std::string(1, l.letter) + "': ";
    const int body = mj_name2id(m, mjOBJ_BODY, body_name.c_str());
    if (body < 0) throw InputError(who() + ": " + what + "the scene has no body '" + body_name + "'");
    const int joint = m->body_jntnum[body] == 1 ? m->body_jntadr[body] : -1;
    if (joint < 0 || m->jnt_type[joint] != mjJNT_FREE) {
      throw InputError(who() + ": " + what + "body '" + body_name + "' needs one free joint and nothing else");
    }
    l.qpos = m->jnt_qposadr[joint];
    l.dof = m->jnt_dofadr[joint];
    l.slot = mj_name2id(m, mjOBJ_SITE, config_.slots[i].c_str());
    if (l.slot < 0) throw InputError(who() + ": " + what + "the scene has no site '" + config_.slots[i] + "' (slot)");
    // the face letters: an alphabet block's text, else the letter on every face
    std::fill(std::begin(l.faces), std::end(l.faces), l.letter);
    const std::string text_name = vision::CubeFacesTextName(body_name);
    const int text = mj_name2id(m, mjOBJ_TEXT, text_name.c_str());
    if (text >= 0) {
      const std::string faces(m->text_data + m->text_adr[text]);
      if (faces.size() != vision::kCubeFaces || !std::all_of(faces.begin(), faces.end(), IsLetter)) {
        throw InputError(who() + ": " + what + "text '" + text_name + "' is '" + faces +
                         "', not six letters A-Z or 0-9 (faces 0-5)");
      }
      if (faces.find(l.letter) == std::string::npos) {
        throw InputError(who() + ": " + what + "block '" + body_name + "' has no face with it (its faces: " + faces +
                         ")");
      }
      std::copy(faces.begin(), faces.end(), l.faces);
    }
    return l;
  }

  // the letter's scores from its cube's pose and velocity
  void Score(const mjData& d, Letter* l) const {
    const mjtNum* q = d.qpos + l->qpos;
    const Eigen::Matrix3d R_WC = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized().toRotationMatrix();
    const mjtNum* slot = d.site_xpos + 3 * l->slot;
    l->pos_error = std::hypot(q[0] - slot[0], q[1] - slot[1]);
    const mjtNum* v = d.qvel + l->dof;  // a free joint's linear velocity: world frame
    l->speed = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    // the face on top: the outward normal with the largest z
    int top = 0;
    for (int f = 1; f < vision::kCubeFaces; ++f) {
      if ((R_WC * vision::CubeFaceNormal(f)).z() > (R_WC * vision::CubeFaceNormal(top)).z()) top = f;
    }
    const double nz = std::clamp((R_WC * vision::CubeFaceNormal(top)).z(), -1.0, 1.0);
    l->tilt = std::acos(nz) * kRadToDeg;
    // reading directions in the xy plane: the letter's up and the slot's y axis
    const Eigen::Vector3d up = R_WC * vision::CubeFaceUp(top);
    const mjtNum* x = d.site_xmat + 9 * l->slot;  // row major: column 1 is the site's y axis
    const double sx = x[1], sy = x[4];
    l->yaw_error = std::abs(std::atan2(sx * up.y() - sy * up.x(), sx * up.x() + sy * up.y())) * kRadToDeg;
    l->on_top = l->faces[top] == l->letter;
  }

  void Values(double* out) const {
    *out++ = spelled_ ? 1.0 : 0.0;
    for (const Letter& l : letters_) {
      for (double v : {l.pos_error, l.yaw_error, l.tilt, l.speed, l.on_top ? 1.0 : 0.0}) *out++ = v;
    }
  }
  std::vector<std::string> ValueNames() const {
    std::vector<std::string> out;
    for (const Letter& l : letters_) {
      for (const char* v : kLetterValues) out.push_back(std::string(1, l.letter) + "." + v);
    }
    return out;
  }

  WordParams config_;
  std::vector<Letter> letters_;
  bool spelled_ = false;
};

}  // namespace

std::shared_ptr<const DeviceParams> ReadWordParams(MapReader& r) {
  auto p = std::make_shared<WordParams>();
  p->word = r.String("word");
  if (p->word.empty()) r.Fail("word", "is empty");
  for (std::size_t i = 0; i < p->word.size(); ++i) {
    const char c = p->word[i];
    if (!IsLetter(c)) r.Fail("word", std::string("'") + c + "' is not A-Z or 0-9");
    if (p->word.find(c) != i) {
      r.Fail("word", std::string("'") + c + "' appears twice (each letter names its log columns)");
    }
  }
  p->slots = r.Strings("slots", {});
  if (p->slots.size() != p->word.size()) {
    r.Fail("slots", "needs one site per letter of '" + p->word + "' (" + std::to_string(p->word.size()) + "), got " +
                        std::to_string(p->slots.size()));
  }
  MapReader letters = r.Map("letters");
  for (char c : p->word) p->bodies.push_back(letters.String(std::string(1, c), std::string("cube_") + c));
  letters.Finish();  // a letter that is not in the word
  MapReader bounds = r.Map("bounds");
  WordBounds& b = p->bounds;
  b.position_m = bounds.Number("position", b.position_m);
  b.angle_deg = bounds.Number("angle_deg", b.angle_deg);
  b.tilt_deg = bounds.Number("tilt_deg", b.tilt_deg);
  b.speed_m_s = bounds.Number("speed", b.speed_m_s);
  if (!(b.position_m > 0)) bounds.Fail("position", "must be > 0 m");
  if (!(b.angle_deg > 0 && b.angle_deg <= 180)) bounds.Fail("angle_deg", "must be > 0 and <= 180 deg");
  if (!(b.tilt_deg > 0 && b.tilt_deg <= 90)) bounds.Fail("tilt_deg", "must be > 0 and <= 90 deg");
  if (!(b.speed_m_s > 0)) bounds.Fail("speed", "must be > 0 m/s");
  bounds.Finish();
  return p;
}

std::unique_ptr<Device> MakeWord(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimWord>(context.model, config);
}

}  // namespace vlab::lab

#include "scene/scene_pose_frame.h"

#include <cstring>

namespace vlab::scene {

namespace {

void Put(std::string* out, std::size_t at, const void* value, std::size_t n) { std::memcpy(&(*out)[at], value, n); }

}  // namespace

void EncodePoseFrame(double time, double seq, const double* poses, int values, std::string* out) {
  static_assert(sizeof(float) == 4 && sizeof(double) == 8, "IEEE-754 sizes");
  out->resize(16 + 4 * static_cast<std::size_t>(values));
  Put(out, 0, &time, 8);
  Put(out, 8, &seq, 8);
  for (int i = 0; i < values; ++i) {
    const float v = static_cast<float>(poses[i]);
    Put(out, 16 + 4 * static_cast<std::size_t>(i), &v, 4);
  }
}

}  // namespace vlab::scene

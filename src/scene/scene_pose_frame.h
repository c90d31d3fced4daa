// One pose frame's bytes: what a scene stream's frame is on `vlab view`'s
// WebSocket and in a run's poses.bin, 16 + 28 n bytes, little-endian:
// float64 time (s), float64 period k, then float32 x, y, z, qw, qx, qy, qz of
// each of the n bodies (world frame, SceneBodies' order).
#pragma once

#include <string>

namespace vlab::scene {

/// The bytes of one pose frame (see above) from `values` doubles of `poses`
/// (7 per body) into `out` (resized; no allocation once it has the capacity).
/// Little-endian hosts only.
void EncodePoseFrame(double time, double seq, const double* poses, int values, std::string* out);

}  // namespace vlab::scene

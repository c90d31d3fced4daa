// A ground-truth scoring device (kind word, lab only): do the lettered cubes
// spell a word in a row of slots (device_word.cc).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "lab/devices/device.h"

namespace vlab::lab {

/// Tolerances of a placed letter: all must hold for the letter to count.
struct WordBounds {
  double position_m = 0.010;  ///< xy distance of the cube's centre to its slot
  double angle_deg = 15;      ///< the letter's reading direction against the slot's
  double tilt_deg = 5;        ///< the top face's normal against the world z axis
  double speed_m_s = 0.005;   ///< the cube's centre, at rest
};

/// The word, its slots and the bodies that carry its letters (kind word).
struct WordParams : DeviceParams {
  std::string word;                 ///< letters A-Z, 0-9, each once (they name the log columns)
  std::vector<std::string> slots;   ///< one MJCF site per letter: origin = where it goes, y = its reading up
  std::vector<std::string> bodies;  ///< one body per letter, in word order (default cube_<L>)
  WordBounds bounds;
};

/// Reads the entry's own keys (word, slots, letters, bounds).
std::shared_ptr<const DeviceParams> ReadWordParams(MapReader& r);
/// Makes the device; throws InputError naming the device and the MJCF element
/// it cannot bind, or a block that has no face with its letter.
std::unique_ptr<Device> MakeWord(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab

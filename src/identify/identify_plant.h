// Planted "real" robots for trying identification without one: a model's parameters changed
// by known amounts, and a log's columns with seeded sensor noise. `vlab bench identify` and
// the identification tests make their planted logs with these.
#pragma once

#include <string>

#include <mujoco/mujoco.h>

namespace vlab::identify {

/// Scales body `body`'s mass and its principal inertia with it (the centre of mass and the
/// inertia's axes stay: a physically consistent body). Throws InputError naming a body the
/// model lacks.
void ScaleBodyMass(mjModel* m, const std::string& body, double factor);

/// Copies the CSV log `in` to `out` with seeded Gaussian noise of standard deviation `sigma`
/// added to every column whose name contains `columns` (e.g. ".q." for the joint angles); the
/// values written in the shortest form that reads back to the same double. Throws InputError
/// naming a file that cannot be read, std::runtime_error one that cannot be written.
void WriteNoisyLog(const std::string& in, const std::string& out, const std::string& columns, double sigma,
                   unsigned seed);

}  // namespace vlab::identify

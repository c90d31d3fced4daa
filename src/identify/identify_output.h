// What vlab identify writes into its output folder (docs/identify.md, "Output"):
//   estimates.json  every parameter: nominal, value, sd, bounds, flags; the correlations
//   overrides.txt   --set lines for vlab run (--overrides FILE): the scene patched with the fit
//   model.xml       the scene as one MJCF file with the fitted model parameters
//   fit.csv         every fitted column, measured, nominal and fitted model, per window row
//   fit_COLUMN.png  the errors of the nominal and fitted model against the measured column
//   report.md       the page that shows them
// The folder is staged and put in place whole (lab_output.h): it never replaces a folder vlab
// did not write.
#pragma once

#include <functional>
#include <string>

#include <mujoco/mujoco.h>

#include "identify/identify_fit.h"
#include "identify/identify_problem.h"

namespace vlab::identify {

/// Loads the MJCF file `scene`, lets `edit` change its compiled model, and writes the model
/// as one MJCF file `out` (MuJoCo's mj_saveLastXML: includes expanded, the model's current
/// numbers written back). Throws InputError when the scene does not load or the file cannot
/// be written. Not thread-safe: MuJoCo keeps the last loaded MJCF in a process-global.
void WriteEditedScene(const std::string& scene, const std::function<void(mjModel*)>& edit, const std::string& out);

/// Sets the model parameters among `values` (one per problem parameter) in `m`: the same
/// fields Problem::Apply sets; sensor transforms are not model fields and are skipped.
void SetModelParameters(const Problem& problem, const std::vector<double>& values, mjModel* m);

/// Writes the output folder `out_dir` (threads: the rollouts of the plots). Returns the
/// folder the files are in; `note` gets lab::OutputDir's note ("" when at out_dir).
std::string WriteOutputs(const Problem& problem, const FitResult& fit, const std::string& out_dir, int threads,
                         std::string* note);

}  // namespace vlab::identify

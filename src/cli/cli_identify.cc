// vlab identify SPEC.yaml: model parameters fitted to recorded logs (src/identify/,
// docs/identify.md). Prints one line per parameter (nominal, fitted, sd, identifiable) and
// writes the output folder (identify_output.h). Exit: 0 fitted and written; 1 a rollout
// diverged, the fit failed or a write failed; 2 bad input (the spec, its scenario, a log).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "cli/cli_commands.h"
#include "core/core_errors.h"
#include "core/core_realtime.h"
#include "identify/identify_fit.h"
#include "identify/identify_output.h"
#include "identify/identify_problem.h"
#include "identify/identify_spec.h"

namespace vlab::cli {

namespace {

struct IdentifyArgs {
  std::string spec;
  std::string out_dir;  // "": out/identify_<spec stem>
  int threads = 0;      // 0: the CPUs this process may run on
  bool quiet = false;
};

int Identify(const IdentifyArgs& a) {
  const identify::Spec spec = identify::LoadSpec(a.spec);
  identify::FitOptions options;
  options.threads = a.threads > 0 ? a.threads : std::max(1, static_cast<int>(ThreadCpus().size()));
  const std::unique_ptr<identify::Problem> problem = identify::Problem::Create(spec, options.threads);
  if (!a.quiet) {
    std::fprintf(stderr, "identify: %d windows (%d left out for contact), %d residuals, %zu parameters, %d threads\n",
                 problem->window_count(), problem->windows_in_contact(), problem->residual_count(),
                 problem->parameters().size(), options.threads);
    options.message = [](const std::string& line) { std::fprintf(stderr, "identify: %s\n", line.c_str()); };
    options.progress = [](int iteration, double cost) {
      std::fprintf(stderr, "identify: iteration %d cost %.6g\n", iteration, cost);
    };
  }
  const identify::FitResult fit = identify::Fit(*problem, options);
  for (const identify::Estimate& e : fit.estimates) {
    char sd[32] = "-";
    if (std::isfinite(e.sd)) std::snprintf(sd, sizeof sd, "%.3g", e.sd);
    std::printf("%-16s nominal %-12.6g start %-12.6g fitted %-12.6g sd %-10s %s%s%s\n", e.name.c_str(), e.nominal,
                fit.start_values[static_cast<std::size_t>(&e - fit.estimates.data())], e.value, sd,
                e.identifiable ? "identifiable" : "NOT identifiable", e.note.empty() ? "" : ": ", e.note.c_str());
  }
  std::printf("first estimate %s%s%s\n", fit.first_estimate.c_str(), fit.first_estimate_note.empty() ? "" : ": ",
              fit.first_estimate_note.c_str());
  std::printf("cost %.6g -> %.6g, residual sd %.4g, %d iterations, %d rollouts, %.1f s: %s\n", fit.cost_nominal,
              fit.cost_fitted, fit.residual_sd, fit.iterations, fit.rollouts, fit.wall_s, fit.termination.c_str());
  const std::string out_dir =
      a.out_dir.empty() ? "out/identify_" + std::filesystem::path(a.spec).stem().string() : a.out_dir;
  std::string note;
  const std::string where = identify::WriteOutputs(*problem, fit, out_dir, options.threads, &note);
  std::printf("output in %s/\n", where.c_str());
  if (!note.empty()) std::fprintf(stderr, "note: %s\n", note.c_str());
  return 0;
}

}  // namespace

Subcommand AddIdentifyCommand(CLI::App& app) {
  auto args = std::make_shared<IdentifyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "identify",
      "Fit model parameters (body masses with their inertia, centres of mass, principal inertias, a payload's mass "
      "and centre of mass, joint damping, armature and friction loss, a column's bias and gain, a q or qd column's "
      "delay, an arm's servo bandwidth and damping ratio) to recorded logs (the arms' q, qd and tau, a wrench "
      "device's filtered wrench, a counter's speed, norms of them): the recorded joint torques, or the arms' "
      "recorded commands through their servos, replayed over short windows from the recorded state (multiple "
      "shooting; a spinning body the log does not hold started from a counter's speed), box-constrained nonlinear "
      "least squares (Ceres) from a linear inverse-dynamics estimate of the masses, damping, armature and friction "
      "loss where it applies. Prints each estimate with its standard deviation and whether the data can tell it; "
      "writes "
      "estimates.json, overrides.txt (for vlab "
      "run --overrides), model.xml (the scene patched), fit.csv, plots and report.md (docs/identify.md). Exit: 0 "
      "fitted; 1 a rollout diverged or a write failed; 2 bad input");
  cmd->add_option("SPEC", args->spec, "Identification spec (YAML: scenario, logs, columns, parameters)")->required();
  cmd->add_option("--out", args->out_dir, "Output folder (default out/identify_<SPEC name>)");
  cmd->add_option("--threads", args->threads, "Rollout threads, 1 to 256 (default: the CPUs vlab may use)")
      ->check(CLI::Range(1, 256));
  cmd->add_flag("-q,--quiet", args->quiet, "No progress lines on stderr");
  return {cmd, [args] { return WithErrorReport([&] { return Identify(*args); }); }};
}

}  // namespace vlab::cli

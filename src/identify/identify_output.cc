#include "identify/identify_output.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include <nlohmann/json.hpp>

#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "core/core_output_file.h"
#include "lab/outputs/lab_output.h"
#include "lab/outputs/lab_plot.h"

namespace vlab::identify {

namespace fs = std::filesystem;

namespace {

std::string Num(double x) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), x);
  return std::string(buffer, result.ptr);
}

// a finite number, or null (an sd the data do not determine)
nlohmann::json JsonNumber(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }

bool IsModelParameter(TargetKind kind) {
  return kind != TargetKind::kColumnBias && kind != TargetKind::kColumnGain && kind != TargetKind::kColumnDelay;
}

bool IsServoParameter(TargetKind kind) {
  return kind == TargetKind::kServoBandwidth || kind == TargetKind::kServoDampingRatio;
}

// a parameter's linear estimate (clamped within its bounds), null where it made none
nlohmann::json LinearValue(const FitResult& fit, std::size_t i) {
  const bool made = fit.linear.applies && fit.linear.status[i] == LinearStatus::kEstimated;
  return made ? nlohmann::json(fit.linear.values[i]) : nlohmann::json(nullptr);
}

nlohmann::json EstimatesJson(const Problem& problem, const FitResult& fit) {
  nlohmann::json j;
  j["spec"] = problem.spec().file;
  j["scenario"] = problem.spec().scenario;
  j["scene"] = problem.scene();
  j["logs"] = problem.spec().logs;
  j["columns"] = problem.columns();
  j["window_s"] = problem.spec().window_s;
  j["windows"] = fit.windows;
  j["rows_left_out"] = problem.rows_left_out();
  j["windows_in_contact"] = problem.windows_in_contact();
  j["wrench_settle_rows"] = problem.wrench_settle_rows();
  j["residuals_left_out"] = problem.residuals_left_out();
  j["window_nuisances"] = problem.window_nuisances();
  j["residuals"] = fit.residuals;
  j["cost_nominal"] = fit.cost_nominal;
  j["first_estimate"] = fit.first_estimate;
  if (!fit.first_estimate_note.empty()) j["first_estimate_note"] = fit.first_estimate_note;
  j["cost_start"] = fit.cost_start;
  if (fit.linear.applies) {
    j["linear"] = {{"samples", fit.linear.samples},
                   {"torque_rows", fit.linear.torque_rows},
                   {"left_out_contact", fit.linear.left_out_contact},
                   {"left_out_clipped", fit.linear.left_out_clipped},
                   {"left_out_slow", fit.linear.left_out_slow},
                   {"rank", fit.linear.rank},
                   {"residual_rms", fit.linear.residual_rms}};
  }
  j["cost_fitted"] = fit.cost_fitted;
  j["residual_sd"] = fit.residual_sd;
  j["iterations"] = fit.iterations;
  j["rollouts"] = fit.rollouts;
  j["termination"] = fit.termination;
  j["thresholds"] = {{"unexcited_column", kUnexcitedColumn}, {"poor_sd", kPoorSd}, {"correlated", kCorrelated}};
  nlohmann::json params = nlohmann::json::array();
  std::vector<std::string> names;
  for (std::size_t i = 0; i < fit.estimates.size(); ++i) {
    const Estimate& e = fit.estimates[i];
    const BoundParameter& p = problem.parameters()[i];
    names.push_back(e.name);
    params.push_back({{"name", e.name},
                      {"target", TargetText(p.spec.kind, p.spec.element, p.spec.axis)},
                      {"nominal", e.nominal},
                      {"linear", LinearValue(fit, i)},
                      {"value", e.value},
                      {"sd", JsonNumber(e.sd)},
                      {"sd_iid", JsonNumber(e.sd_iid)},
                      {"lower", p.spec.lower},
                      {"upper", p.spec.upper},
                      {"frozen", e.frozen},
                      {"excited", e.excited},
                      {"identifiable", e.identifiable},
                      {"note", e.note}});
  }
  j["parameters"] = params;
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index a = 0; a < fit.correlation.rows(); ++a) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index b = 0; b < fit.correlation.cols(); ++b) row.push_back(fit.correlation(a, b));
    rows.push_back(row);
  }
  j["correlation"] = {{"names", names}, {"matrix", rows}};
  return j;
}

// fit.csv: time, log, then per column measured, nominal, fitted and the two errors
std::vector<std::string> WriteFitCsv(const Problem& problem, const FitResult& fit, int threads,
                                     const std::string& path) {
  std::vector<double> nominal, fitted;
  if (!Predict(problem, fit.nominal_values, threads, &nominal) ||
      !Predict(problem, fit.fitted_values, threads, &fitted)) {
    throw std::runtime_error("identify: a rollout diverged while writing fit.csv");
  }
  const std::vector<std::string>& columns = problem.columns();
  std::string text = "time,log";
  std::vector<std::string> header;
  for (const std::string& c : columns) {
    for (const char* what : {"measured", "nominal", "fitted", "error_nominal", "error_fitted"}) {
      text += "," + c + "." + what;
    }
  }
  text += "\n";
  const int n = static_cast<int>(columns.size());
  for (int w = 0; w < problem.window_count(); ++w) {
    const int rows = problem.window_residuals(w) / n;
    for (int k = 1; k <= rows; ++k) {
      const Problem::Sample s = problem.WindowRow(w, k);
      text += Num(s.time_s) + "," + std::to_string(s.log);
      for (int c = 0; c < n; ++c) {
        const int i = problem.window_offset(w) + (k - 1) * n + c;
        const double measured = problem.Measured(w, k, c);
        text += "," + Num(measured) + "," + Num(nominal[i]) + "," + Num(fitted[i]) + "," + Num(nominal[i] - measured) +
                "," + Num(fitted[i] - measured);
      }
      text += "\n";
    }
  }
  WriteOutputFile(path, text);
  return columns;
}

std::string ReportMarkdown(const Problem& problem, const FitResult& fit, const std::vector<std::string>& plots) {
  std::string md = "# Identification: " + problem.spec().file + "\n\n";
  md += "Scenario `" + problem.spec().scenario + "`, scene `" + problem.scene() + "`; " +
        std::to_string(problem.spec().logs.size()) + " log(s), " + std::to_string(fit.windows) + " windows of " +
        SixDigits(problem.spec().window_s) + " s (" + std::to_string(problem.windows_in_contact()) +
        " more left out: their nominal replay made contact), " + std::to_string(fit.residuals) + " residuals" +
        (problem.residuals_left_out() > 0
             ? " (" + std::to_string(problem.residuals_left_out()) + " of them held at 0: a wrench column's first " +
                   std::to_string(problem.wrench_settle_rows()) +
                   " rows of each window, its filter settling; a counter's rows before the first gate the window "
                   "saw whole; rows outside a column's spans)"
             : std::string()) +
        ".\n\n";
  md += "Cost (half the sum of squared weighted residuals): nominal " + SixDigits(fit.cost_nominal) + ", fitted " +
        SixDigits(fit.cost_fitted) + "; residual sd " + SixDigits(fit.residual_sd) +
        " (weighted units; 1 when the weights are 1/σ of the noise). " + std::to_string(fit.iterations) +
        " iterations, " + std::to_string(fit.rollouts) + " window rollouts: " + fit.termination + "\n\n";
  md += "The fit started from the " + fit.first_estimate + " values" +
        (fit.first_estimate_note.empty() ? "" : " (" + fit.first_estimate_note + ")") + ", cost " +
        SixDigits(fit.cost_start) + ".";
  if (fit.linear.applies) {
    md += " The linear estimate (inverse-dynamics regression of the logged joint torques): " +
          std::to_string(fit.linear.rank) + " parameters from " + std::to_string(fit.linear.torque_rows) +
          " joint torques of " + std::to_string(fit.linear.samples) + " log rows; left out " +
          std::to_string(fit.linear.left_out_contact) + " rows near contact, " +
          std::to_string(fit.linear.left_out_clipped) + " clipped and " + std::to_string(fit.linear.left_out_slow) +
          " slow joint torques (friction). A parameter it does not estimate (\"—\") started at its nominal value.";
  }
  md +=
      "\n\n| parameter | target | nominal | linear | fitted | sd | identifiable | note |\n"
      "|---|---|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < fit.estimates.size(); ++i) {
    const Estimate& e = fit.estimates[i];
    const BoundParameter& p = problem.parameters()[i];
    const nlohmann::json linear = LinearValue(fit, i);
    md += "| " + e.name + " | " + TargetText(p.spec.kind, p.spec.element, p.spec.axis) + " | " + SixDigits(e.nominal) +
          " | " + (linear.is_null() ? "—" : SixDigits(linear.get<double>())) + " | " + SixDigits(e.value) + " | " +
          (std::isfinite(e.sd) ? SixDigits(e.sd) : "—") + " | " + (e.identifiable ? "yes" : "no") + " | " + e.note +
          " |\n";
  }
  md += "\nCorrelations above " + SixDigits(kCorrelated) + " in magnitude flag parameters the data cannot tell apart:";
  bool any = false;
  for (Eigen::Index a = 0; a < fit.correlation.rows(); ++a) {
    for (Eigen::Index b = a + 1; b < fit.correlation.cols(); ++b) {
      if (std::abs(fit.correlation(a, b)) > kCorrelated) {
        md += std::string(any ? "," : "") + " " + fit.estimates[a].name + "/" + fit.estimates[b].name + " " +
              SixDigits(fit.correlation(a, b));
        any = true;
      }
    }
  }
  md += any ? ".\n" : " none.\n";
  md += "\n## Fitted columns\n\nErrors of the nominal and the fitted model against the measured column (fit.csv):\n\n";
  for (const std::string& plot : plots) md += "![" + plot + "](" + plot + ")\n";
  return md;
}

// the payload as the arm's scenario declares it: in the frame of the body of the nearest joint
// above its body (the flange frame, when that joint is the arm's last), through the fixed
// bodies between; "" when a body between them has a joint of its own (none: no joint above)
std::string PayloadAtJoint(const mjModel* m, int body, double mass, const double com[3]) {
  int frame = body;
  while (frame > 0 && m->body_jntnum[frame] == 0) frame = m->body_parentid[frame];
  if (frame <= 0) return "";
  DataPtr d = MakeData(m);
  mj_kinematics(m, d.get());
  // com in the world, then in the frame body's axes about its origin
  double world[3], rel[3], local[3];
  mju_rotVecMat(world, com, d->xmat + 9 * body);
  mju_addTo3(world, d->xpos + 3 * body);
  mju_sub3(rel, world, d->xpos + 3 * frame);
  mju_rotVecMatT(local, rel, d->xmat + 9 * frame);
  const char* joint = mj_id2name(m, mjOBJ_JOINT, m->body_jntadr[frame]);
  const char* name = mj_id2name(m, mjOBJ_BODY, frame);
  return "#   declared to the arm whose last joint is " + std::string(joint ? joint : "?") +
         " (the flange frame, body " + (name ? name : "?") + "), its scenario's payload: {mass: " + Num(mass) +
         ", com: [" + Num(local[0]) + ", " + Num(local[1]) + ", " + Num(local[2]) + "]}\n";
}

}  // namespace

void WriteEditedScene(const std::string& scene, const std::function<void(mjModel*)>& edit, const std::string& out) {
  ModelPtr model = LoadModel(scene);
  edit(model.get());
  DataPtr data = MakeData(model.get());
  mj_setConst(model.get(), data.get());
  char error[1024] = "";
  if (!mj_saveLastXML(out.c_str(), model.get(), error, sizeof(error))) {
    throw InputError("scene '" + scene + "': cannot write it as '" + out + "': " + error);
  }
}

void SetModelParameters(const Problem& problem, const std::vector<double>& values, mjModel* m) {
  problem.SetModel(values, m);
}

std::string WriteOutputs(const Problem& problem, const FitResult& fit, const std::string& out_dir, int threads,
                         std::string* note) {
  std::unique_ptr<lab::OutputDir> out = lab::OutputDir::Create(out_dir);
  const std::string dir = out->staging_dir();
  WriteOutputFile(out->File("estimates.json"), EstimatesJson(problem, fit).dump(2) + "\n");
  WriteEditedScene(
      problem.scene(), [&](mjModel* m) { SetModelParameters(problem, fit.fitted_values, m); }, out->File("model.xml"));
  // --set lines: the patched scene (the absolute path of the folder's place) and the arms' servo
  // keys; sensor transforms as comments
  auto overrides = [&](const std::string& folder) {
    std::string text = "# vlab identify " + problem.spec().file + ": the fitted model for vlab run --overrides FILE\n";
    text += "scene=" + fs::absolute(fs::path(folder) / "model.xml").lexically_normal().string() + "\n";
    for (std::size_t i = 0; i < fit.estimates.size(); ++i) {
      const BoundParameter& p = problem.parameters()[i];
      if (IsServoParameter(p.spec.kind)) {
        text += "devices." + p.spec.element + ".servo." +
                (p.spec.kind == TargetKind::kServoBandwidth ? "bandwidth_hz" : "damping_ratio") + "=" +
                Num(fit.fitted_values[i]) + "\n";
        continue;
      }
      if (IsModelParameter(p.spec.kind)) continue;
      text += "# " + TargetText(p.spec.kind, p.spec.element, p.spec.axis) + " = " + Num(fit.fitted_values[i]) +
              " (a sensor's, not the model's: correct the log with it)\n";
    }
    // a payload is in model.xml as part of its body; the arm's scenario declares it apart
    for (std::size_t i = 0; i < fit.estimates.size(); ++i) {
      const BoundParameter& p = problem.parameters()[i];
      if (p.spec.kind != TargetKind::kPayloadMass) continue;
      double com[3] = {0, 0, 0};
      for (std::size_t k = 0; k < fit.estimates.size(); ++k) {
        const BoundParameter& q = problem.parameters()[k];
        if (q.spec.kind == TargetKind::kPayloadCom && q.spec.element == p.spec.element)
          com[q.spec.axis] = fit.fitted_values[k];
      }
      text += "# payload on body " + p.spec.element + " (in model.xml, part of that body): a point mass of " +
              Num(fit.fitted_values[i]) + " kg at [" + Num(com[0]) + ", " + Num(com[1]) + ", " + Num(com[2]) +
              "] m in " + p.spec.element + "'s frame\n";
      text += PayloadAtJoint(problem.model(), p.index, fit.fitted_values[i], com);
    }
    return text;
  };
  WriteOutputFile(out->File("overrides.txt"), overrides(out->final_dir()));
  const std::vector<std::string> columns = WriteFitCsv(problem, fit, threads, out->File("fit.csv"));
  std::vector<std::string> plots;
  for (const std::string& c : columns) {
    lab::PlotConfig plot;
    plot.file = "fit_" + c + ".png";
    plot.csv = "fit.csv";
    plot.y = {c + ".error_nominal", c + ".error_fitted"};
    plot.title = c + ": model minus measured, nominal and fitted";
    plot.ylabel = c.find(".qd.") != std::string::npos    ? "rad/s (m/s)"
                  : c.find(".q.") != std::string::npos   ? "rad (m)"
                  : c.find(".tau.") != std::string::npos ? "N m (N)"
                                                         : "N, N·m";
    plot.where = problem.spec().file;
    lab::WritePlot(dir, plot);
    plots.push_back(plot.file);
  }
  WriteOutputFile(out->File("report.md"), ReportMarkdown(problem, fit, plots));
  const std::string where = out->Commit();
  *note = out->note();
  if (fs::path(where).lexically_normal() != fs::path(out->final_dir()).lexically_normal()) {
    // the folder went elsewhere (DIR.2: another run's folder took DIR meanwhile): overrides.txt
    // names the model.xml beside it, written whole under a temporary name, then renamed over
    // the first version
    const std::string file = (fs::path(where) / "overrides.txt").string();
    WriteOutputFile(file + ".tmp", overrides(where));
    fs::rename(file + ".tmp", file);
  }
  return where;
}

}  // namespace vlab::identify

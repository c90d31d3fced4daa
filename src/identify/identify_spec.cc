#include "identify/identify_spec.h"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "core/core_errors.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::identify {

namespace fs = std::filesystem;

namespace {

// "body NAME mass" etc.: the kind and element of a target's words
bool ParseTarget(const std::string& text, TargetKind* kind, std::string* element, int* axis) {
  std::istringstream in(text);
  std::string what, name, attribute, extra;
  if (!(in >> what >> name >> attribute) || (in >> extra)) return false;
  *element = name;
  *axis = 0;
  const bool com = attribute == "com_x" || attribute == "com_y" || attribute == "com_z";
  if (com) *axis = attribute[4] - 'x';
  const bool inertia = attribute == "inertia_x" || attribute == "inertia_y" || attribute == "inertia_z";
  if (inertia) *axis = attribute[8] - 'x';
  if (what == "body" && attribute == "mass") {
    *kind = TargetKind::kBodyMass;
  } else if (what == "body" && com) {
    *kind = TargetKind::kBodyCom;
  } else if (what == "body" && inertia) {
    *kind = TargetKind::kBodyInertia;
  } else if (what == "payload" && attribute == "mass") {
    *kind = TargetKind::kPayloadMass;
  } else if (what == "payload" && com) {
    *kind = TargetKind::kPayloadCom;
  } else if (what == "joint" && attribute == "damping") {
    *kind = TargetKind::kJointDamping;
  } else if (what == "joint" && attribute == "armature") {
    *kind = TargetKind::kJointArmature;
  } else if (what == "joint" && attribute == "frictionloss") {
    *kind = TargetKind::kJointFrictionLoss;
  } else if (what == "column" && attribute == "bias") {
    *kind = TargetKind::kColumnBias;
  } else if (what == "column" && attribute == "gain") {
    *kind = TargetKind::kColumnGain;
  } else if (what == "column" && attribute == "delay") {
    *kind = TargetKind::kColumnDelay;
  } else if (what == "servo" && attribute == "bandwidth") {
    *kind = TargetKind::kServoBandwidth;
  } else if (what == "servo" && attribute == "damping_ratio") {
    *kind = TargetKind::kServoDampingRatio;
  } else {
    return false;
  }
  return true;
}

constexpr char kTargets[] =
    "'body NAME mass', 'body NAME com_x|com_y|com_z', 'body NAME inertia_x|inertia_y|inertia_z', "
    "'payload BODY mass', 'payload BODY com_x|com_y|com_z', "
    "'joint NAME damping', 'joint NAME armature', 'joint NAME frictionloss', "
    "'column NAME bias', 'column NAME gain', 'column NAME delay', 'servo DEVICE bandwidth' or "
    "'servo DEVICE damping_ratio'";

ParameterSpec ReadParameter(const std::string& file, const YAML::Node& node, const std::string& path) {
  lab::MapReader r(file, node, path);
  ParameterSpec p;
  p.where = lab::YamlWhere(file, node) + ": " + path;
  p.name = r.String("name");
  if (p.name.empty()) r.Fail("name", "must not be empty");
  const std::string target = r.String("target");
  if (!ParseTarget(target, &p.kind, &p.element, &p.axis)) {
    r.Fail("target", "'" + target + "' is none of " + kTargets);
  }
  p.has_nominal = r.Has("nominal");
  if (p.has_nominal) p.nominal = r.Number("nominal");
  p.lower = r.Number("lower");
  p.upper = r.Number("upper");
  p.frozen = r.Bool("frozen", false);
  r.Finish();
  for (const char* key : {"nominal", "lower", "upper"}) {
    const double v = std::string(key) == "nominal" ? p.nominal : std::string(key) == "lower" ? p.lower : p.upper;
    if (!std::isfinite(v)) r.Fail(key, "must be finite");
  }
  if (!(p.upper > p.lower)) r.Fail("upper", "must be greater than lower (" + std::to_string(p.lower) + ")");
  if (p.has_nominal && (p.nominal < p.lower || p.nominal > p.upper)) {
    r.Fail("nominal", "must lie within [lower, upper]");
  }
  // a mass, damping, armature and friction loss are never negative; a gain, a mass and a
  // principal inertia are positive
  const bool positive = p.kind == TargetKind::kBodyMass || p.kind == TargetKind::kBodyInertia ||
                        p.kind == TargetKind::kColumnGain || p.kind == TargetKind::kServoBandwidth ||
                        p.kind == TargetKind::kServoDampingRatio;
  const bool non_negative = p.kind == TargetKind::kJointDamping || p.kind == TargetKind::kJointArmature ||
                            p.kind == TargetKind::kJointFrictionLoss || p.kind == TargetKind::kColumnDelay ||
                            p.kind == TargetKind::kPayloadMass;
  if (positive && !(p.lower > 0)) r.Fail("lower", "must be > 0 for " + TargetText(p.kind, p.element, p.axis));
  if (non_negative && p.lower < 0) r.Fail("lower", "must be >= 0 for " + TargetText(p.kind, p.element, p.axis));
  return p;
}

// `spans: [[from, to], ...]` (s) under `r`, if it has the key
std::vector<std::pair<double, double>> ReadSpans(const std::string& file, lab::MapReader& r, const std::string& path) {
  std::vector<std::pair<double, double>> out;
  if (!r.Has("spans")) return out;
  const YAML::Node spans = r.Sequence("spans");
  for (std::size_t i = 0; i < spans.size(); ++i) {
    const std::string at = lab::YamlWhere(file, spans[i]) + ": " + path + "spans[" + std::to_string(i) + "]";
    std::vector<double> span;
    try {
      span = spans[i].as<std::vector<double>>();
    } catch (const YAML::Exception&) {
      throw InputError(at + ": must be [from, to] in seconds");
    }
    if (span.size() != 2 || !std::isfinite(span[0]) || !std::isfinite(span[1]) || !(span[1] > span[0])) {
      throw InputError(at + ": must be [from, to] in seconds, finite, to > from");
    }
    out.emplace_back(span[0], span[1]);
  }
  if (out.empty()) r.Fail("spans", "name at least one [from, to] span (or leave the key out: the whole log)");
  return out;
}

ColumnSpec ReadColumn(const std::string& file, const YAML::Node& node, const std::string& path) {
  lab::MapReader r(file, node, path);
  ColumnSpec c;
  c.where = lab::YamlWhere(file, node) + ": " + path;
  c.pattern = r.String("name");
  if (c.pattern.empty()) r.Fail("name", "must not be empty");
  c.weight = r.Number("weight", 1.0);
  if (!(c.weight > 0) || !std::isfinite(c.weight)) r.Fail("weight", "must be a finite number > 0");
  c.spans = ReadSpans(file, r, path + ".");
  c.norm = r.Strings("norm", {});
  c.rate = r.Bool("rate", false);
  if (r.Has("norm")) {
    if (c.norm.empty()) r.Fail("norm", "name at least one column");
    if (c.pattern.find('*') != std::string::npos) r.Fail("name", "a derived column's own name has no '*'");
    for (const std::string& part : c.norm) {
      if (part.empty() || part.find('*') != std::string::npos) r.Fail("norm", "'" + part + "' is not a column name");
    }
  } else if (c.rate) {
    r.Fail("rate", "is for a derived column (norm:)");
  }
  r.Finish();
  return c;
}

// a log argument: a run folder (its log.csv) or a CSV file, relative to the spec's folder
std::string ResolveLog(const fs::path& dir, const std::string& text) {
  fs::path p = (dir / text).lexically_normal();
  std::error_code ec;
  if (fs::is_directory(p, ec)) p /= "log.csv";
  return p.string();
}

}  // namespace

std::string TargetText(TargetKind kind, const std::string& element) { return TargetText(kind, element, 0); }

std::string TargetText(TargetKind kind, const std::string& element, int axis) {
  const std::string com = std::string(" com_") + static_cast<char>('x' + axis);
  const std::string inertia = std::string(" inertia_") + static_cast<char>('x' + axis);
  switch (kind) {
    case TargetKind::kBodyMass:
      return "body " + element + " mass";
    case TargetKind::kBodyCom:
      return "body " + element + com;
    case TargetKind::kBodyInertia:
      return "body " + element + inertia;
    case TargetKind::kPayloadMass:
      return "payload " + element + " mass";
    case TargetKind::kPayloadCom:
      return "payload " + element + com;
    case TargetKind::kJointDamping:
      return "joint " + element + " damping";
    case TargetKind::kJointArmature:
      return "joint " + element + " armature";
    case TargetKind::kJointFrictionLoss:
      return "joint " + element + " frictionloss";
    case TargetKind::kColumnBias:
      return "column " + element + " bias";
    case TargetKind::kColumnGain:
      return "column " + element + " gain";
    case TargetKind::kColumnDelay:
      return "column " + element + " delay";
    case TargetKind::kServoBandwidth:
      return "servo " + element + " bandwidth";
    case TargetKind::kServoDampingRatio:
      return "servo " + element + " damping_ratio";
  }
  return "";
}

bool MatchColumn(const std::string& pattern, const std::string& name) {
  // iterative wildcard match: '*' backtracks to the last star only
  std::size_t p = 0, n = 0, star = std::string::npos, mark = 0;
  while (n < name.size()) {
    if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      mark = n;
    } else if (p < pattern.size() && pattern[p] == name[n]) {
      ++p;
      ++n;
    } else if (star != std::string::npos) {
      p = star + 1;
      n = ++mark;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

Spec LoadSpec(const std::string& path) {
  const YAML::Node root = lab::LoadYamlFile(path, "identification spec");
  if (!root.IsMap()) throw InputError(path + ": an identification spec is a mapping (scenario:, logs:, ...)");
  lab::MapReader r(path, root, "");
  const fs::path dir = fs::path(path).parent_path();
  Spec s;
  s.file = path;
  s.scenario = (dir / r.String("scenario")).lexically_normal().string();
  s.sets = r.Strings("set", {});
  for (const std::string& text : r.Strings("logs", {})) s.logs.push_back(ResolveLog(dir, text));
  if (s.logs.empty()) r.Fail("logs", "name at least one log (a run folder or a log.csv)");
  const YAML::Node columns = r.Sequence("columns");
  for (std::size_t i = 0; i < columns.size(); ++i) {
    s.columns.push_back(ReadColumn(path, columns[i], "columns[" + std::to_string(i) + "]"));
  }
  if (s.columns.empty()) r.Fail("columns", "name at least one log column ({name: pa10.q.*, weight: 1e4})");
  s.where_window = lab::YamlWhere(path, r.Has("window") ? root["window"] : root) + ": window";
  s.window_s = r.Number("window", s.window_s);
  if (!(s.window_s > 0) || s.window_s > 1e3) r.Fail("window", "must be > 0 and at most 1000 s");
  s.spans = ReadSpans(path, r, "");
  s.where_start_speed = lab::YamlWhere(path, r.Has("start_speed") ? root["start_speed"] : root) + ": start_speed";
  s.start_speed = r.String("start_speed", "");
  s.run_in_s = r.Number("run_in", 0.0);
  if (!(s.run_in_s >= 0) || s.run_in_s > 100) r.Fail("run_in", "must be from 0 to 100 s");
  if (s.run_in_s > 0 && s.start_speed.empty()) {
    r.Fail("run_in", "needs start_speed (the speed the run-in's motion is scaled back to)");
  }
  s.where_input = lab::YamlWhere(path, r.Has("input") ? root["input"] : root) + ": input";
  s.input = r.String("input", s.input);
  if (s.input != "torque" && s.input != "reference") {
    r.Fail("input",
           "must be 'torque' (the recorded joint torques) or 'reference' (the recorded commands "
           "through the arm's servo), got '" +
               s.input + "'");
  }
  const std::string sensing = r.String("servo_sensing", "scenario");
  if (sensing != "scenario" && sensing != "exact") {
    r.Fail("servo_sensing", "must be 'scenario' or 'exact', got '" + sensing + "'");
  }
  if (sensing == "exact" && s.input != "reference") r.Fail("servo_sensing", "needs input: reference");
  s.servo_sensing_exact = sensing == "exact";
  s.max_iterations = r.Integer("max_iterations", s.max_iterations);
  if (s.max_iterations < 1 || s.max_iterations > 1000) r.Fail("max_iterations", "must be from 1 to 1000");
  s.jacobian_step = r.Number("jacobian_step", s.jacobian_step);
  if (!(s.jacobian_step >= 1e-8 && s.jacobian_step <= 0.1)) r.Fail("jacobian_step", "must be from 1e-8 to 0.1");
  s.start_smoothing = r.Integer("start_smoothing", s.start_smoothing);
  if (s.start_smoothing < 0 || s.start_smoothing > 1000) r.Fail("start_smoothing", "must be from 0 to 1000 rows");
  s.where_wrench_settle =
      lab::YamlWhere(path, r.Has("wrench_settle") ? root["wrench_settle"] : root) + ": wrench_settle";
  if (r.Has("wrench_settle")) {
    s.wrench_settle_s = r.Number("wrench_settle");
    if (!(s.wrench_settle_s >= 0) || s.wrench_settle_s > 1e3) r.Fail("wrench_settle", "must be from 0 to 1000 s");
  }
  const std::string contacts = r.String("contacts", "skip");
  if (contacts != "skip" && contacts != "keep") r.Fail("contacts", "must be 'skip' or 'keep', got '" + contacts + "'");
  s.skip_contacts = contacts == "skip";
  const std::string first = r.String("first_estimate", "linear");
  if (first != "linear" && first != "nominal") {
    r.Fail("first_estimate", "must be 'linear' or 'nominal', got '" + first + "'");
  }
  s.first_estimate = first == "linear" ? FirstEstimate::kLinear : FirstEstimate::kNominal;
  const YAML::Node parameters = r.Sequence("parameters");
  for (std::size_t i = 0; i < parameters.size(); ++i) {
    const std::string item = "parameters[" + std::to_string(i) + "]";
    s.parameters.push_back(ReadParameter(path, parameters[i], item));
    for (std::size_t j = 0; j < i; ++j) {
      if (s.parameters[j].name == s.parameters[i].name) {
        throw InputError(s.parameters[i].where + ".name: duplicate parameter name '" + s.parameters[i].name + "'");
      }
      if (s.parameters[j].kind == s.parameters[i].kind && s.parameters[j].element == s.parameters[i].element &&
          s.parameters[j].axis == s.parameters[i].axis) {
        throw InputError(s.parameters[i].where + ".target: '" +
                         TargetText(s.parameters[i].kind, s.parameters[i].element, s.parameters[i].axis) +
                         "' is already parameter '" + s.parameters[j].name + "'");
      }
    }
  }
  if (s.parameters.empty()) r.Fail("parameters", "name at least one parameter to fit");
  for (const ParameterSpec& p : s.parameters) {
    const bool servo = p.kind == TargetKind::kServoBandwidth || p.kind == TargetKind::kServoDampingRatio;
    if (servo && s.input != "reference") {
      throw InputError(p.where + ".target: '" + TargetText(p.kind, p.element) +
                       "' needs input: reference (the torque replay does not run the servo)");
    }
  }
  // a payload's centre of mass is nothing without its mass
  for (const ParameterSpec& p : s.parameters) {
    if (p.kind != TargetKind::kPayloadCom) continue;
    bool mass = false;
    for (const ParameterSpec& q : s.parameters)
      mass = mass || (q.kind == TargetKind::kPayloadMass && q.element == p.element);
    if (!mass) {
      throw InputError(p.where + ".target: '" + TargetText(p.kind, p.element, p.axis) + "' needs a 'payload " +
                       p.element + " mass' parameter (frozen, if the mass is known)");
    }
  }
  r.Finish();
  return s;
}

}  // namespace vlab::identify

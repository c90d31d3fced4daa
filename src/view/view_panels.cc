// The panels' messages and signal lookups (view_panels.h).
#include "view/view_panels.h"

#include <cstdint>
#include <cstring>
#include <sstream>

#include "core/core_errors.h"
#include "render/image_codec.h"
#include "scene/scene_csv.h"

namespace vlab::view {

namespace {

template <typename T>
void Append(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // little-endian hosts only, as every vlab wire
  out->append(bytes, sizeof(T));
}

}  // namespace

std::string EncodeCameraMessage(const bridge::CameraFrame& frame) {
  std::string out;
  Append(&out, frame.time_s);
  Append(&out, static_cast<double>(frame.id));
  Append(&out, static_cast<std::uint32_t>(frame.width));
  Append(&out, static_cast<std::uint32_t>(frame.height));
  if (frame.encoding == bridge::CameraEncoding::kJpeg) {
    out.append(reinterpret_cast<const char*>(frame.data.data()), frame.data.size());
    return out;
  }
  // raw RGB8 -> PNG, zlib level 1 (fast)
  std::vector<std::uint8_t> png;
  render::EncodePng({frame.width, frame.height, 3, 8, frame.data.data(), 0}, 1, &png);
  out.append(reinterpret_cast<const char*>(png.data()), png.size());
  return out;
}

std::string EncodePlotMessage(double time, double seq, const std::vector<double>& values) {
  std::string out;
  out.reserve(16 + 8 * values.size());
  Append(&out, time);
  Append(&out, seq);
  for (double v : values) Append(&out, v);
  return out;
}

std::vector<std::string> ParsePlotSignals(const std::string& text) {
  std::vector<std::string> names;
  std::istringstream in(text);
  std::string name;
  while (std::getline(in, name, ',')) {
    if (name.empty() || name.size() > 200) {
      throw InputError("--plot '" + text + "': expected signal names separated by commas, e.g. pa10.q.S1,pa10.q.E1");
    }
    names.push_back(name);
  }
  if (names.empty() || text.back() == ',') {
    throw InputError("--plot '" + text + "': expected signal names separated by commas, e.g. pa10.q.S1,pa10.q.E1");
  }
  if (static_cast<int>(names.size()) > kMaxPlotSignals) {
    throw InputError("--plot '" + text + "': at most " + std::to_string(kMaxPlotSignals) + " signals");
  }
  return names;
}

ArmSignals::ArmSignals(const std::string& arm_name, const std::vector<std::string>& joint_names,
                       const std::vector<std::string>& signals) {
  const char* const quantities[] = {"q", "qd", "tau"};
  for (const std::string& signal : signals) {
    bool found = false;
    for (int k = 0; k < 3 && !found; ++k) {
      for (std::size_t j = 0; j < joint_names.size() && !found; ++j) {
        if (signal == arm_name + "." + quantities[k] + "." + joint_names[j]) {
          quantity_.push_back(k);
          joint_.push_back(static_cast<int>(j));
          found = true;
        }
      }
    }
    if (!found) {
      std::string have;
      for (const char* q : quantities) {
        if (!joint_names.empty()) have += " " + arm_name + "." + q + "." + joint_names.front() + " ..";
      }
      throw InputError("--plot: arm '" + arm_name + "' has no signal '" + signal +
                       "' (it has ARM.q.JOINT, ARM.qd.JOINT, ARM.tau.JOINT:" + have + ")");
    }
  }
}

std::vector<double> ArmSignals::Values(const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                       const Eigen::VectorXd& tau) const {
  std::vector<double> values(joint_.size());
  for (std::size_t i = 0; i < joint_.size(); ++i) {
    const Eigen::VectorXd& v = quantity_[i] == 0 ? q : quantity_[i] == 1 ? qd : tau;
    values[i] = joint_[i] < v.size() ? v[joint_[i]] : 0.0;
  }
  return values;
}

std::string ReplayPlotRows(const std::string& log_csv, const std::vector<std::string>& signals) {
  const scene::CsvTable table = scene::ReadCsvTable(log_csv);
  std::vector<int> columns = {table.Column("time")};
  if (columns[0] < 0) throw InputError("vlab view: '" + log_csv + "' has no column 'time'");
  for (const std::string& s : signals) {
    columns.push_back(table.Column(s));
    if (columns.back() < 0) throw InputError("vlab view: --plot: '" + log_csv + "' has no column '" + s + "'");
  }
  std::string out;
  out.reserve(8 * columns.size() * table.rows.size());
  for (const auto& row : table.rows) {
    for (int c : columns) Append(&out, row[c]);
  }
  return out;
}

}  // namespace vlab::view

#include "cli/cli_record_table.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <nlohmann/json.hpp>

#include "core/core_clock.h"

namespace vlab::cli::record {

namespace {

// the lab's name for a wire field where it differs (src/lab/devices/device_gripper.cc)
struct Rename {
  const char* kind;
  const char* field;
  const char* column;
};
constexpr Rename kRenames[] = {
    {"gripper", "opening_velocity", "velocity"},
};

// "q[3]" -> ("q", 3); false for a name without an index
bool SplitIndexed(const std::string& value, std::string* group, int* index) {
  const std::size_t open = value.find('[');
  if (open == std::string::npos || value.back() != ']') return false;
  *group = value.substr(0, open);
  *index = std::stoi(value.substr(open + 1, value.size() - open - 2));
  return true;
}

}  // namespace

std::vector<std::string> StateColumns(const std::string& name, const std::string& kind,
                                      const std::vector<std::string>& state_names, const nlohmann::json& describe) {
  std::vector<std::string> joints;
  if (kind == "arm") {
    const nlohmann::json j = describe.value("joints", nlohmann::json());
    if (j.is_array()) {
      for (const nlohmann::json& v : j) joints.push_back(v.is_string() ? v.get<std::string>() : std::string());
    }
  }
  std::vector<std::string> columns;
  columns.reserve(state_names.size());
  for (const std::string& value : state_names) {
    std::string field = value, group;
    int index = 0;
    if (kind == "arm" && SplitIndexed(value, &group, &index)) {
      // an arm's per-joint value: the lab's NAME.q.S1
      if (index < 0 || index >= static_cast<int>(joints.size()) || joints[static_cast<std::size_t>(index)].empty()) {
        throw std::invalid_argument(name + ": the arm's describe reply names " + std::to_string(joints.size()) +
                                    " joints, its layout has " + value);
      }
      field = group + "." + joints[static_cast<std::size_t>(index)];
    }
    for (const Rename& r : kRenames) {
      if (kind == r.kind && value == r.field) field = r.column;
    }
    columns.push_back(name + "." + field);
  }
  return columns;
}

RecordTable::RecordTable(std::vector<int> widths, double duration_s)
    : widths_(std::move(widths)), duration_s_(duration_s), counts_(widths_.size()) {
  for (int w : widths_) {
    offsets_.push_back(width_);
    width_ += w;
  }
}

bool RecordTable::Add(int device, std::int64_t seq, double stamp, const double* values) {
  DeviceCounts& c = counts_[static_cast<std::size_t>(device)];
  // a duplicate or replay, or a stamp that goes back: refused
  if ((c.seen_seq >= 0 && seq <= c.seen_seq) || (c.seen_seq >= 0 && !(stamp > c.seen_stamp)) || !std::isfinite(stamp)) {
    ++c.refused;
    return false;
  }
  if (!started_) {
    started_ = true;
    if (duration_s_ > 0) end_ = stamp + duration_s_;
  }
  if (c.seen_seq >= 0) c.lost += seq - c.seen_seq - 1;
  c.seen_seq = seq;
  c.seen_stamp = stamp;
  // (the end within kSameTime_s: first + duration need not be a whole number of periods in doubles)
  if (stamp >= end_ - kSameTime_s) c.ended = true;
  if (stamp > end_ + kSameTime_s) return false;  // past the end: not written
  if (rows_ > 0 && !(stamp > last_written_)) {
    ++c.late;
    return false;
  }
  if (c.first_seq < 0) {
    c.first_seq = seq;
    c.first_stamp = stamp;
  }
  c.last_seq = seq;
  c.last_stamp = stamp;
  ++c.states;
  // its row: found from the newest (states come in stamp order), or made in its place
  auto it = pending_.end();
  while (it != pending_.begin() && std::prev(it)->stamp >= stamp) --it;
  if (it == pending_.end() || it->stamp != stamp) {
    Row row;
    row.stamp = stamp;
    row.values.assign(static_cast<std::size_t>(width_), std::numeric_limits<double>::quiet_NaN());
    row.values[0] = stamp;
    it = pending_.insert(it, std::move(row));
  }
  std::copy(values, values + widths_[static_cast<std::size_t>(device)],
            it->values.begin() + offsets_[static_cast<std::size_t>(device)]);
  ++it->filled;
  return true;
}

bool RecordTable::Ready(const Row& row) const {
  if (row.filled == static_cast<int>(widths_.size()) || pending_.size() > kMaxPendingRows) return true;
  // no device can still send a state at this stamp: each is past it (or ended)
  return std::all_of(counts_.begin(), counts_.end(), [&row](const DeviceCounts& c) {
    return c.ended || (c.seen_seq >= 0 && c.seen_stamp > row.stamp);
  });
}

void RecordTable::Drain(bool all, const std::function<void(const double* row)>& write) {
  while (!pending_.empty() && (all || Ready(pending_.front()))) {
    const Row& row = pending_.front();
    write(row.values.data());
    if (rows_ == 0) first_written_ = row.stamp;
    last_written_ = row.stamp;
    ++rows_;
    pending_.pop_front();
  }
}

bool RecordTable::Done() const {
  return std::isfinite(end_) &&
         std::all_of(counts_.begin(), counts_.end(), [](const DeviceCounts& c) { return c.ended; });
}

}  // namespace vlab::cli::record

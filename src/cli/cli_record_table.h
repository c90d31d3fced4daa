// What `vlab record` makes of the states it receives: the log's column names
// for a device, and the rows of log.csv built from the states of several
// devices, one row per stamp.
//
// Columns. A state value gets the name the lab gives the same signal in a
// run's log.csv (src/lab/devices: NAME.q.S1, NAME.Fx, NAME.velocity of a
// gripper's opening_velocity), so that `vlab compare` matches a record with a
// run. A value the lab does not log keeps its wire name after the device's
// (NAME.status, NAME.filter).
//
// Rows. A state's stamp is the time field the device sent (the simulated
// time of a lab device; the device's own clock for any other server). States
// of several devices with the same stamp (the devices of one `vlab serve`)
// share a row; a device with no state at a row's stamp has NaN in its cells.
// Rows are written in stamp order. A row waits until every device has sent a
// state at its stamp or past it (a device's stamps only increase), so the
// devices of one server fill their rows whatever order their datagrams come
// in; at most kMaxPendingRows rows wait (a device that falls silent no longer
// holds them back), and the end of the recording writes those that wait. A
// state stamped at or before the last row written (a device whose clock is
// that far behind the others') can no longer take its place: it is counted
// as late and not written.
//
// Counting, per device: a state whose seq is not above the device's last one
// (a duplicate or a replay), or whose stamp is not after its last one, is
// refused and counted; a seq that skips values counts the skipped ones as
// lost. A state stamped after the end of the recording (--duration, within
// kSameTime_s) is not written nor counted in `states`.
//
// Not thread-safe: one thread adds states and takes rows.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace vlab::cli::record {

/// The log columns of one device's state values, in state order: `name` is
/// the device's name in the record (NAME of NAME=HOST:PORT), `kind` its
/// describe reply's kind ("arm"), `state_names` one name per value as
/// bridge::Device::state_names() gives them ("q[0]", "Fx"), `describe` the
/// describe reply (an arm's "joints" name its joints). Throws
/// std::invalid_argument naming the device when an arm's joints do not match
/// its layout.
std::vector<std::string> StateColumns(const std::string& name, const std::string& kind,
                                      const std::vector<std::string>& state_names, const nlohmann::json& describe);

/// What the table counted for one device.
struct DeviceCounts {
  long states = 0;   ///< states written into rows
  long lost = 0;     ///< seq values skipped between two states taken
  long refused = 0;  ///< states refused: seq or stamp not increasing
  long late = 0;     ///< states stamped at or before the last row written
  /// the first and the last state written (a state past the end, taken as the recorder
  /// stops, is not one of them)
  std::int64_t first_seq = -1, last_seq = -1;
  double first_stamp = std::numeric_limits<double>::quiet_NaN();  ///< s
  double last_stamp = std::numeric_limits<double>::quiet_NaN();   ///< s
  /// the newest state taken, written or not: the next must come after it
  std::int64_t seen_seq = -1;
  double seen_stamp = std::numeric_limits<double>::quiet_NaN();  ///< s
  bool ended = false;                                            ///< sent a state stamped at or after the end
};

class RecordTable {
 public:
  /// Rows that wait for a late device at most.
  static constexpr std::size_t kMaxPendingRows = 4096;

  /// `widths`: the number of state values of each device, in column order
  /// (the row is time, then device 0's values, device 1's, ...). `duration_s`
  /// > 0: states stamped later than the first stamp taken plus duration_s
  /// end the recording; 0: no end.
  RecordTable(std::vector<int> widths, double duration_s);

  /// Takes a state of device `device`: its seq, stamp (s) and widths[device]
  /// values. Returns false when refused (counted) or past the end.
  bool Add(int device, std::int64_t seq, double stamp, const double* values);

  /// Hands the rows that are ready to `write` (1 + sum of widths values
  /// each), oldest first; with `all`, every row that waits.
  void Drain(bool all, const std::function<void(const double* row)>& write);

  /// True when a duration was given and every device has sent a state
  /// stamped at or past its end.
  bool Done() const;

  const DeviceCounts& counts(int device) const { return counts_[static_cast<std::size_t>(device)]; }
  long rows() const { return rows_; }
  double first_stamp() const { return first_written_; }
  double last_stamp() const { return last_written_; }

 private:
  struct Row {
    double stamp = 0;
    std::vector<double> values;  // time, then every device's cells (NaN until filled)
    int filled = 0;              // devices that filled their cells
  };
  bool Ready(const Row& row) const;

  std::vector<int> widths_, offsets_;
  int width_ = 1;
  double duration_s_ = 0;
  double end_ = std::numeric_limits<double>::infinity();
  bool started_ = false;
  std::vector<DeviceCounts> counts_;
  std::deque<Row> pending_;  // in stamp order
  long rows_ = 0;
  double first_written_ = std::numeric_limits<double>::quiet_NaN();
  double last_written_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace vlab::cli::record

// The markers device (kind 5): poses of fiducial markers seen by a camera,
// served by the vision program (`vlab vision`). docs/protocol_markers.md is
// its contract; the header and framing are those of bridge_protocol.h.
//
//   state    (device -> client, type 1), one per camera frame:
//            seq = the camera's frame id, time = the image's exposure time (s,
//            the camera's clock), payload
//              [count, described, unknown,  record_1 .. record_count]
//            count      markers reported in this state (0..kMaxMarkersPerState)
//            described  entries in the device's marker table
//            unknown    detections in this image of markers not in the table
//            record     37 values, kMarkerRecordValues:
//              dictionary  code (MarkerDictionary::code, OpenCV's numbering)
//              id          marker id in that dictionary
//              valid       1: the pose is unambiguous and fits the image;
//                          0: best guess only (ambiguous or poor fit)
//              reprojection_error  RMS over the 4 corners, pixels
//              T_camera    16 values, row-major 4x4 homogeneous transform of
//                          the marker frame in the camera frame (OpenCV
//                          camera: x right, y down, z forward; metres)
//              world_valid 1 when the camera's pose in the world was known
//              T_world     16 values, row-major, the marker frame in the world
//                          frame (all zero when world_valid is 0)
//            Marker frame: origin at the marker's centre, x to the right of
//            the printed marker, y up, z out of the printed side.
//   command  (client -> device, type 2): marker descriptions, 3 values each,
//            as many as fit (1..kMaxDescriptionsPerCommand):
//              [dictionary, id, side_m] ...   side 0 removes the entry
//            Any sender may describe markers (no owner); the last description
//            of a (dictionary, id) wins. A packet with one bad entry is
//            refused whole.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "bridge/bridge_client.h"
#include "bridge/bridge_protocol.h"

namespace vlab::bridge {

inline constexpr int kMarkersStatePrefix = 3;   ///< count, described, unknown
inline constexpr int kMarkerRecordValues = 37;  ///< values per reported marker
inline constexpr int kMaxMarkersPerState =
    (kMaxPacketValues - kHeaderValues - kMarkersStatePrefix) / kMarkerRecordValues;  // 27
inline constexpr int kMarkerDescriptionValues = 3;                                   ///< dictionary, id, side
inline constexpr int kMaxDescriptionsPerCommand = (kMaxPacketValues - kHeaderValues) / kMarkerDescriptionValues;
/// Largest marker side a description may give, m.
inline constexpr double kMaxMarkerSide_m = 10.0;

/// One of OpenCV's predefined marker dictionaries (cv::aruco::PREDEFINED_DICTIONARY_NAME).
struct MarkerDictionary {
  int code;          ///< the value on the wire (OpenCV's enum value)
  const char* name;  ///< "4X4_50", "APRILTAG_36h11", ...
  int bits;          ///< data bits per side (4 for 4X4; the marker is bits + 2 cells wide)
  int markers;       ///< number of ids: 0 .. markers - 1
};
/// All predefined dictionaries, by code (0 .. 20).
const std::vector<MarkerDictionary>& MarkerDictionaries();
/// The dictionary of a code, or null.
const MarkerDictionary* FindMarkerDictionary(int code);
/// The dictionary of a name ("4X4_50", "DICT_4X4_50", any case), or null.
const MarkerDictionary* FindMarkerDictionary(const std::string& name);

/// One marker in a markers state.
struct MarkerRecordMsg {
  int dictionary = 0;
  int id = 0;
  bool valid = false;
  double reprojection_error_px = 0;
  double T_camera[16] = {};  ///< row-major 4x4, camera frame, m
  bool world_valid = false;
  double T_world[16] = {};  ///< row-major 4x4, world frame, m (zero when !world_valid)
};

struct MarkersStateMsg {
  int described = 0;                     ///< entries in the device's marker table
  int unknown = 0;                       ///< detections of markers not in the table
  std::vector<MarkerRecordMsg> markers;  ///< at most kMaxMarkersPerState
};

/// A marker the vision program should track: its dictionary, id and printed
/// side length (outer edge of the black border), m; side 0 removes it.
struct MarkerDescriptionMsg {
  int dictionary = 0;
  int id = 0;
  double side_m = 0;
};

/// Encodes a state (seq = frame id, time = exposure time, s); markers beyond
/// kMaxMarkersPerState are left out. No allocation once `out` has the capacity.
void EncodeMarkersState(double seq, double time, const MarkersStateMsg& m, std::vector<unsigned char>* out);
/// Encodes one command of 1..kMaxDescriptionsPerCommand descriptions (more
/// are left out; none gives an empty, invalid command).
void EncodeMarkersCommand(double seq, double time, const std::vector<MarkerDescriptionMsg>& descriptions,
                          std::vector<unsigned char>* out);

/// Payload -> message, with the layout and domain checks of the kind:
/// whole numbers where the field is one, known dictionary codes, ids within
/// the dictionary, flags 0 or 1, error >= 0, transforms with last row 0 0 0 1
/// (all zero for an invalid world transform), sides in [0, kMaxMarkerSide_m].
/// On error *m is left as it was.
DecodeError ParseMarkersState(const Header& h, const std::vector<double>& payload, MarkersStateMsg* m);
DecodeError ParseMarkersCommand(const Header& h, const std::vector<double>& payload,
                                std::vector<MarkerDescriptionMsg>* descriptions);

/// Client of a markers device (e.g. `vlab vision`): reads the marker poses of
/// each camera frame and tells the device which markers to track.
///
///   input   command [dictionary, id, side_m] x k    (AddMarkers)
///   output  state per camera frame: [count, described, unknown, records]
///
/// Connect makes a session (cookie, describe reply, subscription); the device sends one state per
/// camera frame it processed. A client that only reads must call KeepAlive()
/// now and then (every few seconds) to stay subscribed. Not thread-safe.
class MarkersClient : public DeviceClient {
 public:
  /// One marker seen in a frame.
  struct Marker {
    int dictionary = 0;  ///< MarkerDictionary::code
    int id = 0;
    bool valid = false;                ///< false: ambiguous or poor fit (the pose is a best guess)
    double reprojection_error_px = 0;  ///< RMS over the 4 corners
    Eigen::Matrix4d T_camera_marker = Eigen::Matrix4d::Identity();  ///< OpenCV camera frame, m
    bool world_valid = false;                                       ///< the camera's pose was known
    Eigen::Matrix4d T_world_marker = Eigen::Matrix4d::Zero();       ///< world frame, m (zero if !world_valid)
  };
  struct State {
    std::int64_t seq = 0;  ///< the camera frame id
    double time = 0;       ///< the image's exposure time, s (the camera's clock)
    int described = 0;     ///< entries in the device's marker table
    int unknown = 0;       ///< detections of markers not in the table
    std::vector<Marker> markers;
  };

  /// Connects to the markers device at address:port; throws as Arm::Connect.
  static MarkersClient Connect(const std::string& address, int port, double timeout_s = 1.0,
                               const std::string& bind_address = "0.0.0.0");

  /// The marker table of the describe reply received at connect.
  const std::vector<MarkerDescriptionMsg>& described_at_connect() const { return table_; }

  /// Next state / newest state; throw TimeoutError, ProtocolError.
  State Read(double timeout_s);
  State ReadLatest(double timeout_s);

  /// Describes markers to the device (as many packets as needed; side 0
  /// removes one). Never blocks; false if a datagram could not be sent.
  /// Throws std::invalid_argument on an unknown dictionary, an id outside
  /// it, or a side outside [0, kMaxMarkerSide_m]. The device's `described`
  /// count in the next states shows the table's new size.
  bool AddMarkers(const std::vector<MarkerDescriptionMsg>& descriptions);

 private:
  MarkersClient(const std::string& address, int port, double timeout_s, const std::string& bind_address);
  DecodeError ParseState(const Header& header, const std::vector<double>& payload) override;
  State Copy(const Header& header) const;

  MarkersStateMsg message_;
  std::vector<MarkerDescriptionMsg> table_;
  double last_seq_ = 0;  // seq of the newest state read: the seq of commands
};

}  // namespace vlab::bridge

#include "bridge/bridge_markers.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "bridge/bridge_protocol.h"

namespace vlab::bridge {

namespace {

// OpenCV 4.6's cv::aruco::PREDEFINED_DICTIONARY_NAME, in enum order (the code)
const std::vector<MarkerDictionary> kDictionaries = {
    {0, "4X4_50", 4, 50},
    {1, "4X4_100", 4, 100},
    {2, "4X4_250", 4, 250},
    {3, "4X4_1000", 4, 1000},
    {4, "5X5_50", 5, 50},
    {5, "5X5_100", 5, 100},
    {6, "5X5_250", 5, 250},
    {7, "5X5_1000", 5, 1000},
    {8, "6X6_50", 6, 50},
    {9, "6X6_100", 6, 100},
    {10, "6X6_250", 6, 250},
    {11, "6X6_1000", 6, 1000},
    {12, "7X7_50", 7, 50},
    {13, "7X7_100", 7, 100},
    {14, "7X7_250", 7, 250},
    {15, "7X7_1000", 7, 1000},
    {16, "ARUCO_ORIGINAL", 5, 1024},
    {17, "APRILTAG_16h5", 4, 30},
    {18, "APRILTAG_25h9", 5, 35},
    {19, "APRILTAG_36h10", 6, 2320},
    {20, "APRILTAG_36h11", 6, 587},
};

bool IsFlag(double v) { return v == 0.0 || v == 1.0; }

std::string Upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// a dictionary code and an id within it
bool KnownMarker(double code, double id) {
  if (!IsWhole(code, 0, static_cast<double>(kDictionaries.size()) - 1)) return false;
  return IsWhole(id, 0, kDictionaries[static_cast<std::size_t>(code)].markers - 1);
}

// a row-major 4x4 homogeneous transform: last row 0 0 0 1
bool IsTransform(const double* t) { return t[12] == 0 && t[13] == 0 && t[14] == 0 && t[15] == 1; }
bool IsZero(const double* t) {
  return std::all_of(t, t + 16, [](double v) { return v == 0.0; });
}

// writes a header, then values one by one (sized once, no temporary payload)
class Writer {
 public:
  Writer(MessageType type, double seq, double time, std::size_t count, std::vector<unsigned char>* out) : out_(out) {
    out->resize((kHeaderValues + count) * sizeof(double));
    for (double v : {kMagic, static_cast<double>(kProtocolVersion), static_cast<double>(DeviceKind::kMarkers),
                     static_cast<double>(type), seq, time, static_cast<double>(count)}) {
      Put(v);
    }
  }
  void Put(double v) {
    PutDouble(v, out_->data() + at_);
    at_ += sizeof(double);
  }

 private:
  std::vector<unsigned char>* out_;
  std::size_t at_ = 0;
};

DecodeError Expect(const Header& h, MessageType type) {
  if (h.kind != static_cast<int>(DeviceKind::kMarkers)) return DecodeError::kBadKind;
  if (h.type != static_cast<int>(type)) return DecodeError::kBadType;
  return DecodeError::kNone;
}

}  // namespace

const std::vector<MarkerDictionary>& MarkerDictionaries() { return kDictionaries; }

const MarkerDictionary* FindMarkerDictionary(int code) {
  if (code < 0 || code >= static_cast<int>(kDictionaries.size())) return nullptr;
  return &kDictionaries[static_cast<std::size_t>(code)];
}

const MarkerDictionary* FindMarkerDictionary(const std::string& name) {
  std::string wanted = Upper(name);
  if (wanted.rfind("DICT_", 0) == 0) wanted = wanted.substr(5);
  for (const MarkerDictionary& d : kDictionaries) {
    if (Upper(d.name) == wanted) return &d;
  }
  return nullptr;
}

void EncodeMarkersState(double seq, double time, const MarkersStateMsg& m, std::vector<unsigned char>* out) {
  const std::size_t count = std::min<std::size_t>(m.markers.size(), kMaxMarkersPerState);
  Writer w(MessageType::kState, seq, time, kMarkersStatePrefix + count * kMarkerRecordValues, out);
  w.Put(static_cast<double>(count));
  w.Put(m.described);
  w.Put(m.unknown);
  for (std::size_t i = 0; i < count; ++i) {
    const MarkerRecordMsg& r = m.markers[i];
    w.Put(r.dictionary);
    w.Put(r.id);
    w.Put(r.valid ? 1.0 : 0.0);
    w.Put(r.reprojection_error_px);
    for (double v : r.T_camera) w.Put(v);
    w.Put(r.world_valid ? 1.0 : 0.0);
    for (double v : r.T_world) w.Put(r.world_valid ? v : 0.0);
  }
}

void EncodeMarkersCommand(double seq, double time, const std::vector<MarkerDescriptionMsg>& descriptions,
                          std::vector<unsigned char>* out) {
  const std::size_t count = std::min<std::size_t>(descriptions.size(), kMaxDescriptionsPerCommand);
  Writer w(MessageType::kCommand, seq, time, count * kMarkerDescriptionValues, out);
  for (std::size_t i = 0; i < count; ++i) {
    w.Put(descriptions[i].dictionary);
    w.Put(descriptions[i].id);
    w.Put(descriptions[i].side_m);
  }
}

DecodeError ParseMarkersState(const Header& h, const std::vector<double>& p, MarkersStateMsg* m) {
  if (DecodeError e = Expect(h, MessageType::kState); e != DecodeError::kNone) return e;
  if (h.length < kMarkersStatePrefix || static_cast<std::size_t>(h.length) != p.size()) return DecodeError::kBadLength;
  if (!IsWhole(p[0], 0, kMaxMarkersPerState)) return DecodeError::kBadValue;
  const int count = static_cast<int>(p[0]);
  if (h.length != kMarkersStatePrefix + count * kMarkerRecordValues) return DecodeError::kBadLength;
  if (!IsWhole(p[1], 0, 1e9) || !IsWhole(p[2], 0, 1e9)) return DecodeError::kBadValue;
  // check every record before writing: *m is untouched on error
  for (int i = 0; i < count; ++i) {
    const double* r = p.data() + kMarkersStatePrefix + i * kMarkerRecordValues;
    if (!KnownMarker(r[0], r[1]) || !IsFlag(r[2]) || !(r[3] >= 0) || !IsTransform(r + 4) || !IsFlag(r[20])) {
      return DecodeError::kBadValue;
    }
    if (r[20] == 1.0 ? !IsTransform(r + 21) : !IsZero(r + 21)) return DecodeError::kBadValue;
  }
  m->described = static_cast<int>(p[1]);
  m->unknown = static_cast<int>(p[2]);
  m->markers.resize(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    const double* r = p.data() + kMarkersStatePrefix + i * kMarkerRecordValues;
    MarkerRecordMsg& out = m->markers[static_cast<std::size_t>(i)];
    out.dictionary = static_cast<int>(r[0]);
    out.id = static_cast<int>(r[1]);
    out.valid = r[2] == 1.0;
    out.reprojection_error_px = r[3];
    std::copy(r + 4, r + 20, out.T_camera);
    out.world_valid = r[20] == 1.0;
    std::copy(r + 21, r + 37, out.T_world);
  }
  return DecodeError::kNone;
}

DecodeError ParseMarkersCommand(const Header& h, const std::vector<double>& p,
                                std::vector<MarkerDescriptionMsg>* descriptions) {
  if (DecodeError e = Expect(h, MessageType::kCommand); e != DecodeError::kNone) return e;
  if (h.length < kMarkerDescriptionValues || h.length % kMarkerDescriptionValues != 0 ||
      static_cast<std::size_t>(h.length) != p.size()) {
    return DecodeError::kBadLength;
  }
  const int count = h.length / kMarkerDescriptionValues;
  for (int i = 0; i < count; ++i) {
    const double* d = p.data() + i * kMarkerDescriptionValues;
    if (!KnownMarker(d[0], d[1]) || !(d[2] >= 0 && d[2] <= kMaxMarkerSide_m)) return DecodeError::kBadValue;
  }
  descriptions->resize(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    const double* d = p.data() + i * kMarkerDescriptionValues;
    (*descriptions)[static_cast<std::size_t>(i)] = {static_cast<int>(d[0]), static_cast<int>(d[1]), d[2]};
  }
  return DecodeError::kNone;
}

// ---- MarkersClient ----------------------------------------------------------------

MarkersClient::MarkersClient(const std::string& address, int port, double timeout_s, const std::string& bind_address)
    : DeviceClient(DeviceKind::kMarkers, address, port, timeout_s, bind_address) {
  message_.markers.reserve(kMaxMarkersPerState);
  // the marker table, as the device described it
  const nlohmann::json markers = describe().value("markers", nlohmann::json::array());
  if (!markers.is_array()) throw ProtocolError(Label() + ": describe field \"markers\" is not an array");
  for (const nlohmann::json& entry : markers) {
    const bool ok = entry.is_object() && entry.value("code", nlohmann::json()).is_number_integer() &&
                    entry.value("id", nlohmann::json()).is_number_integer() &&
                    entry.value("side", nlohmann::json()).is_number();
    if (!ok || !KnownMarker(entry["code"].get<double>(), entry["id"].get<double>())) {
      throw ProtocolError(Label() + ": describe field \"markers\" has a bad entry: " + entry.dump());
    }
    table_.push_back({entry["code"].get<int>(), entry["id"].get<int>(), entry["side"].get<double>()});
  }
}

MarkersClient MarkersClient::Connect(const std::string& address, int port, double timeout_s,
                                     const std::string& bind_address) {
  return MarkersClient(address, port, timeout_s, bind_address);
}

DecodeError MarkersClient::ParseState(const Header& header, const std::vector<double>& payload) {
  return ParseMarkersState(header, payload, &message_);
}

MarkersClient::State MarkersClient::Copy(const Header& header) const {
  State state;
  state.seq = static_cast<std::int64_t>(header.seq);
  state.time = header.time;
  state.described = message_.described;
  state.unknown = message_.unknown;
  state.markers.reserve(message_.markers.size());
  for (const MarkerRecordMsg& r : message_.markers) {
    Marker marker;
    marker.dictionary = r.dictionary;
    marker.id = r.id;
    marker.valid = r.valid;
    marker.reprojection_error_px = r.reprojection_error_px;
    marker.T_camera_marker = Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(r.T_camera);
    marker.world_valid = r.world_valid;
    marker.T_world_marker = Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(r.T_world);
    state.markers.push_back(marker);
  }
  return state;
}

MarkersClient::State MarkersClient::Read(double timeout_s) {
  const Header& header = ReceiveState(timeout_s, false);
  last_seq_ = header.seq;
  return Copy(header);
}

MarkersClient::State MarkersClient::ReadLatest(double timeout_s) {
  const Header& header = ReceiveState(timeout_s, true);
  last_seq_ = header.seq;
  return Copy(header);
}

bool MarkersClient::AddMarkers(const std::vector<MarkerDescriptionMsg>& descriptions) {
  for (const MarkerDescriptionMsg& d : descriptions) {
    if (!KnownMarker(d.dictionary, d.id)) {
      throw std::invalid_argument(Label() + ": marker " + std::to_string(d.id) + " of dictionary code " +
                                  std::to_string(d.dictionary) + " does not exist");
    }
    if (!(d.side_m >= 0 && d.side_m <= kMaxMarkerSide_m)) {
      throw std::invalid_argument(Label() + ": marker side " + std::to_string(d.side_m) + " m outside [0, " +
                                  std::to_string(kMaxMarkerSide_m) + "]");
    }
  }
  bool sent = true;
  std::vector<MarkerDescriptionMsg> chunk;
  for (std::size_t at = 0; at < descriptions.size(); at += kMaxDescriptionsPerCommand) {
    const std::size_t end = std::min(descriptions.size(), at + kMaxDescriptionsPerCommand);
    chunk.assign(descriptions.begin() + static_cast<long>(at), descriptions.begin() + static_cast<long>(end));
    EncodeMarkersCommand(last_seq_, ClientTime(), chunk, &packet_);
    sent = Send(packet_) && sent;
  }
  return sent;
}

}  // namespace vlab::bridge

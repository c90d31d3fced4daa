"""Python client of the vlab wire protocol, version 2 (docs/protocol.md).

Standard library only (socket, struct, json, select, math, time; OpenCV's cv2 only to
decode JPEG camera frames, and only if installed): copy this file next to a script, or
put its folder on sys.path.

    from vlab_client import Arm, VELOCITY

    with Arm("127.0.0.1", 50010) as arm:          # session: cookie, describe, subscribe
        print(arm.describe()["joints"])
        state = arm.read(timeout=1.0)              # seq, time (s), status, q, qd, tau
        arm.write(VELOCITY, [0.0] * arm.joints, state.seq)

Devices: Arm (commands: hold, position, velocity, torque), Wrench (output only),
Sim (pause, resume, step, reset, realtime factor), Camera (whole frames, reassembled
from chunks; docs/protocol_camera.md), and LayoutDevice for any float64 kind (base,
gripper, feet, imu, point, yoyo, gaze, pose, ...): states decoded into fields by the
names of the device's describe layout, commands written by field name.

Connecting makes a session (docs/protocol.md, "Sessions"): the client asks for the
cookie of its address and port (a describe request without one is answered with a
challenge only), then with the cookie for the describe reply and a subscription. From
then on the device sends it one state per control period (a camera: every frame), and
to subscribers only. The device drops a subscriber silent for 10 s (its default): a
command renews the subscription, so does keep_alive(), which a client that never
writes must call now and then (every second is plenty; Camera does it by itself).
close() unsubscribes. The seq of a command must be the seq of a state it answers: one
of the newest 101 the device published, higher than the seq of the client's last
accepted command. The first accepted command makes the client the device's owner;
others are refused until the owner was silent (no command, no renewal) for the
device's owner timeout (1 s of wall clock by default). read/read_latest wait up to
their timeout; write never blocks.

    with LayoutDevice("point", "127.0.0.1", 50060) as hand:
        state = hand.read(timeout=1.0)             # state["z"], state.fields, state.values
        hand.write({"x": 0.0, "y": 0.0, "z": state["z"] + 0.01}, state.seq)

    with Camera("127.0.0.1", 50013) as camera:     # raw frames: standard library only
        frame = camera.read_latest(timeout=1.0)    # id, time, width, height, rgb, pose
        # JPEG frames are decoded with OpenCV's cv2 when it is installed

Errors: VlabError > NetworkError, ProtocolError > VersionMismatch, VlabTimeout
(also a builtin TimeoutError); ProtocolError too when the device refuses the
subscription (its subscriber table is full); ValueError for a caller's own mistake
(wrong number of values, non-finite value, negative seq). A handle is not thread-safe.
"""

import collections
import json
import math
import select
import socket
import struct
import time

MAGIC = 1447838018
PROTOCOL_VERSION = 2
HEADER_VALUES = 7
MAX_PACKET_VALUES = 1024
MAX_SEQ = 2 ** 53

# device kinds (docs/protocol.md, "Devices and ports")
KIND_ARM, KIND_WRENCH, KIND_SIM, KIND_CAMERA, KIND_MARKERS = 1, 2, 3, 4, 5
KIND_BASE, KIND_GRIPPER, KIND_FEET, KIND_IMU, KIND_POINT = 6, 7, 8, 9, 10
KIND_YOYO, KIND_GAZE, KIND_POSE, KIND_COUNTER, KIND_SCENE = 11, 12, 13, 14, 15
KIND_WORD, KIND_TOOL = 16, 17
KIND_NAMES = {KIND_ARM: "arm", KIND_WRENCH: "wrench", KIND_SIM: "sim", KIND_CAMERA: "camera",
              KIND_MARKERS: "markers", KIND_BASE: "base", KIND_GRIPPER: "gripper", KIND_FEET: "feet",
              KIND_IMU: "imu", KIND_POINT: "point", KIND_YOYO: "yoyo", KIND_GAZE: "gaze", KIND_POSE: "pose",
              KIND_COUNTER: "counter", KIND_SCENE: "scene", KIND_WORD: "word", KIND_TOOL: "tool"}
KIND_CODES = {name: code for code, name in KIND_NAMES.items()}
# kinds whose payload is not one float64 array per period: their own clients
_NOT_FLOAT64 = {KIND_CAMERA: "docs/protocol_camera.md, class Camera", KIND_MARKERS: "docs/protocol_markers.md"}
# message types: state (device -> client), command, describe and subscribe requests (client ->
# device), session reply (device -> client), an arm's payload (client -> device)
TYPE_STATE, TYPE_COMMAND, TYPE_DESCRIBE, TYPE_SUBSCRIBE, TYPE_SESSION, TYPE_PAYLOAD = 1, 2, 3, 4, 5, 6
KIND_ANY = 0  # a describe request to a device of any kind
# subscribe request actions
UNSUBSCRIBE, SUBSCRIBE = 0, 1
# session reply results (docs/protocol.md, "Sessions")
SESSION_CHALLENGE = 0     # repeat the request with this cookie
SESSION_SUBSCRIBED = 1    # subscribed (or renewed): states follow
SESSION_FULL = 2          # refused: the device has as many subscribers as it takes
SESSION_UNSUBSCRIBED = 3  # no longer subscribed
SESSION_LIMITED = 4       # describe refused by the per-source rate limit: retry later
SESSION_REFUSED = 5       # a command (a sim op) refused: another client controls the device
SESSION_PAYLOAD_SET = 6   # an arm's payload accepted: in force from the next control period
SESSION_PAYLOAD_REFUSED = 7  # an arm's payload refused: not the owner, not a rigid body, or a stale seq
REQUEST_BYTES = 8 * (HEADER_VALUES + 2)  # describe and subscribe requests, session replies: 72

# arm command modes
HOLD, POSITION, VELOCITY, TORQUE = 0, 1, 2, 3
# arm status bits
STATUS_HOLDING, STATUS_REFUSED, STATUS_SATURATED = 1, 2, 4
STATUS_AT_LIMIT, STATUS_WATCHDOG, STATUS_NOT_OWNER = 8, 16, 32
# sim operations
SIM_RESET, SIM_PAUSE, SIM_RESUME, SIM_STEP, SIM_SET_REALTIME_FACTOR = 1, 2, 3, 4, 5

_REQUEST_RETRY_S = 0.25  # resend lost requests this often while connecting


class VlabError(Exception):
    """Any failure of the client (catch this for all)."""


class NetworkError(VlabError):
    """A socket could not be opened or used, or the address is bad."""


class ProtocolError(VlabError):
    """A datagram from the device was not a valid vlab message of the expected kind."""


class VersionMismatch(ProtocolError):
    """The device speaks another protocol version."""


class VlabTimeout(VlabError, TimeoutError):
    """Nothing arrived within the time given."""


class RefusedError(VlabError):
    """The device answered that it refused a request (an arm's payload)."""


ArmState = collections.namedtuple("ArmState", "seq time status q qd tau")
ArmState.__doc__ = "seq (period k), time (s, simulated), status bits, q (rad), qd (rad/s), tau (N m): tuples"
WrenchState = collections.namedtuple("WrenchState", "seq time wrench filter saturated")
WrenchState.__doc__ = "seq, time (s), wrench (Fx Fy Fz N, Mx My Mz N m, sensor frame), filter, saturated (bool)"
SimState = collections.namedtuple(
    "SimState", "seq time sim_time mode clock periods refused_packets missed_deadlines realtime_factor max_lateness")
SimState.__doc__ = ("seq, time (s), sim_time (s), mode (0 running, 1 paused), clock (0 fast, 1 lockstep, "
                    "2 realtime), periods, refused_packets, missed_deadlines, realtime_factor, max_lateness (s)")


def _whole(value, lo, hi):
    return lo <= value <= hi and value == math.floor(value)


def _numeric_address(address):
    for family in (socket.AF_INET, socket.AF_INET6):
        try:
            socket.inet_pton(family, address)
            return True
        except (OSError, TypeError, ValueError):
            pass
    return False


def _host_name(address):
    """Letters, digits, '-' and '.', not all digits: no DNS query for "300.1.2.3"."""
    return isinstance(address, str) and address != "" and \
        all(c.isascii() and (c.isalnum() or c in "-.") for c in address) and \
        not all(c.isdigit() or c == "." for c in address)


def encode(kind, mtype, seq, t, payload):
    """One datagram: header [magic, version, kind, type, seq, time, length] + payload, little-endian float64."""
    values = [MAGIC, PROTOCOL_VERSION, kind, mtype, seq, t, len(payload)] + list(payload)
    return struct.pack("<%dd" % len(values), *values)


def encode_describe_request(kind, cookie):
    """A describe request (72 bytes) to a device of `kind` (KIND_ANY: whatever its kind) with the
    cookie of the sender's address and port (0 before the device gave one: only a challenge comes
    back)."""
    return encode(kind, TYPE_DESCRIBE, 0, 0, [cookie, 0])


def encode_subscribe_request(kind, cookie, action):
    """A subscribe request (72 bytes) to a device of `kind`: action SUBSCRIBE (or renew) or
    UNSUBSCRIBE, with the cookie the device gave."""
    return encode(kind, TYPE_SUBSCRIBE, 0, 0, [cookie, action])


def is_session_reply(data):
    """True for a session reply of this protocol version (72 bytes, type 5): read functions skip
    the replies to renewals."""
    if len(data) != REQUEST_BYTES:
        return False
    magic, version, _, mtype = struct.unpack_from("<4d", data)
    return magic == MAGIC and version == PROTOCOL_VERSION and mtype == TYPE_SESSION


def parse_session_reply(data):
    """(kind, cookie, result) of a session reply, the cookie a whole number 1 <= cookie < 2^53 and
    the result one of SESSION_*; None if the datagram is not one."""
    if not is_session_reply(data):
        return None
    try:
        kind, mtype, _, _, payload = decode(data)
    except ProtocolError:
        return None
    cookie, result = payload
    if not _whole(cookie, 1, MAX_SEQ - 1) or not _whole(result, SESSION_CHALLENGE, SESSION_PAYLOAD_REFUSED):
        return None
    return kind, int(cookie), int(result)


def decode(data):
    """Checks a datagram's framing (the checks of the C++ DecodePacket: size, magic, version,
    finiteness, kind 0..255, type 1..6, seq, length); returns (kind, type, seq, time, payload) or
    raises ProtocolError (VersionMismatch for another protocol version)."""
    size = len(data)
    if size < 8 * HEADER_VALUES or size % 8:
        raise ProtocolError("too short (%d bytes)" % size)
    if size // 8 > MAX_PACKET_VALUES:
        raise ProtocolError("too long (%d bytes)" % size)
    values = struct.unpack("<%dd" % (size // 8), data)
    magic, version, kind, mtype, seq, t, length = values[:HEADER_VALUES]
    if magic != MAGIC:
        raise ProtocolError("bad magic")
    if version != PROTOCOL_VERSION:
        raise VersionMismatch("the device sent a packet of protocol version %g, this client speaks version %d"
                              % (version, PROTOCOL_VERSION))
    if not all(math.isfinite(v) for v in values):
        raise ProtocolError("non-finite value")
    if not _whole(kind, KIND_ANY, 255):
        raise ProtocolError("bad kind")
    if not _whole(mtype, TYPE_STATE, TYPE_PAYLOAD):
        raise ProtocolError("bad type")
    if not _whole(seq, 0, MAX_SEQ):
        raise ProtocolError("bad seq")
    if length != len(values) - HEADER_VALUES:
        raise ProtocolError("bad length")
    return int(kind), int(mtype), int(seq), t, values[HEADER_VALUES:]


class Device:
    """What every device handle shares: socket, session, describe reply, reception of states."""

    KIND = None

    def __init__(self, address="127.0.0.1", port=None, timeout=1.0, bind_address=None):
        """Connects: makes a session with address:port (the cookie, then with it the describe reply
        and a subscription), resending lost requests, within `timeout` s; states arriving meanwhile
        are checked for their kind and skipped. Raises NetworkError (bad address), VlabTimeout (no
        answer, no describe reply or no subscription), VersionMismatch, ProtocolError (wrong kind,
        bad reply, subscription refused: the device's subscriber table is full)."""
        if not isinstance(port, int) or not 1 <= port <= 65535:
            raise NetworkError("port %r out of range 1..65535" % (port,))
        if not _numeric_address(address) and not _host_name(address):
            raise NetworkError("address %r is neither an IP address nor a host name" % (address,))
        try:
            infos = socket.getaddrinfo(address, port, 0, socket.SOCK_DGRAM)
        except (socket.gaierror, UnicodeError) as e:
            raise NetworkError("address %r: %s" % (address, e)) from None
        infos.sort(key=lambda info: info[0] != socket.AF_INET)  # IPv4 first
        family, _, _, _, self._device = infos[0]
        self._label = "%s at %s:%d" % (KIND_NAMES[self.KIND], self._device[0], self._device[1])
        self._sock = socket.socket(family, socket.SOCK_DGRAM)
        try:
            self._sock.bind((bind_address or ("0.0.0.0" if family == socket.AF_INET else "::"), 0))
            self._sock.setblocking(False)
        except OSError as e:
            self._sock.close()
            raise NetworkError("%s: cannot open a UDP socket: %s" % (self._label, e)) from None
        self._start = time.monotonic()
        self.cookie = 0   # the cookie of this client's address and port, given by the device
        self.skipped = 0  # datagrams skipped: describe and session replies, other senders
        try:
            self._describe = self._connect(timeout)
        except BaseException:
            self.close()
            raise
        self.name = self._describe.get("name", "")
        if isinstance(self.name, str) and self.name:
            self._label = "%s '%s' at %s:%d" % (KIND_NAMES[self.KIND], self.name, self._device[0], self._device[1])

    def _connect(self, timeout):
        """The handshake of docs/protocol.md ("Sessions"), as the C++ ClientSession::Connect: a
        describe request without a cookie brings the challenge; with its cookie, the describe
        request and the subscribe request are resent until the JSON and the subscription came.
        Returns the checked describe reply."""
        deadline = time.monotonic() + timeout
        resend = 0.0
        reply, subscribed = None, False
        while True:
            now = time.monotonic()
            if now >= resend:  # first the cookie, then (with it) the reply and the subscription
                sent = True
                if reply is None:
                    sent = self._send(encode_describe_request(self.KIND, self.cookie))
                if self.cookie and not subscribed:
                    sent = self.keep_alive() and sent
                if not sent:
                    raise NetworkError("%s: cannot send to the device" % self._label)
                resend = now + _REQUEST_RETRY_S
            data = self._receive(min(deadline, resend))
            if data is None:
                if time.monotonic() < deadline:
                    continue
                missing = "no answer" if not self.cookie else "no describe reply" if reply is None \
                    else "no subscription"
                raise VlabTimeout("%s: %s within %g s (is a device of this kind and protocol version %d serving "
                                  "that address and port?)" % (self._label, missing, timeout, PROTOCOL_VERSION))
            if data[:1] == b"{":
                if reply is None:
                    reply = self._check_describe(data)
            elif is_session_reply(data):
                session = parse_session_reply(data)
                if session is None:
                    continue
                _, cookie, result = session
                if result == SESSION_FULL:
                    raise ProtocolError("%s: the device refused the subscription: its subscriber table is full "
                                        "(it has as many subscribers as it takes)" % self._label)
                if result == SESSION_CHALLENGE and cookie != self.cookie:
                    self.cookie = cookie
                    resend = time.monotonic()  # at once, with the cookie
                if result == SESSION_SUBSCRIBED:
                    subscribed = True
                # SESSION_LIMITED: the describe request goes again at the next resend
            else:
                self._frame(data)  # a state may come first; anything else raises
            if reply is not None and subscribed:
                return reply

    def _check_describe(self, data):
        try:
            reply = json.loads(data.decode("utf-8"))
        except (UnicodeDecodeError, ValueError) as e:
            raise ProtocolError("%s: describe reply is not valid JSON: %s" % (self._label, e)) from None
        if not isinstance(reply, dict):
            raise ProtocolError("%s: describe reply is not a JSON object" % self._label)
        version = reply.get("protocol")
        if not isinstance(version, (int, float)) or isinstance(version, bool):
            raise ProtocolError('%s: describe reply has no numeric "protocol"' % self._label)
        if version != PROTOCOL_VERSION:
            raise VersionMismatch("%s: the device speaks protocol version %s, this client speaks version %d"
                                  % (self._label, json.dumps(version), PROTOCOL_VERSION))
        kind = reply.get("kind")
        if kind != KIND_NAMES[self.KIND]:
            raise ProtocolError('%s: the device is of kind %s, not "%s"' % (self._label, json.dumps(kind),
                                                                          KIND_NAMES[self.KIND]))
        return reply

    def describe(self):
        """The device's describe reply (a dict), as received at connect."""
        return self._describe

    @property
    def endpoint(self):
        """The device's (address, port)."""
        return self._device[:2]

    @property
    def local_port(self):
        """The local UDP port the states arrive on."""
        return self._sock.getsockname()[1]

    def keep_alive(self):
        """Renews the subscription (a subscribe request with the cookie) without waiting: read skips
        the device's reply. The device drops a subscriber silent for its subscriber timeout (10 s by
        default): a client that never writes must call this now and then (every second is plenty).
        A renewal also keeps an owner the owner. False if the datagram could not be sent."""
        return self._send(encode_subscribe_request(self.KIND, self.cookie, SUBSCRIBE))

    def read(self, timeout=1.0):
        """The next state, waiting up to `timeout` s. Raises VlabTimeout, or ProtocolError on a
        malformed state."""
        deadline = time.monotonic() + timeout
        while True:
            data = self._receive(deadline)
            if data is None:
                raise VlabTimeout("%s: no state within %g s" % (self._label, timeout))
            state = self._state(data)
            if state is not None:
                return state

    def read_latest(self, timeout=1.0):
        """Waits up to `timeout` s for at least one state, then drains the queue and returns the
        newest: what a real-time controller wants. Raises as read."""
        state = self.read(timeout)
        while True:
            data = self._receive(0.0)
            if data is None:
                return state
            newer = self._state(data)
            if newer is not None:
                state = newer

    def close(self):
        """Unsubscribes (a subscribe request with action UNSUBSCRIBE, no reply awaited; an owner
        gives its command input up with it) and closes the socket. Closing twice does nothing."""
        if self._sock.fileno() < 0:
            return
        if self.cookie:
            self._send(encode_subscribe_request(self.KIND, self.cookie, UNSUBSCRIBE))
        self._sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ---- private ----------------------------------------------------------------------

    def _send(self, data):
        try:
            self._sock.sendto(data, self._device)
            return True
        except OSError:  # includes BlockingIOError: never block
            return False

    def _receive(self, deadline):
        """One datagram from the device's port before the deadline (monotonic s), or None."""
        while True:
            left = max(0.0, deadline - time.monotonic())
            ready, _, _ = select.select([self._sock], [], [], left)
            if not ready:
                return None
            try:
                data, sender = self._sock.recvfrom(65536)
            except (BlockingIOError, InterruptedError):
                continue
            except OSError as e:  # e.g. ICMP port unreachable reported on some systems
                raise NetworkError("%s: %s" % (self._label, e)) from None
            # a multi-homed device may answer from another address, never from another port
            if sender[1] != self._device[1]:
                self.skipped += 1
                continue
            return data

    def _frame(self, data):
        """Checks a state datagram's framing, kind and type; returns (seq, time, payload)."""
        try:
            kind, mtype, seq, t, payload = decode(data)
            if kind != self.KIND:
                raise ProtocolError("wrong device kind")
            if mtype != TYPE_STATE:
                raise ProtocolError("wrong message type")
        except VersionMismatch as e:
            raise VersionMismatch("%s: %s" % (self._label, e)) from None
        except ProtocolError as e:
            raise ProtocolError("%s: malformed state datagram (%d bytes): %s" % (self._label, len(data), e)) from None
        return seq, t, payload

    def _state(self, data):
        if data[:1] == b"{" or is_session_reply(data):  # a describe reply, or the answer to a renewal
            self.skipped += 1
            return None
        seq, t, payload = self._frame(data)
        try:
            return self._parse(seq, t, payload)
        except ProtocolError as e:
            raise ProtocolError("%s: malformed state datagram (%d bytes): %s" % (self._label, len(data), e)) from None

    def _time(self):
        return time.monotonic() - self._start

    @staticmethod
    def _check_seq(seq):
        if isinstance(seq, bool) or not isinstance(seq, int) or not 0 <= seq <= MAX_SEQ:
            raise ValueError("command seq %r is not a whole number in 0..2^53" % (seq,))


class Arm(Device):
    """A robot arm: n joints, commanded in HOLD, POSITION (rad), VELOCITY (rad/s) or TORQUE (N m)."""

    KIND = KIND_ARM

    def __init__(self, address="127.0.0.1", port=50010, timeout=1.0, bind_address=None):
        super().__init__(address, port, timeout, bind_address)
        names = self._describe.get("joints")
        if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
            self.close()
            raise ProtocolError('%s: describe reply has no "joints" array of names' % self._label)
        self.joint_names = list(names)
        self.joints = len(names)
        self._payload_seq = 0  # seq of the last payload sent: this handle's own counter
        limits = self._describe.get("limits") or {}
        try:
            self.position_min = self._limit(limits, "position_min")
            self.position_max = self._limit(limits, "position_max")
            self.velocity_max = self._limit(limits, "velocity_max")
            self.torque_max = self._limit(limits, "torque_max")
        except ProtocolError:
            self.close()
            raise

    def _limit(self, limits, field):
        """One limit per joint (rad, rad/s, N m), or [] where the device has none."""
        values = limits.get(field, []) if isinstance(limits, dict) else []
        if not isinstance(values, list) or (values and len(values) != self.joints) or \
                not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
            raise ProtocolError("%s: describe field limits.%s is not an array of %d numbers"
                                % (self._label, field, self.joints))
        return [float(v) for v in values]

    def _parse(self, seq, t, payload):
        n = self.joints
        if len(payload) != 1 + 3 * n:
            raise ProtocolError("bad length")
        if not _whole(payload[0], 0, 2 ** 32 - 1):
            raise ProtocolError("value out of domain")
        return ArmState(seq, t, int(payload[0]), tuple(payload[1:1 + n]), tuple(payload[1 + n:1 + 2 * n]),
                        tuple(payload[1 + 2 * n:]))

    def write(self, mode, values, seq):
        """Sends a command answering state `seq`: mode (HOLD, POSITION, VELOCITY, TORQUE) and one
        value per joint (rad, rad/s, N m; may be empty for HOLD). Never blocks; returns False
        if the datagram could not be sent. Raises ValueError on a bad mode, value count,
        non-finite value or seq. The arm ignores a seq outside its newest 101 states or not
        above the last accepted one; acceptance shows in the status bits of the next states
        (STATUS_REFUSED, STATUS_NOT_OWNER)."""
        if mode not in (HOLD, POSITION, VELOCITY, TORQUE):
            raise ValueError("arm mode %r is not 0..3" % (mode,))
        values = [float(v) for v in values]
        if mode == HOLD and not values:
            values = [0.0] * self.joints
        if len(values) != self.joints:
            raise ValueError("%s: command has %d values, the arm has %d joints" % (self._label, len(values),
                                                                                  self.joints))
        if not all(math.isfinite(v) for v in values):
            raise ValueError("%s: command has a non-finite value" % self._label)
        self._check_seq(seq)
        return self._send(encode(KIND_ARM, TYPE_COMMAND, seq, self._time(), [mode] + values))

    def set_payload(self, mass, com=(0.0, 0.0, 0.0), inertia=(0.0, 0.0, 0.0), timeout=1.0):
        """Declares the load at the flange (docs/protocol.md, "Arm payload"): mass (kg, >= 0), com
        (x, y, z m) and inertia about it (ixx, iyy, izz[, ixy, ixz, iyz] kg m^2), flange frame; then
        waits up to `timeout` s for the device's answer. In force from the device's next control
        period. States that arrive meanwhile are skipped. Each payload sent carries the next value
        of this handle's own payload counter (1, 2, 3, ...) as its seq: the device refuses a seq
        not above the last it took, so a late or replayed copy of an older payload cannot set it
        again. Raises ValueError for a bad count, a non-finite value or a negative mass,
        RefusedError when the device refuses it (another client owns the arm, or the inertia is no
        rigid body's), VlabTimeout when no answer came."""
        com = [float(v) for v in com]
        inertia = [float(v) for v in inertia]
        if len(com) != 3:
            raise ValueError("%s: payload com needs 3 values (x, y, z m), got %d" % (self._label, len(com)))
        if len(inertia) not in (3, 6):
            raise ValueError("%s: payload inertia needs 3 or 6 values (kg m^2), got %d" % (self._label, len(inertia)))
        inertia += [0.0] * (6 - len(inertia))
        values = [float(mass)] + com + inertia
        if not all(math.isfinite(v) for v in values):
            raise ValueError("%s: payload has a non-finite value" % self._label)
        if values[0] < 0:
            raise ValueError("%s: payload mass must be >= 0 kg, got %g" % (self._label, values[0]))
        self._payload_seq += 1
        if not self._send(encode(KIND_ARM, TYPE_PAYLOAD, self._payload_seq, self._time(), values)):
            raise NetworkError("%s: cannot send the payload" % self._label)
        deadline = time.monotonic() + timeout
        while True:
            data = self._receive(deadline)
            if data is None:
                raise VlabTimeout("%s: no answer to the payload within %g s" % (self._label, timeout))
            reply = parse_session_reply(data)
            if reply is not None and reply[2] == SESSION_PAYLOAD_SET:
                self._describe["payload"] = {"mass": values[0], "com": com, "inertia": inertia}
                return
            if reply is not None and reply[2] == SESSION_PAYLOAD_REFUSED:
                raise RefusedError("%s: the device refused the payload (another client owns the arm, or the "
                                   "device found it no rigid body or its seq not above the last one it took)"
                                   % self._label)
            self.skipped += 1  # a state, a describe reply or the answer to a renewal

    @property
    def payload(self):
        """The payload the device reports, {"mass", "com", "inertia"}: its describe reply's at
        connect, or the last one set_payload set; None when the reply has none."""
        return self._describe.get("payload")


class Wrench(Device):
    """A force/torque sensor (output only). Call keep_alive() now and then to stay subscribed."""

    KIND = KIND_WRENCH

    def __init__(self, address="127.0.0.1", port=50011, timeout=1.0, bind_address=None):
        super().__init__(address, port, timeout, bind_address)

    def _parse(self, seq, t, payload):
        if len(payload) != 8:
            raise ProtocolError("bad length")
        if not _whole(payload[6], 0, 6) or not _whole(payload[7], 0, 1):
            raise ProtocolError("value out of domain")
        return WrenchState(seq, t, tuple(payload[:6]), int(payload[6]), payload[7] != 0)


class Sim(Device):
    """The simulation's control device: SIM_RESET, SIM_PAUSE, SIM_RESUME, SIM_STEP (arg periods),
    SIM_SET_REALTIME_FACTOR (arg factor). Its state's seq counts the states it sent (the state sent
    again after an operation while paused has a seq of its own, for the next operation to answer);
    `periods` is the control period. An owner that pauses must keep writing or call keep_alive()
    within the owner timeout (1 s of wall clock by default), or it loses the sim and the lab
    resumes (or stays paused, as the scenario says)."""

    KIND = KIND_SIM

    def __init__(self, address="127.0.0.1", port=50012, timeout=1.0, bind_address=None):
        super().__init__(address, port, timeout, bind_address)

    def _parse(self, seq, t, payload):
        if len(payload) != 8:
            raise ProtocolError("bad length")
        if not _whole(payload[1], 0, 1) or not _whole(payload[2], 0, 2):
            raise ProtocolError("value out of domain")
        p = payload
        return SimState(seq, t, p[0], int(p[1]), int(p[2]), p[3], p[4], p[5], p[6], p[7])

    def write(self, op, arg, seq):
        """Sends an operation answering state `seq` (the seq of the newest state read: each
        operation answers a state of its own). Never blocks; False if not sent. Raises
        ValueError on an unknown op, a non-finite arg or a bad seq."""
        if op not in (SIM_RESET, SIM_PAUSE, SIM_RESUME, SIM_STEP, SIM_SET_REALTIME_FACTOR):
            raise ValueError("sim op %r is not 1..5" % (op,))
        if not math.isfinite(arg):
            raise ValueError("%s: sim command arg is not finite" % self._label)
        self._check_seq(seq)
        return self._send(encode(KIND_SIM, TYPE_COMMAND, seq, self._time(), [op, float(arg)]))


# ---- any float64 kind, by the layout of its describe reply -----------------------------------


class LayoutState:
    """One state of a LayoutDevice: seq (period k), time (s), values (the payload, a tuple, in the
    order of the describe reply's layout.state) and fields (a dict: field name -> value, or a
    tuple of values for a group such as "q[7]"). state["grasped"] is state.fields["grasped"]."""

    __slots__ = ("seq", "time", "values", "fields")

    def __init__(self, seq, t, values, fields):
        self.seq, self.time, self.values, self.fields = seq, t, values, fields

    def __getitem__(self, name):
        try:
            return self.fields[name]
        except KeyError:
            raise KeyError("no state field %r (the fields are %s)" % (name, ", ".join(self.fields))) from None

    def __contains__(self, name):
        return name in self.fields

    def __repr__(self):
        return "LayoutState(seq=%d, time=%g, %s)" % (
            self.seq, self.time, ", ".join("%s=%r" % item for item in self.fields.items()))


def _layout_fields(fields, label, part):
    """[(name, count or None)] of a describe layout list: "x" is one value, "q[7]" a group of 7."""
    if not isinstance(fields, list):
        raise ProtocolError("%s: describe reply has no layout.%s list" % (label, part))
    out = []
    for f in fields:
        if not isinstance(f, str) or not f:
            raise ProtocolError("%s: describe layout.%s holds %s, not a field name" % (label, part, json.dumps(f)))
        name, count = f, None
        if f.endswith("]") and "[" in f:
            name, _, size = f[:-1].partition("[")
            if not size.isdigit() or not 0 < int(size) <= MAX_PACKET_VALUES:
                raise ProtocolError("%s: describe layout.%s field '%s' has no whole count" % (label, part, f))
            count = int(size)
        if any(name == other for other, _ in out):
            raise ProtocolError("%s: describe layout.%s names '%s' twice" % (label, part, name))
        out.append((name, count))
    return out


def _value_count(fields):
    return sum(1 if count is None else count for _, count in fields)


class LayoutDevice(Device):
    """A device of any float64 kind (base, gripper, feet, imu, point, yoyo, gaze, pose; arm, wrench
    and sim too), read and written by field name. The fields are the describe reply's layout, the
    names of the tables of docs/protocol.md ("q[7]" is a group of 7 values).

        with LayoutDevice("gripper", "127.0.0.1", 50050) as gripper:
            state = gripper.read()                            # a LayoutState
            if state["grasped"]: ...
            gripper.write({"mode": 0, "value": 0.04}, state.seq)

    No domain checks beyond the layout's lengths: the device refuses what it does not take (and
    says so in its status value, where it has one)."""

    def __init__(self, kind, address="127.0.0.1", port=None, timeout=1.0, bind_address=None):
        """kind: a name ("gripper") or code (7). Connects as Device does; raises ValueError for an
        unknown kind or one that is not a float64 kind (camera, markers), ProtocolError for a
        describe reply without a usable layout."""
        code = KIND_CODES.get(kind) if isinstance(kind, str) else kind
        if isinstance(code, bool) or code not in KIND_NAMES:
            raise ValueError("device kind %r is not one of %s" % (kind, ", ".join(KIND_CODES)))
        if code in _NOT_FLOAT64:
            raise ValueError("%s devices are not float64 arrays: see %s" % (KIND_NAMES[code], _NOT_FLOAT64[code]))
        self.KIND = code
        super().__init__(address, port, timeout, bind_address)
        try:
            layout = self._describe.get("layout")
            if not isinstance(layout, dict):
                raise ProtocolError("%s: describe reply has no layout" % self._label)
            self.state_fields = _layout_fields(layout.get("state"), self._label, "state")
            self.command_fields = _layout_fields(layout.get("command", []), self._label, "command")
        except ProtocolError:
            self.close()
            raise
        self.state_length = _value_count(self.state_fields)
        self.command_length = _value_count(self.command_fields)

    @property
    def kind(self):
        """The device's kind name ("gripper")."""
        return KIND_NAMES[self.KIND]

    @property
    def state_names(self):
        """The state's field names, in payload order (a group counts once)."""
        return [name for name, _ in self.state_fields]

    @property
    def command_names(self):
        """The command's field names, in payload order (a group counts once)."""
        return [name for name, _ in self.command_fields]

    def _parse(self, seq, t, payload):
        if len(payload) != self.state_length:
            raise ProtocolError("bad length")
        fields, at = {}, 0
        for name, count in self.state_fields:
            if count is None:
                fields[name] = payload[at]
                at += 1
            else:
                fields[name] = tuple(payload[at:at + count])
                at += count
        return LayoutState(seq, t, tuple(payload), fields)

    def write(self, fields, seq):
        """Sends a command answering state `seq`: `fields` maps every command field name to its
        value (a sequence of values for a group), e.g. {"x": 0.1, "y": 0.0, "z": 1.5}. Never
        blocks; returns False if the datagram could not be sent. Raises ValueError naming the
        device and the field for an unknown or missing field, a group of the wrong length or a
        non-finite value, and when the device takes no commands. The seq rules are Arm.write's."""
        if not self.command_fields:
            raise ValueError("%s: this device takes no commands" % self._label)
        if not isinstance(fields, dict):
            raise ValueError("%s: a command is a dict of field name -> value" % self._label)
        unknown = [name for name in fields if name not in self.command_names]
        if unknown:
            raise ValueError("%s: no command field %r (the fields are %s)"
                             % (self._label, unknown[0], ", ".join(self.command_names)))
        payload = []
        for name, count in self.command_fields:
            if name not in fields:
                raise ValueError("%s: command field %r not given" % (self._label, name))
            value = fields[name]
            values = [value] if count is None else list(value)
            if count is not None and len(values) != count:
                raise ValueError("%s: command field %r has %d values, not %d" % (self._label, name, len(values),
                                                                                  count))
            try:
                values = [float(v) for v in values]
            except (TypeError, ValueError):
                raise ValueError("%s: command field %r is not a number" % (self._label, name)) from None
            if not all(math.isfinite(v) for v in values):
                raise ValueError("%s: command field %r is not finite" % (self._label, name))
            payload.extend(values)
        self._check_seq(seq)
        return self._send(encode(self.KIND, TYPE_COMMAND, seq, self._time(), payload))


# ---- camera (kind 4): frames in chunks, docs/protocol_camera.md ------------------------------

ENCODING_RAW, ENCODING_JPEG = 0, 1
ENCODING_NAMES = {ENCODING_RAW: "raw", ENCODING_JPEG: "jpeg"}
CHUNK_VALUES = 16                                      # chunk values after the 7-value header
CHUNK_HEADER_BYTES = 8 * (HEADER_VALUES + CHUNK_VALUES)  # 184: then the chunk's frame bytes
MAX_IMAGE_SIDE = 16384
MAX_CHUNKS = 65535

CameraFrame = collections.namedtuple(
    "CameraFrame", "id time width height encoding data rgb pose_valid position orientation")
CameraFrame.__doc__ = (
    "id (frame number), time (s, middle of the exposure), width, height (px), encoding ('raw' or "
    "'jpeg'), data (the frame's bytes as sent), rgb (RGB8 bytes, rows top-down, width*height*3; None "
    "when not decoded), pose_valid, position (x, y, z m) and orientation (w, x, y, z) of the OpenCV "
    "camera frame (x right, y down, z forward) in the world. As a numpy image: "
    "numpy.frombuffer(frame.rgb, numpy.uint8).reshape(frame.height, frame.width, 3).")
Chunk = collections.namedtuple(
    "Chunk", "frame_id time index count width height encoding frame_bytes offset size pose_valid position "
             "orientation data")
Chunk.__doc__ = "One decoded camera chunk; data is a memoryview of its frame bytes."


class ChunkError(ProtocolError):
    """A camera chunk breaks a rule of docs/protocol_camera.md; `reason` names which."""

    def __init__(self, reason):
        super().__init__(reason)
        self.reason = reason


def decode_chunk(data):
    """Checks one camera chunk datagram and splits it (the same checks, in the same order, as the
    C++ decoder). Returns a Chunk; raises ChunkError(reason) or VersionMismatch."""
    size = len(data)
    if size < 8 * HEADER_VALUES:
        raise ChunkError("too short")
    header = struct.unpack_from("<7d", data)
    magic, version, kind, mtype, seq, t, length = header
    if magic != MAGIC:
        raise ChunkError("bad magic")
    if version != PROTOCOL_VERSION:
        raise VersionMismatch("the device sent a chunk of protocol version %g, this client speaks version %d"
                              % (version, PROTOCOL_VERSION))
    if not all(math.isfinite(v) for v in header):
        raise ChunkError("non-finite value")
    if kind != KIND_CAMERA:
        raise ChunkError("wrong device kind")
    if mtype != TYPE_STATE:
        raise ChunkError("wrong message type")
    if not _whole(seq, 0, MAX_SEQ):
        raise ChunkError("value out of domain")
    if not _whole(length, CHUNK_VALUES, MAX_PACKET_VALUES - HEADER_VALUES):
        raise ChunkError("bad length")
    head = 8 * (HEADER_VALUES + int(length))
    if size < head:
        raise ChunkError("too short")
    c = struct.unpack_from("<%dd" % int(length), data, 8 * HEADER_VALUES)
    if not all(math.isfinite(v) for v in c):
        raise ChunkError("non-finite value")
    index, count, width, height, encoding, frame_bytes, offset, nbytes, pose_valid = c[:9]
    # the image
    if not _whole(width, 1, MAX_IMAGE_SIDE) or not _whole(height, 1, MAX_IMAGE_SIDE) or \
            not _whole(encoding, 0, 1) or not _whole(frame_bytes, 1, 3.0 * MAX_IMAGE_SIDE * MAX_IMAGE_SIDE) or \
            (encoding == ENCODING_RAW and frame_bytes != 3 * width * height):
        raise ChunkError("bad image size or encoding")
    # the layout: chunks of P bytes, chunk i at i * P, the last one ends at frame_bytes
    if not _whole(count, 1, MAX_CHUNKS) or not _whole(index, 0, count - 1) or \
            not _whole(offset, 0, frame_bytes - 1) or not _whole(nbytes, 1, frame_bytes - offset):
        raise ChunkError("bad chunk layout")
    if nbytes != size - head:
        raise ChunkError("bad length")
    if index < count - 1:
        if offset != index * nbytes or math.ceil(frame_bytes / nbytes) != count:
            raise ChunkError("bad chunk layout")
    elif offset + nbytes != frame_bytes or (count == 1 and offset != 0) or \
            (count > 1 and (math.fmod(offset, count - 1) != 0 or offset / (count - 1) < nbytes)):
        raise ChunkError("bad chunk layout")
    # the pose
    if not _whole(pose_valid, 0, 1):
        raise ChunkError("bad pose")
    q = c[12:16]
    if pose_valid == 1 and abs(sum(v * v for v in q) - 1.0) > 2e-6:
        raise ChunkError("bad pose")
    return Chunk(int(seq), t, int(index), int(count), int(width), int(height), int(encoding), int(frame_bytes),
                 int(offset), int(nbytes), pose_valid == 1, tuple(c[9:12]), tuple(q), memoryview(data)[head:])


class _Partial:
    """A frame being reassembled."""

    def __init__(self, chunk, now):
        self.key = chunk[:2] + chunk[3:4] + chunk[4:8] + chunk[10:13]  # id, time, count, size, pose
        self.piece = _piece(chunk)
        self.started = now
        self.received = 0
        self.have = bytearray(chunk.count)
        self.data = bytearray(chunk.frame_bytes)
        self.chunk = chunk


def _piece(chunk):
    """P: the bytes of every chunk but the last."""
    if chunk.index < chunk.count - 1:
        return chunk.size
    return chunk.offset // (chunk.count - 1) if chunk.count > 1 else chunk.frame_bytes


class _FrameAssembler:
    """Reassembly by frame id with the drop rules of docs/protocol_camera.md ("Reassembly")."""

    def __init__(self, slots=4, timeout=1.0, max_frame_bytes=64 << 20, restart_gap=64, restart_time=1.0):
        self.slots, self.timeout, self.max_frame_bytes = slots, timeout, max_frame_bytes
        self.restart_gap, self.restart_time = restart_gap, restart_time
        self.counters = {name: 0 for name in (
            "chunks", "accepted", "duplicates", "late", "refused", "frames_completed", "frames_dropped",
            "dropped_superseded", "dropped_timeout", "dropped_evicted", "overwritten", "restarts")}
        self.refused_by = collections.Counter()
        self._partial = {}
        self._ready = None
        self._floor_id, self._floor_time = -1, 0.0

    def _drop(self, frame_id, reason):
        p = self._partial.pop(frame_id)
        self.counters["frames_dropped"] += 1
        self.counters[reason] += 1
        if frame_id > self._floor_id:
            self._floor_id, self._floor_time = frame_id, p.chunk.time

    def expire(self, now):
        for frame_id in [i for i, p in self._partial.items() if now - p.started > self.timeout]:
            self._drop(frame_id, "dropped_timeout")

    def _refuse(self, reason):
        self.counters["refused"] += 1
        self.refused_by[reason] += 1
        return "refused"

    def add(self, data, now):
        """Offers one datagram (receiver clock `now`, s); returns 'refused', 'accepted', 'duplicate',
        'late' or 'completed'. Raises VersionMismatch for a chunk of another protocol version."""
        self.counters["chunks"] += 1
        try:
            c = decode_chunk(data)
        except VersionMismatch:
            self._refuse("bad version")
            raise
        except ChunkError as e:
            return self._refuse(e.reason)
        if c.frame_bytes > self.max_frame_bytes:
            return self._refuse("frame too large")
        self.expire(now)
        if c.frame_id <= self._floor_id:
            if self._floor_id - c.frame_id <= self.restart_gap and c.time >= self._floor_time - self.restart_time:
                self.counters["late"] += 1
                return "late"
            self.counters["restarts"] += 1  # the sender started again: forget the old stream
            self.counters["frames_dropped"] += len(self._partial)
            self._partial.clear()
            self._floor_id, self._floor_time = -1, 0.0
        p = self._partial.get(c.frame_id)
        if p is None:
            if len(self._partial) >= self.slots:
                oldest = min(self._partial)
                if c.frame_id < oldest:
                    self.counters["late"] += 1
                    return "late"
                self._drop(oldest, "dropped_evicted")
            p = self._partial[c.frame_id] = _Partial(c, now)
        elif p.key != c[:2] + c[3:4] + c[4:8] + c[10:13] or p.piece != _piece(c):
            return self._refuse("inconsistent with its frame")
        if p.have[c.index]:
            self.counters["duplicates"] += 1
            return "duplicate"
        p.data[c.offset:c.offset + c.size] = c.data
        p.have[c.index] = 1
        p.received += 1
        self.counters["accepted"] += 1
        if p.received < c.count:
            return "accepted"
        # complete: older frames still in progress can no longer be shown in order
        del self._partial[c.frame_id]
        if self._ready is not None:
            self.counters["overwritten"] += 1
        self._ready = (c, bytes(p.data))
        self.counters["frames_completed"] += 1
        self._floor_id, self._floor_time = c.frame_id, c.time
        for frame_id in [i for i in self._partial if i < c.frame_id]:
            self._drop(frame_id, "dropped_superseded")
        return "completed"

    def take(self):
        """The completed frame as (last chunk, bytes), or None."""
        ready, self._ready = self._ready, None
        return ready


_CV2 = []  # [module or None], imported on first need


def _cv2():
    if not _CV2:
        try:
            import cv2  # noqa: F401  (optional: JPEG frames only)
            _CV2.append(cv2)
        except ImportError:
            _CV2.append(None)
    return _CV2[0]


class Camera(Device):
    """A camera (webcam, simulated or real): whole frames, never torn. read()/read_latest() return
    CameraFrame tuples. Raw frames need nothing but the standard library; JPEG frames are decoded
    with OpenCV's Python module (cv2) when installed (decode=False gives the JPEG bytes alone).
    The client renews its subscription every `keepalive` s while reading, so it never lapses;
    close() unsubscribes. Incomplete frames are dropped; malformed chunks are counted (counters,
    refused_by), not raised."""

    KIND = KIND_CAMERA

    def __init__(self, address="127.0.0.1", port=50013, timeout=1.0, bind_address=None, decode=True,
                 receive_buffer=8 << 20, keepalive=1.0, frame_timeout=1.0, slots=4, max_frame_bytes=64 << 20):
        """Connects as Device does, then checks the reply's width, height, fps, encoding and
        intrinsics. Raises VlabError when the camera sends JPEG, decode is on and cv2 is missing."""
        self._assembler = _FrameAssembler(slots, frame_timeout, max_frame_bytes)
        self._decode = decode
        self._keepalive = keepalive
        self.undecodable = 0      # whole frames whose JPEG did not decode to their size
        self.frames_skipped = 0   # whole frames read_latest passed over
        super().__init__(address, port, timeout, bind_address)
        try:
            self._check_camera()
        except BaseException:
            self.close()
            raise
        self.receive_buffer = self._grow_receive_buffer(receive_buffer)
        self._next_keepalive = time.monotonic() + keepalive

    def _grow_receive_buffer(self, size):
        """A raw VGA frame is 16 datagrams of 60 kB sent back to back: ask for a large buffer (forced
        where permitted). Returns what the kernel granted, as getsockopt reports it."""
        try:
            self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, size)
            force = getattr(socket, "SO_RCVBUFFORCE", None)
            if force is not None and self._sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF) < 2 * size:
                self._sock.setsockopt(socket.SOL_SOCKET, force, size)
        except OSError:
            pass  # no permission to force: keep what the system allows
        return self._sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)

    def _check_camera(self):
        d = self._describe

        def number(obj, field, path):
            v = obj.get(field) if isinstance(obj, dict) else None
            if not isinstance(v, (int, float)) or isinstance(v, bool):
                raise ProtocolError('%s: describe reply has no number "%s"' % (self._label, path))
            return v

        self.width = int(number(d, "width", "width"))
        self.height = int(number(d, "height", "height"))
        self.fps = float(number(d, "fps", "fps"))
        self.encoding = d.get("encoding")
        if self.encoding not in ("raw", "jpeg"):
            raise ProtocolError('%s: describe reply\'s "encoding" is %s, not "raw" or "jpeg"'
                                % (self._label, json.dumps(self.encoding)))
        k = d.get("intrinsics")
        self.intrinsics = {f: float(number(k, f, "intrinsics." + f)) for f in ("fx", "fy", "cx", "cy")}
        dist = d.get("distortion")
        self.distortion = [float(number(dist, f, "distortion." + f)) for f in ("k1", "k2", "p1", "p2")] \
            if isinstance(dist, dict) else [0.0] * 4
        if self.encoding == "jpeg" and self._decode and _cv2() is None:
            raise VlabError(self._jpeg_error())

    def _jpeg_error(self):
        return ("%s sends JPEG frames; decoding them needs OpenCV's Python module (cv2), which is not "
                "installed: install it (Debian: python3-opencv), serve raw frames (vlab camera --encoding raw; "
                "scenario key encoding: raw), or pass decode=False for the JPEG bytes alone" % self._label)

    @property
    def counters(self):
        """Chunk and frame counters of the reassembly (chunks, accepted, duplicates, late, refused,
        frames_completed, frames_dropped, dropped_superseded, dropped_timeout, dropped_evicted, ...)."""
        return dict(self._assembler.counters)

    @property
    def refused_by(self):
        """Refused chunks by reason."""
        return dict(self._assembler.refused_by)

    def _now(self):
        return time.monotonic() - self._start

    def _frame(self, data):
        """Chunks that arrive while connecting go to the assembler."""
        self._assembler.add(data, self._now())

    def _next(self, deadline, queued_only=False):
        """The next whole frame (chunk, bytes) before the deadline, or None."""
        while True:
            ready = self._assembler.take()
            if ready is not None:
                return ready
            now = time.monotonic()
            if not queued_only and now >= deadline:
                self._assembler.expire(self._now())
                return None
            if now >= self._next_keepalive:
                self.keep_alive()
                self._next_keepalive = now + self._keepalive
            data = self._receive(now if queued_only else min(deadline, self._next_keepalive))
            if data is None:
                self._assembler.expire(self._now())
                if queued_only:
                    return None
                continue
            if data[:1] == b"{" or is_session_reply(data):  # a describe reply, the answer to a keep-alive
                self.skipped += 1
                continue
            try:
                self._assembler.add(data, self._now())
            except VersionMismatch as e:
                raise VersionMismatch("%s: %s" % (self._label, e)) from None

    def _finish(self, ready):
        """CameraFrame from (last chunk, bytes), decoded; None if its JPEG does not decode."""
        c, data = ready
        rgb = None
        if c.encoding == ENCODING_RAW:
            rgb = data
        elif self._decode:
            cv2 = _cv2()
            if cv2 is None:
                raise VlabError(self._jpeg_error())
            import numpy  # cv2 needs it, so it is there
            bgr = cv2.imdecode(numpy.frombuffer(data, numpy.uint8), cv2.IMREAD_COLOR)
            if bgr is None or bgr.shape != (c.height, c.width, 3):
                self.undecodable += 1
                return None
            rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB).tobytes()
        return CameraFrame(c.frame_id, c.time, c.width, c.height, ENCODING_NAMES[c.encoding], data, rgb,
                           c.pose_valid, c.position, c.orientation)

    def read(self, timeout=1.0):
        """The next whole frame, waiting up to `timeout` s. Raises VlabTimeout."""
        deadline = time.monotonic() + timeout
        while True:
            ready = self._next(deadline)
            if ready is None:
                a = self._assembler.counters
                raise VlabTimeout("%s: no whole frame within %g s (%d chunks so far, %d frames dropped incomplete, "
                                  "%d chunks refused)" % (self._label, timeout, a["chunks"], a["frames_dropped"],
                                                          a["refused"]))
            frame = self._finish(ready)
            if frame is not None:
                return frame

    def read_latest(self, timeout=1.0):
        """Waits up to `timeout` s for a whole frame, then takes every datagram already queued and
        returns the newest whole frame. Raises as read."""
        deadline = time.monotonic() + timeout
        while True:
            ready = self._next(deadline)
            if ready is None:
                return self.read(0)  # raises the timeout
            while True:
                newer = self._next(deadline, queued_only=True)
                if newer is None:
                    break
                self.frames_skipped += 1
                ready = newer
            frame = self._finish(ready)
            if frame is not None:
                return frame

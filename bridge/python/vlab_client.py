"""Python client of the vlab wire protocol, version 1 (docs/protocol.md).

Standard library only (socket, struct, json, select, math, time): copy this file
next to a script, or put its folder on sys.path.

    from vlab_client import Arm, VELOCITY

    with Arm("127.0.0.1", 50010) as arm:          # describe + subscribe
        print(arm.describe()["joints"])
        state = arm.read(timeout=1.0)              # seq, time (s), status, q, qd, tau
        arm.write(VELOCITY, [0.0] * arm.joints, state.seq)

Devices: Arm (commands: hold, position, velocity, torque), Wrench (output only),
Sim (pause, resume, step, reset, realtime factor). Connecting sends a describe
request, which also subscribes the client: the device then sends it one state per
control period. The seq of a command must be the seq of the state it answers.
read/read_latest wait up to their timeout; write never blocks.

Errors: VlabError > NetworkError, ProtocolError > VersionMismatch, VlabTimeout
(also a builtin TimeoutError); ValueError for a caller's own mistake (wrong number
of values, non-finite value, negative seq). A handle is not thread-safe.
"""

import collections
import json
import math
import select
import socket
import struct
import time

MAGIC = 1447838018
PROTOCOL_VERSION = 1
HEADER_VALUES = 7
MAX_PACKET_VALUES = 1024
MAX_SEQ = 2 ** 53

KIND_ARM, KIND_WRENCH, KIND_SIM = 1, 2, 3
KIND_NAMES = {KIND_ARM: "arm", KIND_WRENCH: "wrench", KIND_SIM: "sim"}
TYPE_STATE, TYPE_COMMAND, TYPE_DESCRIBE = 1, 2, 3

# arm command modes
HOLD, POSITION, VELOCITY, TORQUE = 0, 1, 2, 3
# arm status bits
STATUS_HOLDING, STATUS_REFUSED, STATUS_SATURATED = 1, 2, 4
STATUS_AT_LIMIT, STATUS_WATCHDOG, STATUS_NOT_OWNER = 8, 16, 32
# sim operations
SIM_RESET, SIM_PAUSE, SIM_RESUME, SIM_STEP, SIM_SET_REALTIME_FACTOR = 1, 2, 3, 4, 5

_DESCRIBE_RETRY_S = 0.25  # resend a lost describe request this often


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


def decode(data):
    """Checks a datagram's framing; returns (kind, type, seq, time, payload) or raises ProtocolError."""
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
    if not _whole(kind, 1, 255):
        raise ProtocolError("bad kind")
    if not _whole(mtype, 1, 3):
        raise ProtocolError("bad type")
    if not _whole(seq, 0, MAX_SEQ):
        raise ProtocolError("bad seq")
    if length != len(values) - HEADER_VALUES:
        raise ProtocolError("bad length")
    return int(kind), int(mtype), int(seq), t, values[HEADER_VALUES:]


class Device:
    """What every device handle shares: socket, describe reply, reception of states."""

    KIND = None

    def __init__(self, address="127.0.0.1", port=None, timeout=1.0, bind_address=None):
        """Connects: sends a describe request to address:port and waits up to `timeout` s for
        the JSON reply (states arriving meanwhile are skipped). Raises NetworkError (bad
        address), VlabTimeout (no reply), VersionMismatch, ProtocolError (wrong kind, bad reply)."""
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
        self._request = encode(self.KIND, TYPE_DESCRIBE, 0, 0, [])
        self.skipped = 0  # datagrams skipped: describe replies, other senders
        try:
            self._describe = self._connect(timeout)
        except BaseException:
            self._sock.close()
            raise
        self.name = self._describe.get("name", "")
        if isinstance(self.name, str) and self.name:
            self._label = "%s '%s' at %s:%d" % (KIND_NAMES[self.KIND], self.name, self._device[0], self._device[1])

    def _connect(self, timeout):
        deadline = time.monotonic() + timeout
        resend = 0.0
        while True:
            now = time.monotonic()
            if now >= resend:
                if not self._send(self._request):
                    raise NetworkError("%s: cannot send the describe request" % self._label)
                resend = now + _DESCRIBE_RETRY_S
            data = self._receive(min(deadline, resend))
            if data is None:
                if time.monotonic() < deadline:
                    continue
                raise VlabTimeout("%s: no describe reply within %g s (is a device of this kind serving that "
                                  "address and port?)" % (self._label, timeout))
            if data[:1] == b"{":
                return self._check_describe(data)
            self._frame(data)  # a state may come first; anything else raises

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
        """Sends a describe request without waiting (read skips the reply). A client that never
        writes must do this now and then (every second is plenty) to stay subscribed."""
        return self._send(self._request)

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
        """Closes the socket (the device drops the subscription after its timeout)."""
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
        if data[:1] == b"{":  # a describe reply (keep-alive)
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
        non-finite value or seq. Acceptance shows in the status bits of the next states."""
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
    SIM_SET_REALTIME_FACTOR (arg factor)."""

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
        """Sends an operation answering state `seq`. Never blocks; False if not sent. Raises
        ValueError on an unknown op, a non-finite arg or a bad seq."""
        if op not in (SIM_RESET, SIM_PAUSE, SIM_RESUME, SIM_STEP, SIM_SET_REALTIME_FACTOR):
            raise ValueError("sim op %r is not 1..5" % (op,))
        if not math.isfinite(arg):
            raise ValueError("%s: sim command arg is not finite" % self._label)
        self._check_seq(seq)
        return self._send(encode(KIND_SIM, TYPE_COMMAND, seq, self._time(), [op, float(arg)]))

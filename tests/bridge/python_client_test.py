#!/usr/bin/env python3
"""Tests bridge/python/vlab_client.py: the Python client against a real device endpoint
(tests/bridge/test_arm_server, C++: sessions, ownership), against a scripted device of
protocol 2 for the faults (loss, rate limits, refusals, garbage, silence), LayoutDevice
against vlab-yoyosim's point and yoyo devices, and the joint_control examples (C++ and
Python) end to end.

    python_client_test.py --server PATH [--joint-control PATH] [--yoyosim PATH] [--vlab PATH]
                          [unittest args, e.g. ClientTest]

Timeouts are seconds, never tight: the tests must pass on a loaded machine.
"""

import argparse
import hashlib
import json
import os
import re
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import unittest

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "bridge", "python"))
import vlab_client as vc  # noqa: E402

SERVER = None          # test_arm_server binary (--server)
JOINT_CONTROL = None   # examples/joint_control binary (--joint-control)
YOYOSIM = None         # vlab-yoyosim binary (--yoyosim)
VLAB = None            # vlab binary (--vlab)
PATIENCE_S = 5.0       # how long a test waits for something that must happen

# docs/protocol.md, "A worked example" (protocol version 2)
WORKED_EXAMPLE_HEX = (
    "000080501093d5410000000000000040000000000000f03f0000000000000040"
    "0000000000004540000000000000f83f00000000000020400000000000000040"
    "000000000000e03f000000000000d0bf000000000000c03f0000000000000000"
    "000000000000f03f000000000000f0bf000000000000b03f")
# the same section: a subscribe request to the arm with cookie 2^52 + 1, action 1
WORKED_SUBSCRIBE_HEX = (
    "000080501093d5410000000000000040000000000000f03f0000000000001040"
    "000000000000000000000000000000000000000000000040"
    "0100000000003043000000000000f03f")


class ArmServer:
    """test_arm_server on a free port (it binds port 0 and prints the port it got)."""

    def __init__(self, seconds=60, follow=False):
        args = [SERVER, "0", str(seconds)] + (["--follow"] if follow else [])
        self.proc = subprocess.Popen(args, stdout=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline()  # "listening 127.0.0.1:PORT"
        if not line.startswith("listening "):
            self.proc.kill()
            raise RuntimeError("test_arm_server did not start: %r" % line)
        self.port = int(line.rsplit(":", 1)[1])
        # read its output as it comes: a full pipe would stop the server
        self.lines = []
        self.reader = threading.Thread(target=lambda: self.lines.extend(self.proc.stdout))
        self.reader.start()

    def stop(self):
        """Stops the server; returns its output lines after the first."""
        self.proc.terminate()
        self.proc.wait(timeout=PATIENCE_S)
        self.reader.join()
        self.proc.stdout.close()
        return [line.rstrip("\n") for line in self.lines]


class Yoyosim:
    """vlab-yoyosim on free ports, run from the source root (its scene path is relative); its start
    line names both ports."""

    def __init__(self, *args):
        command = [YOYOSIM, "--point-port", "0", "--yoyo-port", "0"] + list(args)
        self.proc = subprocess.Popen(command, cwd=SOURCE, stdout=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline()  # "vlab-yoyosim: point on 127.0.0.1:P, yoyo on 127.0.0.1:Q, ..."
        ports = re.search(r"point on [^ ]+:(\d+), yoyo on [^ ]+:(\d+)", line)
        if not ports:
            self.proc.kill()
            raise RuntimeError("vlab-yoyosim did not start: %r" % line)
        self.point_port, self.yoyo_port = int(ports.group(1)), int(ports.group(2))
        self.lines = []
        self.reader = threading.Thread(target=lambda: self.lines.extend(self.proc.stdout))
        self.reader.start()

    def wait(self):
        """Waits for the end of a --duration run; returns (exit code, output lines after the first)."""
        code = self.proc.wait(timeout=60)
        self.reader.join()
        self.proc.stdout.close()
        return code, [line.rstrip("\n") for line in self.lines]

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
        return self.wait()


class Lab:
    """vlab serve scenes/pa10_serve in realtime on free ports, writing into a temporary folder;
    its start line names the ports. sim_ops_from: the sim's `ops_from` key, in a copy of the
    scenario (None: the scenario's own)."""

    def __init__(self, duration_s=60, sim_ops_from=None):
        self.out = tempfile.TemporaryDirectory()
        scenario = "scenes/pa10_serve"
        if sim_ops_from:
            with open(os.path.join(SOURCE, "scenes", "pa10_serve.yaml")) as f:
                text = f.read()
            text = text.replace("scene: pa10.xml", "scene: " + os.path.join(SOURCE, "scenes", "pa10.xml"), 1)
            text = text.replace("    kind: sim\n", "    kind: sim\n    ops_from: %s\n" % sim_ops_from, 1)
            scenario = os.path.join(self.out.name, "pa10_serve.yaml")
            with open(scenario, "w") as f:
                f.write(text)
        command = [VLAB, "serve", scenario, "--clock", "realtime", "-q", "--port", "pa10=0", "--port",
                   "jr3=0", "--port", "sim=0", "--duration", str(duration_s), "--out",
                   os.path.join(self.out.name, "run")]
        # (its stderr too: "interrupted" when the test ends it)
        self.proc = subprocess.Popen(command, cwd=SOURCE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        line = self.proc.stdout.readline()  # "vlab serve: pa10_serve, ...; pa10 (arm) 127.0.0.1:P; ..."
        ports = dict(re.findall(r"(\w+) \(\w+\) [^ ]+:(\d+);", line))
        if not {"pa10", "sim"} <= set(ports):
            self.proc.kill()
            raise RuntimeError("vlab serve did not start: %r" % line)
        self.arm_port, self.sim_port = int(ports["pa10"]), int(ports["sim"])
        self.lines = []
        self.reader = threading.Thread(target=lambda: self.lines.extend(self.proc.stdout))
        self.reader.start()

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
        self.proc.wait(timeout=PATIENCE_S)
        self.reader.join()
        self.proc.stdout.close()
        self.out.cleanup()


class FakeDevice:
    """A scripted device of protocol 2 on a loopback socket (a thread), with the session rules of
    bridge/bridge_session.cc: the cookie of a source is a keyed hash of its address and port; a
    request without it, or with a wrong one, is answered with a challenge only (72 bytes, the size
    of the request); with it, a describe request is answered with `describe` (the JSON reply, or
    whatever datagrams a test scripts) and a subscribe request subscribes (result 1, then the
    datagrams of `on_subscribe`) or unsubscribes (result 3). publish() sends to subscribers only.
    Faults: `drop` first datagrams lost, `limited` first describe requests refused by the rate
    limit (result 4), `full` (every subscription refused, result 2), `subscribes=False` (subscribe
    requests unanswered). Every well-framed datagram is recorded in `requests`."""

    def __init__(self, describe=None, kind=vc.KIND_ARM, on_subscribe=(), drop=0, limited=0, full=False,
                 subscribes=True):
        self.kind = kind
        self.describe = [describe_json()] if describe is None else \
            [describe] if isinstance(describe, bytes) else list(describe)
        self.on_subscribe = list(on_subscribe)
        self.drop, self.limited, self.full, self.subscribes = drop, limited, full, subscribes
        self.key = os.urandom(16)  # the cookies' secret
        self.requests = []         # (source, kind, type, seq, payload), in arrival order
        self.subscribers = set()
        self.lock = threading.Lock()
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.05)
        self.port = self.sock.getsockname()[1]
        self.stopping = threading.Event()
        self.thread = threading.Thread(target=self._serve)
        self.thread.start()

    def cookie(self, source):
        """The cookie of an (address, port): 1 <= cookie < 2^53."""
        data = socket.inet_pton(socket.AF_INET, source[0]) + struct.pack("<H", source[1])
        digest = hashlib.blake2b(data, key=self.key, digest_size=8).digest()
        return (int.from_bytes(digest, "little") & (2 ** 53 - 1)) or 1

    def _reply(self, source, result):
        self.sock.sendto(vc.encode(self.kind, vc.TYPE_SESSION, 0, 0, [self.cookie(source), result]), source)

    def _serve(self):
        while not self.stopping.is_set():
            try:
                data, source = self.sock.recvfrom(65536)
            except socket.timeout:
                continue
            if self.drop > 0:
                self.drop -= 1
                continue
            try:
                kind, mtype, seq, _, payload = vc.decode(data)
            except vc.ProtocolError:
                continue  # refused (a device counts it)
            with self.lock:
                self.requests.append((source, kind, mtype, seq, payload))
            request = mtype in (vc.TYPE_DESCRIBE, vc.TYPE_SUBSCRIBE) and len(payload) == 2
            if not request or (mtype == vc.TYPE_SUBSCRIBE and kind != self.kind):
                continue  # a command (recorded), or a request this device refuses
            if payload[0] != self.cookie(source):
                self._reply(source, vc.SESSION_CHALLENGE)
            elif mtype == vc.TYPE_DESCRIBE and self.limited > 0:
                self.limited -= 1
                self._reply(source, vc.SESSION_LIMITED)
            elif mtype == vc.TYPE_DESCRIBE:
                for d in self.describe:
                    self.sock.sendto(d, source)
            elif not self.subscribes:
                continue
            elif payload[1] == vc.UNSUBSCRIBE:
                with self.lock:
                    self.subscribers.discard(source)
                self._reply(source, vc.SESSION_UNSUBSCRIBED)
            elif self.full:
                self._reply(source, vc.SESSION_FULL)
            else:
                with self.lock:
                    self.subscribers.add(source)
                self._reply(source, vc.SESSION_SUBSCRIBED)
                for d in self.on_subscribe:
                    self.sock.sendto(d, source)

    def publish(self, data):
        """Sends a datagram to every subscriber."""
        with self.lock:
            subscribers = list(self.subscribers)
        for s in subscribers:
            self.sock.sendto(data, s)

    def requests_of(self, mtype):
        """[(source, kind, cookie, arg)] of the requests of a type received so far."""
        with self.lock:
            return [(r[0], r[1]) + tuple(r[4]) for r in self.requests if r[2] == mtype]

    def wait_for(self, condition, what):
        """Waits (PATIENCE_S at most) until condition() is true; fails naming `what`."""
        give_up = time.monotonic() + PATIENCE_S
        while not condition():
            if time.monotonic() > give_up:
                raise AssertionError("the fake device never saw %s: %r" % (what, self.requests))
            time.sleep(0.01)

    def close(self):
        self.stopping.set()
        self.thread.join()
        self.sock.close()


def describe_json(**changes):
    d = {"name": "pa10", "kind": "arm", "protocol": 2, "joints": ["S1", "S2", "S3", "E1", "E2", "W1", "W2"],
         "limits": {"position_min": [], "position_max": [], "velocity_max": [1.0] * 7, "torque_max": []}}
    d.update(changes)
    return json.dumps(d).encode()


def parse_command(line):
    """"command seq=S mode=M values=V1,...,Vn" (test_arm_server) -> (S, M, [V...])."""
    fields = dict(field.split("=", 1) for field in line.split()[1:])
    return int(float(fields["seq"])), int(fields["mode"]), [float(v) for v in fields["values"].split(",")]


def arm_state(seq, joints=7):
    q = [0.1 * i + 0.001 * seq for i in range(joints)]
    return vc.encode(vc.KIND_ARM, vc.TYPE_STATE, seq, 0.002 * seq,
                     [0] + q + [-0.5 * i for i in range(joints)] + [10.0 * i for i in range(joints)])


def receive_all(sock, quiet_s):
    """Every datagram that arrives on `sock` until it has been quiet for quiet_s."""
    sock.settimeout(quiet_s)
    out = []
    while True:
        try:
            out.append(sock.recv(65536))
        except socket.timeout:
            return out


class CodecTest(unittest.TestCase):
    def test_worked_example_of_the_docs(self):
        data = vc.encode(vc.KIND_ARM, vc.TYPE_COMMAND, 42, 1.5, [2, 0.5, -0.25, 0.125, 0, 1, -1, 0.0625])
        self.assertEqual(data.hex(), WORKED_EXAMPLE_HEX)
        self.assertEqual(vc.decode(data), (1, 2, 42, 1.5, (2, 0.5, -0.25, 0.125, 0, 1, -1, 0.0625)))

    def test_decode_refuses_malformed_datagrams(self):
        good = arm_state(3)
        vc.decode(good)
        cases = {
            "too short": [good[:48], good[:-1], b""],
            "too long": [struct.pack("<1025d", vc.MAGIC, 2, 1, 1, 0, 0, 1018, *([0] * 1018))],
            "bad magic": [struct.pack("<d", 1.0) + good[8:]],
            "non-finite": [good[:40] + struct.pack("<d", float("nan")) + good[48:],
                           good[:-8] + struct.pack("<d", float("inf"))],
            "bad length": [good[:48] + struct.pack("<d", 21) + good[56:]],
            "bad seq": [good[:32] + struct.pack("<d", 2.5) + good[40:]],
            "bad kind": [good[:16] + struct.pack("<d", 256) + good[24:], good[:16] + struct.pack("<d", -1) + good[24:]],
            "bad type": [good[:24] + struct.pack("<d", 7) + good[32:], good[:24] + struct.pack("<d", 0) + good[32:]],
        }
        for reason, datagrams in cases.items():
            for data in datagrams:
                with self.assertRaisesRegex(vc.ProtocolError, reason):
                    vc.decode(data)
        with self.assertRaisesRegex(vc.VersionMismatch, "protocol version 1, this client speaks version 2"):
            vc.decode(good[:8] + struct.pack("<d", 1) + good[16:])

    def test_session_requests_and_replies(self):
        # [magic, 2, kind, type, 0, 0, 2, cookie, arg]: 72 bytes
        self.assertEqual(vc.encode_describe_request(vc.KIND_ANY, 0),
                         struct.pack("<9d", vc.MAGIC, 2, 0, 3, 0, 0, 2, 0, 0))
        self.assertEqual(vc.encode_describe_request(vc.KIND_ARM, 2 ** 53 - 1),
                         struct.pack("<9d", vc.MAGIC, 2, 1, 3, 0, 0, 2, 2 ** 53 - 1, 0))
        self.assertEqual(vc.encode_subscribe_request(vc.KIND_CAMERA, 12345, vc.SUBSCRIBE),
                         struct.pack("<9d", vc.MAGIC, 2, 4, 4, 0, 0, 2, 12345, 1))
        self.assertEqual(vc.encode_subscribe_request(vc.KIND_ARM, 7, vc.UNSUBSCRIBE),
                         struct.pack("<9d", vc.MAGIC, 2, 1, 4, 0, 0, 2, 7, 0))
        worked = vc.encode_subscribe_request(vc.KIND_ARM, 2 ** 52 + 1, vc.SUBSCRIBE)
        self.assertEqual(worked.hex(), WORKED_SUBSCRIBE_HEX)
        self.assertEqual(vc.REQUEST_BYTES, 72)

        def reply(*values):
            return struct.pack("<%dd" % len(values), *values)

        self.assertEqual(vc.parse_session_reply(reply(vc.MAGIC, 2, 1, 5, 0, 0, 2, 99, 0)), (1, 99, 0))
        self.assertEqual(vc.parse_session_reply(reply(vc.MAGIC, 2, 4, 5, 0, 0, 2, 2 ** 53 - 1, 4)),
                         (4, 2 ** 53 - 1, vc.SESSION_LIMITED))
        self.assertEqual(vc.parse_session_reply(reply(vc.MAGIC, 2, 3, 5, 0, 0, 2, 9, 5)), (3, 9, vc.SESSION_REFUSED))
        for bad in (reply(vc.MAGIC, 2, 1, 5, 0, 0, 2, 0, 1),        # cookie 0
                    reply(vc.MAGIC, 2, 1, 5, 0, 0, 2, 2 ** 53, 1),  # cookie too large
                    reply(vc.MAGIC, 2, 1, 5, 0, 0, 2, 2.5, 1),      # not whole
                    reply(vc.MAGIC, 2, 1, 5, 0, 0, 2, 9, 8),        # no such result
                    reply(vc.MAGIC, 2, 1, 5, 0, 0, 2, 9, 1.5),
                    reply(vc.MAGIC, 2, 1, 1, 0, 0, 2, 9, 1),        # a state
                    reply(vc.MAGIC, 1, 1, 5, 0, 0, 2, 9, 1),        # version 1
                    reply(vc.MAGIC, 2, 1, 5, 0, 0, 3, 9, 1, 0),     # 80 bytes
                    reply(vc.MAGIC, 2, 1, 5, 0, 0, 2, 9, float("nan"))):
            self.assertIsNone(vc.parse_session_reply(bad), bad.hex())
        self.assertTrue(vc.is_session_reply(reply(vc.MAGIC, 2, 1, 5, 0, 0, 2, 9, 1)))
        self.assertFalse(vc.is_session_reply(describe_json()))
        self.assertFalse(vc.is_session_reply(arm_state(1)))

    def test_error_hierarchy(self):
        self.assertTrue(issubclass(vc.VersionMismatch, vc.ProtocolError))
        for e in (vc.NetworkError, vc.ProtocolError, vc.VlabTimeout):
            self.assertTrue(issubclass(e, vc.VlabError))
        self.assertTrue(issubclass(vc.VlabTimeout, TimeoutError))


class ClientTest(unittest.TestCase):
    def test_describe_read_write_against_the_endpoint(self):
        server = ArmServer()
        try:
            with vc.Arm("127.0.0.1", server.port, timeout=PATIENCE_S) as arm:
                self.assertEqual(arm.describe()["name"], "pa10")
                self.assertEqual(arm.describe()["protocol"], 2)
                self.assertEqual(arm.joints, 7)
                self.assertEqual(arm.joint_names[4], "E2")
                self.assertEqual(arm.velocity_max, [2.0] * 7)
                self.assertTrue(1 <= arm.cookie < 2 ** 53)
                first = arm.read(PATIENCE_S)
                previous = first
                for _ in range(10):
                    s = arm.read(PATIENCE_S)
                    self.assertGreater(s.seq, previous.seq)
                    self.assertAlmostEqual(s.time, 0.002 * s.seq, places=12)
                    for i in range(7):
                        self.assertAlmostEqual(s.q[i], 0.1 * i + 0.001 * s.seq, places=12)
                        self.assertEqual(s.qd[i], -0.5 * i)
                        self.assertEqual(s.tau[i], 10.0 * i)
                    previous = s
                time.sleep(0.05)
                latest = arm.read_latest(PATIENCE_S)
                self.assertGreater(latest.seq, previous.seq)
                self.assertGreater(arm.read(PATIENCE_S).seq, latest.seq)  # the queue was drained

                # a renewal's reply is skipped by read
                skipped = arm.skipped
                self.assertTrue(arm.keep_alive())
                give_up = time.monotonic() + PATIENCE_S
                while arm.skipped == skipped:
                    arm.read(PATIENCE_S)
                    self.assertLess(time.monotonic(), give_up, "the renewal was never answered")

                latest = arm.read_latest(PATIENCE_S)
                qd = [0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7]
                self.assertTrue(arm.write(vc.VELOCITY, qd, latest.seq))
                self.assertTrue(arm.write(vc.VELOCITY, qd, latest.seq))  # duplicate: ignored
                s = arm.read(PATIENCE_S)
                self.assertTrue(arm.write(vc.HOLD, [], s.seq))
                too_fast = [0.0] * 7
                too_fast[1] = 5.0  # beyond 2 rad/s
                self.assertTrue(arm.write(vc.VELOCITY, too_fast, arm.read(PATIENCE_S).seq))
                give_up = time.monotonic() + PATIENCE_S
                while not arm.read(PATIENCE_S).status & vc.STATUS_REFUSED:
                    self.assertLess(time.monotonic(), give_up, "the refused bit never came")

                with self.assertRaisesRegex(ValueError, "6 values, the arm has 7 joints"):
                    arm.write(vc.POSITION, [0.0] * 6, s.seq)
                with self.assertRaises(ValueError):
                    arm.write(vc.TORQUE, [float("nan")] + [0.0] * 6, s.seq)
                with self.assertRaises(ValueError):
                    arm.write(vc.TORQUE, [0.0] * 7, -1)
                with self.assertRaises(ValueError):
                    arm.write(4, [0.0] * 7, s.seq)
        finally:
            lines = server.stop()
        commands = [parse_command(line) for line in lines if line.startswith("command ")]
        self.assertEqual(commands, [(latest.seq, vc.VELOCITY, qd), (s.seq, vc.HOLD, [0.0] * 7)], lines)
        counters = [line for line in lines if line.startswith("counters ")]
        self.assertEqual(len(counters), 1, lines)
        self.assertIn(" accepted=2 ", counters[0])
        self.assertIn(" duplicate=1 ", counters[0])
        self.assertIn(" describes=1", counters[0])

    def test_payload_set_by_the_owner_and_refused_for_another(self):
        """An arm's payload (type 6): the first client's takes the arm and the describe reply
        reports it; its payloads carry its own counter, so two in a row are both taken and a late
        copy of the first is refused; a second client is refused (result 7), and so is a load no
        rigid body has."""
        server = ArmServer()
        try:
            with vc.Arm("127.0.0.1", server.port, timeout=PATIENCE_S) as first:
                self.assertEqual(first.payload["mass"], 0.0)
                first.set_payload(1.0, timeout=PATIENCE_S)  # seq 1
                first.set_payload(1.5, (0.1, 0.0, 0.05), (0.01, 0.012, 0.008), timeout=PATIENCE_S)  # seq 2
                self.assertEqual(first.payload, {"mass": 1.5, "com": [0.1, 0.0, 0.05],
                                                 "inertia": [0.01, 0.012, 0.008, 0.0, 0.0, 0.0]})
                # a late copy of the first (seq 1) from the owner's address: refused, nothing changes
                first._send(vc.encode(vc.KIND_ARM, vc.TYPE_PAYLOAD, 1, 0.0, [1.0] + [0.0] * 9))
                deadline = time.monotonic() + PATIENCE_S
                reply = None
                while reply is None or reply[2] not in (vc.SESSION_PAYLOAD_SET, vc.SESSION_PAYLOAD_REFUSED):
                    data = first._receive(deadline)
                    self.assertIsNotNone(data, "no answer to the late copy")
                    reply = vc.parse_session_reply(data)
                self.assertEqual(reply[2], vc.SESSION_PAYLOAD_REFUSED)
                with vc.Arm("127.0.0.1", server.port, timeout=PATIENCE_S) as second:
                    self.assertEqual(second.payload["mass"], 1.5)  # the device reports it
                    self.assertEqual(second.payload["inertia"], [0.01, 0.012, 0.008, 0.0, 0.0, 0.0])
                    with self.assertRaisesRegex(vc.RefusedError, "refused the payload"):
                        second.set_payload(1.0, timeout=PATIENCE_S)
                with self.assertRaises(vc.RefusedError):  # the triangle inequality: the device's check
                    first.set_payload(1.0, inertia=(0.01, 0.01, 0.03), timeout=PATIENCE_S)
                self.assertEqual(first.payload["mass"], 1.5)
                with self.assertRaisesRegex(ValueError, "mass must be >= 0"):
                    first.set_payload(-1.0)
                with self.assertRaisesRegex(ValueError, "com needs 3 values"):
                    first.set_payload(1.0, com=(0.0, 0.0))
                with self.assertRaisesRegex(ValueError, "non-finite"):
                    first.set_payload(float("nan"))
        finally:
            lines = server.stop()
        counters = [line for line in lines if line.startswith("counters ")]
        self.assertIn(" refused=2 ", counters[0], lines)
        self.assertIn(" stale=1 ", counters[0], lines)  # the late copy

    def test_sessions_of_the_endpoint(self):
        """Without the cookie a request gets a 72-byte challenge and nothing else; with it, a
        describe request gets the JSON but no state: states go to subscribers only, and a command
        from a source that never subscribed is refused."""
        server = ArmServer()
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        device = ("127.0.0.1", server.port)
        try:
            sock.bind(("127.0.0.1", 0))
            sock.sendto(vc.encode_describe_request(vc.KIND_ARM, 0), device)
            answer = receive_all(sock, 0.5)
            self.assertEqual([len(d) for d in answer], [72], answer)
            kind, cookie, result = vc.parse_session_reply(answer[0])
            self.assertEqual((kind, result), (vc.KIND_ARM, vc.SESSION_CHALLENGE))
            self.assertTrue(1 <= cookie < 2 ** 53)

            # a wrong cookie (or a subscribe request without one): the same challenge, nothing else
            for request in (vc.encode_describe_request(vc.KIND_ANY, cookie ^ 1),
                            vc.encode_subscribe_request(vc.KIND_ARM, 0, vc.SUBSCRIBE)):
                sock.sendto(request, device)
                self.assertEqual(receive_all(sock, 0.5), [answer[0]])

            # the cookie brings the describe reply, and no state: no subscription yet
            sock.sendto(vc.encode_describe_request(vc.KIND_ANY, cookie), device)
            answer = receive_all(sock, 0.5)
            self.assertEqual(len(answer), 1, [d[:80] for d in answer])
            self.assertEqual(json.loads(answer[0].decode())["kind"], "arm")
            # a command from a source that never subscribed is refused
            sock.sendto(vc.encode(vc.KIND_ARM, vc.TYPE_COMMAND, 0, 0, [vc.HOLD] + [0.0] * 7), device)
            self.assertEqual(receive_all(sock, 0.5), [])

            # subscribed: states come; unsubscribed: they stop right after the reply
            sock.sendto(vc.encode_subscribe_request(vc.KIND_ARM, cookie, vc.SUBSCRIBE), device)
            sock.settimeout(PATIENCE_S)
            self.assertEqual(vc.parse_session_reply(sock.recv(65536)), (vc.KIND_ARM, cookie, vc.SESSION_SUBSCRIBED))
            state = vc.decode(sock.recv(65536))
            self.assertEqual(state[:2], (vc.KIND_ARM, vc.TYPE_STATE))
            sock.sendto(vc.encode_subscribe_request(vc.KIND_ARM, cookie, vc.UNSUBSCRIBE), device)
            while True:
                data = sock.recv(65536)
                if vc.is_session_reply(data):
                    break
                self.assertEqual(vc.decode(data)[:2], (vc.KIND_ARM, vc.TYPE_STATE))
            self.assertEqual(vc.parse_session_reply(data), (vc.KIND_ARM, cookie, vc.SESSION_UNSUBSCRIBED))
            self.assertEqual(receive_all(sock, 0.5), [])
        finally:
            sock.close()
            lines = server.stop()
        self.assertFalse([line for line in lines if line.startswith("command ")], lines)
        counters = [line for line in lines if line.startswith("counters ")]
        self.assertEqual(len(counters), 1, lines)
        self.assertIn(" accepted=0 refused=1 ", counters[0])  # the command of a non-subscriber
        self.assertIn(" describes=1", counters[0])

    def test_owner_keeps_the_arm_while_it_renews(self):
        """The first accepted command makes its client the owner; renewals keep it the owner past
        the owner timeout (1 s, wall clock); a closed owner gives the arm up (it unsubscribes);
        an owner silent for the timeout loses it."""
        server = ArmServer()

        def state_with(arm, not_owner):
            """The first state (newest first) whose not-owner bit is as asked."""
            give_up = time.monotonic() + PATIENCE_S
            while True:
                s = arm.read_latest(PATIENCE_S)
                if bool(s.status & vc.STATUS_NOT_OWNER) == not_owner:
                    return s
                self.assertLess(time.monotonic(), give_up, "the not-owner bit never became %s" % not_owner)

        def accepted(count):
            """Waits until the server printed `count` accepted commands."""
            give_up = time.monotonic() + PATIENCE_S
            while len([line for line in list(server.lines) if line.startswith("command ")]) < count:
                self.assertLess(time.monotonic(), give_up, "the server never accepted command %d" % count)
                time.sleep(0.01)

        first_qd, refused_qd, second_qd = [0.1] * 7, [0.2] * 7, [0.3] * 7
        try:
            with vc.Arm("127.0.0.1", server.port, timeout=PATIENCE_S) as second:
                with vc.Arm("127.0.0.1", server.port, timeout=PATIENCE_S) as first:
                    s = first.read_latest(PATIENCE_S)
                    first_seq = s.seq
                    self.assertTrue(first.write(vc.VELOCITY, first_qd, s.seq))
                    accepted(1)
                    state_with(second, not_owner=True)
                    # the owner renews but sends no command for longer than the owner timeout
                    until = time.monotonic() + 1.5
                    while time.monotonic() < until:
                        self.assertTrue(first.keep_alive())
                        self.assertFalse(first.read_latest(PATIENCE_S).status & vc.STATUS_NOT_OWNER)
                        time.sleep(0.1)
                    self.assertTrue(second.write(vc.VELOCITY, refused_qd, second.read_latest(PATIENCE_S).seq))
                    for _ in range(10):  # refused: the first still owns the arm
                        self.assertTrue(second.read(PATIENCE_S).status & vc.STATUS_NOT_OWNER)
                # the first closed: unsubscribed, the arm is free at once
                s = state_with(second, not_owner=False)
                second_seq = s.seq
                self.assertTrue(second.write(vc.VELOCITY, second_qd, s.seq))
                accepted(2)
                # the second owner falls silent: after the owner timeout a third takes over
                with vc.Arm("127.0.0.1", server.port, timeout=PATIENCE_S) as third:
                    s = state_with(third, not_owner=False)
                    third_seq = s.seq
                    self.assertTrue(third.write(vc.HOLD, [], s.seq))
                    accepted(3)
                    state_with(second, not_owner=True)
        finally:
            lines = server.stop()
        commands = [parse_command(line) for line in lines if line.startswith("command ")]
        self.assertEqual(commands, [(first_seq, vc.VELOCITY, first_qd), (second_seq, vc.VELOCITY, second_qd),
                                    (third_seq, vc.HOLD, [0.0] * 7)], lines)

    def test_states_before_the_reply_and_later_replies_are_skipped(self):
        device = FakeDevice(describe=[arm_state(1), describe_json()])
        try:
            arm = vc.Arm("127.0.0.1", device.port, timeout=PATIENCE_S)
            source = ("127.0.0.1", arm.local_port)
            cookie = device.cookie(source)
            self.assertEqual(arm.cookie, cookie)
            # describe without a cookie, then describe and subscribe with it
            self.assertEqual(device.requests_of(vc.TYPE_DESCRIBE)[:2],
                             [(source, vc.KIND_ARM, 0, 0), (source, vc.KIND_ARM, cookie, 0)])
            self.assertEqual(device.requests_of(vc.TYPE_SUBSCRIBE)[0], (source, vc.KIND_ARM, cookie, vc.SUBSCRIBE))
            self.assertEqual(device.subscribers, {source})
            device.publish(describe_json())
            device.publish(vc.encode(vc.KIND_ARM, vc.TYPE_SESSION, 0, 0, [cookie, vc.SESSION_SUBSCRIBED]))
            device.publish(arm_state(5))
            device.publish(arm_state(6))
            time.sleep(0.05)
            self.assertEqual(arm.read_latest(PATIENCE_S).seq, 6)
            self.assertGreaterEqual(arm.skipped, 2)  # (more if a request was resent)
            with self.assertRaises(vc.VlabTimeout):
                arm.read(0.05)
            device.publish(arm_state(7, joints=6))
            with self.assertRaisesRegex(vc.ProtocolError, "bad length"):
                arm.read(PATIENCE_S)
            device.publish(vc.encode(vc.KIND_WRENCH, vc.TYPE_STATE, 8, 0, [0] * 8))
            with self.assertRaisesRegex(vc.ProtocolError, "wrong device kind"):
                arm.read(PATIENCE_S)
            device.publish(vc.encode(vc.KIND_ARM, vc.TYPE_SESSION, 0, 0, [cookie, vc.SESSION_SUBSCRIBED, 0]))
            with self.assertRaisesRegex(vc.ProtocolError, "wrong message type"):  # 80 bytes: no session reply
                arm.read(PATIENCE_S)

            # renewals, and closing unsubscribes
            self.assertTrue(arm.keep_alive())
            arm.close()
            arm.close()  # twice: nothing more
            device.wait_for(lambda: device.requests_of(vc.TYPE_SUBSCRIBE)[-1][3] == vc.UNSUBSCRIBE,
                            "the unsubscribe request")
            renew, leave = device.requests_of(vc.TYPE_SUBSCRIBE)[-2:]
            self.assertEqual(renew, (source, vc.KIND_ARM, cookie, vc.SUBSCRIBE))
            self.assertEqual(leave, (source, vc.KIND_ARM, cookie, vc.UNSUBSCRIBE))
            device.wait_for(lambda: not device.subscribers, "the client's leave")
        finally:
            device.close()

    def test_lost_and_rate_limited_requests_are_resent(self):
        # lost: the first three describe requests (resent every 0.25 s); limited: the first two with
        # the cookie are refused by the rate limit, the third is answered
        for faults, resends in (({"drop": 3}, 3), ({"limited": 2}, 2)):
            device = FakeDevice(**faults)
            try:
                begin = time.monotonic()
                with vc.Arm("127.0.0.1", device.port, timeout=PATIENCE_S) as arm:
                    self.assertGreaterEqual(time.monotonic() - begin, 0.25 * resends - 0.01, faults)
                    self.assertEqual(arm.joints, 7)
                    self.assertIn(("127.0.0.1", arm.local_port), device.subscribers)
                    with_cookie = [r for r in device.requests_of(vc.TYPE_DESCRIBE) if r[2] == arm.cookie]
                    self.assertGreaterEqual(len(with_cookie), 1 + faults.get("limited", 0), device.requests)
            finally:
                device.close()

    def test_refused_or_missing_subscription(self):
        device = FakeDevice(full=True)
        try:
            with self.assertRaisesRegex(vc.ProtocolError, "refused the subscription: its subscriber table is full"):
                vc.Arm("127.0.0.1", device.port, timeout=PATIENCE_S)
        finally:
            device.close()
        device = FakeDevice(subscribes=False)
        try:
            begin = time.monotonic()
            with self.assertRaisesRegex(vc.VlabTimeout, "127.0.0.1:%d: no subscription within 0.6 s" % device.port):
                vc.Arm("127.0.0.1", device.port, timeout=0.6)
            self.assertGreaterEqual(time.monotonic() - begin, 0.59)
            # the subscribe request was resent, every 0.25 s
            self.assertGreaterEqual(len(device.requests_of(vc.TYPE_SUBSCRIBE)), 2)
        finally:
            device.close()
        device = FakeDevice(describe=[])
        try:
            with self.assertRaisesRegex(vc.VlabTimeout, "no describe reply within"):
                vc.Arm("127.0.0.1", device.port, timeout=0.6)
        finally:
            device.close()

    def test_faulty_replies(self):
        v1_state = arm_state(0)[:8] + struct.pack("<d", 1) + arm_state(0)[16:]
        cases = [(b'{"kind": "arm", "protocol": 2,', vc.ProtocolError, "not valid JSON"),
                 (b"\xab" * 64, vc.ProtocolError, "bad magic"),
                 (describe_json(protocol=1), vc.VersionMismatch, "protocol version 1, this client speaks version 2"),
                 (describe_json(kind="wrench"), vc.ProtocolError, 'not "arm"'),
                 (describe_json(joints=[]), vc.ProtocolError, '"joints"'),
                 (v1_state, vc.VersionMismatch, "version 1")]
        for reply, error, message in cases:
            device = FakeDevice(describe=reply)
            try:
                with self.assertRaisesRegex(error, message):
                    vc.Arm("127.0.0.1", device.port, timeout=PATIENCE_S)
            finally:
                device.close()

    def test_silence_is_a_timeout_naming_the_endpoint(self):
        silent = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        silent.bind(("127.0.0.1", 0))
        port = silent.getsockname()[1]
        try:
            begin = time.monotonic()
            with self.assertRaisesRegex(vc.VlabTimeout, "127.0.0.1:%d: no answer within 0.3 s .*protocol version 2"
                                        % port):
                vc.Arm("127.0.0.1", port, timeout=0.3)
            self.assertGreaterEqual(time.monotonic() - begin, 0.29)
            with self.assertRaises(TimeoutError):  # also the builtin
                vc.Wrench("127.0.0.1", port, timeout=0.1)
        finally:
            silent.close()

    def test_bad_address_is_a_network_error(self):
        for address, port in (("300.1.2.3", 50010), ("no such host!", 50010), ("127.0.0.1", 0),
                              ("127.0.0.1", 70000)):
            with self.assertRaises(vc.NetworkError):
                vc.Arm(address, port)


class LayoutDeviceTest(unittest.TestCase):
    """LayoutDevice: any float64 kind by the names of its describe layout."""

    def test_point_and_yoyo_of_vlab_yoyosim_by_field_name(self):
        sim = Yoyosim("--duration", "0.1", "--start-timeout", "10", "--timeout", "5")
        try:
            with vc.LayoutDevice("point", "127.0.0.1", sim.point_port, timeout=PATIENCE_S) as hand, \
                    vc.LayoutDevice(vc.KIND_YOYO, "127.0.0.1", sim.yoyo_port, timeout=PATIENCE_S) as yoyo:
                self.assertEqual(hand.kind, "point")
                self.assertEqual(hand.state_names, ["status", "x", "y", "z", "vx", "vy", "vz"])
                self.assertEqual(hand.command_names, ["x", "y", "z"])
                self.assertEqual(yoyo.state_names, ["status", "x", "y", "z", "vz", "string_force", "spin"])
                self.assertEqual(yoyo.command_length, 0)
                start = hand.describe()["start"]
                h = hand.read(PATIENCE_S)
                y = yoyo.read(PATIENCE_S)
                self.assertEqual((h.seq, y.seq), (0, 0))
                self.assertEqual(h["status"], vc.STATUS_HOLDING)  # no command yet
                self.assertEqual([h["x"], h["y"], h["z"]], start)
                self.assertEqual(h.values, tuple(h.fields[name] for name in hand.state_names))
                self.assertEqual(y["status"], 0)
                self.assertLess(y["z"], h["z"])  # the yo-yo hangs below the hand
                self.assertGreaterEqual(y["string_force"], 0.0)
                self.assertIn("spin", y)
                with self.assertRaisesRegex(KeyError, "no state field 'grasped'"):
                    y["grasped"]

                with self.assertRaisesRegex(ValueError, "point 'point' at 127.0.0.1:%d: command field 'z' not given"
                                            % sim.point_port):
                    hand.write({"x": 0.0, "y": 0.0}, h.seq)
                with self.assertRaisesRegex(ValueError, "no command field 'w'"):
                    hand.write({"x": 0.0, "y": 0.0, "z": 1.5, "w": 1.0}, h.seq)
                with self.assertRaisesRegex(ValueError, "command field 'x' is not finite"):
                    hand.write({"x": float("nan"), "y": 0.0, "z": 1.5}, h.seq)
                with self.assertRaisesRegex(ValueError, "takes no commands"):
                    yoyo.write({"z": 1.0}, y.seq)

                # lockstep: every period waits for the hand's command; the hand rises 1 mm a period
                for k in range(10):
                    self.assertTrue(hand.write({"z": start[2] + 0.001 * (k + 1), "y": start[1], "x": start[0]},
                                               h.seq))
                    h, y = hand.read(PATIENCE_S), yoyo.read(PATIENCE_S)
                    self.assertEqual((h.seq, y.seq), (k + 1, k + 1))
                    self.assertEqual(h["status"], 0)  # accepted: no longer holding
                self.assertAlmostEqual(h["z"], start[2] + 0.010, delta=0.002)
                self.assertGreater(h["vz"], 0.0)
            code, lines = sim.wait()
        finally:
            sim.stop()
        self.assertEqual(code, 0, lines)
        self.assertTrue(any("accepted 10, refused 0" in line for line in lines), lines)

    def test_an_arm_by_layout_groups_its_joint_values(self):
        server = ArmServer()
        try:
            with vc.LayoutDevice("arm", "127.0.0.1", server.port, timeout=PATIENCE_S) as arm:
                self.assertEqual(arm.state_fields, [("status", None), ("q", 7), ("qd", 7), ("tau", 7)])
                self.assertEqual(arm.command_fields, [("mode", None), ("value", 7)])
                s = arm.read(PATIENCE_S)
                self.assertEqual(len(s["q"]), 7)
                for i in range(7):
                    self.assertAlmostEqual(s["q"][i], 0.1 * i + 0.001 * s.seq, places=12)
                    self.assertEqual(s["tau"][i], 10.0 * i)
                with self.assertRaisesRegex(ValueError, "command field 'value' has 6 values, not 7"):
                    arm.write({"mode": vc.VELOCITY, "value": [0.0] * 6}, s.seq)
                qd = [0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7]
                self.assertTrue(arm.write({"value": qd, "mode": vc.VELOCITY}, s.seq))
                arm.read(PATIENCE_S)
        finally:
            lines = server.stop()
        commands = [parse_command(line) for line in lines if line.startswith("command ")]
        self.assertEqual(commands, [(s.seq, vc.VELOCITY, qd)], lines)

    def test_kinds_without_a_float64_layout_or_without_a_usable_layout(self):
        for kind, message in (("camera", "camera devices are not float64 arrays"),
                              (vc.KIND_MARKERS, "markers devices are not float64 arrays"),
                              ("webcam", "device kind 'webcam' is not one of arm, wrench"), (99, "99")):
            with self.assertRaisesRegex(ValueError, message):
                vc.LayoutDevice(kind, "127.0.0.1", 50010)
        gripper = {"name": "g", "kind": "gripper", "protocol": 2}
        cases = [(dict(gripper), "has no layout"),
                 (dict(gripper, layout={"state": ["status", "marker[count]"]}), "'marker\\[count\\]' has no whole"),
                 (dict(gripper, layout={"state": ["x", "x"]}), "names 'x' twice"),
                 (dict(gripper, layout={"state": ["x", 3]}), "holds 3, not a field name")]
        for reply, message in cases:
            device = FakeDevice(describe=json.dumps(reply).encode(), kind=vc.KIND_GRIPPER)
            try:
                with self.assertRaisesRegex(vc.ProtocolError, message):
                    vc.LayoutDevice("gripper", "127.0.0.1", device.port, timeout=PATIENCE_S)
            finally:
                device.close()

    def test_kind_codes_are_the_protocol_pages(self):
        # docs/protocol.md, "Devices and ports": | kind | code | ... |
        with open(os.path.join(SOURCE, "docs", "protocol.md"), encoding="utf-8") as page:
            text = page.read()
        table = text[text.index("## Devices and ports"):]
        rows = re.findall(r"^\| (\w+) \| (\d+) \|", table[:table.index("\n\n", table.index("| kind |"))], re.M)
        self.assertEqual({int(code): name for name, code in rows}, vc.KIND_NAMES)


class SimTest(unittest.TestCase):
    """Sim against the lab's sim device (vlab serve, realtime): each operation answers a state the
    sim device sent (the state sent again after an operation has a seq of its own); a paused owner
    that renews keeps the pause past the owner timeout, one that falls silent loses the sim and the
    lab resumes."""

    def read_until_mode(self, sim, mode):
        """The states read up to and with the first one in `mode`."""
        states = [sim.read(PATIENCE_S)]
        while states[-1].mode != mode:
            self.assertLess(len(states), 5000, "the sim never went to mode %d" % mode)
            states.append(sim.read(PATIENCE_S))
        return states

    def test_pause_step_resume_and_a_silent_owner(self):
        if not VLAB:
            self.skipTest("no --vlab given")
        # the test's arm and sim are two sockets, like a person who pauses a run a controller drives
        lab = Lab(sim_ops_from="anyone")
        try:
            with vc.Sim("127.0.0.1", lab.sim_port, timeout=PATIENCE_S) as sim, \
                    vc.Arm("127.0.0.1", lab.arm_port, timeout=PATIENCE_S) as arm:
                a = arm.read(PATIENCE_S)
                self.assertTrue(arm.write(vc.HOLD, [], a.seq))  # the lab's period 0 waits for a controller
                s = sim.read_latest(PATIENCE_S)
                self.assertEqual((s.mode, s.clock), (0, 2))
                self.assertTrue(sim.write(vc.SIM_PAUSE, 0, s.seq))
                paused = self.read_until_mode(sim, 1)[-1]

                # paused, the owner renews for longer than the owner timeout: no state, still paused
                until = time.monotonic() + 1.5
                while time.monotonic() < until:
                    self.assertTrue(sim.keep_alive())
                    with self.assertRaises(vc.VlabTimeout):
                        sim.read(0.2)

                self.assertTrue(sim.write(vc.SIM_STEP, 5, paused.seq))
                stepped = self.read_until_mode(sim, 1)
                seqs = [paused.seq] + [x.seq for x in stepped]
                self.assertEqual(seqs, list(range(paused.seq, paused.seq + len(seqs))))  # one per state sent
                self.assertEqual(stepped[-1].periods, paused.periods + 5)
                self.assertAlmostEqual(stepped[-1].sim_time, paused.sim_time + 5 * 0.002, places=9)
                with self.assertRaises(vc.VlabTimeout):
                    sim.read(0.3)
                self.assertTrue(sim.write(vc.SIM_RESUME, 0, stepped[-1].seq))
                self.read_until_mode(sim, 0)

                # paused again, the owner falls silent: the lab resumes after the owner timeout
                s = sim.read_latest(PATIENCE_S)
                self.assertTrue(sim.write(vc.SIM_PAUSE, 0, s.seq))
                self.read_until_mode(sim, 1)
                silent_since = time.monotonic()
                resumed = sim.read(PATIENCE_S)
                self.assertEqual(resumed.mode, 0)
                self.assertGreater(time.monotonic() - silent_since, 0.9)
        finally:
            lab.stop()


class ExampleTest(unittest.TestCase):
    """The joint_control examples against a kinematic arm that follows their commands."""

    def run_example(self, command):
        server = ArmServer(seconds=120, follow=True)
        try:
            result = subprocess.run(command + ["--arm", "127.0.0.1:%d" % server.port, "--max-error", "0.05"],
                                    stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=60)
        finally:
            server.stop()
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        lines = result.stdout.splitlines()
        self.assertEqual(len([line for line in lines if line.startswith("pose ")]), 3, lines)
        self.assertRegex(lines[-1], r"^max tracking error: \d+\.\d+ rad$")
        self.assertLess(float(lines[-1].split()[3]), 0.05)

    def test_cpp_example(self):
        if not JOINT_CONTROL:
            self.skipTest("no --joint-control given")
        self.run_example([JOINT_CONTROL])

    def test_python_example(self):
        self.run_example([sys.executable, os.path.join(SOURCE, "examples", "joint_control.py")])

    def test_bridge_error_exits_2(self):
        silent = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        silent.bind(("127.0.0.1", 0))
        try:
            result = subprocess.run([sys.executable, os.path.join(SOURCE, "examples", "joint_control.py"),
                                     "--arm", "127.0.0.1:%d" % silent.getsockname()[1]],
                                    stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=60)
        finally:
            silent.close()
        self.assertEqual(result.returncode, 2)
        self.assertIn("no answer within", result.stderr)


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--server", required=True)
    parser.add_argument("--joint-control", default=None)
    parser.add_argument("--yoyosim", default=None)
    parser.add_argument("--vlab", default=None)
    args, rest = parser.parse_known_args()
    SERVER, JOINT_CONTROL = args.server, args.joint_control
    # (they run from the source root)
    YOYOSIM = os.path.abspath(args.yoyosim) if args.yoyosim else None
    VLAB = os.path.abspath(args.vlab) if args.vlab else None
    unittest.main(argv=[sys.argv[0], "-v"] + rest)

#!/usr/bin/env python3
"""Tests bridge/python/vlab_client.py: the Python client against a real device endpoint
(tests/bridge/test_arm_server, C++), against scripted peers for the faults, LayoutDevice
against vlab-yoyosim's point and yoyo devices, and the joint_control examples (C++ and
Python) end to end.

    python_client_test.py --server PATH [--joint-control PATH] [--yoyosim PATH]
                          [unittest args, e.g. ClientTest]

Timeouts are seconds, never tight: the tests must pass on a loaded machine.
"""

import argparse
import json
import os
import re
import socket
import struct
import subprocess
import sys
import threading
import time
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "bridge", "python"))
import vlab_client as vc  # noqa: E402

SERVER = None          # test_arm_server binary (--server)
JOINT_CONTROL = None   # examples/joint_control binary (--joint-control)
YOYOSIM = None         # vlab-yoyosim binary (--yoyosim)
PATIENCE_S = 5.0       # how long a test waits for something that must happen

# docs/protocol.md, "A worked example"
WORKED_EXAMPLE_HEX = (
    "000080501093d541000000000000f03f000000000000f03f0000000000000040"
    "0000000000004540000000000000f83f00000000000020400000000000000040"
    "000000000000e03f000000000000d0bf000000000000c03f0000000000000000"
    "000000000000f03f000000000000f0bf000000000000b03f")


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


class Peer:
    """A scripted device: answers the first datagram it gets with the given replies."""

    def __init__(self, *replies):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(PATIENCE_S)
        self.port = self.sock.getsockname()[1]
        self.request = None
        self.client = None
        self.thread = threading.Thread(target=self._answer, args=(replies,))
        self.thread.start()

    def _answer(self, replies):
        try:
            self.request, self.client = self.sock.recvfrom(65536)
        except socket.timeout:
            return
        for r in replies:
            self.sock.sendto(r, self.client)

    def send(self, data):
        self.sock.sendto(data, self.client)

    def close(self):
        self.thread.join()
        self.sock.close()


def describe_json(**changes):
    d = {"name": "pa10", "kind": "arm", "protocol": 1, "joints": ["S1", "S2", "S3", "E1", "E2", "W1", "W2"],
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
            "too long": [struct.pack("<1025d", vc.MAGIC, 1, 1, 1, 0, 0, 1018, *([0] * 1018))],
            "bad magic": [struct.pack("<d", 1.0) + good[8:]],
            "non-finite": [good[:40] + struct.pack("<d", float("nan")) + good[48:],
                           good[:-8] + struct.pack("<d", float("inf"))],
            "bad length": [good[:48] + struct.pack("<d", 21) + good[56:]],
            "bad seq": [good[:32] + struct.pack("<d", 2.5) + good[40:]],
            "bad kind": [good[:16] + struct.pack("<d", 0) + good[24:]],
            "bad type": [good[:24] + struct.pack("<d", 4) + good[32:]],
        }
        for reason, datagrams in cases.items():
            for data in datagrams:
                with self.assertRaisesRegex(vc.ProtocolError, reason):
                    vc.decode(data)
        with self.assertRaises(vc.VersionMismatch):
            vc.decode(good[:8] + struct.pack("<d", 2) + good[16:])

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
                self.assertEqual(arm.describe()["protocol"], 1)
                self.assertEqual(arm.joints, 7)
                self.assertEqual(arm.joint_names[4], "E2")
                self.assertEqual(arm.velocity_max, [2.0] * 7)
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

    def test_states_before_the_reply_and_keep_alive_replies_are_skipped(self):
        peer = Peer(arm_state(1), describe_json())
        try:
            arm = vc.Arm("127.0.0.1", peer.port, timeout=PATIENCE_S)
            peer.thread.join()
            self.assertEqual(vc.decode(peer.request)[:2], (vc.KIND_ARM, vc.TYPE_DESCRIBE))
            peer.send(describe_json())
            peer.send(arm_state(5))
            peer.send(arm_state(6))
            time.sleep(0.05)
            self.assertEqual(arm.read_latest(PATIENCE_S).seq, 6)
            with self.assertRaises(vc.VlabTimeout):
                arm.read(0.05)
            peer.send(arm_state(7, joints=6))
            with self.assertRaisesRegex(vc.ProtocolError, "bad length"):
                arm.read(PATIENCE_S)
            peer.send(vc.encode(vc.KIND_WRENCH, vc.TYPE_STATE, 8, 0, [0] * 8))
            with self.assertRaisesRegex(vc.ProtocolError, "wrong device kind"):
                arm.read(PATIENCE_S)
            arm.close()
        finally:
            peer.close()

    def test_faulty_replies(self):
        cases = [(b'{"kind": "arm", "protocol": 1,', vc.ProtocolError, "not valid JSON"),
                 (b"\xab" * 64, vc.ProtocolError, "bad magic"),
                 (describe_json(protocol=2), vc.VersionMismatch, "protocol version 2, this client speaks version 1"),
                 (describe_json(kind="wrench"), vc.ProtocolError, 'not "arm"'),
                 (describe_json(joints=[]), vc.ProtocolError, '"joints"'),
                 (arm_state(0)[:8] + struct.pack("<d", 2) + arm_state(0)[16:], vc.VersionMismatch, "version 2")]
        for reply, error, message in cases:
            peer = Peer(reply)
            try:
                with self.assertRaisesRegex(error, message):
                    vc.Arm("127.0.0.1", peer.port, timeout=PATIENCE_S)
            finally:
                peer.close()

    def test_silence_is_a_timeout_naming_the_endpoint(self):
        silent = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        silent.bind(("127.0.0.1", 0))
        port = silent.getsockname()[1]
        try:
            begin = time.monotonic()
            with self.assertRaisesRegex(vc.VlabTimeout, "127.0.0.1:%d: no describe reply" % port):
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
        gripper = {"name": "g", "kind": "gripper", "protocol": 1}
        cases = [(dict(gripper), "has no layout"),
                 (dict(gripper, layout={"state": ["status", "marker[count]"]}), "'marker\\[count\\]' has no whole"),
                 (dict(gripper, layout={"state": ["x", "x"]}), "names 'x' twice"),
                 (dict(gripper, layout={"state": ["x", 3]}), "holds 3, not a field name")]
        for reply, message in cases:
            peer = Peer(json.dumps(reply).encode())
            try:
                with self.assertRaisesRegex(vc.ProtocolError, message):
                    vc.LayoutDevice("gripper", "127.0.0.1", peer.port, timeout=PATIENCE_S)
            finally:
                peer.close()

    def test_kind_codes_are_the_protocol_pages(self):
        # docs/protocol.md, "Devices and ports": | kind | code | ... |
        with open(os.path.join(SOURCE, "docs", "protocol.md"), encoding="utf-8") as page:
            text = page.read()
        table = text[text.index("## Devices and ports"):]
        rows = re.findall(r"^\| (\w+) \| (\d+) \|", table[:table.index("\n\n", table.index("| kind |"))], re.M)
        self.assertEqual({int(code): name for name, code in rows}, vc.KIND_NAMES)


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
        self.assertIn("no describe reply", result.stderr)


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--server", required=True)
    parser.add_argument("--joint-control", default=None)
    parser.add_argument("--yoyosim", default=None)
    args, rest = parser.parse_known_args()
    SERVER, JOINT_CONTROL = args.server, args.joint_control
    YOYOSIM = os.path.abspath(args.yoyosim) if args.yoyosim else None  # it runs from the source root
    unittest.main(argv=[sys.argv[0], "-v"] + rest)

#!/usr/bin/env python3
"""Tests the Camera class of bridge/python/vlab_client.py against a real camera device
(tests/camera/test_camera_server, C++ CameraServer) over loopback, and the camera's
sessions (frames go to subscribers only).

    camera_python_test.py --server PATH [unittest args]

Timeouts are seconds, never tight: the tests must pass on a loaded machine.
"""

import argparse
import json
import os
import socket
import subprocess
import sys
import threading
import unittest

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "bridge", "python"))
import vlab_client as vc  # noqa: E402

SERVER = None  # test_camera_server binary (--server)

# docs/protocol_camera.md, "A worked example": the last chunk of a 4x2 raw frame (protocol version 2)
WORKED_EXAMPLE_HEX = (
    "000080501093d54100000000000000400000000000001040000000000000f03f"
    "0000000000001c40000000000000d03f0000000000003040000000000000f03f"
    "0000000000000040000000000000104000000000000000400000000000000000"
    "000000000000384000000000000030400000000000002040000000000000f03f"
    "000000000000e03f0000000000000000333333333333f33f0000000000000000"
    "000000000000f03f000000000000000000000000000000001011121314151617")


def pattern(frame_id, size):
    """Raw frame `frame_id` of test_camera_server: byte i = (7 i + 13 (i >> 8) + 31 id) mod 256."""
    return bytes((i * 7 + (i >> 8) * 13 + frame_id * 31) & 0xFF for i in range(size))


class CameraServer:
    """test_camera_server with the given options; it prints its port, then a line per frame."""

    def __init__(self, *args):
        self.proc = subprocess.Popen([SERVER] + [str(a) for a in args], stdout=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline()  # "listening 127.0.0.1:PORT"
        if not line.startswith("listening "):
            self.proc.kill()
            raise RuntimeError("test_camera_server did not start: %r" % line)
        self.port = int(line.rsplit(":", 1)[1])
        self.lines = []
        self.reader = threading.Thread(target=lambda: self.lines.extend(self.proc.stdout))
        self.reader.start()

    def stop(self):
        """Waits for the server to finish; returns its frame lines as {id: 'whole' | 'damaged'}."""
        self.proc.wait(timeout=60)
        self.reader.join()
        self.proc.stdout.close()
        frames = {}
        for line in self.lines:
            words = line.split()
            if words[:1] == ["frame"]:
                frames[int(words[1])] = words[2]
        return frames


class ChunkCodecTest(unittest.TestCase):
    def test_worked_example(self):
        c = vc.decode_chunk(bytes.fromhex(WORKED_EXAMPLE_HEX))
        self.assertEqual((c.frame_id, c.time, c.index, c.count), (7, 0.25, 1, 2))
        self.assertEqual((c.width, c.height, c.encoding, c.frame_bytes, c.offset, c.size), (4, 2, 0, 24, 16, 8))
        self.assertTrue(c.pose_valid)
        self.assertEqual(c.position, (0.5, 0.0, 1.2))
        self.assertEqual(c.orientation, (0.0, 1.0, 0.0, 0.0))
        self.assertEqual(bytes(c.data), bytes(range(16, 24)))

    def test_refusals_name_their_reason(self):
        good = bytearray(bytes.fromhex(WORKED_EXAMPLE_HEX))

        def reason(index, value, data=None):
            b = bytearray(data if data is not None else good)
            b[8 * index:8 * index + 8] = vc.struct.pack("<d", value)
            with self.assertRaises(vc.ChunkError) as e:
                vc.decode_chunk(bytes(b))
            return e.exception.reason

        self.assertEqual(reason(0, 1.0), "bad magic")
        self.assertEqual(reason(2, 1), "wrong device kind")
        self.assertEqual(reason(3, 2), "wrong message type")
        self.assertEqual(reason(4, 0.5), "value out of domain")
        self.assertEqual(reason(6, 15), "bad length")
        self.assertEqual(reason(5, float("nan")), "non-finite value")
        self.assertEqual(reason(9, 0), "bad image size or encoding")
        self.assertEqual(reason(13, 15), "bad chunk layout")
        self.assertEqual(reason(15, 2), "bad pose")
        with self.assertRaises(vc.ChunkError) as e:
            vc.decode_chunk(bytes(good[:-1]))
        self.assertEqual(e.exception.reason, "bad length")
        b = bytearray(good)
        b[8:16] = vc.struct.pack("<d", 1)
        with self.assertRaisesRegex(vc.VersionMismatch, "protocol version 1, this client speaks version 2"):
            vc.decode_chunk(bytes(b))


class CameraClientTest(unittest.TestCase):
    def test_raw_frames_every_byte(self):
        w, h, n = 160, 120, 15
        server = CameraServer("--frames", n, "--width", w, "--height", h, "--fps", 30, "--chunk-bytes", 8000)
        with vc.Camera("127.0.0.1", server.port, timeout=5.0) as camera:
            d = camera.describe()
            self.assertEqual((d["kind"], d["name"], d["encoding"]), ("camera", "pattern", "raw"))
            self.assertEqual((camera.width, camera.height, camera.fps), (w, h, 30.0))
            self.assertEqual(camera.intrinsics, {"fx": 160.0, "fy": 160.0, "cx": 79.5, "cy": 59.5})
            self.assertGreaterEqual(camera.receive_buffer, 2 * 1024 * 1024)
            for want in range(n):
                f = camera.read(timeout=5.0)
                self.assertEqual(f.id, want)
                self.assertEqual((f.width, f.height, f.encoding), (w, h, "raw"))
                self.assertEqual(f.data, pattern(want, 3 * w * h), "frame %d torn" % want)
                self.assertEqual(f.rgb, f.data)
                self.assertAlmostEqual(f.time, want / 30.0)
                self.assertTrue(f.pose_valid)
                self.assertEqual(f.position, (0.5, 0.0, 1.2))
                self.assertEqual(f.orientation, (0.0, 1.0, 0.0, 0.0))
            self.assertEqual(camera.counters["frames_dropped"], 0)
            self.assertEqual(camera.counters["refused"], 0)
            with self.assertRaises(vc.VlabTimeout):
                camera.read(timeout=0.3)
        server.stop()

    def test_lost_chunks_drop_exactly_the_damaged_frames(self):
        w, h, n = 160, 120, 40
        server = CameraServer("--frames", n, "--width", w, "--height", h, "--fps", 60, "--chunk-bytes", 4000,
                              "--drop", 0.03, "--seed", 5)
        received = []
        with vc.Camera("127.0.0.1", server.port, timeout=5.0, frame_timeout=0.3) as camera:
            while True:
                try:
                    f = camera.read(timeout=1.5)
                except vc.VlabTimeout:
                    break
                self.assertEqual(f.data, pattern(f.id, 3 * w * h), "frame %d torn" % f.id)
                received.append(f.id)
            counters = camera.counters
        frames = server.stop()
        whole = [i for i in sorted(frames) if frames[i] == "whole"]
        damaged = [i for i in sorted(frames) if frames[i] == "damaged"]
        self.assertEqual(len(frames), n)
        self.assertGreater(len(damaged), 2, "the test hook must damage some frames")
        self.assertEqual(received, whole)
        self.assertEqual(counters["frames_dropped"], len(damaged))
        self.assertGreater(whole[-1], damaged[0], "later frames still arrive")

    def test_read_latest_returns_the_newest(self):
        server = CameraServer("--frames", 6, "--width", 32, "--height", 24, "--fps", 1000)
        with vc.Camera("127.0.0.1", server.port, timeout=5.0) as camera:
            server.proc.wait(timeout=30)  # every frame is queued by now
            f = camera.read_latest(timeout=2.0)
            self.assertEqual(f.id, 5)
            self.assertEqual(camera.frames_skipped, 5)
        server.stop()

    def test_jpeg(self):
        server = CameraServer("--frames", 20, "--width", 64, "--height", 48, "--encoding", "jpeg", "--fps", 20)
        try:
            if vc._cv2() is None:
                # no OpenCV for Python: a clear error, and the JPEG bytes on request
                with self.assertRaises(vc.VlabError) as e:
                    vc.Camera("127.0.0.1", server.port, timeout=5.0)
                self.assertIn("cv2", str(e.exception))
                self.assertIn("--encoding raw", str(e.exception))
                with vc.Camera("127.0.0.1", server.port, timeout=5.0, decode=False) as camera:
                    f = camera.read(timeout=5.0)
                    self.assertEqual(f.encoding, "jpeg")
                    self.assertEqual(f.data[:2], b"\xff\xd8")  # a JPEG file's start-of-image marker
                    self.assertIsNone(f.rgb)
            else:
                with vc.Camera("127.0.0.1", server.port, timeout=5.0) as camera:
                    f = camera.read(timeout=5.0)
                    self.assertEqual(len(f.rgb), 64 * 48 * 3)
                    # test_camera_server's gradient: green = row, blue = 128
                    self.assertLess(abs(f.rgb[3 * (64 * 20 + 10) + 1] - 20), 6)
                    self.assertLess(abs(f.rgb[3 * (64 * 20 + 10) + 2] - 128), 6)
        finally:
            server.stop()

    def test_wrong_kind_is_refused(self):
        server = CameraServer("--frames", 1, "--fps", 1)
        try:
            with self.assertRaises(vc.ProtocolError) as e:
                vc.Arm("127.0.0.1", server.port, timeout=5.0)
            self.assertIn('kind "camera", not "arm"', str(e.exception))
            # (an arm cannot subscribe to a camera: a camera client does, and the server ends)
            with vc.Camera("127.0.0.1", server.port, timeout=5.0) as camera:
                self.assertEqual(camera.read(timeout=5.0).id, 0)
        finally:
            server.stop()

    def test_frames_go_to_subscribers_only(self):
        """A describe request without the cookie gets a 72-byte challenge and nothing else; with
        it, the JSON and no chunk; a subscribe request of kind 4 with it brings the frames."""
        w, h = 32, 24
        server = CameraServer("--frames", 2, "--width", w, "--height", h, "--fps", 10)
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        device = ("127.0.0.1", server.port)

        def receive_all(quiet_s):
            sock.settimeout(quiet_s)
            out = []
            while True:
                try:
                    out.append(sock.recv(65536))
                except socket.timeout:
                    return out

        try:
            sock.bind(("127.0.0.1", 0))
            sock.sendto(vc.encode_describe_request(vc.KIND_CAMERA, 0), device)
            answer = receive_all(0.5)
            self.assertEqual([len(d) for d in answer], [72])
            kind, cookie, result = vc.parse_session_reply(answer[0])
            self.assertEqual((kind, result), (vc.KIND_CAMERA, vc.SESSION_CHALLENGE))
            sock.sendto(vc.encode_describe_request(vc.KIND_ANY, cookie), device)
            answer = receive_all(0.5)
            self.assertEqual(len(answer), 1)
            self.assertEqual(json.loads(answer[0].decode())["kind"], "camera")
            self.assertTrue(server.proc.poll() is None and not server.lines, "no frame without a subscriber")

            sock.sendto(vc.encode_subscribe_request(vc.KIND_CAMERA, cookie, vc.SUBSCRIBE), device)
            sock.settimeout(5.0)
            self.assertEqual(vc.parse_session_reply(sock.recv(65536)), (vc.KIND_CAMERA, cookie, vc.SESSION_SUBSCRIBED))
            chunks = [vc.decode_chunk(sock.recv(65536)) for _ in range(2)]
            self.assertEqual([(c.frame_id, c.index, c.count) for c in chunks], [(0, 0, 1), (1, 0, 1)])
            self.assertEqual(bytes(chunks[1].data), pattern(1, 3 * w * h))
            sock.sendto(vc.encode_subscribe_request(vc.KIND_CAMERA, cookie, vc.UNSUBSCRIBE), device)
            self.assertEqual(vc.parse_session_reply(sock.recv(65536)),
                             (vc.KIND_CAMERA, cookie, vc.SESSION_UNSUBSCRIBED))
        finally:
            sock.close()
            frames = server.stop()
        self.assertEqual(frames, {0: "whole", 1: "whole"})


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--server", required=True)
    args, rest = parser.parse_known_args()
    SERVER = args.server
    unittest.main(argv=[sys.argv[0]] + rest)

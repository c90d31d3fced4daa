#!/usr/bin/env python3
"""joint_control.py: a joint-space controller for the PA10, in Python, using only
bridge/python/vlab_client.py (standard library; no pip installs).

    python3 examples/joint_control.py [--arm HOST:PORT] [--gain K] [--max-error E]

The same program as examples/joint_control.cc: read the first state, move through
a fixed set of poses along quintic joint paths (about 2 s each, longer when the
arm's velocity limits ask for it) and back to the start pose in velocity mode,
    qd_cmd = qd_des + K (q_des - q),   K = 10 /s by default,
answering each state with seq = state.seq. Time is the state's simulated time
relative to the first state's, so it runs in lockstep and in realtime alike.

Prints one line per pose reached and "max tracking error: X rad". Exit 0; 1 when
--max-error is given and exceeded; 2 on a bridge error (printed) or bad arguments.
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bridge", "python"))
import vlab_client  # noqa: E402

SEGMENT_S = 2.0        # nominal duration of one move
HOLD_S = 0.5           # hold at the end before stopping
READ_TIMEOUT_S = 1.0
POSES = [[0.3, 0.2, 0.2, 1.2, -0.3, 1.0, 0.5],
         [-0.3, 0.4, -0.2, 0.9, 0.3, 1.4, -0.5]]


def make_path(start, velocity_max):
    """Waypoints start -> POSES -> start and each segment's end time (s); a segment is
    stretched so that its peak speed (15/8 of the mean) stays below 80% of a limit."""
    poses = [list(start)] + POSES + [list(start)]
    end_s, t = [], 0.0
    for a, b in zip(poses, poses[1:]):
        length = SEGMENT_S
        for j, vmax in enumerate(velocity_max):
            length = max(length, 1.875 * abs(b[j] - a[j]) / (0.8 * vmax))
        t += length
        end_s.append(t)
    return poses, end_s


def sample(poses, end_s, t):
    """q_des (rad), qd_des (rad/s) at t: quintic s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5."""
    i = 0
    while i + 1 < len(end_s) and t > end_s[i]:
        i += 1
    begin = end_s[i - 1] if i > 0 else 0.0
    length = end_s[i] - begin
    tau = min(max((t - begin) / length, 0.0), 1.0)
    s = tau ** 3 * (10 - 15 * tau + 6 * tau * tau)
    ds = 30 * tau * tau * (1 - 2 * tau + tau * tau) / length
    a, b = poses[i], poses[i + 1]
    return [x + s * (y - x) for x, y in zip(a, b)], [ds * (y - x) for x, y in zip(a, b)]


def run(host, port, gain, max_error_allowed):
    with vlab_client.Arm(host, port, timeout=READ_TIMEOUT_S) as arm:
        if arm.joints != 7:
            print("joint_control.py: %s has %d joints, this controller drives 7" % (arm.name, arm.joints),
                  file=sys.stderr)
            return 2
        print("connected to arm '%s' at %s:%d" % ((arm.name,) + tuple(arm.endpoint)))
        state = arm.read(READ_TIMEOUT_S)
        t0 = state.time
        poses, end_s = make_path(state.q, arm.velocity_max)
        max_error, reported = 0.0, 0
        while True:
            t = state.time - t0
            q_des, qd_des = sample(poses, end_s, t)
            max_error = max(max_error, max(abs(d - q) for d, q in zip(q_des, state.q)))
            while reported < len(end_s) and t >= end_s[reported]:
                reported += 1
                print("pose %d of %d at t = %.3f s: max tracking error so far %.6f rad"
                      % (reported, len(end_s), t, max_error))
            if t >= end_s[-1] + HOLD_S:
                break
            qd_cmd = [v + gain * (d - q) for v, d, q in zip(qd_des, q_des, state.q)]
            if arm.velocity_max:
                qd_cmd = [min(max(v, -0.95 * m), 0.95 * m) for v, m in zip(qd_cmd, arm.velocity_max)]
            arm.write(vlab_client.VELOCITY, qd_cmd, state.seq)
            state = arm.read_latest(READ_TIMEOUT_S)  # lockstep: the next one; realtime: the newest
        arm.write(vlab_client.HOLD, [], state.seq)
    print("max tracking error: %.6f rad" % max_error)
    if max_error_allowed is not None and max_error > max_error_allowed:
        print("exceeds --max-error %g rad" % max_error_allowed)
        return 1
    return 0


def main():
    parser = argparse.ArgumentParser(description="Joint-space PA10 controller over the vlab wire protocol.")
    parser.add_argument("--arm", default="127.0.0.1:50010", help="HOST:PORT of the arm device")
    parser.add_argument("--gain", type=float, default=10.0, help="position feedback gain K, 1/s")
    parser.add_argument("--max-error", type=float, default=None, help="fail (exit 1) above this error, rad")
    args = parser.parse_args()  # exits 2 on bad arguments
    host, _, port = args.arm.rpartition(":")
    host = host[1:-1] if host.startswith("[") and host.endswith("]") else host
    if not host or not port.isdigit() or args.gain < 0:
        parser.error("--arm must be HOST:PORT and --gain >= 0")
    try:
        return run(host, int(port), args.gain, args.max_error)
    except vlab_client.VlabError as e:
        print("joint_control.py: %s" % e, file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

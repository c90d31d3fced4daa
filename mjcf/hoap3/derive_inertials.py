#!/usr/bin/env python3
"""Derives the <inertial> elements of hoap3.xml from the manufacturer mass properties.

Input: the HOAP-3 "MassProperty" numbers as given in the vlab data sheet (DATASHEET 3.4,
from rokv/hoap-sl user/hoap3User/config/LinkParametersSim.cf, SL row format
`mass cmx cmy cmz i11 i12 i13 i22 i23 i33`, central inertia, SL product signs; the left-side
rows are the file's own LL_*/LA_* rows). The COM and inertia are expressed in the
Fujitsu/URDF link frame of each link; jrl-umi3218/hoap3_description urdf/hoap3.urdf gives
how those frames are turned in the zero pose (R_W_LINK below, columns = link axes in the
world frame, x forward, y left, z up). hoap3.xml uses world-aligned body frames in the zero
pose, so every COM becomes R c and every inertia R I R^T.

The forearm row (0.216 kg, "incl. wrist/hand") is split over three bodies: forearm, wrist
(the hand part that turns with RA_J5) and gripper finger (RA_J6). The wrist and finger get
small estimated masses; the forearm gets the rest, with its COM and central inertia solved
so that the three bodies together, at zero wrist and gripper angles, have exactly the data
sheet's mass, COM and central inertia.

Run: python3 derive_inertials.py   (prints one <inertial> line per body; standard library only)
"""

import math

# columns of R = link axes (x, y, z) in the world frame, zero pose (from the URDF origins)
R_W_LINK = {
    "WAIST": ((1, 0, 0), (0, 0, 1), (0, -1, 0)),    # pelvis
    "CHEST": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),     # waist-joint frame (SL/UC3M chest COM frame)
    "H_PAN": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    "H_ROLL": ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
    "SFE": ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
    "SAA": ((0, 1, 0), (-1, 0, 0), (0, 0, 1)),
    "SHR": ((0, 0, 1), (0, -1, 0), (1, 0, 0)),
    "EB": ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
    "LR": ((0, 1, 0), (-1, 0, 0), (0, 0, 1)),
    "LAA": ((0, 0, 1), (0, -1, 0), (1, 0, 0)),
    "LFE": ((0, 0, 1), (1, 0, 0), (0, 1, 0)),        # thigh, shank, ankle-pitch links
    "AAA": ((0, 0, 1), (0, -1, 0), (1, 0, 0)),
}

# body: (link frame, mass kg, COM m, (i11, i12, i13, i22, i23, i33) kg m^2)
LINKS = {
    "hoap3_pelvis": ("WAIST", 0.417, (-0.032271, 0.011138, -0.000329),
                     (6.6078e-4, -6.75e-6, -4.93e-6, 6.4212e-4, 1.52e-6, 1.7018e-4)),
    "hoap3_chest": ("CHEST", 3.26, (-0.049489, 0.000893, 0.084174),
                    (1.21947e-2, -2.9548e-4, -6.8400e-4, 1.75644e-2, -1.4580e-4, 1.56708e-2)),
    "hoap3_neck": ("H_PAN", 0.071, (0.005397, -0.001581, 0.056403),
                   (6.906e-5, -1.09e-6, 9.84e-6, 6.412e-5, -5.09e-6, 3.335e-5)),
    "hoap3_head": ("H_ROLL", 0.412, (-0.001040, -0.005180, 0.000018),
                   (5.5236e-4, -7.77e-6, -3.18e-6, 7.3214e-4, -4.6e-7, 6.8213e-4)),
    "hoap3_r_hip_yaw": ("LR", 0.0587, (-0.003015, -0.002240, 0.033585),
                        (5.983e-5, -4.1e-7, -5.70e-6, 4.320e-5, 2.94e-6, 2.958e-5)),
    "hoap3_r_hip_roll": ("LAA", 0.210, (-0.002727, 0.001135, 0.002378),
                         (6.941e-5, 8.9e-7, -4.5e-7, 5.871e-5, -5.1e-7, 5.474e-5)),
    "hoap3_r_thigh": ("LFE", 0.519, (-0.069821, 0.006165, -0.003264),
                      (3.3344e-4, 1.047e-5, -2.862e-5, 7.1543e-4, 1.853e-5, 6.6966e-4)),
    "hoap3_r_shank": ("LFE", 0.328, (-0.050852, 0.005368, -0.004697),
                      (2.1400e-4, 2.631e-5, 1.527e-5, 3.3474e-4, 9.48e-6, 2.7348e-4)),
    "hoap3_r_ankle": ("LFE", 0.195, (0.002937, 0.003668, -0.001337),
                      (6.355e-5, -3.0e-7, 5.9e-7, 5.298e-5, 9.5e-7, 5.279e-5)),
    "hoap3_r_foot": ("AAA", 0.154, (-0.029224, 0.003242, 0.008276),
                     (2.1926e-4, -3.30e-6, -1.634e-5, 1.7831e-4, 3.48e-6, 8.203e-5)),
    "hoap3_l_hip_yaw": ("LR", 0.0587, (0.003005, -0.002251, 0.033585),
                        (5.982e-5, 3.9e-7, 5.72e-6, 4.321e-5, 2.91e-6, 2.958e-5)),
    "hoap3_l_hip_roll": ("LAA", 0.210, (-0.002712, -0.001247, 0.002387),
                         (6.932e-5, -5.1e-7, -4.4e-7, 5.857e-5, 6.2e-7, 5.456e-5)),
    "hoap3_l_thigh": ("LFE", 0.519, (-0.069922, 0.006276, 0.003315),
                      (3.3312e-4, 1.043e-5, 2.935e-5, 7.1436e-4, -2.113e-5, 6.6904e-4)),
    "hoap3_l_shank": ("LFE", 0.328, (-0.050839, 0.005370, 0.004878),
                      (2.1099e-4, 2.628e-5, -1.584e-5, 3.3177e-4, -8.61e-6, 2.7352e-4)),
    "hoap3_l_ankle": ("LFE", 0.195, (0.002921, 0.003692, 0.001197),
                      (6.355e-5, -2.7e-7, -8.7e-7, 5.315e-5, -8.9e-7, 5.269e-5)),
    "hoap3_l_foot": ("AAA", 0.154, (-0.029224, -0.003346, 0.008276),
                     (2.1916e-4, 2.72e-6, -1.634e-5, 1.7831e-4, -2.85e-6, 8.193e-5)),
    "hoap3_r_shoulder": ("SFE", 0.210, (0.000083, 0.006668, 0.006348),
                         (8.667e-5, -7e-8, 5.2e-7, 6.700e-5, -3.25e-6, 7.296e-5)),
    "hoap3_r_upper_arm": ("SAA", 0.234, (-0.000658, -0.046385, -0.003774),
                          (1.9021e-4, -4.38e-6, 1.9e-7, 9.556e-5, -1.095e-5, 1.6691e-4)),
    "hoap3_r_arm_yaw": ("SHR", 0.1965, (-0.002722, -0.001603, -0.002204),
                        (6.500e-5, 1.2e-7, -1.21e-6, 5.291e-5, -6.0e-7, 6.807e-5)),
    "hoap3_r_forearm": ("EB", 0.216, (0.001002, 0.066422, -0.000616),
                        (3.6057e-4, 4.5e-7, -9.0e-7, 1.0338e-4, -2.205e-5, 3.3660e-4)),
    "hoap3_l_shoulder": ("SFE", 0.210, (-0.000036, 0.006642, -0.006348),
                         (8.668e-5, -9e-8, -2.1e-7, 6.700e-5, 3.15e-6, 7.297e-5)),
    "hoap3_l_upper_arm": ("SAA", 0.234, (0.000747, -0.046362, -0.003774),
                          (1.9070e-4, 4.54e-6, -4.7e-7, 9.553e-5, -1.082e-5, 1.6738e-4)),
    "hoap3_l_arm_yaw": ("SHR", 0.1965, (-0.002710, 0.001602, -0.002090),
                        (6.511e-5, -1.2e-7, -1.66e-6, 5.304e-5, 5.7e-7, 6.810e-5)),
    "hoap3_l_forearm": ("EB", 0.216, (0.000962, 0.066477, 0.000559),
                        (3.5907e-4, 7.3e-7, 7.3e-7, 1.0330e-4, 2.223e-5, 3.3523e-4)),
}

# Forearm split [EST]: wrist (servo + palm) and finger bodies, relative to the elbow point
# (forearm body origin), world-aligned, arm pointing +x in the zero pose.
WRIST = (0.110, 0.0, 0.0)            # elbow -> wrist joint (SL ARMLINK3)
FINGER = (0.150, 0.0, 0.010)          # elbow -> finger hinge (40 mm past the wrist, 10 mm up)
SPLIT = {
    # body: (mass, COM relative to its own body origin, central diag inertia)
    "wrist": (0.030, (0.022, 0.0, 0.0), (4.0e-6, 6.0e-6, 6.0e-6)),
    "finger": (0.005, (0.011, 0.0, 0.0), (2.0e-8, 2.5e-7, 2.5e-7)),
}


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def rot(frame):
    cols = R_W_LINK[frame]
    return [[cols[j][i] for j in range(3)] for i in range(3)]


def tensor(i):
    i11, i12, i13, i22, i23, i33 = i
    return [[i11, i12, i13], [i12, i22, i23], [i13, i23, i33]]


def to_world(frame, com, inertia):
    r = rot(frame)
    c = [sum(r[i][k] * com[k] for k in range(3)) for i in range(3)]
    rt = [[r[j][i] for j in range(3)] for i in range(3)]
    return c, matmul(matmul(r, tensor(inertia)), rt)


def shift(d, m):
    """m S(d): the parallel-axis term of a point mass m at offset d."""
    dd = sum(x * x for x in d)
    return [[m * ((dd if i == j else 0.0) - d[i] * d[j]) for j in range(3)] for i in range(3)]


def add(a, b, s=1.0):
    return [[a[i][j] + s * b[i][j] for j in range(3)] for i in range(3)]


def check(name, inertia):
    ev = principal(inertia)
    ok = min(ev) > 0 and ev[0] + ev[1] >= ev[2] and ev[1] + ev[2] >= ev[0] and ev[0] + ev[2] >= ev[1]
    if not ok:
        raise SystemExit(f"{name}: inertia not physical, principal moments {ev}")


def principal(a):
    """Eigenvalues of a symmetric 3x3 matrix (closed form)."""
    p1 = a[0][1] ** 2 + a[0][2] ** 2 + a[1][2] ** 2
    q = (a[0][0] + a[1][1] + a[2][2]) / 3
    p2 = sum((a[i][i] - q) ** 2 for i in range(3)) + 2 * p1
    p = math.sqrt(p2 / 6)
    b = [[(a[i][j] - (q if i == j else 0)) / p for j in range(3)] for i in range(3)]
    det = (b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0])
           + b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]))
    phi = math.acos(max(-1.0, min(1.0, det / 2))) / 3
    e1 = q + 2 * p * math.cos(phi)
    e3 = q + 2 * p * math.cos(phi + 2 * math.pi / 3)
    return sorted([e1, 3 * q - e1 - e3, e3])


def line(name, mass, c, i):
    check(name, i)
    full = (i[0][0], i[1][1], i[2][2], i[0][1], i[0][2], i[1][2])
    pos = " ".join(f"{x:.6f}" for x in c)
    fi = " ".join(f"{x:.6g}" for x in full)
    return f'{name:20s} <inertial pos="{pos}" mass="{mass:.6g}" fullinertia="{fi}"/>'


def split_forearm(side, c_tot, i_tot, m_tot):
    """Forearm, wrist and finger inertials whose composite equals the data-sheet forearm."""
    parts = []
    m_rest = 0.0
    moment = [0.0, 0.0, 0.0]
    for key, origin in (("wrist", WRIST), ("finger", FINGER)):
        m, com, diag = SPLIT[key]
        c = [origin[k] + com[k] for k in range(3)]
        parts.append((f"hoap3_{side}_{key}", m, com, c, [[diag[0], 0, 0], [0, diag[1], 0], [0, 0, diag[2]]]))
        m_rest += m
        moment = [moment[k] + m * c[k] for k in range(3)]
    m_f = m_tot - m_rest
    c_f = [(m_tot * c_tot[k] - moment[k]) / m_f for k in range(3)]
    i_f = i_tot
    for _, m, _, c, i in parts:
        d = [c[k] - c_tot[k] for k in range(3)]
        i_f = add(add(i_f, i, -1.0), shift(d, m), -1.0)
    d_f = [c_f[k] - c_tot[k] for k in range(3)]
    i_f = add(i_f, shift(d_f, m_f), -1.0)
    out = [line(f"hoap3_{side}_forearm", m_f, c_f, i_f)]
    for name, m, com, _, i in parts:
        out.append(line(name, m, com, i))
    return out


def main():
    total = 0.0
    for name, (frame, mass, com, inertia) in LINKS.items():
        c, i = to_world(frame, com, inertia)
        total += mass
        if name.endswith("_forearm"):
            for text in split_forearm(name.split("_")[1], c, i, mass):
                print(text)
        else:
            print(line(name, mass, c, i))
    print(f"total mass {total:.4f} kg")


if __name__ == "__main__":
    main()

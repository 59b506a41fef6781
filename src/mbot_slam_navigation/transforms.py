"""Rigid transforms: 4x4 numpy matrices (URDF/SDF xyz + roll-pitch-yaw), planar poses (x, y, yaw),
quaternions (x, y, z, w). Metres and radians."""
import math
from typing import Optional, Sequence, Tuple

import numpy as np


def from_xyz_rpy(xyz: Sequence[float], rpy: Sequence[float]) -> np.ndarray:
    """The transform of a URDF <origin>/SDF <pose>: rotation R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    t = np.eye(4)
    t[:3, :3] = [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                 [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                 [-sp, cp * sr, cp * cr]]
    t[:3, 3] = xyz
    return t


def planar(t: np.ndarray) -> Tuple[float, float, float]:
    """(x, y, yaw) of a transform, dropping z, roll and pitch."""
    return float(t[0, 3]), float(t[1, 3]), math.atan2(t[1, 0], t[0, 0])


def normalize_angle(a: float) -> float:
    """The angle [rad] wrapped into (-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))


def compose2d(a: Sequence[float], b: Sequence[float]) -> Tuple[float, float, float]:
    """Planar pose composition a (+) b: b given in a's frame, returned in a's parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    yaw = normalize_angle(a[2] + b[2])
    return a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], yaw


def inverse2d(a: Sequence[float]) -> Tuple[float, float, float]:
    """The inverse planar pose: compose2d(a, inverse2d(a)) == (0, 0, 0)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return -c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2]


def relative2d(a: Sequence[float], b: Sequence[float]) -> Tuple[float, float, float]:
    """Pose b expressed in the frame of pose a (inverse2d(a) (+) b)."""
    return compose2d(inverse2d(a), b)


def yaw_to_quaternion(yaw: float) -> Tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation about z."""
    return 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


def quaternion_to_yaw(x: float, y: float, z: float, w: float) -> float:
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def check_planar_quaternion(q: Sequence[float], what: str = 'the orientation') -> Tuple[Optional[float], str]:
    """(yaw, warning) of a quaternion (x, y, z, w) for planar navigation, or (None, why) when it
    cannot be used (ROS's isQuaternionValid): NaN, zero length or tilted. One that is not unit length
    is normalized, and the warning (else '') says so; `what` names it in the messages."""
    v = np.array(q, float)
    if not np.all(np.isfinite(v)):
        return None, '%s has NaN or infinite components' % what
    n = float(np.linalg.norm(v))
    if n < 1e-6:
        return None, '%s is a zero quaternion (length %.3g); it has no heading' % (what, n)
    warning = ''
    if abs(n - 1.0) > 1e-3:
        warning = '%s (%.3f, %.3f, %.3f, %.3f) has length %.3f; normalized' % ((what,) + tuple(v) + (n,))
    x, y, z, w = v / n
    up = 1.0 - 2.0 * (x * x + y * y)  # z component of the rotated z axis
    if up < 1.0 - 1e-3:
        return None, '%s tilts the robot (its z axis must stay vertical for planar navigation)' % what
    return quaternion_to_yaw(x, y, z, w), warning


def matrix_to_quaternion(t: np.ndarray) -> Tuple[float, float, float, float]:
    """(x, y, z, w) of the rotation part of a 4x4 (or 3x3) matrix."""
    r = np.asarray(t)[:3, :3]
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    if trace > 0:
        s = 2.0 * math.sqrt(trace + 1.0)
        q = ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s)
    else:  # pick the largest diagonal element for a stable square root
        i = int(np.argmax(np.diag(r)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(1.0 + r[i, i] - r[j, j] - r[k, k])
        v = [0.0, 0.0, 0.0]
        v[i] = 0.25 * s
        v[j] = (r[j, i] + r[i, j]) / s
        v[k] = (r[k, i] + r[i, k]) / s
        q = (v[0], v[1], v[2], (r[k, j] - r[j, k]) / s)
    return tuple(float(c) for c in q)


def quaternion_multiply(a, b) -> Tuple[float, float, float, float]:
    """Hamilton product a * b of (x, y, z, w) quaternions: rotate by b, then by a."""
    x1, y1, z1, w1 = a
    x2, y2, z2, w2 = b
    return (w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2, w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2, w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2)


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise convex hull of 2D points (Andrew's monotone chain)."""
    pts = sorted(set(map(tuple, np.round(np.asarray(points, float), 9))))
    if len(pts) <= 2:
        return np.array(pts)

    def half(seq):
        out = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(reversed(pts))
    return np.array(lower[:-1] + upper[:-1])

"""The relations metric of Kümmerle et al. (2009), "On measuring the accuracy of SLAM algorithms".

A relation (t1, t2, x, y, yaw) is the true motion from t1 to t2 in the robot frame at t1. With the
estimated poses P1, P2 at those times, the error is E = (P1^-1 P2) * R^-1; we report the mean and
standard deviation of |translation(E)| [m] and |angle(E)| [deg] over all relations (also of the
squares). Poses are looked up by time: interpolated between the two nearest estimates, which must
lie within `max_gap` seconds of the relation's time.
"""
import math
from dataclasses import dataclass

import numpy as np

from mbot_slam_navigation.transforms import compose2d, inverse2d, normalize_angle, relative2d


@dataclass
class RelationError:
    count: int
    trans_mean: float      # [m]
    trans_std: float
    trans2_mean: float     # [m^2]
    rot_mean: float        # [deg]
    rot_std: float
    rot2_mean: float       # [deg^2]
    skipped: int           # relations whose times had no estimate near enough


def read_relations(path: str) -> np.ndarray:
    """(N, 5): t1, t2, x, y, yaw."""
    rows = []
    with open(path) as f:
        for lineno, line in enumerate(f, 1):
            line = line.split('#', 1)[0].strip()
            if not line:
                continue
            v = line.split()
            if len(v) != 8:
                raise ValueError('%s:%d: a relation has 8 numbers (t1 t2 x y z roll pitch yaw), got %d'
                                 % (path, lineno, len(v)))
            t1, t2, x, y, _, _, _, yaw = map(float, v)
            rows.append((t1, t2, x, y, yaw))
    return np.array(rows)


def pose_at(times: np.ndarray, poses: np.ndarray, t: float, max_gap: float = 0.1):
    """The pose at time t, interpolated; None when no estimate lies within max_gap of t."""
    i = int(np.searchsorted(times, t))
    if i < len(times) and abs(times[i] - t) < 1e-6:
        return poses[i]
    if i == 0 or i == len(times):
        j = min(max(i, 0), len(times) - 1)
        return poses[j] if abs(times[j] - t) <= max_gap else None
    t0, t1 = times[i - 1], times[i]
    if min(t - t0, t1 - t) > max_gap:
        return None
    a = (t - t0) / (t1 - t0) if t1 > t0 else 0.0
    p0, p1 = poses[i - 1], poses[i]
    dyaw = normalize_angle(p1[2] - p0[2])
    return np.array([p0[0] + a * (p1[0] - p0[0]), p0[1] + a * (p1[1] - p0[1]), p0[2] + a * dyaw])


def evaluate(times: np.ndarray, poses: np.ndarray, relations: np.ndarray, max_gap: float = 0.1) -> RelationError:
    order = np.argsort(times)
    times, poses = np.asarray(times)[order], np.asarray(poses)[order]
    trans, rot, skipped = [], [], 0
    for t1, t2, x, y, yaw in relations:
        p1, p2 = pose_at(times, poses, t1, max_gap), pose_at(times, poses, t2, max_gap)
        if p1 is None or p2 is None:
            skipped += 1
            continue
        err = compose2d(relative2d(p1, p2), inverse2d((x, y, yaw)))
        trans.append(math.hypot(err[0], err[1]))
        rot.append(abs(math.degrees(normalize_angle(err[2]))))
    trans, rot = np.array(trans), np.array(rot)
    if len(trans) == 0:
        raise ValueError('no relation could be evaluated: are the trajectory times those of the log?')
    return RelationError(count=len(trans), trans_mean=float(trans.mean()), trans_std=float(trans.std()),
                         trans2_mean=float((trans ** 2).mean()), rot_mean=float(rot.mean()), rot_std=float(rot.std()),
                         rot2_mean=float((rot ** 2).mean()), skipped=skipped)

"""Maps in map_server's format: a PGM image and a YAML file, written atomically.

map_saver's conventions: occupied cells (>= occupied_thresh * 100) are 0 (black), free cells
(<= free_thresh * 100) are 254, unknown 205; the image's top row is the map's highest y.
"""
import os
import tempfile
from typing import Sequence

import numpy as np
import yaml

FREE, OCCUPIED, UNKNOWN = 254, 0, 205


def _atomic_write(path: str, data: bytes) -> None:
    """Writes to a temporary file beside `path` and renames it over: never a half-written file."""
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix='.' + os.path.basename(path) + '.', dir=directory)
    try:
        with os.fdopen(fd, 'wb') as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def occupancy_to_image(data: np.ndarray, occupied_thresh: float = 0.65, free_thresh: float = 0.196) -> np.ndarray:
    """(H, W) occupancy values (-1, 0..100, rows from the lowest y) to a PGM image (top row = max y)."""
    data = np.asarray(data)
    img = np.full(data.shape, UNKNOWN, np.uint8)
    img[(data >= 0) & (data <= free_thresh * 100)] = FREE
    img[data >= occupied_thresh * 100] = OCCUPIED
    return img[::-1]


def save_map(basename: str, data: np.ndarray, resolution: float, origin: Sequence[float],
             occupied_thresh: float = 0.65, free_thresh: float = 0.196) -> None:
    """Writes basename.pgm and basename.yaml (image path relative, as map_saver writes it)."""
    img = occupancy_to_image(data, occupied_thresh, free_thresh)
    h, w = img.shape
    _atomic_write(basename + '.pgm', b'P5\n# CREATOR: mbot_slam_navigation %.3f m/pix\n%d %d\n255\n' % (resolution, w, h)
                  + img.tobytes())
    meta = {'image': os.path.basename(basename) + '.pgm', 'resolution': float(resolution),
            'origin': [float(origin[0]), float(origin[1]), float(origin[2]) if len(origin) > 2 else 0.0],
            'negate': 0, 'occupied_thresh': float(occupied_thresh), 'free_thresh': float(free_thresh)}
    _atomic_write(basename + '.yaml', yaml.safe_dump(meta, default_flow_style=None, sort_keys=False).encode())

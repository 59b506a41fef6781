"""Maps in map_server's format: a YAML file naming an image, loaded as map_server does and written
atomically as map_saver does.

map_saver's conventions: occupied cells (>= occupied_thresh * 100) are 0 (black), free cells
(<= free_thresh * 100) are 254, unknown 205; the image's top row is the map's highest y.
map_server's: see load_map (the pixel rules are the C++ core's, include/.../core/map_image.h).
"""
import math
import os
import tempfile
from dataclasses import dataclass
from typing import Sequence, Tuple

import numpy as np
import yaml

FREE, OCCUPIED, UNKNOWN = 254, 0, 205
# map_saver's default thresholds as OccupancyGrid values: >= SAVER_OCCUPIED saved occupied,
# 0..SAVER_FREE free. Every module that calls a cell of a SLAM map occupied or free uses these.
SAVER_OCCUPIED, SAVER_FREE = 65, 25


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
    img[(data >= 0) & (data <= free_thresh * 100 + 1e-9)] = FREE  # 1e-9: 0.29 * 100 < 29
    img[data >= occupied_thresh * 100 - 1e-9] = OCCUPIED
    return img[::-1]


# map_server reads the unknown grey (205, occ = 50/255 = 0.19608) as unknown only while
# free_thresh <= 0.19608 <= occupied_thresh: the YAML's thresholds are kept inside these bounds.
_UNKNOWN_OCC = (255 - UNKNOWN) / 255.0


def save_map(basename: str, data: np.ndarray, resolution: float, origin: Sequence[float],
             occupied_thresh: float = 0.65, free_thresh: float = 0.196) -> None:
    """Writes basename.pgm, then basename.yaml (image path relative, as map_saver writes it), each
    atomically: a YAML file on disk always names a complete image.

    Cells >= occupied_thresh * 100 are saved occupied, 0..free_thresh * 100 free. The YAML records
    these thresholds, except where map_server would then read the unknown grey as free (free_thresh
    above 0.196) or occupied (occupied_thresh below 0.197): there it records the bound, and a comment
    says which thresholds the image was saved with."""
    img = occupancy_to_image(data, occupied_thresh, free_thresh)
    h, w = img.shape
    _atomic_write(basename + '.pgm', b'P5\n# CREATOR: mbot_slam_navigation %.3f m/pix\n%d %d\n255\n' % (resolution, w, h)
                  + img.tobytes())
    read_occ = max(float(occupied_thresh), 0.197)
    read_free = min(float(free_thresh), round(_UNKNOWN_OCC, 3))
    # Six decimals, as map_saver's %f: a float32 resolution from a message (0.05000000074505806) or
    # an origin summed from cells (-5.199999999999999) reads back as what it means.
    meta = {'image': os.path.basename(basename) + '.pgm', 'resolution': round(float(resolution), 6),
            'origin': [round(float(v), 6) for v in (origin[0], origin[1], origin[2] if len(origin) > 2 else 0.0)],
            'negate': 0, 'occupied_thresh': read_occ, 'free_thresh': read_free}
    text = yaml.safe_dump(meta, default_flow_style=None, sort_keys=False)
    if (read_occ, read_free) != (occupied_thresh, free_thresh):
        text += ('# saved with occupied_thresh %g, free_thresh %g; the thresholds above keep the unknown grey '
                 '(205) unknown when map_server reads the image\n' % (occupied_thresh, free_thresh))
    _atomic_write(basename + '.yaml', text.encode())


MODES = ('trinary', 'scale', 'raw')


def save_mask(basename: str, values: np.ndarray, resolution: float, origin: Sequence[float], speed: bool = False) -> None:
    """Writes a costmap filter's mask as map_server files (basename.pgm, basename.yaml, atomically).

    Keep-out (`speed` False): cells of `values` at 100 are forbidden (black), the rest free (white);
    trinary mode, so map_server serves 100 and 0. Speed: `values` are percentages 0..99 (0: no limit),
    written in scale mode with occupied_thresh 1.0 and free_thresh 0.0 (Nav2's speed masks): map_server
    serves floor(99 * darkness), and each grey is the darkest that still reads back as its value."""
    values = np.asarray(values)
    if speed:
        if values.min() < 0 or values.max() > 99:
            raise ValueError('speed mask values are percentages 0..99, got %g..%g' % (values.min(), values.max()))
        img = (255 - np.ceil(values.astype(float) * 255.0 / 99.0)).clip(0, 255).astype(np.uint8)[::-1]
        thresholds = {'mode': 'scale', 'occupied_thresh': 1.0, 'free_thresh': 0.0}
    else:
        img = np.where(values >= 100, OCCUPIED, FREE).astype(np.uint8)[::-1]
        thresholds = {'mode': 'trinary', 'occupied_thresh': 0.65, 'free_thresh': 0.196}
    h, w = img.shape
    _atomic_write(basename + '.pgm', b'P5\n# CREATOR: mbot_slam_navigation mask %.3f m/pix\n%d %d\n255\n'
                  % (resolution, w, h) + img.tobytes())
    meta = {'image': os.path.basename(basename) + '.pgm', 'resolution': round(float(resolution), 6),
            'origin': [round(float(v), 6) for v in (origin[0], origin[1], origin[2] if len(origin) > 2 else 0.0)],
            'negate': 0}
    meta.update(thresholds)
    _atomic_write(basename + '.yaml', yaml.safe_dump(meta, default_flow_style=None, sort_keys=False).encode())


class MapFileError(ValueError):
    """A map YAML or image that cannot be loaded; the message names the file and, where one is at
    fault, the key."""

    def __init__(self, path: str, message: str, key: str = ''):
        self.path, self.key = path, key
        super().__init__('%s: %s%s' % (path, "key '%s': " % key if key else '', message))


@dataclass
class LoadedMap:
    data: np.ndarray              # (height, width) int8 occupancy, row 0 = lowest y
    resolution: float             # [m/cell]
    origin: Tuple[float, float, float]  # lower-left cell's corner: x [m], y [m], yaw [rad]
    image: str                    # absolute path of the image
    negate: bool
    occupied_thresh: float
    free_thresh: float
    mode: str


def _number(doc: dict, path: str, key: str) -> float:
    if key not in doc:
        raise MapFileError(path, 'missing (map_server needs image, resolution, origin, negate, '
                                 'occupied_thresh and free_thresh)', key)
    value = doc[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise MapFileError(path, 'must be a finite number, not %r' % (value,), key)
    return float(value)


def load_map(yaml_path: str) -> LoadedMap:
    """Loads a map as map_server does: the YAML keys image (relative to the YAML's folder unless
    absolute), resolution, origin [x, y, yaw], negate, occupied_thresh, free_thresh and the optional
    mode (trinary, scale or raw). Raises MapFileError naming the file and key."""
    try:
        with open(yaml_path) as f:
            doc = yaml.safe_load(f)
    except OSError as e:
        raise MapFileError(yaml_path, 'cannot be read: %s' % e.strerror) from None
    except yaml.YAMLError as e:
        raise MapFileError(yaml_path, 'is not valid YAML: %s' % str(e).replace('\n', ' ')) from None
    if not isinstance(doc, dict):
        raise MapFileError(yaml_path, 'must be a YAML mapping of map_server keys')
    if not isinstance(doc.get('image'), str) or not doc.get('image'):
        raise MapFileError(yaml_path, 'missing or not a file name', 'image')
    resolution = _number(doc, yaml_path, 'resolution')
    if resolution <= 0:
        raise MapFileError(yaml_path, 'must be positive [m/cell], not %g' % resolution, 'resolution')
    origin = doc.get('origin')
    if origin is None:
        raise MapFileError(yaml_path, 'missing (the pose [x, y, yaw] of the lower-left pixel)', 'origin')
    if (not isinstance(origin, list) or len(origin) != 3
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) for v in origin)):
        raise MapFileError(yaml_path, 'must be [x, y, yaw] of finite numbers, not %r' % (origin,), 'origin')
    negate = _number(doc, yaml_path, 'negate')
    if negate not in (0.0, 1.0):
        raise MapFileError(yaml_path, 'must be 0 or 1, not %g' % negate, 'negate')
    occ = _number(doc, yaml_path, 'occupied_thresh')
    free = _number(doc, yaml_path, 'free_thresh')
    for key, value in (('occupied_thresh', occ), ('free_thresh', free)):
        if not 0.0 <= value <= 1.0:
            raise MapFileError(yaml_path, 'must be in [0, 1], not %g' % value, key)
    if free >= occ:
        raise MapFileError(yaml_path, 'must be smaller than occupied_thresh (%g), not %g' % (occ, free), 'free_thresh')
    mode = doc.get('mode', 'trinary')
    if mode not in MODES:
        raise MapFileError(yaml_path, 'must be one of %s, not %r' % (', '.join(MODES), mode), 'mode')
    image = doc['image']
    if not os.path.isabs(image):
        image = os.path.join(os.path.dirname(os.path.abspath(yaml_path)), image)
    from mbot_slam_navigation import _core  # the C++ pixel rules; imported late so saving needs no build
    try:
        data = _core._load_map_image(image, occ, free, bool(negate), mode)
    except (RuntimeError, ValueError) as e:
        raise MapFileError(yaml_path, str(e), 'image') from None
    return LoadedMap(data=np.asarray(data), resolution=resolution,
                     origin=(float(origin[0]), float(origin[1]), float(origin[2])), image=image,
                     negate=bool(negate), occupied_thresh=occ, free_thresh=free, mode=mode)

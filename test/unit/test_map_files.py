"""map_server's YAML rules, map_saver's output and compare_maps, on files in a temporary folder."""
import math

import cv2
import numpy as np
import pytest
import yaml

from mbot_slam_navigation.maps.compare import compare_maps
from mbot_slam_navigation.maps.map_io import MapFileError, load_map, save_map


def room(width=120, height=90, seed=3):
    """A walled room with a few boxes and some unknown cells outside: -1 / 0 / 100 values."""
    rng = np.random.default_rng(seed)
    data = np.zeros((height, width), np.int8)
    data[:, :2] = data[:, -2:] = data[:2, :] = data[-2:, :] = 100
    for _ in range(4):
        x, y = rng.integers(10, width - 20), rng.integers(10, height - 20)
        data[y:y + 8, x:x + 5] = 100
    data[:6, :15] = -1
    return data


def write_yaml(path, **keys):
    doc = {'image': 'm.pgm', 'resolution': 0.05, 'origin': [0.0, 0.0, 0.0], 'negate': 0,
           'occupied_thresh': 0.65, 'free_thresh': 0.196}
    doc.update(keys)
    doc = {k: v for k, v in doc.items() if v is not None}
    with open(path, 'w') as f:
        yaml.safe_dump(doc, f)
    return str(path)


def test_save_then_load_gives_the_same_grid_and_pose(tmp_path):
    data = room()
    save_map(str(tmp_path / 'home'), data, 0.05, (-3.2, 1.5, 0.3), occupied_thresh=0.65, free_thresh=0.25)
    loaded = load_map(str(tmp_path / 'home.yaml'))
    np.testing.assert_array_equal(loaded.data, data)
    assert loaded.resolution == 0.05
    assert loaded.origin == pytest.approx((-3.2, 1.5, 0.3))
    # map_saver's default --free 25 is recorded as 0.196: above it the unknown grey would read free.
    assert (loaded.occupied_thresh, loaded.free_thresh, loaded.mode) == (0.65, 0.196, 'trinary')
    assert 'free_thresh 0.25' in (tmp_path / 'home.yaml').read_text()
    save_map(str(tmp_path / 'strict'), data, 0.05, (0, 0, 0), occupied_thresh=0.7, free_thresh=0.1)
    strict = load_map(str(tmp_path / 'strict.yaml'))
    assert (strict.occupied_thresh, strict.free_thresh) == (0.7, 0.1)  # the ones used, as given
    np.testing.assert_array_equal(strict.data, data)
    meta = yaml.safe_load(open(tmp_path / 'home.yaml'))
    assert meta['image'] == 'home.pgm'  # relative, so the pair can be moved together
    img = cv2.imread(str(tmp_path / 'home.pgm'), cv2.IMREAD_UNCHANGED)
    assert set(np.unique(img)) == {0, 205, 254}
    # The image's top row is the map's highest row: walls and the unknown corner land flipped.
    np.testing.assert_array_equal(img[::-1] == 0, data == 100)
    np.testing.assert_array_equal(img[::-1] == 205, data == -1)
    assert img[-1, 5] == 205 and img[0, 5] == 0


def test_saver_thresholds_decide_cells_between_them(tmp_path):
    data = np.array([[0, 20, 25, 30, 64, 65, 100, -1]], np.int8)
    save_map(str(tmp_path / 'm'), data, 0.1, (0, 0, 0), occupied_thresh=0.65, free_thresh=0.25)
    img = cv2.imread(str(tmp_path / 'm.pgm'), cv2.IMREAD_UNCHANGED)
    assert img[0].tolist() == [254, 254, 254, 205, 205, 0, 0, 205]
    # 0.29 * 100 is 28.999...: a cell of 29 is still free with --free 29.
    save_map(str(tmp_path / 'n'), np.array([[29]], np.int8), 0.1, (0, 0, 0), free_thresh=0.29)
    assert cv2.imread(str(tmp_path / 'n.pgm'), cv2.IMREAD_UNCHANGED)[0, 0] == 254


def test_negate_and_scale_mode_and_png_with_alpha(tmp_path):
    img = np.zeros((1, 3, 4), np.uint8)
    img[0, 0] = (255, 255, 255, 255)   # white
    img[0, 1] = (0, 0, 0, 255)         # black
    img[0, 2] = (128, 128, 128, 0)     # transparent grey
    cv2.imwrite(str(tmp_path / 'm.png'), img)
    m = load_map(write_yaml(tmp_path / 'a.yaml', image='m.png', mode='scale'))
    assert m.data[0].tolist() == [0, 100, -1]
    m = load_map(write_yaml(tmp_path / 'b.yaml', image='m.png', negate=1))
    assert m.data[0].tolist() == [100, 0, -1]


def test_absolute_image_path_and_relative_to_the_yaml_not_the_cwd(tmp_path, monkeypatch):
    save_map(str(tmp_path / 'm'), room(), 0.05, (0, 0, 0))
    monkeypatch.chdir('/')
    assert load_map(str(tmp_path / 'm.yaml')).data.shape == (90, 120)
    sub = tmp_path / 'sub'
    sub.mkdir()
    assert load_map(write_yaml(sub / 'abs.yaml', image=str(tmp_path / 'm.pgm'))).data.shape == (90, 120)


@pytest.mark.parametrize('keys, key, words', [
    ({'resolution': None}, 'resolution', 'missing'),
    ({'resolution': -0.05}, 'resolution', 'positive'),
    ({'resolution': 'fine'}, 'resolution', 'number'),
    ({'origin': [0, 0]}, 'origin', '[x, y, yaw]'),
    ({'origin': None}, 'origin', 'missing'),
    ({'negate': 2}, 'negate', '0 or 1'),
    ({'free_thresh': 0.7}, 'free_thresh', 'smaller than occupied_thresh'),
    ({'occupied_thresh': 1.5}, 'occupied_thresh', '[0, 1]'),
    ({'mode': 'ternary'}, 'mode', 'trinary, scale, raw'),
    ({'image': None}, 'image', 'missing'),
    ({'image': 'nothere.pgm'}, 'image', 'nothere.pgm'),
])
def test_bad_yaml_names_the_file_and_the_key(tmp_path, keys, key, words):
    save_map(str(tmp_path / 'm'), room(), 0.05, (0, 0, 0))
    path = write_yaml(tmp_path / 'bad.yaml', **keys)
    with pytest.raises(MapFileError) as e:
        load_map(path)
    assert e.value.key == key
    assert path in str(e.value) and key in str(e.value) and words in str(e.value)


def test_unreadable_image_and_yaml_are_errors(tmp_path):
    (tmp_path / 'm.pgm').write_bytes(b'P5\n10 10\n255\n' + b'\0' * 7)  # truncated
    with pytest.raises(MapFileError, match='image'):
        load_map(write_yaml(tmp_path / 'a.yaml'))
    (tmp_path / 'b.yaml').write_text('image: [unclosed\n')
    with pytest.raises(MapFileError, match='YAML'):
        load_map(str(tmp_path / 'b.yaml'))
    with pytest.raises(MapFileError, match='cannot be read'):
        load_map(str(tmp_path / 'none.yaml'))


def moved(data, dx_cells, dy_cells, yaw_deg):
    """The room as another run would map it: shifted and rotated about the grid centre."""
    h, w = data.shape
    img = np.where(data == 100, 0, np.where(data == 0, 254, 205)).astype(np.uint8)
    m = cv2.getRotationMatrix2D((w / 2, h / 2), yaw_deg, 1.0)
    m[:, 2] += (dx_cells, dy_cells)
    out = cv2.warpAffine(img, m, (w + 40, h + 40), flags=cv2.INTER_NEAREST, borderValue=205)
    return np.where(out == 0, 100, np.where(out == 254, 0, -1)).astype(np.int8)


def test_compare_maps_finds_the_alignment_and_scores_alike_maps_high(tmp_path):
    data = room()
    save_map(str(tmp_path / 'a'), data, 0.05, (0, 0, 0))
    save_map(str(tmp_path / 'b'), moved(data, 12, 7, 30), 0.05, (0, 0, 0))
    save_map(str(tmp_path / 'c'), room(seed=11), 0.05, (0, 0, 0))
    a, b, c = (load_map(str(tmp_path / n) + '.yaml') for n in 'abc')
    same, overlay = compare_maps(a, a)
    assert same.alignment == pytest.approx((0, 0, 0), abs=1e-6)
    assert same.similarity == pytest.approx(1.0)
    ab, _ = compare_maps(a, b)
    assert ab.occupied_f1 > 0.9 and ab.free_iou > 0.85, ab
    # The image rotation (counter-clockwise in the image, whose rows go down) is clockwise in the map.
    assert math.degrees(ab.alignment[2]) == pytest.approx(30, abs=1.5)
    ac, _ = compare_maps(a, c)
    assert ac.occupied_f1 < ab.occupied_f1 - 0.1, (ab, ac)
    unaligned, _ = compare_maps(a, b, align=False)
    assert unaligned.similarity < ab.similarity - 0.2
    assert overlay.shape[2] == 3 and overlay.dtype == np.uint8

"""Worlds from other sources than boxes: heights (lintels, tables), SDF <image> geometry, model://
includes through GAZEBO_MODEL_PATH, and a map_server map as the world; and the ground truth of them."""
import math
import os

import cv2
import numpy as np
import pytest

from mbot_slam_navigation.maps.map_io import MapFileError, save_map
from mbot_slam_navigation.sim.ground_truth import as_the_robot_meets_it, distance_to_surfaces, rasterize
from mbot_slam_navigation.sim.sdf_world import load_world, parse_world
from mbot_slam_navigation.sim.simulation import Simulation, SimulationError
from mbot_slam_navigation.sim.urdf_robot import LaserSpec, parse_urdf
from mbot_slam_navigation.sim.xmlutil import XmlError
from test_urdf_robot import BASE, DRIVE, LASER

ROBOT = BASE % (DRIVE + LASER % 180)  # body from the floor to 0.2 m, laser plane at 0.2 m


def sdf(models: str) -> str:
    return '<sdf version="1.6"><world name="w">%s</world></sdf>' % models


def box(name, x, y, z, sx, sy, sz):
    return ('<model name="%s"><static>true</static><pose>%g %g %g 0 0 0</pose><link name="l"><collision name="c">'
            '<geometry><box><size>%g %g %g</size></box></geometry></collision></link></model>'
            % (name, x, y, z, sx, sy, sz))


def robot():
    spec = parse_urdf(ROBOT)
    laser = spec.lasers[0]  # at (0.2, 0.15) in the base frame, facing +y (the base's left)
    laser.angle_min, laser.angle_max, laser.samples = -math.pi, math.pi, 361
    laser.noise_stddev = laser.range_resolution = 0.0
    return spec


def run(sim, name, v, seconds):
    for _ in range(int(round(seconds / sim.step_size))):
        sim.command(name, v, 0.0)
        sim.step()


# --- heights --------------------------------------------------------------------------------------
def doorway_world():
    # Walls 2 m high with a 1 m door at y in [-0.5, 0.5] through x = 2, and a lintel above the door.
    return parse_world(sdf(box('wall_s', 2.0, -2.0, 1.0, 0.1, 3.0, 2.0) + box('wall_n', 2.0, 2.0, 1.0, 0.1, 3.0, 2.0)
                           + box('lintel', 2.0, 0.0, 2.1, 0.1, 1.0, 0.2)
                           + box('tile', 0.0, -1.5, -0.05, 1.0, 1.0, 0.1)), 'door.world')


def test_shapes_keep_their_heights_and_what_is_under_the_floor_is_left_out():
    w = doorway_world()
    names = {s.name.split('/')[0]: s for s in w.shapes}
    assert 'tile' not in names  # wholly under the floor
    assert (names['lintel'].z_lo, names['lintel'].z_hi) == pytest.approx((2.0, 2.2))
    assert (names['wall_s'].z_lo, names['wall_s'].z_hi) == pytest.approx((0.0, 2.0))


def test_a_lintel_over_a_door_neither_stops_the_robot_nor_is_seen():
    sim = Simulation(doorway_world(), slip_stddev=0.0)
    r = sim.spawn('r', robot(), (0.0, 0.0, 0.0))
    ranges = sim.scan(r, r.lasers[0])
    assert math.isinf(ranges[180])  # straight ahead, through the door: nothing within range
    run(sim, 'r', 0.5, 8.0)
    assert r.collisions == 0 and r.pose[0] > 3.0  # drove through


def test_a_shape_above_the_robot_does_not_stop_it_and_a_low_one_does():
    w = parse_world(sdf(box('table_top', 2.0, 0.0, 0.72, 1.0, 1.0, 0.04) + box('step', -2.0, 0.0, 0.05, 0.2, 2.0, 0.1)))
    sim = Simulation(w, slip_stddev=0.0)
    r = sim.spawn('r', robot(), (0.0, 0.0, 0.0))
    ranges = sim.scan(r, r.lasers[0])
    assert math.isinf(ranges[180]) and math.isinf(ranges[0])  # neither cuts the plane at 0.2 m
    run(sim, 'r', 0.5, 8.0)
    assert r.collisions == 0 and r.pose[0] > 3.0
    run(sim, 'r', -0.5, 16.0)
    assert r.collisions == 1 and r.pose[0] > -2.0  # the step under the laser stops it


def test_spawning_in_a_wall_names_the_nearest_free_place():
    sim = Simulation(doorway_world(), slip_stddev=0.0)
    with pytest.raises(SimulationError, match=r'at \(2\.00, -2\.00\) would overlap an obstacle; the nearest free '
                                              r'place is \(2\.35, -2\.00\)'):
        sim.spawn('r', robot(), (2.0, -2.0, 0.0))  # the body reaches 0.3 m ahead and behind: 2.05 + 0.3 is free


def test_ground_truth_follows_the_robot():
    w, warning = as_the_robot_meets_it(doorway_world(), ROBOT)
    assert warning is None and sorted(s.name.split('/')[0] for s in w.shapes) == ['wall_n', 'wall_s']
    everything, warning = as_the_robot_meets_it(doorway_world(), '<robot name="x">')
    assert len(everything.shapes) == 3 and 'height is not known' in warning


# --- SDF <image> ----------------------------------------------------------------------------------
def image_world(tmp_path, extra='', uri='plan.png', scale=0.1):
    img = np.full((20, 30), 255, np.uint8)  # 30 x 20 px, white floor
    img[5, 10:25] = 0                         # a dark wall along row 5, columns 10..24
    img[12:15, 2] = 150                       # grey, below the threshold of 200: solid too
    cv2.imwrite(str(tmp_path / 'plan.png'), img)
    text = sdf('<model name="plan"><static>true</static><pose>1 2 0 0 0 0</pose><link name="l">'
               '<collision name="c"><geometry><image><uri>%s</uri><scale>%g</scale><height>2</height>%s'
               '</image></geometry></collision></link></model>' % (uri, scale, extra))
    (tmp_path / 'plan.world').write_text(text)
    return load_world(str(tmp_path / 'plan.world'))


def test_image_geometry_as_gazebo_places_it(tmp_path):
    w = image_world(tmp_path)
    (s,) = w.shapes
    assert s.kind == 'grid' and s.cells.shape == (20, 30) and s.resolution == 0.1
    assert (s.z_lo, s.z_hi) == (0.0, 2.0) and s.cells.sum() == 15 + 3
    sim = Simulation(w)
    g = sim.geometry
    # Row 5 is y in [0.5, 0.6) of the model, columns 10..24 x in [1.0, 2.5): at (1 + x, 2 + y) in the world.
    assert g.cast_ray(np.array([2.7, 2.0]), math.pi / 2, 5.0) == pytest.approx(0.5, abs=1e-9)
    assert math.isinf(g.cast_ray(np.array([3.7, 2.0]), math.pi / 2, 5.0))  # past the wall's end
    assert distance_to_surfaces(w, np.array([[2.7, 2.3]]))[0] == pytest.approx(0.2, abs=0.02)


def test_image_threshold_granularity_and_bad_images(tmp_path):
    strict = image_world(tmp_path, '<threshold>100</threshold>')
    assert strict.shapes[0].cells.sum() == 15  # the grey pixels are floor now
    coarse = image_world(tmp_path, '<granularity>4</granularity>')
    assert coarse.shapes[0].cells.sum() == 4 * 8 + 4 * 2  # 2 x 2 blocks: 8 along the wall, 2 for the grey
    with pytest.raises(XmlError, match=r'plan.world:\d+: <image> <uri>missing.png</uri>: no such file'):
        image_world(tmp_path, uri='missing.png')
    (tmp_path / 'text.png').write_text('not an image')
    with pytest.raises(XmlError, match='is not an image OpenCV can read'):
        image_world(tmp_path, uri='text.png')
    with pytest.raises(XmlError, match=r'<scale>: must be positive'):
        image_world(tmp_path, scale=0.0)


# --- model:// includes ----------------------------------------------------------------------------
def write_model(folder, name, body, config=True):
    d = folder / name
    d.mkdir(parents=True)
    (d / 'shelf.sdf').write_text('<sdf version="1.6"><model name="%s">%s</model></sdf>' % (name, body))
    if config:
        (d / 'model.config').write_text('<model><name>%s</name><sdf version="1.5">old.sdf</sdf>'
                                        '<sdf version="1.6">shelf.sdf</sdf></model>' % name)


def test_includes_are_found_on_gazebo_model_path(tmp_path, monkeypatch):
    models = tmp_path / 'models'
    write_model(models, 'shelf', '<link name="l"><collision name="c"><pose>0.5 0 0.5 0 0 0</pose><geometry>'
                                 '<box><size>1 0.4 1</size></box></geometry></collision></link>')
    write_model(models, 'statue', '<link name="l"><collision name="c"><geometry><mesh><uri>model://statue/s.dae</uri>'
                                  '</mesh></geometry></collision></link>')
    write_model(models, 'door_frame', '<include><uri>model://shelf</uri><pose>0 1 0 0 0 0</pose></include>'
                                      '<link name="l"><collision name="c"><geometry><mesh><uri>x.dae</uri></mesh>'
                                      '</geometry></collision></link>', config=False)
    (models / 'door_frame' / 'model.sdf').write_text((models / 'door_frame' / 'shelf.sdf').read_text())
    monkeypatch.setenv('GAZEBO_MODEL_PATH', '/nonexistent:' + str(models))
    w = parse_world(sdf('<include><uri>model://shelf</uri><name>left_shelf</name><pose>3 0 0 0 0 1.5707963</pose>'
                        '</include><include><uri>model://statue</uri></include>'
                        '<include><uri>model://door_frame</uri><pose>-2 0 0 0 0 0</pose></include>'
                        '<include><uri>model://missing</uri></include>'), 'inc.world')
    shelf = next(s for s in w.shapes if s.name.startswith('left_shelf/'))
    assert (shelf.x, shelf.y, shelf.yaw) == pytest.approx((3.0, 0.5, math.pi / 2), abs=1e-6)
    assert (shelf.z_lo, shelf.z_hi) == pytest.approx((0.0, 1.0))
    nested = next(s for s in w.shapes if s.name.startswith('shelf/') and s is not shelf)
    assert (nested.x, nested.y) == pytest.approx((-1.5, 1.0))  # door_frame's own include, in its frame
    statue, door_frame, missing = w.warnings  # one warning per model, none for what was read
    assert 'statue/shelf.sdf:1: <model name="statue">: 1 <mesh> collision left out' in statue \
        and 'the model is not in the world' in statue
    assert door_frame.endswith('<model name="door_frame">: 1 <mesh> collision left out (not simulated in 2D); '
                               'its 1 other collision kept')
    assert 'inc.world:1: <include>: model://missing not found in GAZEBO_MODEL_PATH' in missing \
        and '/nonexistent' in missing


# --- a map_server map as the world ----------------------------------------------------------------
def saved_map(tmp_path, name='room'):
    data = np.full((40, 60), -1, np.int8)  # 3 x 2 m at 0.05 m, unknown outside
    data[5:35, 5:55] = 0                    # the room's floor
    data[5:35, [5, 54]] = 100               # its walls
    data[[5, 34], 5:55] = 100
    save_map(str(tmp_path / name), data, 0.05, (-1.0, -0.5, 0.0))
    return str(tmp_path / (name + '.yaml'))


def test_a_saved_map_is_a_world(tmp_path):
    w = load_world(saved_map(tmp_path))
    (s,) = w.shapes
    # a frame of solid cells around the image: beyond a saved map is solid too
    assert s.kind == 'grid' and (s.x, s.y) == pytest.approx((-1.05, -0.55)) and s.cells.shape == (42, 62)
    assert s.cells[0].all() and s.cells[-1].all() and s.cells[:, 0].all() and s.cells[:, -1].all()
    sim = Simulation(w, slip_stddev=0.0)
    r = sim.spawn('r', robot(), (0.5, 0.5, 0.0))
    ranges = sim.scan(r, r.lasers[0])
    # North wall: row 34 starts at y = -0.5 + 34 * 0.05 = 1.2; the laser sits at y = 0.65, facing north.
    assert ranges[180] == pytest.approx(1.2 - 0.65, abs=1e-6)
    truth, origin = rasterize(w, 0.05, margin=0.0)
    assert (truth > 0).sum() == (s.cells > 0).sum()  # the same cells, on the same grid
    free_outside = load_world(saved_map(tmp_path), map_unknown='free')
    assert free_outside.shapes[0].cells.shape == (40, 60) and free_outside.shapes[0].cells.sum() == 2 * 50 + 2 * 28


def test_a_map_cropped_through_a_room_keeps_the_robot_in(tmp_path):
    data = np.zeros((20, 40), np.int8)  # 2 x 1 m of floor, open at every edge
    save_map(str(tmp_path / 'cropped'), data, 0.05, (0.0, 0.0, 0.0))
    sim = Simulation(load_world(str(tmp_path / 'cropped.yaml')), slip_stddev=0.0)
    r = sim.spawn('r', robot(), (0.5, 0.5, 0.0))
    run(sim, 'r', 0.5, 6.0)
    assert r.collisions == 1 and r.pose[0] < 2.0  # stopped at the image's edge


def test_spawning_outside_a_saved_map_is_refused_with_a_free_place(tmp_path):
    sim = Simulation(load_world(saved_map(tmp_path)), slip_stddev=0.0)
    with pytest.raises(SimulationError, match=r'at \(-0\.85, 0\.50\) would overlap an obstacle; the nearest free place'):
        sim.spawn('r', robot(), (-0.85, 0.5, 0.0))  # in the unknown outside the room


def test_bad_maps_name_the_file_and_key(tmp_path):
    path = saved_map(tmp_path)
    text = open(path).read()
    (tmp_path / 'zero.yaml').write_text(text.replace('resolution: 0.05', 'resolution: 0'))
    with pytest.raises(MapFileError, match=r"zero.yaml: key 'resolution': must be positive"):
        load_world(str(tmp_path / 'zero.yaml'))
    (tmp_path / 'noimage.yaml').write_text(text.replace('image: room.pgm', 'image: gone.pgm'))
    with pytest.raises(MapFileError, match=r"noimage.yaml: key 'image'"):
        load_world(str(tmp_path / 'noimage.yaml'))
    with pytest.raises(MapFileError, match=r"key 'map_unknown'"):
        load_world(path, map_unknown='maybe')


def test_ground_truth_of_a_world_that_cannot_be_read_is_left_out_with_why(tmp_path):
    from mbot_slam_navigation.sim.ground_truth import load_truth
    world, why = load_truth(str(tmp_path / 'gone.world'))
    assert world is None and 'gone.world does not exist' in why
    world, why = load_truth(saved_map(tmp_path), 'solid', ROBOT)
    assert why is None and world.shapes[0].kind == 'grid'

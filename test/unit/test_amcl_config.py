"""amcl's parameters and update rule, ROS-free: launch/amcl_diff.launch as the node reads it, bad
values naming their key, and when the filter updates (the Localizer shared by node and bench)."""
import math
import os

import numpy as np
import pytest

from mbot_slam_navigation import _core
from mbot_slam_navigation.launch_files import node_params
from mbot_slam_navigation.nav.amcl import read_parameters
from mbot_slam_navigation.nav.localizer import Localizer
from mbot_slam_navigation.nav.params import ParamError, ParamReader
from mbot_slam_navigation.transforms import compose2d

LAUNCH = os.path.join(os.path.dirname(__file__), '..', '..', 'launch', 'amcl_diff.launch')


def launch_values(*args):
    return node_params(LAUNCH, '/amcl', args)


def test_amcl_diff_launch_reads_without_warnings_and_keeps_the_example_values():
    warnings = []
    r = ParamReader(launch_values(), '/amcl', warnings.append)
    p, s = read_parameters(r)
    assert r.report_unknown() == [] and warnings == []
    assert (p.min_particles, p.max_particles, p.kld_err, p.max_beams) == (500, 5000, 0.05, 30)
    assert (p.z_hit, p.z_rand, p.sigma_hit, p.laser_model, p.odom_model) == (0.5, 0.5, 0.2, 'likelihood_field', 'diff')
    assert s['transform_tolerance'] == 0.1  # the second of the two lines wins, as in roslaunch
    assert (s['update_min_d'], s['update_min_a'], s['resample_interval']) == (0.2, 0.5, 1)
    # The alphas are the example's converted to the corrected model at one update step.
    assert p.alpha3 == pytest.approx((0.8 * 0.2) ** 2) and p.alpha1 == pytest.approx((0.2 * 0.5) ** 2)
    assert s['base_frame_id'] == 'base_link' and s['global_frame_id'] == 'map' and s['tf_broadcast'] is True


def test_ros_defaults_when_nothing_is_set():
    p, s = read_parameters(ParamReader({}, '/amcl', print))
    assert (p.min_particles, p.max_particles, p.kld_err, p.kld_z) == (100, 5000, 0.01, 0.99)
    assert (p.z_hit, p.z_short, p.z_max, p.z_rand, p.sigma_hit) == (0.95, 0.1, 0.05, 0.05, 0.2)
    assert s['update_min_a'] == pytest.approx(math.pi / 6) and s['resample_interval'] == 2
    assert s['initial_cov'] == pytest.approx((0.25, 0.25, (math.pi / 12) ** 2))


@pytest.mark.parametrize('values, words', [
    ({'max_particles': 50, 'min_particles': 100}, '/amcl/max_particles'),
    ({'odom_model_type': 'diff-drive'}, '/amcl/odom_model_type'),
    ({'laser_model_type': 'beams'}, '/amcl/laser_model_type'),
    ({'laser_sigma_hit': 0}, '/amcl/laser_sigma_hit'),
    ({'kld_err': 'small'}, '/amcl/kld_err'),
    ({'laser_max_beams': 1}, '/amcl/laser_max_beams'),
])
def test_bad_values_name_the_key(values, words):
    with pytest.raises(ParamError, match=words):
        read_parameters(ParamReader(values, '/amcl', print))


def test_misspelt_key_gets_the_nearest_name_and_frames_lose_a_leading_slash():
    warnings = []
    r = ParamReader({'odom_alpha_1': 0.1, 'base_frame_id': '/base_footprint'}, '/amcl', warnings.append)
    _, s = read_parameters(r)
    r.report_unknown()
    assert s['base_frame_id'] == 'base_footprint'
    assert any('odom_alpha_1' in w and 'odom_alpha1' in w for w in warnings), warnings


def test_localizer_updates_on_motion_thresholds_and_resamples_every_interval():
    data = np.zeros((60, 60), np.int8)
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 100
    p = _core._AmclParams()
    p.min_particles = p.max_particles = 200
    pf = _core._Amcl(p, 1)
    pf.set_map(_core._AmclMap(data, 0.1, (0.0, 0.0)))
    pf.init_gaussian(np.array([3.0, 3.0, 0.0]), np.diag([0.01, 0.01, 0.01]))
    loc = Localizer(pf, update_min_d=0.2, update_min_a=0.5, resample_interval=2)
    ranges = np.full(90, 2.9, np.float32)
    args = (-math.pi, 2 * math.pi / 90, 0.1, 8.0, ranges, (0.0, 0.0))
    assert loc.update((0.0, 0.0, 0.0), *args)            # first scan: always
    assert not loc.update((0.15, 0.1, 0.3), *args)       # below every threshold
    assert loc.update((0.25, 0.0, 0.0), *args)           # x moved 0.25 > 0.2
    assert not loc.update((0.3, 0.1, 0.4), *args)
    assert loc.update((0.3, 0.1, 0.8), *args)            # turned 0.8 > 0.5
    loc.force_update = True                               # request_nomotion_update
    assert loc.update((0.3, 0.1, 0.8), *args) and not loc.force_update
    assert loc.updates == 4
    # map -> odom composed with the odometry pose of the last update gives the estimate back.
    est = loc.estimate()[0]
    back = compose2d(loc.map_to_odom(est), (0.3, 0.1, 0.8))
    assert back == pytest.approx(est)


def test_fit_monitor_says_lost_when_the_fit_falls_and_found_when_it_returns_never_on_noise():
    from mbot_slam_navigation.nav.localizer import FitMonitor
    rng = np.random.default_rng(3)
    m = FitMonitor()
    changes = [m.add(float(np.clip(rng.normal(0.93, 0.04), 0, 1))) for _ in range(300)]  # tracking, with noise
    assert not any(changes)
    after = [m.add(f) for f in (0.55, 0.6, 0.5, 0.55, 0.5)]     # carried: about half the returns fit
    assert 'lost' in after  # within five updates (the quick average falls, then three updates below)
    assert m.lost and m.ratio() < FitMonitor.LOST_RATIO
    held = m.slow
    assert [m.add(0.5) for _ in range(50)] == [None] * 50 and m.slow == held  # the good level is kept
    back = [m.add(0.92) for _ in range(5)]
    assert 'found' in back and not m.lost


def test_the_filter_reports_a_scan_fit_that_falls_when_the_robot_is_elsewhere():
    """Amcl::lastScanFit: the share of returns near a wall, seen from the heaviest particle."""
    data = np.zeros((60, 60), np.int8)
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 100   # a 6 m box, walls at 0.05 and 5.95 m
    p = _core._AmclParams()
    p.min_particles = p.max_particles = 100
    pf = _core._Amcl(p, 1)
    pf.set_map(_core._AmclMap(data, 0.1, (0.0, 0.0)))
    pf.init_gaussian(np.array([3.0, 3.0, 0.0]), np.diag([1e-6, 1e-6, 1e-6]))
    angles = -math.pi + np.arange(90) * 2 * math.pi / 90
    box = lambda x, y: np.array([min(((5.95 - x) if math.cos(a) > 0 else (x - 0.05)) / max(abs(math.cos(a)), 1e-9),  # noqa: E731
                                     ((5.95 - y) if math.sin(a) > 0 else (y - 0.05)) / max(abs(math.sin(a)), 1e-9))
                                 for a in angles], np.float32)
    pf.sensor_update(-math.pi, 2 * math.pi / 90, 0.1, 8.0, box(3.0, 3.0), np.zeros(3))
    assert pf.last_scan_fit > 0.9
    pf.sensor_update(-math.pi, 2 * math.pi / 90, 0.1, 8.0, box(1.0, 4.5), np.zeros(3))  # taken elsewhere
    assert pf.last_scan_fit < 0.5


def _carry_in_a_room(seed: int):
    """A 6 m room with a cupboard in one corner (so that no turn of the room looks the same); the
    robot tracked at (3, 3) is carried to (1.6, 2.2), 1.6 m away, while odometry sees nothing, then
    drives on along x and back, 0.25 m an update. Returns (fit changes, search changes, the final
    estimate, the final true x)."""
    world = _core._World2D()
    data = np.zeros((60, 60), np.int8)
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 100
    data[45:55, 5:20] = 100                                   # the cupboard: x 0.5-2.0, y 4.5-5.5
    for (cx, cy, sx, sy) in ((3.0, 0.05, 6.0, 0.1), (3.0, 5.95, 6.0, 0.1), (0.05, 3.0, 0.1, 6.0), (5.95, 3.0, 0.1, 6.0),
                             (1.25, 5.0, 1.5, 1.0)):
        world.add_box(np.array([cx, cy]), 0.0, sx, sy)
    angles = -math.pi + np.arange(90) * 2 * math.pi / 90

    def scan(x, y):
        return np.array([min(world.cast_ray(np.array([x, y]), a, 8.0), 8.0) for a in angles], np.float32)

    p = _core._AmclParams()
    p.min_particles, p.max_particles = 500, 3000
    pf = _core._Amcl(p, seed)
    pf.set_map(_core._AmclMap(data, 0.1, (0.0, 0.0)))
    pf.init_gaussian(np.array([3.0, 3.0, 0.0]), np.diag([0.01, 0.01, 0.01]))
    loc = Localizer(pf, update_min_d=0.2, update_min_a=0.5, resample_interval=1, search_radius=3.0)
    args = (-math.pi, 2 * math.pi / 90, 0.1, 8.0)
    for _ in range(20):
        loc.force_update = True
        loc.update((0.0, 0.0, 0.0), *args, scan(3.0, 3.0), (0.0, 0.0))
    assert not loc.fit.lost and loc.search is None
    changes, searches = [], []
    xs = (list(np.arange(1.6, 4.2, 0.25)) + list(np.arange(4.1, 1.5, -0.25))) * 2
    for x in xs:
        loc.update((x - 1.6, 0.0, 0.0), *args, scan(x, 2.2), (0.0, 0.0))
        changes.append(loc.fit_change)
        searches.append(loc.search_change)
    return changes, searches, loc.estimate()[0], xs[-1]


def test_localizer_searches_near_the_last_estimate_when_lost_and_finds_the_carried_robot():
    # Ten seeds: one seed says little about a particle filter (with this one room, a quarter of
    # the seeds settle on a wrong place whichever way the search draws its particles).
    back = 0
    for seed in range(1, 11):
        changes, searches, est, x = _carry_in_a_room(seed)
        assert 'lost' in changes and searches[changes.index('lost')] == 'near', (seed, changes, searches)
        assert 'found' in changes, (seed, changes)
        assert changes.index('found') - changes.index('lost') <= 10, (seed, changes)
        back += math.hypot(est[0] - x, est[1] - 2.2) < 0.3 and abs(est[2]) < 0.2
    assert back >= 7, '%d of 10 carries found again within 0.3 m' % back


def test_launch_file_names_are_unique_so_roslaunch_by_name_works():
    # `roslaunch mbot_slam_navigation move_base.launch` (the tutorial's command) fails when two files
    # in the package share the name.
    root = os.path.join(os.path.dirname(__file__), '..', '..')
    names = [f for d, _, files in os.walk(os.path.join(root, 'launch')) for f in files if f.endswith('.launch')]
    assert len(names) == len(set(names)), sorted(names)
    assert 'move_base.launch' in names and 'myrobot_world.launch' in names and 'amcl_diff.launch' in names

"""slam_offline: the SLAM core on a CARMEN log (or a rosbag), as fast as the CPU allows.

Writes OUT.traj (`t x y theta` per scan: the estimated trajectory, with odometry between its map
updates), OUT.pgm/OUT.yaml (map_server format) and OUT.timing.json (CPU seconds, scans, updates).
Usage: slam_offline LOG [-o OUT] [--backend graph|rbpf] [--relations FILE] [--param name=value ...]
[--quiet] [--scans FROM:TO] [--session-out NAME] [--session-in NAME [--start-pose X,Y,YAW |
--start-at-dock] [--localize]]. With sessions a log can be mapped in parts: the first part saved,
the next continued from it (the trajectory written then covers both parts, as the graph holds them).
"""
import argparse
import json
import os
import sys
import time

import numpy as np

from mbot_slam_navigation.maps.map_io import save_map
from mbot_slam_navigation.slam.carmen import read_log
from mbot_slam_navigation.slam.backends import BACKENDS, DEFAULT_BACKEND, OFFLINE_MAX_RANGE, GraphSlam, make_slam
from mbot_slam_navigation.slam.relations import evaluate, read_relations
from mbot_slam_navigation.transforms import compose2d, normalize_angle, quaternion_to_yaw, relative2d


def per_scan_poses(trajectory: np.ndarray, scans) -> np.ndarray:
    """The pose at every scan: the last filter update before it, moved on by odometry."""
    out = np.zeros((len(scans), 3))
    times = trajectory[:, 0]
    for i, scan in enumerate(scans):
        k = max(0, int(np.searchsorted(times, scan.time, side='right')) - 1)
        node_pose, node_odom = trajectory[k, 1:4], trajectory[k, 4:7]
        out[i] = compose2d(node_pose, relative2d(node_odom, scan.odom))
    return out


def estimated_poses(slam, scans) -> np.ndarray:
    """The backend's pose at every scan: the graph's tracked scan poses (matched by time: a session
    continued holds the saved part's too, and scans that came before the robot was found on it have
    none), else (the particle filter, those scans) its trajectory moved on by odometry."""
    if hasattr(slam, 'scan_poses'):
        tracked = slam.scan_poses()
        if len(tracked) == len(scans):
            return tracked[:, 1:4]
        out = per_scan_poses(slam.trajectory(), scans)
        if len(tracked):
            times = np.array([s.time for s in scans])
            k = np.clip(np.searchsorted(tracked[:, 0], times), 0, len(tracked) - 1)
            same = tracked[k, 0] == times
            out[same] = tracked[k[same], 1:4]
        return out
    return per_scan_poses(slam.trajectory(), scans)


class BagError(ValueError):
    """A bag that cannot be read; the message names the file and what is wrong."""


def read_rosbag(path, scan_topic='/scan', odom_topic='/odom'):
    """Scans from a bag with their odometry at each scan's stamp, interpolated between the odom
    messages either side of it (by their stamps, not the order the bag holds them in: a bag
    recorded live holds them up to several tenths of a second out of order). Scans outside the
    odometry's span, or in a gap of it longer than 0.5 s, are left out."""
    import rosbag  # only needed for bags
    from mbot_slam_navigation.slam.carmen import Scan
    with open(path, 'rb') as f:
        head = f.read(13)
    if not head.startswith(b'#ROSBAG V2.0'):
        raise BagError('%s: not a rosbag: expected the header "#ROSBAG V2.0", found %s' % (
            path, repr(head.decode('ascii')) if head.isascii() and head.decode('ascii').isprintable() else
            'bytes ' + head[:8].hex(' ')))
    odom, raw = [], []
    try:
        with rosbag.Bag(path) as bag:
            for topic, msg, _ in bag.read_messages(topics=[scan_topic, odom_topic]):
                if topic == odom_topic:
                    p = msg.pose.pose
                    odom.append((msg.header.stamp.to_sec(), p.position.x, p.position.y,
                                 quaternion_to_yaw(p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w)))
                else:
                    raw.append(msg)
    except (rosbag.ROSBagException, UnicodeDecodeError, ValueError) as e:
        raise BagError('%s: the bag cannot be read: %s' % (path, e)) from None
    if not odom or not raw:
        return []
    odom = np.array(sorted(odom))
    times = odom[:, 0]
    raw.sort(key=lambda m: m.header.stamp.to_sec())
    stamps = np.array([m.header.stamp.to_sec() for m in raw])
    after = np.minimum(np.searchsorted(times, stamps, side='right'), len(times) - 1)
    usable = (stamps >= times[0]) & (stamps <= times[-1]) & (times[after] - times[np.maximum(after - 1, 0)] <= 0.5)
    x, y = np.interp(stamps, times, odom[:, 1]), np.interp(stamps, times, odom[:, 2])
    yaw = np.interp(stamps, times, np.unwrap(odom[:, 3]))  # along the shorter arc between samples
    scans = []
    for i in np.flatnonzero(usable):
        msg = raw[i]
        scans.append(Scan(time=stamps[i], odom=(x[i], y[i], normalize_angle(yaw[i])), laser_pose=(0.0, 0.0, 0.0),
                          angle_min=msg.angle_min, angle_increment=msg.angle_increment,
                          ranges=np.asarray(msg.ranges, np.float32),
                          range_max=float(msg.range_max) if msg.range_max > 0.0 else None))
    return scans


class Progress:
    """A one-line progress bar on stderr: scans done, rate, time left."""

    def __init__(self, total, enabled=True):
        self.total, self.enabled, self.start, self.last = total, enabled and sys.stderr.isatty() or enabled, time.time(), 0.0

    def update(self, done, updates):
        now = time.time()
        if not self.enabled or (now - self.last < 0.5 and done < self.total):
            return
        self.last = now
        rate = done / max(now - self.start, 1e-9)
        left = (self.total - done) / rate if rate > 0 else float('inf')
        bar = '#' * int(30 * done / self.total)
        sys.stderr.write('\r[%-30s] %d/%d scans, %d updates, %.0f scans/s, %.0f s left ' %
                         (bar, done, self.total, updates, rate, left))
        if done >= self.total:
            sys.stderr.write('\n')
        sys.stderr.flush()


def run(scans, params, progress=True, backend=DEFAULT_BACKEND, rate=0.0, background=False, online=None, slam=None):
    """Runs a backend over the scans; returns (slam, cpu_seconds). The CPU time is the process's,
    so it counts every thread (the graph backend runs synchronously here, on one core, unless
    `background`: then its loop closure runs in its own thread, as in the slam_gmapping node).
    rate > 0 feeds the scans no faster than `rate` times the log's own time (as `rosbag play -r`
    feeds a node), so that the CPU compares with a node's: a process that waits between scans
    finds its caches cold and costs more than one that runs flat out. `online`, a list, receives
    the pose the backend gives each scan as it is processed (what a node publishes then). `slam`:
    a backend to go on with (a loaded session) instead of a new one."""
    if slam is None:
        slam = make_slam(backend, params, scans[0].laser_pose, background=background)
    bar = Progress(len(scans), progress)
    cpu = 0.0
    wall0, t0, start = time.time(), scans[0].time, time.process_time()
    for i, s in enumerate(scans):
        if rate > 0:
            wait = wall0 + (s.time - t0) / rate - time.time()
            if wait > 0:
                time.sleep(wait)
        c0 = time.process_time()
        slam.process_scan(s.odom, s.angle_min, s.angle_increment, 0.0, params.get('maxRange', OFFLINE_MAX_RANGE), s.ranges,
                        s.time)
        cpu += time.process_time() - c0
        if online is not None:
            online.append(slam.current_pose())
        bar.update(i + 1, slam.updates)
    c0 = time.process_time()
    slam.finish()
    cpu += time.process_time() - c0
    if background or rate > 0:  # the closure thread also works while this one waits or updates the bar
        cpu = time.process_time() - start
    return slam, cpu


def parse_param(text):
    name, _, value = text.partition('=')
    try:
        return name, float(value)
    except ValueError:
        raise argparse.ArgumentTypeError('--param takes name=value with a number, got "%s"' % text) from None


def argument_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog='slam_offline', description=__doc__.split('\n')[0])
    ap.add_argument('log', help='CARMEN log (.clf, .log, optionally .bz2) or rosbag (.bag)')
    ap.add_argument('-o', '--out', help='output base name (default: the log name without extension)')
    ap.add_argument('--relations', help='relations file: print the Kümmerle et al. error')
    ap.add_argument('--backend', choices=BACKENDS, default=DEFAULT_BACKEND, help='SLAM backend (default %(default)s)')
    ap.add_argument('--param', action='append', type=parse_param, default=[], help='slam_gmapping name=value')
    ap.add_argument('--quiet', action='store_true', help='no progress bar')
    ap.add_argument('--scans', metavar='FROM:TO', type=parse_slice, default=slice(None),
                    help='process only these scans (Python slice of their indices, e.g. 0:5000 or 5000:)')
    ap.add_argument('--session-out', metavar='NAME', help='write the session to NAME.posegraph at the end (graph)')
    ap.add_argument('--session-in', metavar='NAME',
                    help='start from the session NAME.posegraph (graph); the robot found on its map by matching the '
                         'first scans, unless --start-pose or --start-at-dock')
    ap.add_argument('--start-pose', metavar='X,Y,YAW', type=parse_pose, help='with --session-in: the robot near here')
    ap.add_argument('--start-at-dock', action='store_true', help='with --session-in: where the session began')
    ap.add_argument('--localize', action='store_true',
                    help='with --session-in: track on the saved map only (slam_gmapping mode localization)')
    return ap


def parse_slice(text):
    a, sep, b = text.partition(':')
    try:
        if not sep:
            raise ValueError
        return slice(int(a) if a else None, int(b) if b else None)
    except ValueError:
        raise argparse.ArgumentTypeError('--scans takes FROM:TO (scan indices, either may be left out), got "%s"'
                                         % text) from None


def parse_pose(text):
    try:
        x, y, yaw = (float(v) for v in text.split(','))
        return x, y, yaw
    except ValueError:
        raise argparse.ArgumentTypeError('--start-pose takes X,Y,YAW (metres, radians), got "%s"' % text) from None


def main(argv=None):
    ap = argument_parser()
    args = ap.parse_args(argv)
    if not os.path.isfile(args.log):
        ap.error('log file %s does not exist' % args.log)
    try:
        scans = read_rosbag(args.log) if args.log.endswith('.bag') else read_log(args.log)
    except ValueError as e:  # CarmenError, BagError: the file and what is wrong with it
        ap.exit(2, 'slam_offline: %s\n' % e)
    params = dict(args.param)
    # maxUrange and maxRange not given: the scan's range_max, as the node takes them (a log without
    # one: OFFLINE_MAX_RANGE). Longer, the beams without a return would clear the map out to it.
    range_max = next((s.range_max for s in scans if s.range_max), None)
    if range_max is not None:
        for key in ('maxUrange', 'maxRange'):
            params.setdefault(key, range_max)
    if (args.session_in or args.session_out) and args.backend != 'graph':
        ap.error('sessions are the graph backend\'s (--backend graph)')
    if (args.start_pose or args.start_at_dock or args.localize) and not args.session_in:
        ap.error('--start-pose, --start-at-dock and --localize go with --session-in')
    before = scans[:args.scans.start or 0] if args.session_in else []
    scans = scans[args.scans]
    if not scans:
        ap.error('--scans %s leaves no scan' % (args.scans,))
    slam = None
    if args.session_in:
        try:
            slam, notes = GraphSlam.load_session(args.session_in, laser_pose=scans[0].laser_pose, **params)
        except KeyError as e:
            ap.error(e.args[0])
        except ValueError as e:  # SessionError: the file and what is wrong with it
            ap.exit(2, 'slam_offline: %s\n' % e)
        if notes:
            print('slam_offline: %s' % notes)
        slam.resume(slam.first_pose() if args.start_at_dock else args.start_pose, args.localize)
    try:
        slam, cpu = run(scans, params, progress=not args.quiet, backend=args.backend, slam=slam)
    except KeyError as e:
        ap.error(e.args[0])
    if args.session_in and slam.resuming():
        ap.exit(3, 'slam_offline: no scan joined the session %s: %s\n' % (args.session_in, slam.resume_failure()))
    if args.session_out:
        try:
            print('slam_offline: session written to %s' % slam.save_session(args.session_out))
        except RuntimeError as e:  # the path and why it cannot be written
            ap.exit(2, 'slam_offline: the session was not written: %s\n' % e)
    out = args.out or os.path.basename(args.log).split('.')[0]
    if args.session_in and not args.localize:
        scans = before + scans  # the whole trajectory, the session's scans too, as the graph holds it now
    poses = estimated_poses(slam, scans)
    times = np.array([s.time for s in scans])
    np.savetxt(out + '.traj', np.column_stack([times, poses]), fmt='%.6f', header='t x y theta')
    data, origin, res = slam.occupancy()
    save_map(out, data, res, (origin[0], origin[1], 0.0))
    duration = scans[-1].time - scans[0].time
    summary = dict(log=args.log, backend=args.backend, scans=len(scans), updates=slam.updates,
                   cpu_seconds=cpu, log_duration_s=duration, params=params)
    if args.relations:
        e = evaluate(times, poses, read_relations(args.relations))
        summary['relations'] = e.__dict__
        print('error over %d relations: translation %.4f +- %.4f m, rotation %.3f +- %.3f deg'
              % (e.count, e.trans_mean, e.trans_std, e.rot_mean, e.rot_std))
    with open(out + '.timing.json', 'w') as f:
        json.dump(summary, f, indent=1)
    print('%d scans (%d updates) in %.1f CPU s for %.0f s of log (%.0fx); wrote %s.traj, %s.pgm, %s.yaml'
          % (len(scans), slam.updates, cpu, duration, duration / max(cpu, 1e-9), out, out, out))
    return 0

"""slam_demo: drives the mbot through the simulated home under slam_gmapping and reports.

Steers on ground truth (RouteDriver: a stand-in until move_base and the explorer exist), prints
progress every 10 s of simulated time (waypoints, known map area, simulated and wall time), then
writes to ~report_dir: map.pgm/map.yaml (map_server format), map.png (the map with the driven path),
report.json (the figures), and prints them. Exits when done, which ends the launch.
"""
import json
import math
import os
import time

import numpy as np
import rospy
import tf2_ros
from geometry_msgs.msg import Twist
from nav_msgs.msg import OccupancyGrid, Odometry

from mbot_slam_navigation.map_stats import map_stats
from mbot_slam_navigation.maps.map_io import occupancy_to_image, save_map
from mbot_slam_navigation.route_driver import HOME_TOUR, RouteDriver
from mbot_slam_navigation.sim.ground_truth import distance_to_surfaces, occupied_points
from mbot_slam_navigation.sim.sdf_world import load_world
from mbot_slam_navigation.transforms import quaternion_to_yaw


def draw(msg: OccupancyGrid, path, filename: str) -> None:
    import cv2
    data = np.asarray(msg.data, np.int16).reshape(msg.info.height, msg.info.width)
    img = cv2.cvtColor(occupancy_to_image(data), cv2.COLOR_GRAY2BGR)
    res, o = msg.info.resolution, msg.info.origin.position
    pts = np.array([[(x - o.x) / res, msg.info.height - 1 - (y - o.y) / res] for x, y in path], np.int32)
    if len(pts) > 1:
        cv2.polylines(img, [pts], False, (0, 0, 220), 1)
    scale = max(1, 800 // max(img.shape[:2]))
    cv2.imwrite(filename, cv2.resize(img, None, fx=scale, fy=scale, interpolation=cv2.INTER_NEAREST))


def main() -> None:
    rospy.init_node('slam_demo')
    report_dir = os.path.abspath(rospy.get_param('~report_dir', 'report'))
    world_name = rospy.get_param('~world_name', '')
    os.makedirs(report_dir, exist_ok=True)
    truth, latest_map = {}, {}
    rospy.Subscriber('/base_pose_ground_truth', Odometry, lambda m: truth.update(msg=m))
    rospy.Subscriber('/map', OccupancyGrid, lambda m: latest_map.update(msg=m))
    cmd = rospy.Publisher('/cmd_vel', Twist, queue_size=5)
    tf_buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(tf_buffer)
    print('slam_demo: waiting for the simulator and the first map...', flush=True)
    rospy.wait_for_message('/map', OccupancyGrid, timeout=120.0)

    driver = RouteDriver(HOME_TOUR)
    wall0, sim0 = time.time(), rospy.Time.now()
    path, errors, next_print = [], [], sim0
    progress_index, progress_time = 0, sim0
    outcome = 'route completed'
    rate = rospy.Rate(20)
    while not rospy.is_shutdown() and not driver.done:
        if driver.index != progress_index:
            progress_index, progress_time = driver.index, rospy.Time.now()
        elif rospy.Time.now() - progress_time > rospy.Duration(90.0):
            outcome = 'stopped: waypoint %d %s not reached in 90 s' % (driver.index, driver.waypoints[driver.index])
            print('slam_demo: %s; reporting what was mapped' % outcome, flush=True)
            break
        m = truth.get('msg')
        if m is None:
            rate.sleep()
            continue
        p = m.pose.pose
        pose = (p.position.x, p.position.y, quaternion_to_yaw(p.orientation.x, p.orientation.y, p.orientation.z,
                                                              p.orientation.w))
        c = driver.command(pose)
        if c is None:
            break
        t = Twist()
        t.linear.x, t.angular.z = c
        cmd.publish(t)
        if not path or math.hypot(pose[0] - path[-1][0], pose[1] - path[-1][1]) > 0.05:
            path.append(pose[:2])
        now = rospy.Time.now()
        if now >= next_print:
            next_print = now + rospy.Duration(10.0)
            try:
                tf = tf_buffer.lookup_transform('map', 'base_footprint', m.header.stamp, rospy.Duration(0.2))
                errors.append(math.hypot(tf.transform.translation.x - pose[0], tf.transform.translation.y - pose[1]))
            except tf2_ros.TransformException:
                pass
            area = map_stats(latest_map['msg']).known_area_m2 if 'msg' in latest_map else 0.0
            print('slam_demo: waypoint %d/%d, map %.1f m^2 known, %.0f s simulated in %.0f s wall'
                  % (driver.index, len(driver.waypoints), area, (now - sim0).to_sec(), time.time() - wall0), flush=True)
        rate.sleep()
    cmd.publish(Twist())
    rospy.sleep(6.0)  # slam_gmapping publishes the map every map_update_interval
    msg = latest_map['msg']
    stats = map_stats(msg)
    data = np.asarray(msg.data, np.int16).reshape(msg.info.height, msg.info.width)
    origin = (msg.info.origin.position.x, msg.info.origin.position.y, 0.0)
    save_map(os.path.join(report_dir, 'map'), data, msg.info.resolution, origin)
    draw(msg, path, os.path.join(report_dir, 'map.png'))
    figures = dict(outcome=outcome, known_area_m2=round(stats.known_area_m2, 2), occupied_cells=stats.occupied_cells,
                   distance_driven_m=round(sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(path, path[1:])), 2),
                   simulated_s=round((rospy.Time.now() - sim0).to_sec(), 1), wall_s=round(time.time() - wall0, 1),
                   pose_error_max_m=round(max(errors), 3) if errors else None,
                   pose_error_mean_m=round(float(np.mean(errors)), 3) if errors else None)
    if world_name:
        d = distance_to_surfaces(load_world(world_name), occupied_points(msg))
        figures.update(wall_distance_median_m=round(float(np.median(d)), 3),
                       wall_distance_p95_m=round(float(np.percentile(d, 95)), 3))
    with open(os.path.join(report_dir, 'report.json'), 'w') as f:
        json.dump(figures, f, indent=1)
    print('slam_demo: done; report in %s (map.pgm, map.yaml, map.png, report.json)' % report_dir)
    for k, v in figures.items():
        print('  %-24s %s' % (k, v))

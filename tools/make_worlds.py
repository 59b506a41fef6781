#!/usr/bin/env python3
"""Writes worlds/mbot_sim_gazebo_navigation.world (the home of ../shared/DESIGN.md),
worlds/mbot_home_people.world (the same home with people walking between rooms) and
worlds/wall.world (the four-wheel-car tutorial's enclosure) as Gazebo SDF 1.6.

Walls are 0.1 m thick, 1 m high boxes on the listed centre lines, lengthened by half a thickness at
each end so that corners close. Run it again after editing the tables; the outputs are committed.
"""
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
T = 0.1  # wall thickness [m]

# Home: wall centre lines (x1, y1, x2, y2) [m], doors already cut out.
HOME_WALLS = [
    (-5.4, -6.0, 4.5, -6.0),                                   # south
    (4.5, -6.0, 4.5, 3.6),                                     # east
    (-5.4, 3.6, 4.5, 3.6),                                     # north
    (-5.4, -6.0, -5.4, -2.6), (-5.4, -1.4, -5.4, 3.6),         # west, sliding door to the balcony
    (-7.5, -4.2, -5.4, -4.2), (-7.5, -4.2, -7.5, 0.0), (-7.5, 0.0, -5.4, 0.0),  # balcony
    (1.2, -3.6, 2.6, -3.6), (3.5, -3.6, 4.5, -3.6),            # kitchen | dining, door x 2.6..3.5
    (1.2, -6.0, 1.2, -3.6),                                    # kitchen | living room
    (1.2, -3.6, 1.2, -3.3), (1.2, -1.5, 1.2, -1.2),            # dining | living room, open -3.3..-1.5
    (1.2, -1.2, 4.5, -1.2),                                    # dining | bathroom
    (1.2, -1.2, 1.2, -0.5), (1.2, 0.4, 1.2, 0.9),              # bathroom | living room, door -0.5..0.4
    (-5.4, 0.9, -3.2, 0.9), (-2.3, 0.9, -1.6, 0.9),            # bedrooms' south wall with doors at
    (-0.7, 0.9, 0.25, 0.9), (1.15, 0.9, 4.5, 0.9),             # x -3.2..-2.3, -1.6..-0.7, 0.25..1.15
    (-2.0, 0.9, -2.0, 3.6),                                    # master bedroom | study
    (0.2, 0.9, 0.2, 3.6),                                      # study | second bedroom
]
# Furniture: name, centre x, y, size x, y [m] (boxes), or name, x, y, radius (cylinders).
HOME_BOXES = [
    ('kitchen_counter', 4.15, -4.8, 0.6, 2.0), ('dining_table', 3.6, -2.4, 0.8, 1.2),
    ('bathtub', 4.1, 0.45, 0.7, 0.8), ('second_bed', 3.6, 2.6, 1.4, 2.0), ('desk', -1.2, 3.25, 1.2, 0.6),
    ('master_bed', -2.75, 2.95, 1.2, 1.2), ('wardrobe', -5.05, 2.5, 0.5, 1.6), ('sofa', -2.5, -5.4, 2.0, 0.8),
    ('coffee_table', -2.5, -4.2, 1.0, 0.6), ('washing_machine', -7.15, -0.35, 0.6, 0.6),
]
HOME_CYLINDERS = [('plant', -4.6, -0.6, 0.2)]
# The rooms (name, xmin, xmax, ymin, ymax) [m], as DESIGN.md's table and home_rooms.HOME_ROOMS give
# them, for the exploration report's coverage per room (worlds/<name>.rooms.yaml).
HOME_ROOMS = [
    ('living room', -5.4, 1.2, -6.0, 0.9), ('kitchen', 1.2, 4.5, -6.0, -3.6), ('dining room', 1.2, 4.5, -3.6, -1.2),
    ('bathroom', 1.2, 4.5, -1.2, 0.9), ('second bedroom', 0.2, 4.5, 0.9, 3.6), ('study', -2.0, 0.2, 0.9, 3.6),
    ('master bedroom', -5.4, -2.0, 0.9, 3.6), ('balcony', -7.5, -5.4, -4.2, 0.0),
]

# People of mbot_home_people.world: name and route (x, y) [m], walked there and back at WALK_SPEED,
# living room <-> kitchen, living room <-> balcony, study <-> bathroom,
# waiting PAUSE s at each end; every route goes through doors, at least 0.1 m clear of walls and
# furniture (a person is a 0.25 m cylinder; a 0.9 m door leaves 0.15 m each side).
WALK_SPEED = 0.8  # [m/s] an unhurried walk indoors
PAUSE = 5.0       # [s]
HOME_PEOPLE = [  # each rests 0.6 m from the spawn point and p1..p9, and walks 0.45 m clear of p1..p9
    ('alice', [(-3.0, -2.0), (0.6, -2.4), (2.0, -2.9), (2.8, -3.05), (3.05, -3.45), (3.05, -4.0), (2.0, -5.3)]),
    # Not through the master bedroom: every way from its door into the room passes within 0.45 m of
    # p6 or p7, and a person there makes move_base refuse the goal as occupied (9 of 12 at p6 in a soak).
    ('bob', [(-2.75, 0.0), (-4.0, -1.6), (-5.4, -2.0), (-5.9, -1.6), (-6.0, -0.5)]),
    ('carol', [(-1.5, 1.9), (-1.15, 1.3), (-1.15, 0.2), (-0.6, -0.8), (0.6, -0.8), (0.7, -0.05), (1.2, -0.05),
               (2.4, -0.3)]),
]

# wall.world: a 10 m x 10 m enclosure; two interior walls leave gaps at opposite ends, so the
# way from the south-west to the north-east corner is an S, never a straight line.
WALL_WALLS = [
    (-5.0, -5.0, 5.0, -5.0), (5.0, -5.0, 5.0, 5.0), (5.0, 5.0, -5.0, 5.0), (-5.0, 5.0, -5.0, -5.0),
    (-1.5, -5.0, -1.5, 2.0), (1.5, -2.0, 1.5, 5.0),
]
WALL_BOXES = [('pillar', 3.2, -3.0, 0.6, 0.6)]


def box_link(name, x, y, yaw, sx, sy, h=1.0):
    geometry = '<geometry><box><size>%.4f %.4f %.2f</size></box></geometry>' % (sx, sy, h)
    return ('      <link name="%s">\n        <pose>%.4f %.4f %.2f 0 0 %.6f</pose>\n'
            '        <collision name="%s_collision">%s</collision>\n'
            '        <visual name="%s_visual">%s</visual>\n      </link>\n'
            % (name, x, y, h / 2, yaw, name, geometry, name, geometry))


def walls_model(name, walls):
    links = []
    for i, (x1, y1, x2, y2) in enumerate(walls):
        length = math.hypot(x2 - x1, y2 - y1) + T
        links.append(box_link('wall_%d' % i, (x1 + x2) / 2, (y1 + y2) / 2, math.atan2(y2 - y1, x2 - x1), length, T))
    return '    <model name="%s">\n      <static>true</static>\n%s    </model>\n' % (name, ''.join(links))


def furniture(boxes, cylinders):
    out = []
    for name, x, y, sx, sy in boxes:
        out.append('    <model name="%s">\n      <static>true</static>\n      <pose>%.3f %.3f 0 0 0 0</pose>\n%s'
                   '    </model>\n' % (name, x, y, box_link('body', 0, 0, 0, sx, sy, 0.8)))
    for name, x, y, r in cylinders:
        geometry = '<geometry><cylinder><radius>%.3f</radius><length>0.8</length></cylinder></geometry>' % r
        out.append('    <model name="%s">\n      <static>true</static>\n      <pose>%.3f %.3f 0.4 0 0 0</pose>\n'
                   '      <link name="body">\n        <collision name="body_collision">%s</collision>\n'
                   '        <visual name="body_visual">%s</visual>\n      </link>\n    </model>\n'
                   % (name, x, y, geometry, geometry))
    return ''.join(out)


def actors(people, speed=WALK_SPEED, pause=PAUSE):
    """SDF <actor>s, each walking its route there and back, looping (Gazebo's <script>)."""
    out = []
    for name, route in people:
        legs = route + route[-2::-1]
        t, points = 0.0, []
        for i, (x, y) in enumerate(legs):
            if i:
                px, py = legs[i - 1]
                t += math.hypot(x - px, y - py) / speed
            yaw = math.atan2(y - legs[i - 1][1], x - legs[i - 1][0]) if i else 0.0
            points.append((t, x, y, yaw))
            if i in (len(route) - 1, len(legs) - 1):  # wait at each end of the route
                t += pause
                points.append((t, x, y, yaw))
        waypoints = ''.join('        <waypoint><time>%.2f</time><pose>%.3f %.3f 0 0 0 %.4f</pose></waypoint>\n'
                            % p for p in points)
        out.append('    <actor name="%s">\n      <pose>%.3f %.3f 0 0 0 0</pose>\n'
                   '      <link name="body"><collision name="body_collision"><geometry><cylinder><radius>0.25</radius>'
                   '<length>1.7</length></cylinder></geometry></collision></link>\n'
                   '      <script>\n        <loop>true</loop>\n        <delay_start>0</delay_start>\n'
                   '        <auto_start>true</auto_start>\n        <trajectory id="0" type="walking">\n%s'
                   '        </trajectory>\n      </script>\n    </actor>\n' % (name, route[0][0], route[0][1], waypoints))
    return ''.join(out)


def rooms_yaml(world_file, rooms):
    return ('# Generated by tools/make_worlds.py.\nworld: %s\nspawn: {x: 0.0, y: 0.0, yaw: 0.0}\nrooms:\n' % world_file
            + ''.join('- {name: %s, xmin: %.1f, xmax: %.1f, ymin: %.1f, ymax: %.1f}\n' % r for r in rooms))


def world(name, body, origin='tools/make_worlds.py; edit the tables there'):
    return ('<?xml version="1.0"?>\n<!-- Generated by %s. -->\n'
            '<sdf version="1.6">\n  <world name="%s">\n'
            '    <include><uri>model://ground_plane</uri></include>\n'
            '    <include><uri>model://sun</uri></include>\n%s  </world>\n</sdf>\n' % (origin, name, body))


if __name__ == '__main__':
    out = os.path.join(HERE, '..', 'worlds')
    with open(os.path.join(out, 'mbot_sim_gazebo_navigation.world'), 'w') as f:
        f.write(world('home', walls_model('home_walls', HOME_WALLS) + furniture(HOME_BOXES, HOME_CYLINDERS)))
    with open(os.path.join(out, 'mbot_sim_gazebo_navigation.rooms.yaml'), 'w') as f:
        f.write(rooms_yaml('mbot_sim_gazebo_navigation.world', HOME_ROOMS))
    with open(os.path.join(out, 'mbot_home_people.world'), 'w') as f:
        f.write(world('home_people', walls_model('home_walls', HOME_WALLS) + furniture(HOME_BOXES, HOME_CYLINDERS)
                      + actors(HOME_PEOPLE)))
    with open(os.path.join(out, 'mbot_home_people.rooms.yaml'), 'w') as f:
        f.write(rooms_yaml('mbot_home_people.world', HOME_ROOMS))
    with open(os.path.join(out, 'wall.world'), 'w') as f:
        f.write(world('wall', walls_model('walls', WALL_WALLS) + furniture(WALL_BOXES, [])))

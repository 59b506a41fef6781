#!/usr/bin/env python3
"""Draws a keep-out or speed mask for move_base's costmap filters (keepout_mask:=, speed_mask:=)
as map_server files, over a saved map or given bounds.

    tools/make_mask.py keepout --like maps/home.yaml --rect -2.0,0.9,0.2,3.6
    tools/make_mask.py lobby_speed --speed --like maps/home.yaml --rect -5.4,-6.0,1.2,0.9=30
    tools/make_mask.py zones --bounds -10 -10 10 10 --zone "1,1 3,1 3,2 1,2"

Zones are rectangles (xmin,ymin,xmax,ymax) or polygons ("x,y x,y x,y ...") in the map frame [m],
each optionally =VALUE: keep-out masks forbid (100, the default); speed masks take the percentage
of max_vel_x (required). The mask has the map's resolution and origin with --like (the costmap
filters need the costmap's resolution), else --bounds at --resolution. Any image editor does the
same: the darker a pixel, the higher the value (docs/navigation.md, "Keep-out and speed zones").
"""
import argparse
import sys

import cv2
import numpy as np

from mbot_slam_navigation.maps.map_io import MapFileError, load_map, save_mask


def parse_zone(text: str, rect: bool):
    """(points (N, 2) [m], value or None) from 'x,y x,y ...' or 'xmin,ymin,xmax,ymax', each '=VALUE'."""
    shape, _, value = text.partition('=')
    try:
        if rect:
            x0, y0, x1, y1 = (float(v) for v in shape.split(','))
            points = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
        else:
            points = np.array([[float(v) for v in p.split(',')] for p in shape.split()])
        value = float(value) if value else None
    except ValueError:
        raise ValueError('cannot read zone "%s"' % text) from None
    if points.ndim != 2 or points.shape[1] != 2 or len(points) < 3:
        raise ValueError('zone "%s": a polygon needs at least 3 points x,y' % text)
    return points, value


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('out', help='basename of the mask: writes OUT.pgm and OUT.yaml')
    ap.add_argument('--speed', action='store_true', help='a speed mask (values: percent of max_vel_x)')
    ap.add_argument('--like', help="a map_server YAML whose resolution, origin and size the mask takes")
    ap.add_argument('--bounds', nargs=4, type=float, metavar=('XMIN', 'YMIN', 'XMAX', 'YMAX'))
    ap.add_argument('--resolution', type=float, default=0.05, help='[m/cell] with --bounds')
    ap.add_argument('--rect', action='append', default=[], help='xmin,ymin,xmax,ymax[=VALUE] [m]')
    ap.add_argument('--zone', action='append', default=[], help='"x,y x,y x,y ...[=VALUE]" [m]')
    a = ap.parse_args(argv)
    try:
        if a.like:
            m = load_map(a.like)
            resolution, origin = m.resolution, m.origin[:2]
            height, width = m.data.shape
        elif a.bounds:
            x0, y0, x1, y1 = a.bounds
            resolution, origin = a.resolution, (x0, y0)
            width, height = int(np.ceil((x1 - x0) / resolution)), int(np.ceil((y1 - y0) / resolution))
        else:
            ap.error('give --like MAP.yaml or --bounds')
        zones = [parse_zone(t, True) for t in a.rect] + [parse_zone(t, False) for t in a.zone]
        if not zones:
            ap.error('no zone: give --rect or --zone')
        values = np.zeros((height, width), np.float64)
        for points, value in zones:
            if a.speed and value is None:
                raise ValueError('a speed zone needs =PERCENT')
            cells = np.rint(((points - np.asarray(origin)) / resolution - 0.5) * 16).astype(np.int32)
            layer = np.zeros((height, width), np.uint8)
            cv2.fillPoly(layer, [cells], 1, lineType=cv2.LINE_8, shift=4)
            values[layer > 0] = 100 if value is None else value
        save_mask(a.out, values, resolution, (origin[0], origin[1], 0.0), speed=a.speed)
    except (ValueError, MapFileError) as e:
        print('make_mask: %s' % e, file=sys.stderr)
        return 2
    print('make_mask: %s.yaml and %s.pgm: %d x %d cells at %g m, %.1f m^2 in zones'
          % (a.out, a.out, width, height, resolution, np.count_nonzero(values) * resolution ** 2))
    return 0


if __name__ == '__main__':
    sys.exit(main())

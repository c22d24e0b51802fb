#!/usr/bin/python3
"""The Python consumer of the CI comparison: one "lit value" line per "x y z" point, like
c-consumer and cpp-consumer.   query_points.py LOCATION POINTS_FILE METHOD"""
import sys

import numpy as np

import shadowtiles


def main():
    if len(sys.argv) != 4:
        sys.exit("usage: query_points.py LOCATION POINTS_FILE METHOD")
    location, points_file, method = sys.argv[1:]
    points = np.loadtxt(points_file, dtype=np.float64, ndmin=2)
    try:
        with shadowtiles.open(location) as m:
            lit, values = m.query(points, method)
    except shadowtiles.Error as e:
        sys.exit("query_points.py: %s (%s)" % (e, e.code))
    sys.stdout.write("".join("%d %.9g\n" % (l, v) for l, v in zip(lit, values.astype(np.float64))))


if __name__ == "__main__":
    main()

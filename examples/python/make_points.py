#!/usr/bin/python3
"""Writes COUNT receiver points of the terrain (receivers.py) as "x y z" lines with 17 digits, so
every consumer and `shadowtiles query` read the same doubles.   make_points.py OVERHEAD_STORE COUNT OUT"""
import sys

import numpy as np

from receivers import terrain_receivers

if __name__ == "__main__":
    store, count, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    np.savetxt(out, terrain_receivers(store, count), fmt="%.17g")

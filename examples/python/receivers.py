"""Receiver points on a heightfield without a mesh library: the first surface met straight down.

An overhead build of the same scene (`shadowtiles build SCENE --light-dir 0,0,-1 -m raw`) stores the
first hit under every texel of a regular x-y grid; Map.surface_points() turns those depths back into
world points. For a terrain (one height per x, y) that is the whole terrain surface, sampled evenly
by area in plan view, including the parts the sun never reaches.
"""
import numpy as np

import shadowtiles


def terrain_receivers(overhead_store, count=None, seed=1):
    with shadowtiles.open(overhead_store) as top:
        points = top.surface_points()
    if count is not None and count < len(points):
        points = points[np.random.default_rng(seed).choice(len(points), count, replace=False)]
    return points

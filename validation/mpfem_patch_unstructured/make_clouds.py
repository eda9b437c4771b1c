#!/usr/bin/env python3
"""Writes the particle files of this validation case (deterministic: numpy's PCG64 with fixed seeds).

Plate [0, 3] x [0, 1.5], boundary particles on a regular spacing h = 0.125 (25 x 13 on the sides,
72 in all, corners included):
  min_spacing_287.csv  issue 21's user case: 215 random interior points, each at least 0.6 h from
                       every other particle (dart throwing), 287 particles in all;
  uniform_random.csv   215 interior points uniformly random (no minimum distance; points closer
                       than 0.05 h to the boundary are redrawn so that none falls on it).
Usage: /usr/bin/python3 make_clouds.py   (in this folder)
"""
import numpy as np

W, H, h = 3.0, 1.5, 0.125
nx, ny = 25, 13


def boundary():
    pts = [(i * h, 0.0) for i in range(nx)] + [(i * h, H) for i in range(nx)]
    pts += [(0.0, j * h) for j in range(1, ny - 1)] + [(W, j * h) for j in range(1, ny - 1)]
    return np.array(pts)


def write(name, pts):
    with open(name, "w") as f:
        f.write("x,y,z\n")
        for x, y in pts:
            f.write(f"{x:.17g},{y:.17g},0.05\n")


def min_spacing(seed=21, count=215, dmin=0.6 * h):
    rng = np.random.Generator(np.random.PCG64(seed))
    pts = list(boundary())
    added = 0
    while added < count:
        p = rng.uniform((0, 0), (W, H))
        if np.min(np.hypot(*(np.array(pts) - p).T)) >= dmin:
            pts.append(tuple(p))
            added += 1
    return np.array(pts)


def uniform(seed=5, count=215):
    rng = np.random.Generator(np.random.PCG64(seed))
    pts = list(boundary())
    added = 0
    while added < count:
        p = rng.uniform((0, 0), (W, H))
        if min(p[0], W - p[0], p[1], H - p[1]) > 0.05 * h:
            pts.append(tuple(p))
            added += 1
    return np.array(pts)


if __name__ == "__main__":
    write("min_spacing_287.csv", min_spacing())
    write("uniform_random.csv", uniform())

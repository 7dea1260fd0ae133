#!/usr/bin/env python3
"""Writes the meshes and the hand-placed particles of the rotating-drum and conical-hopper
examples, and the hopper and its gate of the hopper-fill-discharge example (pure Python 3; the files it writes are shipped, so users need not run it).

    python3 examples/make_geometry.py

Particles sit on a cubic lattice of spacing 1.1 d, clear of the walls, with a small
deterministic jitter of their velocities so that the bed does not settle as a crystal.
"""

import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def ring(r, z, n, phase=0.0):
    return [(r * math.cos(2 * math.pi * k / n + phase), r * math.sin(2 * math.pi * k / n + phase), z) for k in range(n)]


def write_obj(path, title, vertices, faces):
    with open(path, "w") as f:
        f.write(f"# {title}\n# {len(vertices)} vertices, {len(faces)} triangles, metres; normals face the particles\n")
        for v in vertices:
            f.write("v {:.9g} {:.9g} {:.9g}\n".format(*v))
        for t in faces:
            f.write("f {} {} {}\n".format(*(i + 1 for i in t)))


def jitter(k):
    """A small velocity, m/s, from the particle's number (no random module: the same files
    on every machine)."""
    h = (k * 2654435761) % 4294967296 / 4294967296.0
    g = (k * 40503 + 12345) % 65536 / 65536.0
    return (0.02 * (h - 0.5), 0.02 * (g - 0.5), 0.0)


def write_particles(path, points, d):
    with open(path, "w") as f:
        f.write("id,phase,x,y,z,diameter,u,v,w\n")
        for k, (x, y, z) in enumerate(points, start=1):
            u, v, w = jitter(k)
            f.write(f"{k},glass,{x:.6f},{y:.6f},{z:.6f},{d},{u:.4f},{v:.4f},{w:.4f}\n")


def drum():
    """A drum of radius 50 mm and depth 40 mm about the z axis, mantle of 48 flat facets and
    end caps as fans; half filled with 4 mm beads."""
    R, L, n, d = 0.05, 0.04, 48, 0.004
    v = ring(R, -L / 2, n) + ring(R, L / 2, n) + [(0.0, 0.0, -L / 2), (0.0, 0.0, L / 2)]
    lo, hi = (lambda k: k % n), (lambda k: n + k % n)
    c0, c1 = 2 * n, 2 * n + 1
    faces = []
    for k in range(n):
        # Mantle: normals towards the axis.
        faces.append((lo(k), hi(k + 1), lo(k + 1)))
        faces.append((lo(k), hi(k), hi(k + 1)))
        # Caps: the back one faces +z, the front one −z.
        faces.append((c0, lo(k), lo(k + 1)))
        faces.append((c1, hi(k + 1), hi(k)))
    write_obj(os.path.join(HERE, "rotating-drum", "drum.obj"), "rotating drum, R = 50 mm, depth 40 mm", v, faces)
    s, r = 1.1 * d, d / 2
    inner = R * math.cos(math.pi / n) - r - 0.2 * d
    pts = []
    m = int(R / s) + 1
    for i in range(-m, m + 1):
        for j in range(-m, 1):
            for k in range(-6, 7):
                x, y, z = i * s, j * s - 0.5 * s, k * s
                if math.hypot(x, y) < inner and abs(z) < L / 2 - r - 0.2 * d:
                    pts.append((x, y, z))
    write_particles(os.path.join(HERE, "rotating-drum", "particles.csv"), pts, d)
    return len(pts)


def hopper():
    """A conical hopper about the z axis: orifice 24 mm across at z = 0, cone of 60° included
    angle up to 80 mm across, a cylinder above it to z = 100 mm; open at both ends. Filled
    with 4 mm beads from z = 10 mm up."""
    r0, r1, top, n, d = 0.012, 0.040, 0.100, 48, 0.004
    z1 = (r1 - r0) / math.tan(math.radians(30))
    rings = [(r0, 0.0), (r1, z1), (r1, top)]
    v = []
    for r, z in rings:
        v += ring(r, z, n)
    faces = []
    for a in range(len(rings) - 1):
        lo, hi = (lambda k, a=a: a * n + k % n), (lambda k, a=a: (a + 1) * n + k % n)
        for k in range(n):
            faces.append((lo(k), hi(k + 1), lo(k + 1)))
            faces.append((lo(k), hi(k), hi(k + 1)))
    for example in ("conical-hopper", "hopper-fill-discharge"):
        write_obj(os.path.join(HERE, example, "hopper.obj"), "conical hopper, orifice 24 mm, 60 degrees, D = 80 mm", v, faces)
    s, r = 1.1 * d, d / 2
    pts = []
    m = int(r1 / s) + 1
    z = 0.010
    while z < top - r:
        # Radius inside the wall at this height, less a clearance: the cone's wall is at
        # r0 + z·tan 30°, its normal tilted 60° from the axis.
        wall = min(r0 + z * math.tan(math.radians(30)), r1) * math.cos(math.pi / n)
        clear = (r / math.cos(math.radians(30)) if z < z1 else r) + 0.2 * d
        for i in range(-m, m + 1):
            for j in range(-m, m + 1):
                x, y = i * s, j * s
                if math.hypot(x, y) < wall - clear:
                    pts.append((x, y, z))
        z += s
    write_particles(os.path.join(HERE, "conical-hopper", "particles.csv"), pts, d)
    return len(pts)


def gate():
    """The hopper-fill-discharge example's gate: a square plate 32 mm across, 0.5 mm under the
    orifice (24 mm across at z = 0), two triangles facing up, towards the beads."""
    h, z = 0.016, -0.0005
    v = [(-h, -h, z), (h, -h, z), (h, h, z), (-h, h, z)]
    write_obj(os.path.join(HERE, "hopper-fill-discharge", "gate.obj"), "gate under the orifice, 32 mm square", v, [(0, 1, 2), (0, 2, 3)])


if __name__ == "__main__":
    gate()
    print("drum:", drum(), "particles")
    print("hopper:", hopper(), "particles")

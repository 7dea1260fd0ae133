#!/usr/bin/env python3
"""Tiles a settled LAMMPS bed (atom_style sphere data file) k x k times in x and y: the large
beds of the memory and scaling benchmarks (k = 10 turns the 10 000-particle box bed into
1 000 000 particles). Ids are renumbered tile by tile; velocities are copied. Tiles are
GAP apart (default 0.1 mm): particles pressed into a tile's wall (a few % of a radius) would
otherwise overlap their neighbours across the seam. The seams' particles settle a little at
first.

    bench/make-large-bed.py IN.data K OUT.data [GAP]
"""
import sys


def main():
    src, k, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    gap = float(sys.argv[4]) if len(sys.argv) > 4 else 1e-4
    lines = open(src).read().splitlines()
    n = next(int(l.split()[0]) for l in lines if l.strip().endswith(" atoms"))
    box = {}
    for l in lines:
        w = l.split()
        if len(w) == 4 and w[2].endswith("lo"):
            box[w[2][0]] = (float(w[0]), float(w[1]))
    start = next(i for i, l in enumerate(lines) if l.startswith("Atoms")) + 2
    atoms = [l.split() for l in lines[start:start + n]]
    vstart = next((i for i, l in enumerate(lines) if l.startswith("Velocities")), None)
    vel = {}
    if vstart is not None:
        for l in lines[vstart + 2:vstart + 2 + n]:
            w = l.split()
            vel[w[0]] = w[1:]
    lx = box["x"][1] - box["x"][0] + gap
    ly = box["y"][1] - box["y"][0] + gap
    with open(out, "w") as f:
        f.write(f"{k}x{k} tiles of {src}\n\n{n * k * k} atoms\n1 atom types\n\n")
        f.write(f"{box['x'][0]} {box['x'][0] + k * lx - gap} xlo xhi\n")
        f.write(f"{box['y'][0]} {box['y'][0] + k * ly - gap} ylo yhi\n")
        f.write(f"{box['z'][0]} {box['z'][1]} zlo zhi\n\nAtoms # sphere\n\n")
        vout = []
        for t in range(k * k):
            dx, dy = (t % k) * lx, (t // k) * ly
            for a in atoms:
                new_id = t * n + int(a[0])
                x, y = float(a[4]) + dx, float(a[5]) + dy
                f.write(f"{new_id} {a[1]} {a[2]} {a[3]} {x!r} {y!r} {a[6]}\n")
                if a[0] in vel:
                    vout.append(f"{new_id} {' '.join(vel[a[0]])}\n")
        if vout:
            f.write("\nVelocities\n\n")
            f.writelines(vout)


if __name__ == "__main__":
    main()

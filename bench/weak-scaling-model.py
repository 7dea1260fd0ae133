#!/usr/bin/env python3
"""The weak-scaling model of docs/parallel.md: the time of a step on P ranks of n particles
each, from the costs measured on this machine (bench/results/2026-12-06-comm-cost.md,
-ranks.md) and stated assumptions for a cluster. Prints the table docs/parallel.md quotes.

    python3 bench/weak-scaling-model.py
"""
import math

# Measured here.
C = 95e-9            # s per particle-step, box_hm on one rank (10.51e6 particle-steps/s)
GHOST_BYTES = 72     # a ghost's refresh: position, velocity, spin (9 words)
EXCHANGES = 1.1      # exchanges a step (the refresh, and at rebuilds the migration)
GATHERS = 2          # one-word all-gathers a step (the rebuild decision, the largest load)
RHO_D3 = 1.146       # particles per d^3 in a bed of solid fraction 0.6
REACH_D = 1.1        # the list's reach, 2 r_max + skin, in diameters (skin 0.1 d)

# Assumed for the cluster (see docs/parallel.md).
RANKS_PER_NODE = 64
ALPHA_ON, ALPHA_OFF = 0.3e-6, 1.5e-6     # s per message, within a node and across
BETA_SMALL = 0.42e-9                     # s per byte within a node, messages <= 32 kB (measured)
BETA_ON = 2.3e-9                         # s per byte within a node, larger (measured here)
BETA_OFF = 1 / (25e9 / RANKS_PER_NODE)   # s per byte across: a 200 Gb/s link shared by a node
OFF_NODE = 0.25                          # share of halo bytes leaving a node (4x4x4 ranks a node)
ALPHA_EMPTY = 0.2e-6                     # s per empty message of an all-to-all-v on P ranks


def cut_faces(p):
    """Per axis, the cut faces of the busiest rank's cube when p ranks form a 3-D grid cut by
    bisection: 1 on the first axis at 2 ranks, one axis more at 4 and 8, then both faces."""
    if p == 1:
        return (0, 0, 0)
    axes = [0, 0, 0]
    k = 0
    for _ in range(math.ceil(math.log2(p))):
        axes[k % 3] = min(2, axes[k % 3] + 1)
        k += 1
    return tuple(axes)


def ghosts(n, p):
    """Ghosts of the busiest rank holding a cube of n particles: the layers of width REACH_D
    beyond its cut faces."""
    side = (n / RHO_D3) ** (1 / 3)
    grow = 1.0
    for a in cut_faces(p):
        grow *= 1 + a * REACH_D / side
    return n * (grow - 1)


def step(n, p):
    """Seconds a step on p ranks of n particles each: compute, halo, collectives."""
    compute = C * n
    if p == 1:
        return compute, 0.0, 0.0
    halo_bytes = GHOST_BYTES * ghosts(n, p)
    faces = sum(cut_faces(p))
    neighbours = min(p - 1, 26)
    on = BETA_SMALL if halo_bytes / faces <= 32 * 1024 else BETA_ON
    beta = (1 - OFF_NODE) * on + OFF_NODE * BETA_OFF if p > RANKS_PER_NODE else on
    alpha = ALPHA_OFF if p > RANKS_PER_NODE else ALPHA_ON
    halo = EXCHANGES * (neighbours * alpha + halo_bytes * beta)
    levels = math.ceil(math.log2(p))
    gather = GATHERS * levels * alpha
    # Today's exchange: a count all-to-all (log2 p steps) and an all-to-all-v over every rank.
    alltoall = EXCHANGES * (levels * alpha + (p - 1 - neighbours) * ALPHA_EMPTY)
    return compute, halo, gather + alltoall


def main():
    print("| n per rank | P | compute, ms | halo, ms | collectives, ms | efficiency |")
    print("|---|---|---|---|---|---|")
    for n in (10**4, 10**5, 10**6):
        t1 = sum(step(n, 1))
        for p in (2, 8, 64, 1000):
            c, h, g = step(n, p)
            print(f"| {n:.0e} | {p} | {c*1e3:.2f} | {h*1e3:.3f} | {g*1e3:.3f} | {t1/(c+h+g):.2f} |")


if __name__ == "__main__":
    main()

"""A rotating drum whose speed a Python function sets, with the bed's dynamic angle of repose
measured while it runs and plotted with matplotlib.

The drum of examples/rotating-drum (100 mm across, half full of 4 mm glass beads) starts at
rest; a callback run every 10 ms of simulated time sets its angular velocity from `speed(t)`,
a ramp to 10 rpm and a hold, and measures the angle of the bed's free surface from the centre
of mass of the beads: for a flat surface at any fill the centroid lies on the perpendicular to
the surface through the axis, so the surface's angle is atan2(x_c, -y_c) (the drum turns about
+z, lifting the bed on its +x side).

    python python/examples/drum_ramp.py             # 3 s of the drum, writes drum_ramp.png
"""

import argparse
import math
import pathlib

import numpy as np

import grainflow

CASE = pathlib.Path(__file__).resolve().parents[2] / "examples" / "rotating-drum" / "case.toml"
RPM = 10.0  # the speed held after the ramp
RAMP = (0.2, 0.8)  # s: the ramp's start and end
EVERY = 0.01  # s of simulated time between callbacks


def speed(t):
    """The drum's angular velocity at time t, rad/s: at rest, a linear ramp, then RPM."""
    f = min(max((t - RAMP[0]) / (RAMP[1] - RAMP[0]), 0.0), 1.0)
    return f * RPM * 2.0 * math.pi / 60.0


def surface_angle(sim):
    """The bed's surface angle from the centroid of its beads, degrees."""
    p = sim.particles
    m = p.mass
    xc, yc = (m @ p.position[:, :2]) / m.sum()
    return math.degrees(math.atan2(xc, -yc))


def main(t_stop=3.0):
    """Runs the drum to t_stop s; returns the records (time, set speed, angle) as arrays and
    the angle the drum turned by its own pose."""
    sim = grainflow.Simulation.from_case(CASE, overrides={"time.t_stop": t_stop})
    drum = sim.meshes["drum"]
    drum.set_omega(0.0, axis=[0.0, 0.0, 1.0], origin=[0.0, 0.0, 0.0])  # the script drives it
    record = {"time": [], "omega": [], "angle": []}

    def each(sim):
        w = speed(sim.time)
        drum.set_omega(w, axis=[0.0, 0.0, 1.0], origin=[0.0, 0.0, 0.0])
        record["time"].append(sim.time)
        record["omega"].append(w)
        record["angle"].append(surface_angle(sim))

    sim.run(until=t_stop, every=EVERY, callback=each)
    q = drum.rotation
    turned = 2.0 * math.atan2(math.copysign(math.hypot(q[0], q[1], q[2]), q[2]), q[3])
    return {k: np.array(v) for k, v in record.items()}, turned, sim


def plot(record, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(record["time"], record["angle"], label="surface angle (centroid)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("dynamic angle of repose (°)")
    ax.axhline(25.0, color="grey", ls=":", label="rounded grains, about 25° (Kleinhans et al. 2011)")
    rpm = ax.twinx()
    rpm.plot(record["time"], record["omega"] * 60.0 / (2.0 * math.pi), color="C1", label="drum speed")
    rpm.set_ylabel("drum speed (rpm)", color="C1")
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    cli = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    cli.add_argument("--plot", default="drum_ramp.png", help="the figure's file")
    args = cli.parse_args()
    record, turned, sim = main()
    steady = record["time"] >= 2.0
    print(f"mean surface angle over 2-3 s: {record['angle'][steady].mean():.1f} deg")
    print(f"the drum turned {math.degrees(turned):.2f} deg; {sim.step_count} steps")
    plot(record, args.plot)
    print(f"wrote {args.plot}")

"""MFIX's DEM05 test case (oblique impacts of alumina spheres on a wall and on resting
spheres, Kharaz et al. 2001) run from its own MFIX decks, against the values MFIX 21.3 prints.

Each deck holds 31 spheres hitting the wall at 0-65 degrees (ids 1-31) and 31 hitting a sphere
held at rest (ids 32-62, their targets 63-93, held by the deck's user functions, which
`motion.toml` gives as a prescribed-motion rule). After the run each impactor's rebound is
measured from its velocity before and after: the rebound angle atan(v_t / v_n), the tangential
restitution v_t / v_t0 and the spin |omega|, and compared with MFIX's printed values (four
decimals: equal once rounded as MFIX prints them, i.e. within 5e-5). The figure shows the
tangential restitution against the impact angle for both models.

    python python/examples/dem05.py                  # both decks, writes dem05.png
"""

import argparse
import csv
import math
import pathlib
import warnings

import numpy as np

import grainflow

REPO = pathlib.Path(__file__).resolve().parents[2]
DECKS = REPO / "crates" / "grainflow-case" / "tests" / "mfix_decks" / "dem05"
REFERENCE = REPO / "crates" / "grainflow-verify" / "data" / "mfix-dem05" / "reference.csv"
MODELS = {"lsd": "lsd.dat", "hertz": "hertz.mfx"}


def rebounds(deck):
    """Runs one deck; returns, by (collision, impact angle rounded to 0.1 degree), the rebound
    angle (degrees), the tangential restitution (None at normal impact) and the spin (rad/s)."""
    with warnings.catch_warnings():
        # The deck's notices: its user functions are the motion file's rule, its fluid grid
        # and energy equations do not act on the particles.
        warnings.simplefilter("ignore", UserWarning)
        sim = grainflow.Simulation.from_case(DECKS / deck, motion=DECKS / "motion.toml")
    p = sim.particles
    v0 = dict(zip(p.ids, p.velocity.copy()))
    sim.run()
    p = sim.particles  # the particles may have been re-sorted since: go by id
    ids = p.ids
    out = {}
    for i in np.flatnonzero((ids >= 1) & (ids <= 62)):
        (ux, uy, uz), (vx, vy, vz) = v0[ids[i]], p.velocity[i]
        vt0, vt = math.hypot(ux, uz), math.hypot(vx, vz)
        collision = "particle" if ids[i] >= 32 else "wall"
        theta = round(math.degrees(math.atan2(vt0, -uy)), 1)
        w = p.omega[i]
        out[(collision, theta)] = (
            math.degrees(math.atan2(vt, vy)),
            vt / vt0 if vt0 > 1e-12 else None,
            math.hypot(w[0], w[2]),
        )
    return out


def mfix_values(model):
    """MFIX 21.3's printed DEM05 values for a model, keyed as `rebounds`'s."""
    with open(REFERENCE, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["model"] == model]
    number = lambda s: float(s) if s else None  # noqa: E731
    return {
        (r["collision"], round(float(r["impact_angle_deg"]), 1)): (
            float(r["rebound_angle_deg"]),
            number(r["tangential_restitution"]),
            float(r["angular_velocity_rad_s"]),
        )
        for r in rows
    }


def main():
    """Both models: ours and MFIX's values, and the largest difference of each quantity."""
    results = {}
    for model, deck in MODELS.items():
        ours, theirs = rebounds(deck), mfix_values(model)
        assert ours.keys() == theirs.keys(), f"{model}: the impacts are not MFIX's"
        worst = [0.0, 0.0, 0.0]
        for key, row in ours.items():
            for q, (a, b) in enumerate(zip(row, theirs[key])):
                if a is not None and b is not None:
                    worst[q] = max(worst[q], abs(a - b))
                else:
                    assert a is None and b is None, f"{model} {key}: e_t only one side"
        results[model] = (ours, theirs, worst)
    return results


def plot(results, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(9, 3.8), sharey=True)
    for ax, collision in zip(axes, ["wall", "particle"]):
        for color, (model, (ours, theirs, _)) in zip(["C0", "C2"], results.items()):
            keys = sorted(k for k in ours if k[0] == collision and ours[k][1] is not None)
            angles = [k[1] for k in keys]
            ax.plot(angles, [ours[k][1] for k in keys], color=color, label=f"grainflow, {model}")
            mfix = [theirs[k][1] for k in keys]
            ax.plot(angles, mfix, "o", color=color, mfc="none", ms=4, label=f"MFIX 21.3, {model}")
        ax.set_title(f"sphere on a {collision}")
        ax.set_xlabel("impact angle (deg)")
    axes[0].set_ylabel("tangential restitution")
    axes[1].legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    cli = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    cli.add_argument("--plot", default="dem05.png", help="the figure's file")
    args = cli.parse_args()
    results = main()
    for model, (_, _, worst) in results.items():
        print(
            f"{model}: largest difference from MFIX: rebound angle {worst[0]:.1e} deg, "
            f"e_t {worst[1]:.1e}, spin {worst[2]:.1e} rad/s (MFIX prints 4 decimals: 5e-5)"
        )
    plot(results, args.plot)
    print(f"wrote {args.plot}")

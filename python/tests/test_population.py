"""Adding and removing particles from Python, the books that count them, contacts and meshes."""

import math

import numpy as np
import pytest

import grainflow
from conftest import EXAMPLES, assert_last_snapshot_is, bits, run_cli

G = 9.80665  # the settling bed's gravity, m/s²


def bed(t_stop=0.05):
    return grainflow.Simulation.from_case(EXAMPLES / "settling-bed" / "case.toml", overrides={"time.t_stop": t_stop})


def test_books_close_through_insert_and_remove():
    sim = bed()
    sim.step(50)
    d = np.array([0.004, 0.003, 0.005])
    new = sim.insert(np.array([[0.01, 0.15, 0.01], [0.025, 0.15, 0.025], [0.04, 0.15, 0.04]]), d)
    sim.step(50)
    gone = sim.remove(np.array([int(new[1]), 5], dtype=np.int64))
    assert gone == 2
    b = sim.books()
    assert b["closes"]
    assert b["initial"][0] == 486 and b["added"][0] == 3 and b["taken"][0] == 2
    assert b["present"][0] == 487 == len(sim.particles)
    # Masses in the books' quanta (2^-60 of the largest particle's mass or finer): exact to 1e-15.
    assert b["added"][1] == pytest.approx(2500.0 * math.pi / 6 * float(np.sum(d**3)), rel=1e-15)
    assert b["inserted"] == (0, 0.0) and b["removed"] == (0, 0.0)


def test_inserted_ids_follow_every_id_and_the_particles_fall():
    sim = bed()
    new = sim.insert(np.array([[0.025, 0.18, 0.025]]), np.array([0.004]), velocities=np.zeros((1, 3)))
    assert list(new) == [487]
    assert 487 in set(sim.particles.ids)
    sim.step(200)
    t = 200 * sim.dt
    p = sim.particles
    k = int(np.nonzero(p.ids == 487)[0][0])
    # Euler's free fall over n steps lies within 1/n of the closed form g t²/2; n = 200: 1 %.
    assert 0.18 - p.position[k, 1] == pytest.approx(0.5 * G * t * t, rel=0.01)


def test_insert_and_remove_refuse_what_does_not_fit():
    sim = bed()
    with pytest.raises(grainflow.EngineError, match="shape"):
        sim.insert(np.zeros((2, 3)), np.array([0.004]))
    with pytest.raises(grainflow.EngineError, match="no phase is named 'sand'"):
        sim.insert(np.array([[0.02, 0.15, 0.02]]), np.array([0.004]), phase="sand")
    with pytest.raises(grainflow.EngineError, match="diameter|radius"):
        sim.insert(np.array([[0.02, 0.15, 0.02]]), np.array([-0.004]))
    with pytest.raises(grainflow.EngineError, match="id 9999"):
        sim.remove(np.array([3, 9999], dtype=np.int64))
    assert len(sim.particles) == 486 and sim.books()["closes"]


def test_a_settled_bed_rests_on_the_walls_with_its_weight():
    # At rest the contact forces on the beads hold their weight (the pairs' cancel): their sum
    # is m g up to the bed's remaining acceleration (1 % is ample after 0.5 s of settling).
    # The floor's normal forces carry most of it, the side walls' friction (mu = 0.4) the rest.
    sim = grainflow.Simulation.from_case(EXAMPLES / "settling-bed" / "case.toml")
    sim.run()
    c = sim.contacts()
    weight = float(np.sum(sim.particles.mass)) * G
    assert float(np.sum(sim.particles.force[:, 1])) == pytest.approx(weight, rel=0.01)
    floor = np.array([name == "y_min" for name in c["other"]])
    assert floor.any()
    assert 0.9 * weight < float(np.sum(c["normal_force"][floor])) <= 1.001 * weight
    # Every contact overlaps, with a unit normal, and names particles the bed has.
    assert np.all(c["overlap"] > 0)
    np.testing.assert_allclose(np.linalg.norm(c["normal"], axis=1), 1.0, rtol=1e-12)
    ids = set(sim.particles.ids)
    assert set(c["id"]) <= ids
    pairs = c["other_id"] >= 0
    assert set(c["other_id"][pairs]) <= ids
    assert np.all(c["triangle"] == -1)


def test_a_mesh_is_named_and_its_load_balances_the_beads_momentum():
    # The drum is the only wall: over one Euler step the beads' momentum changes by
    # dt (M g − F_drum) (the pairs' loads cancel exactly), to rounding.
    case = EXAMPLES / "rotating-drum" / "case.toml"
    sim = grainflow.Simulation.from_case(case, overrides={"time.t_stop": 0.05, "time.integrator": "euler"})
    assert list(sim.meshes) == ["drum"]
    sim.step(400)
    p = sim.particles
    m = np.asarray(p.mass)[:, None]
    before = np.sum(m * p.velocity, axis=0)
    sim.step(1)
    p = sim.particles
    after = np.sum(np.asarray(p.mass)[:, None] * p.velocity, axis=0)
    drum = sim.meshes["drum"]
    weight = float(np.sum(p.mass)) * np.array([0.0, -9.80665, 0.0])
    expected = weight - np.array(drum.force)
    np.testing.assert_allclose((after - before) / sim.dt, expected, rtol=0, atol=1e-9 * np.linalg.norm(weight))
    assert drum.force[1] < 0  # the beads press on it
    assert np.linalg.norm(drum.rotation) == pytest.approx(1.0, rel=1e-12)
    c = sim.contacts()
    on_drum = np.array([name == "drum" for name in c["other"]])
    assert on_drum.any() and np.all(c["triangle"][on_drum] >= 0)


def angle_of(q):
    """The rotation angle of a unit quaternion (x, y, z, w), rad."""
    return 2.0 * math.atan2(math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2), q[3])


def drum(t_stop=0.05):
    return grainflow.Simulation.from_case(EXAMPLES / "rotating-drum" / "case.toml", overrides={"time.t_stop": t_stop})


def test_a_drum_set_turning_from_python_turns_at_that_rate():
    sim = drum()
    sim.step(100)
    mesh = sim.meshes["drum"]
    before = angle_of(mesh.rotation)
    mesh.set_omega(3.0)
    sim.step(200)
    # From where it was, 3 rad/s for 200 steps (the quaternion's angle to 1e-12 rad).
    assert angle_of(mesh.rotation) - before == pytest.approx(3.0 * 200 * sim.dt, abs=1e-12)


def test_a_restart_goes_on_with_the_motion_python_set(tmp_path):
    case = EXAMPLES / "rotating-drum" / "case.toml"
    ran = []
    for restart in (False, True):
        sim = drum()
        sim.step(100)
        sim.meshes["drum"].set_omega(-4.0)
        sim.step(100)
        if restart:
            sim.checkpoint(tmp_path / "c.gfc")
            # The case file says the drum turns at its own rate: the checkpoint's motion wins.
            sim = grainflow.Simulation.restart(tmp_path / "c.gfc", case, accept_changed_case=True)
            assert sim.step_count == 200
        sim.step(300)
        ran.append((bits(sim.particles.position), sim.meshes["drum"].rotation))
    np.testing.assert_array_equal(ran[0][0], ran[1][0])
    assert ran[0][1] == ran[1][1]


def test_the_program_restarts_a_python_checkpoint_with_its_motion(tmp_path):
    case = EXAMPLES / "rotating-drum" / "case.toml"
    sim = drum()
    sim.step(100)
    sim.meshes["drum"].set_omega(-4.0)
    sim.step(100)
    sim.checkpoint(tmp_path / "c.gfc")
    sim.run()
    # The same case (the override as the program's --set): the program takes the checkpoint
    # as its own and ends where the script's run ended, to the bit.
    out = tmp_path / "out"
    done = run_cli("run", case, "--set", "time.t_stop=0.05", "--restart", tmp_path / "c.gfc", "--out", out, "-q")
    assert done.returncode == 0, done.stderr
    assert_last_snapshot_is(out, sim)


def test_a_mesh_set_moving_translates_and_refuses_bad_motions():
    sim = drum()
    mesh = sim.meshes["drum"]
    sim.step(10)
    x0 = np.array(mesh.translation)
    mesh.set_velocity([0.0, 0.0, 0.01])
    sim.step(100)
    np.testing.assert_allclose(np.array(mesh.translation) - x0, [0.0, 0.0, 0.01 * 100 * sim.dt], atol=1e-15)
    with pytest.raises(grainflow.EngineError, match="give the axis"):
        mesh.set_omega(1.0)
    with pytest.raises(grainflow.EngineError, match="axis"):
        mesh.set_omega(1.0, axis=[0.0, 0.0, 0.0], origin=[0.0, 0.0, 0.0])
    with pytest.raises(grainflow.EngineError):
        mesh.set_velocity([float("nan"), 0.0, 0.0])

"""Physics from Python: closed forms of free fall and of a linear spring-dashpot rebound."""

import math

import numpy as np
import pytest

import grainflow
from conftest import ball_case


def test_free_fall_follows_the_parabola_under_velocity_verlet():
    # Velocity Verlet is exact for a constant acceleration: x = x0 + g t²/2 to rounding.
    sim = grainflow.Simulation.from_dict(ball_case(t_stop=0.2))
    sim.step(1000)
    t = sim.time
    assert t == pytest.approx(0.1, rel=1e-12)
    z = sim.particles.position[0, 2]
    assert z == pytest.approx(0.5 - 0.5 * 9.81 * t * t, rel=1e-12)


def test_free_fall_velocity_grows_as_g_t():
    sim = grainflow.Simulation.from_dict(ball_case(t_stop=0.2))
    sim.step(1500)
    v = sim.particles.velocity[0]
    assert v[2] == pytest.approx(-9.81 * sim.time, rel=1e-12)
    assert v[0] == 0.0 and v[1] == 0.0


def test_kinetic_energy_of_the_diagnostics_is_half_m_v_squared():
    sim = grainflow.Simulation.from_dict(ball_case(t_stop=0.2))
    sim.step(700)
    p = sim.particles
    expected = 0.5 * float(np.sum(p.mass * np.sum(p.velocity**2, axis=1)))
    assert sim.diagnostics()["kinetic_translational"] == pytest.approx(expected, rel=1e-12)


def test_mass_view_is_density_times_volume():
    sim = grainflow.Simulation.from_dict(ball_case())
    p = sim.particles
    assert p.radius[0] == 0.1
    assert p.mass[0] == pytest.approx(2600.0 * 4.0 / 3.0 * math.pi * 0.1**3, rel=1e-15)


def test_a_rebound_off_the_floor_keeps_en_of_the_impact_speed():
    # A linear spring-dashpot with MFIX's damping restores e_n exactly in continuous time; at
    # dt = 1e-5 s against a contact of about 14 ms the integration changes it by ~1e-4, so 1e-3.
    en = 0.9
    sim = grainflow.Simulation.from_dict(ball_case(t_stop=0.45, dt=1.0e-5, height=0.3, en=en))
    speeds = []

    def watch(s):
        speeds.append(s.particles.velocity[0, 2])

    sim.run(until=0.45, every=1.0e-5, callback=watch)
    w = np.array(speeds)
    impact = w.min()
    assert impact == pytest.approx(-math.sqrt(2 * 9.81 * (0.3 - 0.1)), rel=2e-3)
    after = w[np.argmin(w):].max()
    assert after / -impact == pytest.approx(en, rel=1e-3)


def test_set_velocity_moves_a_free_particle_by_v_dt():
    sim = grainflow.Simulation.from_dict(ball_case(gravity=0.0))
    ids = np.array(sim.particles.ids, dtype=np.int64)
    sim.set_velocity(ids, np.array([[0.1, -0.2, 0.3]]))
    x0 = np.array(sim.particles.position)
    sim.step(100)
    moved = sim.particles.position - x0
    # 100 additions to coordinates near 0.5 m, each rounded to half an ulp (5.6e-17 m).
    np.testing.assert_allclose(moved[0], np.array([0.1, -0.2, 0.3]) * 100 * sim.dt, rtol=0, atol=1e-14)


def test_set_position_and_omega_take_effect():
    sim = grainflow.Simulation.from_dict(ball_case(gravity=0.0))
    ids = np.array([1], dtype=np.int64)
    sim.set_position(ids, np.array([[0.3, 0.4, 0.6]]))
    sim.set_omega(ids, np.array([[0.0, 0.0, 2.0]]))
    sim.step(10)
    np.testing.assert_array_equal(sim.particles.position[0], [0.3, 0.4, 0.6])
    np.testing.assert_array_equal(sim.particles.omega[0], [0.0, 0.0, 2.0])

"""The package's contract: stepping, views, exceptions, files and equality with the CLI."""

import gc
import math
import threading

import numpy as np
import pytest

import grainflow
from conftest import DECKS, assert_last_snapshot_is, ball_case, bits, run_cli


# --- stepping ---------------------------------------------------------------------------

def test_step_count_time_and_dt_agree():
    sim = grainflow.Simulation.from_dict(ball_case(t_stop=0.1, dt=1.0e-4))
    assert sim.total_steps == 1000
    sim.step(37)
    assert sim.step_count == 37
    assert sim.time == 37 * sim.dt


def test_run_until_ends_at_the_step_of_that_t_stop():
    # t_stop = 0.05 s at dt = 1e-4 s is 500 steps (rounded to the whole number it is).
    sim = grainflow.Simulation.from_dict(ball_case(t_stop=0.1, dt=1.0e-4))
    sim.run(until=0.05)
    assert sim.step_count == 500
    sim.run()
    assert sim.step_count == 1000


def test_step_stops_at_the_end_of_the_run():
    sim = grainflow.Simulation.from_dict(ball_case(t_stop=0.01, dt=1.0e-4))
    sim.step(10_000)
    assert sim.step_count == 100


def test_run_past_t_stop_is_refused():
    sim = grainflow.Simulation.from_dict(ball_case(t_stop=0.1))
    with pytest.raises(grainflow.EngineError, match="t_stop = 0.1"):
        sim.run(until=0.2)


def test_callback_every_is_called_on_its_schedule():
    sim = grainflow.Simulation.from_dict(ball_case(t_stop=0.1, dt=1.0e-4))
    seen = []
    sim.run(until=0.1, every=0.01, callback=lambda s: seen.append(s.step_count))
    assert seen == list(range(100, 1001, 100))


def test_a_raising_callback_stops_the_run_and_propagates_unchanged():
    sim = grainflow.Simulation.from_dict(ball_case(t_stop=0.1, dt=1.0e-4))
    mine = KeyError("stop here")

    def cb(s):
        if s.step_count >= 300:
            raise mine

    with pytest.raises(KeyError) as err:
        sim.run(every=0.01, callback=cb)
    assert err.value is mine
    assert sim.step_count == 300


def test_steps_in_any_chunks_give_the_same_bits(settling_bed):
    over = {"time.t_stop": 0.02}
    one = grainflow.Simulation.from_case(settling_bed, overrides=over)
    one.step(600)
    chunks = grainflow.Simulation.from_case(settling_bed, overrides=over)
    for n in [1, 7, 92, 200, 300]:
        chunks.step(n)
    assert chunks.step_count == 600
    np.testing.assert_array_equal(bits(one.particles.position), bits(chunks.particles.position))
    np.testing.assert_array_equal(bits(one.particles.velocity), bits(chunks.particles.velocity))


def test_threads_give_the_same_bits(settling_bed):
    over = {"time.t_stop": 0.01}
    a = grainflow.Simulation.from_case(settling_bed, overrides=over, threads=1)
    b = grainflow.Simulation.from_case(settling_bed, overrides=over, threads=2)
    a.run()
    b.run()
    np.testing.assert_array_equal(bits(a.particles.position), bits(b.particles.position))


def test_step_releases_the_gil():
    sim = grainflow.Simulation.from_dict(ball_case(t_stop=20.0, dt=1.0e-5))
    started = threading.Event()

    def work():
        started.set()
        sim.step(1_000_000)

    t = threading.Thread(target=work)
    t.start()
    started.wait()
    spins = 0
    while t.is_alive():
        spins += 1
    t.join()
    # Holding the GIL, the step would leave this thread a handful of switch intervals at most.
    assert spins > 10_000


# --- equality with the command line -----------------------------------------------------

def test_a_run_equals_grainflow_run_to_the_bit(settling_bed, tmp_path):
    out = tmp_path / "out"
    done = run_cli("run", settling_bed, "--set", "time.t_stop=0.02", "--out", out, "-q")
    assert done.returncode == 0, done.stderr
    sim = grainflow.Simulation.from_case(settling_bed, overrides={"time.t_stop": 0.02})
    sim.run()
    assert_last_snapshot_is(out, sim)
    series = grainflow.read_timeseries(out / "timeseries.csv")
    assert series["step"][-1] == sim.step_count
    assert series["kinetic_translational"][-1] == sim.diagnostics()["kinetic_translational"]


# --- views --------------------------------------------------------------------------------

def test_two_reads_share_memory_and_are_read_only():
    sim = grainflow.Simulation.from_dict(ball_case())
    a, b = sim.particles.position, sim.particles.position
    assert np.shares_memory(a, b)
    assert a.__array_interface__["data"][0] == b.__array_interface__["data"][0]
    assert not a.flags.writeable
    with pytest.raises(ValueError):
        a[0, 0] = 1.0


def test_every_view_has_its_shape_and_type(settling_bed):
    sim = grainflow.Simulation.from_case(settling_bed, overrides={"time.t_stop": 0.01})
    p = sim.particles
    n = len(p)
    assert n == 486
    for name in ["position", "velocity", "omega", "force", "torque"]:
        v = getattr(p, name)
        assert v.shape == (n, 3) and v.dtype == np.float64 and not v.flags.writeable
    for name, dtype in [("ids", np.uint32), ("phase", np.uint32), ("radius", np.float64), ("mass", np.float64)]:
        v = getattr(p, name)
        assert v.shape == (n,) and v.dtype == dtype and not v.flags.writeable
    assert sorted(p.ids) == list(range(1, 487))


def test_a_held_view_keeps_what_it_showed_after_steps():
    sim = grainflow.Simulation.from_dict(ball_case())
    held = sim.particles.position
    before = held.copy()
    sim.step(500)
    np.testing.assert_array_equal(held, before)
    now = sim.particles.position
    assert now[0, 2] < before[0, 2]
    assert not np.shares_memory(held, now)


def test_a_view_outlives_its_simulation():
    sim = grainflow.Simulation.from_dict(ball_case())
    sim.step(10)
    v = sim.particles.velocity
    expected = v.copy()
    del sim
    gc.collect()
    np.testing.assert_array_equal(v, expected)


# --- exceptions ---------------------------------------------------------------------------

def test_a_bad_value_names_its_table_and_key():
    d = ball_case()
    d["contact"]["wall"]["en"] = 1.5
    with pytest.raises(grainflow.CaseError) as err:
        grainflow.Simulation.from_dict(d)
    message = str(err.value)
    assert "en" in message and "1.5" in message


def test_an_unknown_key_is_refused_in_text():
    text = 'version = 1\n[domain]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nbogus = 3\n'
    with pytest.raises(grainflow.CaseError, match="bogus"):
        grainflow.Simulation.from_case_text(text)


def test_a_missing_case_file_is_a_case_error(tmp_path):
    with pytest.raises(grainflow.CaseError, match="nothing.toml"):
        grainflow.Simulation.from_case(tmp_path / "nothing.toml")


def test_a_value_toml_cannot_hold_names_its_key():
    d = ball_case()
    d["time"]["t_stop"] = object()
    with pytest.raises(grainflow.CaseError, match="time.t_stop"):
        grainflow.Simulation.from_dict(d)


def test_motion_is_refused_for_a_toml_case(settling_bed):
    with pytest.raises(grainflow.CaseError, match="MFIX decks"):
        grainflow.Simulation.from_case(settling_bed, motion="motion.toml")


def test_unknown_ids_shapes_and_values_are_refused():
    sim = grainflow.Simulation.from_dict(ball_case())
    with pytest.raises(grainflow.EngineError, match="id 7"):
        sim.set_velocity(np.array([7], dtype=np.int64), np.zeros((1, 3)))
    with pytest.raises(grainflow.EngineError, match="shape"):
        sim.set_velocity(np.array([1], dtype=np.int64), np.zeros((2, 3)))
    with pytest.raises(grainflow.EngineError, match="not finite"):
        sim.set_omega(np.array([1], dtype=np.int64), np.array([[0.0, np.nan, 0.0]]))
    # Nothing was changed by the refused calls.
    np.testing.assert_array_equal(sim.particles.velocity, np.zeros((1, 3)))


def test_a_panic_becomes_an_internal_error():
    with pytest.raises(grainflow.InternalError, match="on purpose"):
        grainflow.Simulation._panic_for_test()


def test_the_exceptions_share_a_base():
    for e in [grainflow.CaseError, grainflow.EngineError, grainflow.InternalError]:
        assert issubclass(e, grainflow.GrainflowError) and issubclass(e, Exception)


# --- cases ----------------------------------------------------------------------------------

def test_dict_and_text_cases_run_alike():
    d = ball_case(t_stop=0.3)
    text = (
        'version = 1\ntitle = "ball"\n[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n'
        '[physics]\ngravity = [0.0, 0.0, -9.81]\n'
        '[[phases]]\nname = "ball"\ndiameter = 0.2\ndensity = 2600.0\n'
        '[contact]\nmodel = "lsd"\n[contact.particle]\nkn = 5.0e4\n[contact.wall]\nkn = 5.0e4\nen = 0.9\n'
        '[time]\nt_stop = 0.3\ndt = 1.0e-4\nintegrator = "velocity_verlet"\n'
        '[output]\ninterval = 0.01\nsnapshots = false\n'
        '[[particles.list]]\nphase = "ball"\nposition = [0.5, 0.5, 0.5]\n'
    )
    a = grainflow.Simulation.from_dict(d)
    b = grainflow.Simulation.from_case_text(text)
    a.run()
    b.run()
    np.testing.assert_array_equal(bits(a.particles.position), bits(b.particles.position))
    assert a.particles.position[0, 2] < 0.2  # it reached the floor


def test_toml_overrides_are_validated_as_the_file(settling_bed):
    full = grainflow.Simulation.from_case(settling_bed)
    short = grainflow.Simulation.from_case(settling_bed, overrides={"time.t_stop": 0.05})
    # The same time step, a tenth of the run (t_stop 0.5 s in the file).
    assert short.dt == full.dt
    assert short.total_steps == pytest.approx(full.total_steps / 10, abs=1)
    with pytest.raises(grainflow.CaseError) as err:
        grainflow.Simulation.from_case(settling_bed, overrides={"contact.particle.en": 1.5})
    assert "en" in str(err.value) and "1.5" in str(err.value)


def test_an_mfix_deck_runs_with_overrides():
    deck = DECKS / "dem01" / "mfix.dat"
    with pytest.warns(UserWarning, match="ignored"):
        sim = grainflow.Simulation.from_case(deck, overrides={"TSTOP": 0.1})
    assert sim.t_stop == pytest.approx(0.1)
    # MFIX's rule: dt = TCOLL/50, and ceil(TSTOP/dt) steps in single precision.
    assert sim.total_steps == math.ceil(np.float32(0.1) / np.float32(sim.dt))
    sim.run()
    # Free fall from 0.5 m, 0.1 s, Euler at dt = 1 ms (MFIX DEM01): above the floor yet.
    y = sim.particles.position[0, 1]
    assert 0.4 < y < 0.5


def test_a_bad_deck_override_is_a_case_error():
    deck = DECKS / "dem01" / "mfix.dat"
    with pytest.raises(grainflow.CaseError, match="TSTOP"):
        grainflow.Simulation.from_case(deck, overrides={"TSTOP": "soon"})


# --- files --------------------------------------------------------------------------------

def test_a_restart_goes_on_with_the_same_bits(settling_bed, tmp_path):
    over = {"time.t_stop": 0.02}
    whole = grainflow.Simulation.from_case(settling_bed, overrides=over)
    whole.step(600)
    half = grainflow.Simulation.from_case(settling_bed, overrides=over)
    half.step(300)
    half.checkpoint(tmp_path / "c.gfc")
    # The checkpoint names the case it was written for: the shortened one is another case.
    with pytest.raises(grainflow.EngineError):
        grainflow.Simulation.restart(tmp_path / "c.gfc", settling_bed)
    again = grainflow.Simulation.restart(tmp_path / "c.gfc", settling_bed, accept_changed_case=True)
    assert again.step_count == 300
    again.step(300)
    np.testing.assert_array_equal(bits(whole.particles.position), bits(again.particles.position))
    np.testing.assert_array_equal(bits(whole.particles.omega), bits(again.particles.omega))


def test_read_timeseries_refuses_a_ragged_file(tmp_path):
    f = tmp_path / "t.csv"
    f.write_text("step,time\n0,0\n1\n")
    with pytest.raises(grainflow.EngineError, match="row 3"):
        grainflow.read_timeseries(f)


def vtk_arrays(path):
    """The point count and the named data arrays of a .vtp file written in binary (base64, each
    array after its UInt64 byte count), decoded."""
    import base64
    import xml.etree.ElementTree as ET

    root = ET.parse(path).getroot()
    assert root.get("header_type") == "UInt64" and root.get("byte_order") == "LittleEndian"
    piece = root.find("PolyData/Piece")
    kinds = {"Float64": np.float64, "Int64": np.int64, "Int32": np.int32}
    arrays = {}
    for a in piece.iter("DataArray"):
        raw = base64.b64decode(a.text.strip())
        size = int(np.frombuffer(raw[:8], dtype="<u8")[0])
        values = np.frombuffer(raw[8 : 8 + size], dtype=kinds[a.get("type")])
        k = int(a.get("NumberOfComponents", "1"))
        arrays[a.get("Name") or "Points"] = values.reshape(-1, k) if k > 1 else values
    return int(piece.get("NumberOfPoints")), arrays


def test_write_vtk_holds_the_particles_in_id_order(settling_bed, tmp_path):
    sim = grainflow.Simulation.from_case(settling_bed, overrides={"time.t_stop": 0.02})
    sim.run()
    sim.write_vtk(tmp_path / "p.vtp", contacts=tmp_path / "c.vtp")
    n, a = vtk_arrays(tmp_path / "p.vtp")
    order = np.argsort(sim.particles.ids)
    assert n == 486
    np.testing.assert_array_equal(a["id"], np.sort(sim.particles.ids))
    np.testing.assert_array_equal(bits(a["radius"]), bits(np.asarray(sim.particles.radius)[order]))
    np.testing.assert_array_equal(bits(a["velocity"]), bits(np.asarray(sim.particles.velocity)[order]))
    # Each contact is counted at both its particles (once for a wall).
    c = sim.contacts()
    assert int(np.sum(a["contacts"])) == len(c["id"]) + int(np.sum(c["other_id"] >= 0))
    m, _ = vtk_arrays(tmp_path / "c.vtp")
    assert m == 2 * len(c["id"])

"""Tests of the Python module (python/mjtether_python.cc), run by CTest (tests/python.cmake).

Environment: PYTHONPATH with the built module, MJTETHER_CLI (the command-line tool),
MJTETHER_REFERENCE_RUN (tests/python/reference_run.cc), MJTETHER_MODELS_DIR.
"""
import csv
import os
import subprocess
import threading

import numpy as np
import pytest

import mjtether

MODELS = os.environ.get("MJTETHER_MODELS_DIR", mjtether.models_dir)
CLI = os.environ.get("MJTETHER_CLI", "mjtether")
REFERENCE = os.environ.get("MJTETHER_REFERENCE_RUN")
ROV = os.path.join(MODELS, "bluerov2_heavy.xml")  # thrust schedule and a moving boat
HOSTILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "hostile")

# Two straight tethers between world sites, no gravity, dry: each carries the uniform tension
# EA (span / length - 1): "hot" 1.9e4 * (10 / 9.5 - 1) = 1000 N, "mid" 500 N (the same scene
# as tests/render_test.cc). A fixed camera 15 m in front looks along +y.
TWO_TETHERS = """
<mujoco>
  <option gravity="0 0 0"/>
  <custom>
    <text name="tether:hot" data="ends=h0,h1 length=9.5 segments=10 diameter=0.02
          mass_per_length=0.3 EA=1.9e4"/>
    <text name="tether:mid" data="ends=m0,m1 length=9.5 segments=10 diameter=0.02
          mass_per_length=0.3 EA=0.95e4"/>
  </custom>
  <worldbody>
    <site name="h0" pos="0 0 1"/>  <site name="h1" pos="10 0 1"/>
    <site name="m0" pos="0 0 -1"/> <site name="m1" pos="10 0 -1"/>
    <camera name="side" pos="5 -15 0" xyaxes="1 0 0 0 0 1"/>
  </worldbody>
</mujoco>"""

# A 20 m line of 40 segments between two world sites, explicit with one substep per 2 ms step:
# beyond its stability limit, it diverges within 0.2 s (tests/robust_test.cc).
UNSTABLE = """<mujoco><option timestep="0.002"/><custom>
  <text name="tether:line" data="ends=a,b length=20 diameter=0.02 mass_per_length=0.5
        damping=10 EA=1e6 segments=40 integrator=explicit substeps=1"/></custom>
  <worldbody><site name="a" pos="0 0 0"/><site name="b" pos="15 0 0"/></worldbody>
</mujoco>"""


def state(sim):
    """time, qpos, qvel and every tether's nodes, as Python floats."""
    values = [sim.time] + list(sim.qpos) + list(sim.qvel)
    for name in sim.tethers:
        values += list(sim.tether(name).nodes.ravel())
    return [float(v) for v in values]


# --- Agreement with C++ and with the command-line tool ---------------------------------------


@pytest.mark.skipif(REFERENCE is None, reason="MJTETHER_REFERENCE_RUN not set")
def test_python_run_is_bit_identical_to_the_cpp_run():
    # Same library, same call sequence: every double must be equal, bit for bit (no tolerance:
    # the bindings add no arithmetic of their own).
    chunks, steps = 10, 50  # 1 s of the BlueROV2 scene, its boat moving and thrusters running
    out = subprocess.run([REFERENCE, ROV, str(chunks), str(steps)], check=True,
                         capture_output=True, text=True).stdout.split()
    expected = [float.fromhex(v) for v in out]
    sim = mjtether.Simulation(ROV)
    for _ in range(chunks):
        sim.step(steps)
    got = state(sim)
    assert len(got) == len(expected)
    mismatches = [i for i, (a, b) in enumerate(zip(got, expected)) if a.hex() != b.hex()]
    assert mismatches == []


def test_step_matches_the_cli_log(tmp_path):
    # `mjtether run --log` samples every 0.1 s after the schedules and mj_forward, as
    # Simulation.step does at its end: the log, printed with 9 significant digits, must be
    # reproduced digit for digit.
    log = tmp_path / "run.csv"
    subprocess.run([CLI, "run", ROV, "--duration", "1", "--every", "0.1", "--log", str(log)],
                   check=True, capture_output=True)
    with open(log) as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], rows[1:]
    sim = mjtether.Simulation(ROV)
    per_sample = round(0.1 / sim.timestep)
    assert len(rows) == 11
    for i, row in enumerate(rows):
        if i > 0:
            sim.step(per_sample)
        ours = [sim.time]
        for column in header[1:]:
            name, key = column.rsplit(".", 1)
            if key in "xyz":
                ours.append(sim.body(name).pos["xyz".index(key)])
            else:
                t = sim.tether(name)
                T = t.tensions
                ours.append({"tension_A": t.reactions["tension_a"],
                             "tension_B": t.reactions["tension_b"],
                             "tension_max": T.max(initial=0.0),
                             "slack_segments": int((T <= 0).sum())}[key])
        # The CLI observes each sample on a copy of mjData (issue 14: observing must not change
        # the run), while step() settles the simulation in place with mj_forward so that every
        # view is current. The in-place call perturbs the trajectory at round-off level (1e-10
        # relative after 1 s here); 1e-7 relative is far above that and far below any physical
        # difference (a wrong schedule or force changes these values in the second digit).
        assert format(ours[0], ".9g") == row[0], f"sample {i} time"
        assert ours[1:] == pytest.approx([float(v) for v in row[1:]], rel=1e-7, abs=1e-9), \
            f"sample {i} ({header})"


# --- State: copy, reset, threads -------------------------------------------------------------


def test_copy_continues_exactly_and_independently():
    # A copy carries the whole state, tethers included: rolled out for the same steps it must
    # end bit for bit where the original does; and writing to it leaves the original alone.
    sim = mjtether.Simulation(ROV)
    sim.step(100)
    twin = sim.copy()
    sim.step(150)
    twin.step(150)
    assert state(twin) == state(sim)
    before = sim.qpos.copy()
    twin.qpos[0] += 1.0
    np.testing.assert_array_equal(sim.qpos, before)


def test_reset_repeats_the_run():
    # reset() returns to the initial state, the tethers' included: the same steps repeat the
    # same trajectory exactly.
    sim = mjtether.Simulation(ROV)
    start = state(sim)
    sim.step(200)
    first = state(sim)
    sim.reset()
    assert state(sim) == start
    sim.step(200)
    assert state(sim) == first


def test_threads_step_in_parallel_with_sequential_results():
    # The GIL is released in step(): simulations in threads (two from one file, one a copy
    # sharing its model) must reach exactly the state of the same runs made one after another.
    def run(sim):
        sim.step(300)

    sequential = mjtether.Simulation(ROV)
    run(sequential)
    a = mjtether.Simulation(ROV)
    b = mjtether.Simulation(ROV)
    c = b.copy()
    threads = [threading.Thread(target=run, args=(s,)) for s in (a, b, c)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for s in (a, b, c):
        assert state(s) == state(sequential)


# --- Views ------------------------------------------------------------------------------------


def test_views_alias_mujoco_memory():
    sim = mjtether.Simulation(ROV)
    # Writable views: a write is seen by a later view of the same array.
    sim.ctrl[:] = 0.25
    assert np.all(sim.ctrl == 0.25)
    assert np.shares_memory(sim.qpos, sim.qpos)
    # The ROV is the root body of the first free joint (qpos[0:3] is its position): raising
    # qpos[2] by 0.5 m raises its body frame by 0.5 m after forward (exact up to one rounding).
    rov = sim.body("rov")
    z0 = float(rov.pos[2])
    sim.qpos[2] += 0.5
    sim.forward()
    assert rov.pos[2] == pytest.approx(z0 + 0.5, abs=1e-12)
    # The tether's nodes and the body pose are results: read-only.
    nodes = sim.tether("umbilical").nodes
    with pytest.raises(ValueError):
        nodes[0, 0] = 1.0
    with pytest.raises(ValueError):
        rov.pos[0] = 1.0
    # The boat is a mocap body: its mocap position is writable, other bodies have none.
    assert sim.body("boat").mocap_pos is not None and rov.mocap_pos is None


def test_time_is_readable_and_writable():
    sim = mjtether.Simulation(ROV)
    sim.step(10)
    assert sim.time == pytest.approx(10 * sim.timestep, rel=1e-12)  # 10 additions of h
    sim.time = 3.0
    assert sim.time == 3.0


def test_tether_of_two_straight_lines_matches_the_closed_form():
    sim = mjtether.Simulation.from_xml(TWO_TETHERS, "two.xml")
    assert sim.tethers == ["hot", "mid"]
    for name, T_expected, z in (("hot", 1000.0, 1.0), ("mid", 500.0, -1.0)):
        t = sim.tether(name)
        assert t.nodes.shape == (11, 3) and t.velocities.shape == (11, 3)
        assert t.tensions.shape == (10,)
        # Straight, evenly spaced nodes from site to site: tension EA (l / l0 - 1) in every
        # segment; 1e-9 relative covers the rounding of 10 segment lengths.
        np.testing.assert_allclose(t.tensions, T_expected, rtol=1e-9)
        np.testing.assert_allclose(t.nodes[0], [0, 0, z], atol=1e-12)
        np.testing.assert_allclose(t.nodes[-1], [10, 0, z], atol=1e-12)
        assert t.length == pytest.approx(10.0, rel=1e-12)
        assert t.rest_length == 9.5
        r = t.reactions
        # Each end is pulled towards the other by the tension.
        np.testing.assert_allclose(r["force_a"], [T_expected, 0, 0], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(r["force_b"], [-T_expected, 0, 0], rtol=1e-9, atol=1e-9)
        assert r["tension_a"] == pytest.approx(T_expected, rel=1e-9)
        # Fixed sites, no consistent coupling: no slow-mode correction in force_b.
        np.testing.assert_array_equal(r["correction_b"], [0, 0, 0])


def test_render_is_top_down_with_the_tension_colours():
    # The 1000 N tether (red on a 0-1000 N scale) is 2 m above the 500 N one (green): in a
    # top-down H x W x 3 image its pixels lie in rows above the green ones.
    sim = mjtether.Simulation.from_xml(TWO_TETHERS, "two.xml")
    img = sim.render(160, 120, camera="side", tension_max=1000, hud=False)
    assert img.shape == (120, 160, 3) and img.dtype == np.uint8
    r, g, b = (img[..., i].astype(int) for i in range(3))
    red = np.argwhere((r > 150) & (g < 90) & (b < 90))
    green = np.argwhere((g > 150) & (r < 120) & (b < 120))
    assert len(red) > 20 and len(green) > 20
    assert red[:, 0].mean() < green[:, 0].mean() - 10


# --- Errors -----------------------------------------------------------------------------------


def cli_error(*args):
    """The CLI's exit status and its message without the 'mjtether: ' prefix."""
    p = subprocess.run([CLI, *args], capture_output=True, text=True)
    lines = [l for l in p.stderr.splitlines() if l.startswith("mjtether: ")]
    return p.returncode, lines[-1][len("mjtether: "):] if lines else p.stderr


def test_load_errors_carry_the_cli_message(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text(TWO_TETHERS.replace("EA=1.9e4", "EA=-5"))
    status, message = cli_error("info", str(bad))
    assert status == 2 and "EA" in message
    with pytest.raises(mjtether.Error) as e:
        mjtether.Simulation(str(bad))
    assert str(e.value) == message
    with pytest.raises(mjtether.Error):
        mjtether.Simulation(str(tmp_path / "missing.xml"))
    with pytest.raises(KeyError):
        mjtether.Simulation(ROV).tether("no_such_tether")


def test_set_overrides_are_the_file_edited_by_hand(tmp_path):
    # Simulation(path, set=[...]) takes `mjtether run --set`'s overrides: the scene with EA
    # overridden runs bit for bit as the file edited by hand (loaded from its text under the
    # same path), and differs from the file as it is (the override is not ignored).
    with open(ROV) as f:
        text = f.read()
    assert text.count("EA=6e4 ") == 1
    edited = mjtether.Simulation.from_xml(text.replace("EA=6e4 ", "EA=2e4 "), ROV)
    overridden = mjtether.Simulation(ROV, set=["tether:umbilical.EA=2e4"])
    plain = mjtether.Simulation(ROV)
    for sim in (edited, overridden, plain):
        sim.step(250)
    assert state(overridden) == state(edited)
    assert state(overridden) != state(plain)
    # A refused override carries the CLI's message for the same --set.
    status, message = cli_error("info", ROV, "--set", "tether:umbilical.EA=-5")
    assert status == 2
    with pytest.raises(mjtether.Error) as e:
        mjtether.Simulation(ROV, set=["tether:umbilical.EA=-5"])
    assert str(e.value) == message
    with pytest.raises(mjtether.Error, match="TEXT.KEY=VALUE|KEY=VALUE|="):
        mjtether.Simulation(ROV, set=["no_equals_sign"])


def test_set_timestep_runs_the_same_scene_at_a_smaller_step():
    # The comparison `mjtether run --check-step 10` makes, from Python: the same scene at h/10,
    # stepped ten times as often, ends where the run at h ends, within the step check's
    # tolerance for a body (max(5 cm, 2% of the span); docs/step_check.md).
    coarse = mjtether.Simulation(ROV)
    fine = mjtether.Simulation(ROV, set=["option.timestep=%r" % (coarse.timestep / 10)])
    assert fine.timestep == pytest.approx(coarse.timestep / 10, rel=1e-15)
    start = coarse.body("rov").pos.copy()
    coarse.step(1500)  # 3 s: the thrust schedule moves the vehicle 0.23 m
    fine.step(15000)
    assert fine.time == pytest.approx(coarse.time, rel=1e-9)
    assert np.linalg.norm(coarse.body("rov").pos - start) > 0.1  # not two resting bodies
    assert np.linalg.norm(coarse.body("rov").pos - fine.body("rov").pos) < 0.05


def test_divergence_raises_the_cli_message(tmp_path):
    path = tmp_path / "unstable.xml"
    path.write_text(UNSTABLE)
    status, message = cli_error("run", str(path), "--duration", "1")
    assert status == 1 and "diverged" in message
    sim = mjtether.Simulation(str(path))
    with pytest.raises(mjtether.DivergenceError) as e:
        sim.step(500)
    assert str(e.value) == message


def test_run_warnings_are_what_the_cli_prints_at_the_end_of_a_run():
    # tests/hostile/ringing.xml: an undamped bdf2 line whose slack segments snap taut within 1 s
    # at omega_n h 7.5 (docs/reference.md, "Internal damping"). `mjtether run` warns at its end;
    # a Python user reading only the result was told nothing before run_warnings.
    path = os.path.join(HOSTILE, "ringing.xml")
    out = subprocess.run([CLI, "run", path, "--duration", "1"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    prefix = "mjtether: warning: "
    cli = [line[len(prefix):] for line in out.stderr.splitlines() if line.startswith(prefix)]
    assert len(cli) == 1 and "damping_ratio=1" in cli[0]
    sim = mjtether.Simulation(path)
    assert sim.run_warnings == []  # nothing has snapped at t = 0
    twin = sim.copy()
    sim.step(round(1 / sim.timestep))
    assert sim.run_warnings == cli
    twin.step(round(0.5 / twin.timestep))  # the copy carries its own record
    assert len(twin.run_warnings) == 1
    sim.reset()
    assert sim.run_warnings == []
    damped = mjtether.Simulation(path, set=["tether:t.damping_ratio=1"])
    damped.step(round(1 / damped.timestep))
    assert damped.run_warnings == []  # the cure the warning names silences it


def test_bad_step_count_is_refused():
    with pytest.raises(ValueError):
        mjtether.Simulation(ROV).step(-1)


# Hostile calls found by hand in session 21 (docs/python.md): each was silent before.
def test_a_state_that_is_not_finite_stops_the_step_instead_of_a_silent_reset():
    # MuJoCo resets the data on a NaN (or |x| > 1e10) qpos or qvel and steps on from t = 0: step
    # returned as if the run had gone on (time 0.01 s after 5 steps from 0.02 s).
    for field, index in (("qpos", 0), ("qvel", 2)):
        sim = mjtether.Simulation(ROV)
        sim.step(10)
        getattr(sim, field)[index] = np.nan if field == "qpos" else 1e30
        with pytest.raises(mjtether.DivergenceError) as e:
            sim.step(5)
        assert "MuJoCo reset the simulation" in str(e.value)
        assert ("index %d of %s" % (index, field)) in str(e.value)


def test_time_and_render_scale_must_be_finite():
    sim = mjtether.Simulation(ROV)
    with pytest.raises(ValueError, match="time must be a finite number"):
        sim.time = float("nan")  # the tethers, which advance with the time, stood still
    assert sim.time == 0.0
    with pytest.raises(mjtether.Error, match="tension_max = nan"):
        sim.render(64, 48, tension_max=float("nan"))  # rendered with an undefined scale
    with pytest.raises(mjtether.Error, match="the XML text is empty"):
        mjtether.Simulation.from_xml("")  # was MuJoCo's "mj_makeEmptyFileVFS expects ..."

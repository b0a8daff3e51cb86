"""The Python module teleop (client/python, docs/python.md), run by ctest as python.teleop:
sessions against the C++ campaign runner, traces, the world step, recordings (one made here, one
of a live session recorded by teleop_record) and bad input.

The live session runs on the loopback profile in domain 180 (kPythonRecording of
tests/support/domains.hpp)."""

import csv
import os
import signal
import subprocess
import time

import numpy as np
import pytest

import teleop

# A small tool scene: the free tool over a level-2 mass-spring ball on the floor (cheap to load
# and step).
SCENE = """\
name: python-test
kind: tool
physics: {rate_hz: 1000, visual_rate_hz: 60, gravity_mps2: [0, 0, -9.81]}
tool: {radius_m: 0.05, start_position_m: [0.0, 0.0, 0.7]}
planes:
  - {name: floor, normal: [0, 0, 1], offset_m: 0.0, stiffness_n_per_m: 20000, damping_ns_per_m: 50}
deformables:
  - id: 10
    body: {model: mass_spring, level: 2, radius_m: 0.25, centre_m: [0, 0, 0.25]}
"""

# Point-model campaign: two schemes x two delays, 1.5 s sessions, lossy jittery channels.
CAMPAIGN = """\
name: python-check
model: point
duration_s: 1.5
sweeps:
  - name: grid
    scheme: [position-position, wave-variables]
    delay_ms: [0, 30]
    jitter_ms: 2
    loss: 0.02
    seed: 7
"""


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text(SCENE)
    return str(path)


@pytest.fixture
def campaign_file(tmp_path):
    path = tmp_path / "campaign.yaml"
    path.write_text(CAMPAIGN)
    return str(path)


def test_same_seed_gives_the_same_arrays_and_another_seed_others():
    kw = dict(scheme="tdpa", delay_ms=20, jitter_ms=3, loss=0.05)
    a = teleop.run_session(seed=11, **kw)
    b = teleop.run_session(seed=11, **kw)
    c = teleop.run_session(seed=12, **kw)
    assert a.row == b.row
    for name, values in a.traces.items():
        np.testing.assert_array_equal(values, b.traces[name], err_msg=name)
    assert a.summary["seed"] == 11 and c.summary["seed"] == 12
    assert not np.array_equal(a.traces["contact_force_at_master_n"],
                              c.traces["contact_force_at_master_n"])


def test_traces_are_finite_and_consistent():
    r = teleop.run_session(scheme="position-position", delay_ms=10, duration_s=6.0)
    t = r.traces["time_s"]
    n = len(t)
    assert r.dropped == 0
    assert 5900 <= n <= 6100  # 6 s at 1 kHz
    assert np.all(np.diff(t) > 0)
    np.testing.assert_allclose(np.diff(t), 1e-3, rtol=1e-6)
    for name, values in r.traces.items():
        assert values.shape[0] == n, name
        assert values.shape[1:] in ((), (3,)), name
        assert np.all(np.isfinite(values)), name
    # the press task touches the sphere: contact force only while in contact, pushing up
    f = r.traces["contact_force_n"]
    touching = r.traces["in_contact"] > 0
    assert touching.sum() > 100
    assert np.all(np.linalg.norm(f[~touching], axis=1) < 1e-9)
    assert f[touching, 2].mean() > 0.5
    # the summary's contact figures are the traces' over the contact cycles
    mean_norm = np.linalg.norm(f[touching], axis=1).mean()
    assert r.summary["mean_contact_force_n"] == pytest.approx(mean_norm, rel=1e-6)
    assert r.summary["contact_time_s"] == pytest.approx(touching.sum() * 1e-3, abs=2e-3)


def test_campaign_runs_equal_teleop_campaign_rows(campaign_file, tmp_path):
    exe = os.environ["TELEOP_CAMPAIGN_EXE"]
    out = tmp_path / "out"
    subprocess.run([exe, "run", campaign_file, "--out", str(out), "--jobs", "1", "--no-chart"],
                   check=True, stdout=subprocess.DEVNULL)
    with open(out / "results.csv") as f:
        lines = f.read().splitlines()
    runs = teleop.campaign_runs(campaign_file)
    assert len(lines) == 1 + len(runs) == 5
    for i in range(len(runs)):
        r = teleop.run_campaign_point(campaign_file, i)
        assert r.header == lines[0]
        assert r.row == lines[1 + i]
        assert r.summary["delay_ms"] == runs[i]["delay_ms"]
    # run_session with a run's parameters gives that run's figures (names as the table's)
    rows = list(csv.DictReader(lines))
    wave30 = next(i for i, p in enumerate(runs)
                  if p["scheme"] == "wave-variables" and p["delay_ms"] == 30)
    s = teleop.run_session(scheme="wave-variables", delay_ms=30, jitter_ms=2, loss=0.02, seed=7,
                           duration_s=1.5).summary
    assert list(s) == list(rows[wave30])
    figures = list(s)[list(s).index("verdict"):]
    assert len(figures) > 30
    for name in figures:
        want = rows[wave30][name]
        if isinstance(s[name], str):
            assert s[name] == want, name
        else:
            assert float(want) == s[name] or (want == "nan" and np.isnan(s[name])), name


def test_a_sweep_on_threads_is_the_sessions_one_by_one():
    grid = dict(scheme=["position-position", "tdpa"], delay_ms=[0, 40, 80], loss=0.02, seed=5)
    parallel = teleop.sweep(jobs=2, **grid)
    assert [(r.summary["scheme"], r.summary["delay_ms"]) for r in parallel] == [
        (s, d) for s in grid["scheme"] for d in grid["delay_ms"]]
    for r in parallel:
        one = teleop.run_session(scheme=r.summary["scheme"], delay_ms=r.summary["delay_ms"],
                                 loss=0.02, seed=5)
        assert r.row == one.row
        np.testing.assert_array_equal(r.traces["device_force_n"], one.traces["device_force_n"])
    t = teleop.table(parallel)
    assert t["delay_ms"].tolist() == [0, 40, 80, 0, 40, 80]
    assert t["seed"].dtype == np.int64 and t["verdict"].dtype.kind == "U"
    # the grid holds both verdicts: position-position loses stability with delay, tdpa does not
    assert "stable" in t["verdict"] and "unstable" in t["verdict"][:3]
    with pytest.raises(ValueError, match="jobs = 0"):
        teleop.sweep(jobs=0, delay_ms=[0])


def test_a_scene_session_and_the_world_step(scene_file):
    scene = teleop.load_scene(scene_file)
    assert scene.description["name"] == "python-test"
    kinds = [o["kind"] for o in scene.description["objects"]]
    assert 3 in kinds  # the deformable body
    r = teleop.run_session(scene=scene, scheme="position-position", duration_s=2.0)
    assert r.summary["model"] == "world"
    assert r.traces["homing"][0] == 1 and r.traces["homing"][-1] == 0
    assert np.all(np.isfinite(r.traces["slave_position_m"]))

    w = teleop.World(scene)
    rest = w.nodes()
    assert rest.shape == (162, 3) and w.triangles().shape == (320, 3)
    top = rest[:, 2].max()
    w.set_tip([0.0, 0.0, top + 0.05 - 0.02])  # 2 cm into the ball
    w.step(1000)
    assert w.time_s == pytest.approx(1.0)
    assert w.in_contact and w.faults == 0
    assert w.contact_force_n[2] > 0.1  # the ball pushes the tip up
    assert np.abs(w.nodes() - rest).max() > 1e-3  # and is dented
    again = teleop.World(scene)
    again.set_tip([0.0, 0.0, top + 0.05 - 0.02])
    again.step(1000)
    np.testing.assert_array_equal(again.nodes(), w.nodes())


@pytest.mark.parametrize("name", ["session.mcap", "session.db"])
def test_read_recording_decodes_a_recording_made_here(tmp_path, name):
    r = teleop.run_session(scheme="force-position", delay_ms=5, duration_s=1.0)
    path = str(tmp_path / name)
    n = len(r.traces["time_s"])
    assert teleop.write_recording(path, r) == 2 * n
    d = teleop.read_recording(path)
    assert set(d) == {"teleop/slave_state", "teleop/master_state"}
    s, m = d["teleop/slave_state"], d["teleop/master_state"]
    assert s["type"] == "teleop::SlaveState" and s["malformed"] == 0
    np.testing.assert_array_equal(s["tip_position_m"], r.traces["slave_position_m"])
    np.testing.assert_array_equal(s["contact_force_n"], r.traces["contact_force_n"])
    np.testing.assert_array_equal(s["in_contact"], r.traces["in_contact"])
    np.testing.assert_array_equal(m["rendered_force_n"], r.traces["device_force_n"])
    np.testing.assert_array_equal(s["receive_ns"], np.round(r.traces["time_s"] * 1e9))
    assert s["joint_position_rad"].shape == (n, 16)


LIVE_DOMAIN = "180"


def test_read_recording_decodes_a_live_session_of_teleop_record(tmp_path):
    build = os.environ["TELEOP_BUILD_DIR"]
    env = dict(os.environ, TELEOP_PROFILE="loopback")
    env.pop("TELEOP_DOMAIN", None)
    mcap, db = str(tmp_path / "live.mcap"), str(tmp_path / "live.db")
    log = open(tmp_path / "record.log", "w+")
    procs = []
    try:
        rec = subprocess.Popen([build + "/client/teleop_record", "--domain", LIVE_DOMAIN,
                                "--out", mcap], stdout=log, stderr=subprocess.STDOUT, env=env)
        procs.append(rec)
        for _ in range(100):  # until it listens
            if "recording" in open(tmp_path / "record.log").read():
                break
            time.sleep(0.1)
        server = subprocess.Popen([build + "/server/teleop_server", "--domain", LIVE_DOMAIN,
                                   "--duration", "60", "--quiet"], stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL, env=env)
        procs.append(server)
        subprocess.run([build + "/client/teleop_master", "--domain", LIVE_DOMAIN, "--duration",
                        "2", "--homing", "0.5", "--quiet"], check=True, timeout=60, env=env,
                       stdout=subprocess.DEVNULL)
        server.send_signal(signal.SIGTERM)
        assert server.wait(timeout=30) == 0
        time.sleep(0.2)
        rec.send_signal(signal.SIGINT)
        assert rec.wait(timeout=30) == 0
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.wait()
    subprocess.run([build + "/client/teleop_play", mcap, "--convert", db], check=True,
                   stdout=subprocess.DEVNULL)
    d = teleop.read_recording(mcap)
    assert all(v["malformed"] == 0 for v in d.values())
    cmd, state = d["teleop/master_command"], d["teleop/slave_state"]
    assert len(cmd["seq"]) > 1000 and len(state["seq"]) > 1000  # 2.5 s at 1 kHz, most of it
    assert np.all(np.diff(state["seq"]) > 0) and np.all(np.diff(cmd["seq"]) > 0)
    assert cmd["position_m"].shape == (len(cmd["seq"]), 3)
    assert np.all(np.isfinite(state["tip_position_m"]))
    assert np.all(np.linalg.norm(state["contact_force_n"], axis=1) < 100)
    assert any("server started" in m for m in d["teleop/events"]["message"])
    scene = d["teleop/scene"]["description"][0]
    assert scene["name"] == "default" and scene["physics_rate_hz"] == 1000
    # the surface of the default scene's FEM ball
    assert d["teleop/mesh_topology"]["triangles"][0].shape == (950, 3)
    assert d["teleop/mesh_frame"]["positions_m"][0].shape == (477, 3)
    # the same samples, decoded the same, from the SQLite copy
    s = teleop.read_recording(db)
    assert set(s) == set(d)
    for topic in ("teleop/master_command", "teleop/slave_state", "teleop/master_state"):
        for name, values in d[topic].items():
            if isinstance(values, np.ndarray):
                np.testing.assert_array_equal(s[topic][name], values, err_msg=topic + name)


def test_bad_input_raises_value_error_naming_it(tmp_path, campaign_file, scene_file):
    cases = [
        (dict(scheme="telepathy"), "scheme = 'telepathy' is not one of position-position"),
        (dict(delay_ms=-5), "delay_ms = -5 is outside the allowed range (0 to 10000)"),
        (dict(loss=1.5), "loss = 1.5 is outside the allowed range (0 to 1)"),
        (dict(seed=-1), "seed = -1 is outside"),
        (dict(script="dance"), "script = 'dance' is not one of"),
        (dict(params={"delay": 3}), "params: unknown key(s) delay"),
        (dict(scene=str(tmp_path / "missing.yaml")), "missing.yaml"),
    ]
    for kw, message in cases:
        with pytest.raises(ValueError) as e:
            teleop.run_session(**kw)
        assert message in str(e.value), (kw, str(e.value))
    with pytest.raises(ValueError, match="index = 4 is outside"):
        teleop.run_campaign_point(campaign_file, 4)
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not a recording at all")
    with pytest.raises(ValueError):
        teleop.read_recording(str(junk))
    world = teleop.World(teleop.load_scene(scene_file))
    with pytest.raises(ValueError, match="n = -1 is negative"):
        world.step(-1)
    with pytest.raises(ValueError, match="body = 1 is outside"):
        world.nodes(1)

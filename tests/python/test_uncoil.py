"""The Python package as a user meets it: installed from a wheel into a fresh virtual
environment (`.ci/run`), run from another folder.

    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install '.[test]'
    /tmp/venv/bin/python -m pytest tests/python
"""

import csv
import json
import math
import os
import pathlib
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import uncoil

ROOT = pathlib.Path(__file__).resolve().parents[2]
YOGA = ROOT / "scenes" / "yoga-mat.toml"
THIN = ROOT / "scenes" / "thin-tape.toml"


@pytest.fixture(scope="module")
def yoga(tmp_path_factory):
    """The yoga mat, run once with its files written."""
    out = tmp_path_factory.mktemp("yoga")
    return uncoil.run(YOGA, out=out), out


def test_samples_are_the_csv_columns_as_float_arrays(yoga):
    result, out = yoga
    with open(out / "samples.csv", newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    assert list(result.samples) == header
    for k, name in enumerate(header):
        column = result.samples[name]
        assert column.dtype == np.float64 and column.shape == (len(body),), name
        # The CSV keeps 10 significant digits; an empty cell is a NaN.
        cells = np.array([float(r[k]) if r[k] else math.nan for r in body])
        assert np.allclose(column, cells, rtol=1e-9, atol=0, equal_nan=True), name


def test_report_ledger_milestones_and_stop_reason(yoga):
    result, out = yoga
    on_disk = json.loads((out / "report.json").read_text())
    assert result.report["links"] == on_disk["links"] > 0
    assert result.report["sim_time_s"] == on_disk["sim_time_s"]
    assert result.stop_reason == "at-rest"
    assert result.ledger["mgr_j"] > 0
    labels = [m["label"] for m in result.milestones]
    assert "0.75R" in labels
    # r(t) falls from R to the bang radius.
    r = result.samples["r_m"]
    assert r[0] == pytest.approx(0.06, rel=1e-3) and r[-1] < 0.006


def test_to_pandas_without_pandas_says_what_to_install(yoga, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # `import pandas` then fails
    with pytest.raises(ModuleNotFoundError, match=r"needs pandas.*pip install pandas.*\[pandas\]"):
        yoga[0].to_pandas()


def test_to_pandas_is_the_samples_frame(yoga):
    # The README's install line, `pip install ".[pandas]"`, brings pandas; so does `.[test]`.
    import pandas as pd
    frame = yoga[0].to_pandas()
    assert isinstance(frame, pd.DataFrame)
    assert list(frame.columns) == list(yoga[0].samples)
    assert frame["t_s"].iloc[-1] == yoga[0].samples["t_s"][-1]


def test_a_run_without_out_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = uncoil.run(YOGA, overrides={"push.contact_speed_m_s": 0.4})
    assert result.report["scene"]["push"]["contact_speed_m_s"] == 0.4
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ValueError, match="out="):
        uncoil.run(YOGA, mcap=True)


def test_mcap_is_written_only_when_asked(tmp_path):
    uncoil.run(YOGA, out=tmp_path / "plain")
    assert not (tmp_path / "plain" / "run.mcap").exists()
    uncoil.run(YOGA, out=tmp_path / "log", mcap=True)
    assert (tmp_path / "log" / "run.mcap").stat().st_size > 0


def test_a_bad_scene_raises_scene_error_with_the_command_lines_text(tmp_path):
    with pytest.raises(uncoil.SceneError) as caught:
        uncoil.load_scene(YOGA, {"tape.thickness_m": -1})
    message = str(caught.value)
    assert message.startswith("tape.thickness_m = -1: must be > 0")
    binary = next(
        (p for p in (ROOT / "target" / d / "uncoil" for d in ("release", "debug")) if p.exists()),
        None,
    )
    if binary is None:
        pytest.skip("no uncoil binary built to compare with")
    cli = subprocess.run(
        [str(binary), "run", str(YOGA), "--set", "tape.thickness_m=-1", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
    )
    assert cli.returncode == 2
    assert cli.stderr.strip() == f"error: {message}"


def test_a_shipped_scene_runs_by_name_from_any_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert "yoga-mat" in uncoil.scenes() and "thin-tape" in uncoil.scenes()
    scene = uncoil.load_scene("yoga-mat")
    assert scene.source_text == YOGA.read_text()
    result = uncoil.run("yoga-mat", overrides={"discretisation.links_per_turn": 12})
    assert result.stop_reason == "at-rest"
    assert list(tmp_path.iterdir()) == []


def test_a_folder_another_run_is_writing_is_refused(tmp_path):
    out = tmp_path / "run"
    first = threading.Thread(
        target=uncoil.run, args=(THIN,), kwargs={"overrides": {"stop.max_time_s": 5}, "out": out}
    )
    first.start()
    lock = out / ".uncoil.lock"
    deadline = time.monotonic() + 10
    while not (lock.exists() and lock.read_text()) and time.monotonic() < deadline:
        time.sleep(0.01)
    try:
        with pytest.raises(Exception, match="is being written by another run"):
            uncoil.run(YOGA, out=out)
    finally:
        first.join()
    assert json.loads((out / "report.json").read_text())["scene"]["name"] == "thin-tape"


def test_scene_error_is_raised_as_uncoil_scene_error():
    assert uncoil.SceneError.__module__ == "uncoil"
    with pytest.raises(uncoil.SceneError, match="a shipped scene can be named instead: yoga-mat"):
        uncoil.load_scene("no-such-scene")


def test_a_scene_object_runs_and_rejects_overrides():
    scene = uncoil.load_scene(YOGA, {"discretisation.links_per_turn": 16})
    assert scene.name == "yoga-mat"
    assert "# override: discretisation.links_per_turn = 16" in scene.source_text
    assert json.loads(scene.to_json())["discretisation"]["links_per_turn"] == 16
    with pytest.raises(ValueError):
        uncoil.run(scene, overrides={"push.contact_speed_m_s": 0.4})


def test_ctrl_c_stops_the_run_with_its_files_and_raises_keyboard_interrupt(tmp_path):
    # The thin tape runs for most of a minute; a SIGINT 0.5 s in must end it within seconds.
    # The timer's thread can only fire while the run has let go of the GIL.
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        uncoil.run(THIN, out=tmp_path)
    elapsed = time.monotonic() - start
    timer.join()
    assert elapsed < 10, f"stopped after {elapsed:.1f} s"
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["stop"]["reason"] == "interrupted"
    assert (tmp_path / "samples.csv").stat().st_size > 0


def test_theory_gives_the_references_the_run_compared_itself_with(yoga):
    result, _ = yoga
    scene = uncoil.load_scene(YOGA)
    milestones = result.milestones
    r = np.array([m["r_m"] for m in milestones])
    f = np.array([m["laid_fraction"] for m in milestones])
    for name, got in [
        ("t_eq7_s", uncoil.theory.eq7_time_at_radius(scene, r)),
        ("t_eq17_s", uncoil.theory.eq17_time_at_radius(scene, r)),
        ("t_geo_s", uncoil.theory.exact_time_at_fraction(scene, f)),
    ]:
        want = np.array([m[name] for m in milestones])
        assert np.allclose(got, want, rtol=1e-12, atol=0), name
    # The exact model's speed against the run's approach curve, [r, x'] at f = 1 - (r/R)^2.
    curve = np.array(result.report["approach"]["exact_curve"])
    big_r = result.report["scene"]["tape"]["outer_radius_m"]
    speed = uncoil.theory.exact_speed_at_fraction(scene, 1 - (curve[:, 0] / big_r) ** 2)
    assert np.allclose(speed, curve[:, 1], rtol=1e-12, atol=0)
    # A scalar gives a float; past the end, NaN.
    assert isinstance(uncoil.theory.eq7_time_at_radius(scene, 0.03), float)
    assert math.isnan(uncoil.theory.exact_time_at_fraction(scene, 2.0))


def test_eq7_from_rest_is_the_limit_of_a_gentle_push():
    # Pushed at 1 mm/s the coil is nearly at rest: eq. (7) from the push approaches the
    # closed form from rest, which drops terms of order b/r from the energy integral; they
    # make 0.11-0.17 % here.
    scene = uncoil.load_scene(YOGA, {"push.contact_speed_m_s": 0.001})
    r = np.array([0.05, 0.04, 0.03])
    numeric = uncoil.theory.eq7_time_at_radius(scene, r)
    closed = uncoil.theory.eq7_time_from_rest(scene, r)
    assert np.all(np.abs(numeric / closed - 1) < 0.005), numeric / closed


def test_sweep_gives_the_table_as_columns_and_writes_only_into_out(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    table = uncoil.sweep(
        YOGA, vary={"discretisation.links_per_turn": [8, 16], "stop.bang_cap_s": 0}, jobs=1
    )
    assert list(tmp_path.iterdir()) == []
    assert list(table["discretisation.links_per_turn"]) == [8.0, 16.0]
    assert table["status"] == ["ok", "ok"]
    assert table["links"].dtype == np.float64 and np.all(table["links"] > 0)
    # The same runs as uncoil.run's, row by row.
    for k, n in enumerate([8, 16]):
        one = uncoil.run(YOGA, {"discretisation.links_per_turn": n, "stop.bang_cap_s": 0})
        assert table["links"][k] == one.report["links"]
        assert table["sim_time_s"][k] == pytest.approx(one.report["sim_time_s"], rel=1e-6)
    written = uncoil.sweep(YOGA, vary={"discretisation.links_per_turn": [8]}, out=tmp_path / "s")
    assert (tmp_path / "s" / "sweep.csv").exists() and written["status"] == ["ok"]


def test_ctrl_c_stops_a_sweep(tmp_path):
    # Two thin-tape runs take minutes; a SIGINT 0.5 s in must end the sweep within seconds,
    # the running run's row saying so.
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        uncoil.sweep(THIN, vary={"push.contact_speed_m_s": [0.1, 0.11]}, jobs=1, out=tmp_path)
    elapsed = time.monotonic() - start
    timer.join()
    assert elapsed < 10, f"stopped after {elapsed:.1f} s"
    rows = list(csv.DictReader(open(tmp_path / "sweep.csv", newline="")))
    assert [r["status"] for r in rows] == ["interrupted"]


def test_every_shipped_scene_is_listed_with_its_kind():
    scenes = uncoil.scenes()
    assert list(scenes)[:2] == ["yoga-mat", "thin-tape"]
    assert scenes["folded-chain"] == "folded-chain"
    assert scenes["yoga-mat"] == "coil" and scenes["hard/thin-300"] == "coil"
    for name, kind in scenes.items():
        try:
            assert uncoil.load_scene(name).kind == kind, name
        except uncoil.SceneError:
            # The hard case made to be refused: one link per turn is longer than R.
            assert name == "hard/one-link-per-turn"


def test_the_folded_chain_runs_by_name_and_gives_what_its_files_hold(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    small = {"chain.links": 40}
    result = uncoil.run("folded-chain", overrides=small, out="chain")
    assert result.kind == "folded-chain"
    assert result.stop_reason == "tip-fraction"
    with open(tmp_path / "chain" / "samples.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert list(result.samples) == list(rows[0])
    for name, values in result.samples.items():
        written = np.array([float(r[name]) if r[name] else math.nan for r in rows])
        np.testing.assert_array_equal(values, written, err_msg=name)
    on_disk = json.loads((tmp_path / "chain" / "report.json").read_text())
    assert on_disk["report"] == result.report["report"]
    assert result.milestones == on_disk["report"]["crossings"] and result.milestones
    assert set(result.ledger) >= {"floor_normal_j", "joints_j"}
    # Without `out`, the same run and nothing written.
    again = uncoil.run(uncoil.load_scene("folded-chain", small))
    assert again.report["report"]["crossings"] == result.milestones
    assert sorted(p.name for p in tmp_path.iterdir()) == ["chain"]
    with pytest.raises(uncoil.SceneError, match="a folded chain's scene; sweep takes a coil's"):
        uncoil.sweep("folded-chain", {"chain.links": [20, 40]})


def test_an_ensemble_lands_from_its_pushes_and_pools_the_shares(tmp_path):
    e = uncoil.ensemble(
        "yoga-mat", n=3, overrides={"discretisation.links_per_turn": 8}, out=tmp_path
    )
    runs = e["runs"]
    assert list(runs["push.contact_speed_m_s"]) == [0.3, 0.301, 0.302]
    assert list(runs["discretisation.links_per_turn"]) == [8, 8, 8]
    assert e["n"] == 3 and (tmp_path / "sweep.csv").exists()
    x = np.asarray(runs["bang_floor_normal_of"])
    mean, se = e["pooled"]["bang_floor_normal_of"]
    assert mean == pytest.approx(x.mean()) and se == pytest.approx(x.std(ddof=1) / 3**0.5)
    t = np.asarray(runs["t_sim_0.5R"])
    assert e["milestones"]["0.5R"] == pytest.approx((t.mean(), t.std(ddof=1)))
    assert list(e["milestones"])[:2] == ["0.75R", "0.5R"]
    assert list(e["milestones"])[-2:] == ["release", "bang ends"]
    with pytest.raises(ValueError, match="from 2 to 1000"):
        uncoil.ensemble("yoga-mat", n=1)


def test_sweep_takes_a_range_and_keys_varied_together_as_the_command_line_does(tmp_path):
    t = uncoil.sweep(
        "yoga-mat",
        {
            "discretisation.links_per_turn:stop.bang_radius_m": [(8, 0.005), (8, 0.0075)],
            "push.contact_speed_m_s": "0.300..0.301/2",
        },
        jobs=1,
    )
    assert list(t["push.contact_speed_m_s"]) == [0.3, 0.301, 0.3, 0.301]
    assert list(t["stop.bang_radius_m"]) == [0.005, 0.005, 0.0075, 0.0075]
    assert list(t["discretisation.links_per_turn"]) == [8, 8, 8, 8]

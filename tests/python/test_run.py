"""dentsim.run: the report of `dentsim run` without the files.

The probe scene run by the command and by the module gives the same report: the same keys (plus
"timeseries"), every deterministic value exactly equal (the same library call on the same
inputs; `wall_s` and `timing_us` are wall-clock measurements and differ run to run), and the time
series equal to timeseries.csv to its 9 significant digits. A scene file runs like the built-in
scene it was written from; bad inputs raise with the command's message.
"""

import csv
import json

import numpy as np
import pytest

import dentsim
from conftest import PROBE_S

WALL_CLOCK_KEYS = {"wall_s", "setup_s", "timing_us"}


@pytest.fixture(scope="module")
def probe_run():
    return dentsim.run("probe", duration=PROBE_S)


def test_report_equals_the_commands_report_json(probe_run, probe_cli_run):
    expected = json.loads((probe_cli_run / "report.json").read_text())
    assert set(probe_run) == set(expected) | {"timeseries"}
    for key in set(expected) - WALL_CLOCK_KEYS:
        assert probe_run[key] == expected[key], key
    assert set(probe_run["timing_us"]) == set(expected["timing_us"])
    # The run touched the tooth, so the equality covers the contact numbers too.
    assert probe_run["contact_ticks"] > 100
    assert probe_run["max_contact_force_n"] > 0.1
    assert probe_run["ticks"] == round(PROBE_S * 1000) and probe_run["pipeline"] == "fast"


def test_time_series_equals_timeseries_csv(probe_run, probe_cli_run):
    with open(probe_cli_run / "timeseries.csv") as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], rows[1:]
    series = probe_run["timeseries"]
    assert list(series) == header  # the same columns in the same order
    assert series["phase"] == [r[header.index("phase")] for r in rows]
    for i, name in enumerate(header):
        if name == "phase":
            continue
        a = series[name]
        assert a.dtype == np.float64 and a.shape == (len(rows),), name
        # The file keeps 9 significant digits: relative rounding <= 5e-9.
        np.testing.assert_allclose(a, [float(r[i]) for r in rows], rtol=5e-9, atol=0, err_msg=name)
    assert series["contact_force_n"].max() == pytest.approx(probe_run["max_contact_force_n"])


def test_a_scene_file_runs_like_its_builtin_scene(tmp_path):
    doc = json.loads(dentsim.scene_text("probe"))
    doc["duration_s"] = 0.3
    path = tmp_path / "probe.json"
    path.write_text(json.dumps(doc))
    loaded = dentsim.load_scene(path)
    assert (loaded["name"], loaded["duration_s"], loaded["builtin"]) == ("probe", 0.3, False)
    assert loaded["document"] == doc
    a = dentsim.run(path)  # os.PathLike; the file's own duration
    b = dentsim.run("probe", duration=0.3)
    assert a["scene_origin"] != b["scene_origin"]
    for key in set(b) - WALL_CLOCK_KEYS - {"scene_origin", "timeseries"}:
        assert a[key] == b[key], key
    for name, col in b["timeseries"].items():
        np.testing.assert_array_equal(a["timeseries"][name], col)


def test_options_map_onto_the_commands_flags():
    r = dentsim.run("probe", duration=0.2, tick_hz=2000, log_every=4, pipeline="reference")
    assert (r["ticks"], r["tick_hz"], r["pipeline"]) == (400, 2000.0, "reference")
    assert len(r["timeseries"]["t_s"]) == 100
    np.testing.assert_allclose(np.diff(r["timeseries"]["t_s"]), 4 / 2000, rtol=1e-9)


def test_an_injected_fault_is_reported_not_raised():
    r = dentsim.run("probe", duration=0.5, inject_fault="nan-sample@0.3")
    assert r["faults"] == ["tick_bad_sample at t = 0.300000 s"]
    assert r["ticks"] == 300
    assert r["torque_after_fault_n_m"] == 0.0


def test_builtin_scenes():
    assert dentsim.builtin_scenes() == ["probe", "probe-groove", "drill"]
    for name in dentsim.builtin_scenes():
        s = dentsim.load_scene(name)
        assert s["builtin"] and s["name"] == name and s["tick_hz"] == 1000.0


def test_bad_inputs_raise_the_commands_message(cli, tmp_path):
    with pytest.raises(dentsim.InputError) as e:
        dentsim.run("nope")
    assert str(e.value) == cli.error("run", "nope", "--out", tmp_path / "out")
    bad = tmp_path / "bad.json"
    bad.write_text('{"dentsim_scene": 1, "name": "x", "duration_s": -1}')
    with pytest.raises(dentsim.InputError) as e:
        dentsim.run(bad)
    assert str(e.value) == cli.error("run", bad, "--out", tmp_path / "out")
    with pytest.raises(dentsim.InputError, match=r"pipeline 'turbo': expected one of reference, fast"):
        dentsim.run("probe", pipeline="turbo")
    with pytest.raises(dentsim.InputError, match=r"duration"):
        dentsim.run("probe", duration=-1.0)
    with pytest.raises(dentsim.InputError, match=r"tick_hz: must be within \[100, 20000\] Hz"):
        dentsim.run("probe", tick_hz=50)
    with pytest.raises(dentsim.InputError, match=r"inject_fault"):
        dentsim.run("probe", inject_fault="meltdown@1")
    assert not (tmp_path / "out" / "report.json").exists()

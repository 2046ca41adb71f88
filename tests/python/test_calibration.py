"""Calibration logs and fits through the bindings, against `dentsim excite` and `dentsim calibrate`.

The log the command wrote reads back to exactly the numbers in the file (it keeps 17 significant
digits); the fit of the same log with the same options gives exactly the command's report (the
same Ceres problem on the same inputs), and the fitted model file it wrote.
"""

import csv
import json

import numpy as np
import pytest

import dentsim

# Short fits: a 2 s log, 400 samples (seconds, not minutes; converges in 73 iterations).
FIT = {"max_samples": 400}


def test_calibration_log_reads_back_what_excite_wrote(excite_log):
    log = dentsim.read_calibration_log(excite_log)
    lines = excite_log.read_text().splitlines()
    comments = [l[1:] for l in lines if l.startswith("#")]
    rows = list(csv.reader(l for l in lines if not l.startswith("#")))
    header, rows = rows[0], np.array(rows[1:], dtype=float)
    col = {name: i for i, name in enumerate(header)}
    assert log["comments"] == comments
    assert log["t"].shape == (2001,) and log["q"].shape == (2001, 6)
    np.testing.assert_array_equal(log["t"], rows[:, col["t_s"]])
    for j in range(6):
        np.testing.assert_array_equal(log["q"][:, j], rows[:, col[f"q{j + 1}_rad"]])
        np.testing.assert_array_equal(log["qd"][:, j], rows[:, col[f"qd{j + 1}_rad_s"]])
        np.testing.assert_array_equal(log["tau"][:, j], rows[:, col[f"tau{j + 1}_n_m"]])
    assert np.ptp(log["q"], axis=0).min() > 1e-3  # every joint moved (the log is usable)


def test_fit_equals_the_commands_report(excite_log, cli, tmp_path):
    cli("calibrate", excite_log, "--json", tmp_path / "fit.json", "-o", tmp_path / "model.json",
        "--max-samples", FIT["max_samples"])
    expected = json.loads((tmp_path / "fit.json").read_text())
    r = dentsim.calibrate(excite_log, **FIT)
    assert set(r) == set(expected) | {"fitted_model", "samples_used"}
    assert r["log"] == str(excite_log)
    for key in expected:
        assert r[key] == expected[key], key
    assert r["converged"] and r["residual_rms_n_m"] > 0.0 and r["identifiable_count"] > 0
    assert r["fitted_model"] == (tmp_path / "model.json").read_text()
    used = r["samples_used"]
    assert len(used["t"]) == r["samples"] > 0
    assert used["tau_measured"].shape == used["tau_predicted"].shape == (r["samples"], 6)
    res = used["tau_predicted"] - used["tau_measured"]
    # A row dropped near stiction (min_speed) is a zero in both; the RMS is over the rows used.
    assert 0 < sum(r["rows_used"]) <= res.size
    assert np.sqrt(np.sum(res ** 2) / sum(r["rows_used"])) == pytest.approx(
        r["residual_rms_n_m"], rel=1e-12)
    # The fitted file loads as a device model.
    path = tmp_path / "fitted.json"
    path.write_text(r["fitted_model"])
    assert dentsim.PhantomModel(path).dof == 6


def test_without_the_law_term_equals_the_commands_flag(excite_log, cli, tmp_path):
    cli("calibrate", excite_log, "--json", tmp_path / "fit.json", "-o", tmp_path / "model.json",
        "--max-samples", FIT["max_samples"], "--no-law-mismatch")
    expected = json.loads((tmp_path / "fit.json").read_text())
    r = dentsim.calibrate(excite_log, law_mismatch_term=False, **FIT)
    assert r["parameters"] == expected["parameters"] and not r["law_mismatch_term"]
    # The law term off: the reported std is the statistical and the slow-row terms alone.
    for p in r["parameters"]:
        assert p["std_law"] == 0.0
        assert p["std"] == pytest.approx(np.hypot(p["std_statistical"], p["std_model"]), rel=1e-12)


def test_bad_logs_and_options_raise_the_commands_message(cli, tmp_path, excite_log):
    bad = tmp_path / "bad.csv"
    bad.write_text("t_s,q1_rad\n0,0\n")
    with pytest.raises(dentsim.InputError) as e:
        dentsim.read_calibration_log(bad)
    assert str(e.value) == cli.error("calibrate", bad, "--json", tmp_path / "j.json",
                                     "-o", tmp_path / "m.json")
    with pytest.raises(dentsim.InputError) as e:
        dentsim.calibrate(bad)
    assert str(e.value).startswith(str(bad))
    with pytest.raises(dentsim.InputError, match=r"lowpass_hz .*Nyquist"):
        dentsim.calibrate(excite_log, lowpass_hz=900.0)
    with pytest.raises(dentsim.InputError, match=r"velocity_lag"):
        dentsim.calibrate(excite_log, velocity_lag="soon")


def test_incomplete_log_is_refused_unless_allowed_as_the_command(cli, tmp_path):
    """A log an excitation stopped early (here a device lost at 1.5 s of a 2 s run) is refused
    with the command's message, and with allow_incomplete=True fitted to exactly the report of
    `dentsim calibrate --allow-incomplete` (issue #33)."""
    cut = tmp_path / "cut.csv"
    r = cli("excite", "-o", cut, "--duration", 2, "--design-iterations", 0,
            "--inject-fault", "device-loss@1.5", check=False)
    assert r.returncode == 3, (r.stdout, r.stderr)
    log = dentsim.read_calibration_log(cut)
    assert log["incomplete"] and "device" in log["incomplete"]
    assert 0 < len(log["t"]) < 2001  # the log up to the stop
    with pytest.raises(dentsim.InputError) as e:
        dentsim.calibrate(cut, **FIT)
    message = str(e.value)
    assert message.startswith(f"{cut}: the log is marked incomplete ({log['incomplete']})")
    assert message.endswith("refused unless allow_incomplete=True is given")
    cli.error("calibrate", cut, "--json", tmp_path / "j.json", "-o", tmp_path / "m.json")
    assert not (tmp_path / "j.json").exists()

    cli("calibrate", cut, "--json", tmp_path / "fit.json", "-o", tmp_path / "model.json",
        "--max-samples", FIT["max_samples"], "--allow-incomplete")
    expected = json.loads((tmp_path / "fit.json").read_text())
    assert expected["log_incomplete"] == log["incomplete"]
    fit = dentsim.calibrate(cut, allow_incomplete=True, **FIT)
    for key in expected:
        assert fit[key] == expected[key], key


def test_a_complete_log_reads_as_complete(excite_log):
    assert dentsim.read_calibration_log(excite_log)["incomplete"] is None

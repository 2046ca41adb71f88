"""dentsim.Pipeline: the servo tick, tick by tick, against the command's own ticks.

A drill session recorded by `dentsim run drill --record` (fast pipeline) holds every tick's
device sample and the torque the tick commanded. Ticked from Python on the same samples in the
same scene, the fast pipeline reproduces every command bit for bit; the reference pipeline gives
exactly the torque differences `dentsim replay --pipeline reference --json` reports, and agrees
with the fast one to 1e-9 N until the first discrete drilling event (docs/tolerance_policy.md
item 9). In free space the two implementations agree to 1e-9 relative, and a device at rest under
a proxy at rest gets exactly its gravity compensation.
"""

import json

import numpy as np
import pytest

import dentsim


def tick_session(pipeline, s):
    """Every record of session dict `s` through `pipeline`, as the replay does: reset on the
    first sample, T_0 = 1 / tick_rate_hz, then T_k = t_k - t_k-1. The torques and contact counts."""
    n = len(s["t"])
    tau = np.zeros((n, s["dof"]))
    contacts = np.zeros(n, dtype=np.int64)
    pipeline.reset(s["q"][0], s["qd"][0], s["t"][0])
    for k in range(n):
        T = 1.0 / s["tick_rate_hz"] if k == 0 else s["t"][k] - s["t"][k - 1]
        r = pipeline.tick(s["q"][k], s["qd"][k], s["t"][k], T)
        assert r["status"] == "ok", (k, r["status"])
        tau[k] = r["tau"]
        contacts[k] = r["contacts"]
    return tau, contacts


@pytest.fixture(scope="module")
def session(drill_session):
    rec, report = drill_session
    s = dentsim.read_session(rec)
    assert len(s["t"]) == report["recorded_ticks"] == report["ticks"]
    assert (s["contacts"] > 0).sum() > 300, "the session must exercise contact"
    return s


def test_fast_pipeline_reproduces_the_recorded_commands_bit_for_bit(session):
    p = dentsim.Pipeline("fast", scene="drill")
    assert (p.impl, p.scene, p.tick_s) == ("fast", "drill", 1e-3)
    tau, contacts = tick_session(p, session)
    np.testing.assert_array_equal(tau, session["tau"])
    np.testing.assert_array_equal(contacts, session["contacts"])


def test_reference_pipeline_gives_the_differences_of_dentsim_replay(session, drill_session, cli,
                                                                    tmp_path, model):
    rec, _ = drill_session
    tau, _ = tick_session(dentsim.Pipeline("reference", scene="drill"), session)
    cli("replay", rec, "--pipeline", "reference", "--json", tmp_path / "ref.json")
    expected = json.loads((tmp_path / "ref.json").read_text())
    d = np.abs(tau - session["tau"]).max(axis=1)
    # The same reference ticks on the same samples: the same numbers, exactly.
    assert d.max() == expected["max_torque_diff_n_m"]
    assert int(d.argmax()) == expected["worst_tick"]
    # Before the first divergent tick the force difference f of J1^T (tau' - tau) is round-off
    # (policy item 9: 1e-9 N), through the first contacts.
    first = expected["first_divergent_tick"]
    end = len(d) if first < 0 else first
    assert (session["contacts"][:end] > 0).sum() > 100, f"first divergent tick {first}"
    f = [np.linalg.norm((np.linalg.inv(model.jacobian(session["q"][k])).T
                         @ (tau[k] - session["tau"][k]))[:3]) for k in range(end)]
    assert max(f) <= 1e-9


def test_free_space_fast_agrees_with_the_reference(model):
    fast, ref = dentsim.Pipeline("fast"), dentsim.Pipeline("reference")
    assert fast.scene is None and fast.tick_s == 1e-3
    np.testing.assert_array_equal(fast.home_q, model.home_q)
    # A smooth motion around home: 200 ticks of 1 ms, every joint on its own sine.
    t = np.arange(200) * 1e-3
    w = np.array([3.0, 5.0, 7.0, 11.0, 13.0, 17.0])
    q = model.home_q + 0.05 * np.sin(np.outer(t, w))
    qd = 0.05 * w * np.cos(np.outer(t, w))
    for k in range(len(t)):
        a = fast.tick(q[k], qd[k], t[k])
        b = ref.tick(q[k], qd[k], t[k])
        for key in ("tau", "T1", "F_coupling", "V_hat", "proxy_x"):
            scale = np.abs(b[key]).max()
            err = np.abs(a[key] - b[key]).max()
            assert err <= max(1e-9 * scale, 1e-15), (k, key, err, scale)
    assert np.abs(b["T1"]).max() > 1e-3  # the coupling was loaded (signal guard)


def test_device_at_rest_gets_its_gravity_compensation(model):
    for impl in ("fast", "reference"):
        p = dentsim.Pipeline(impl)
        q = model.home_q
        assert p.reset(q) == "ok"
        r = p.tick(q, np.zeros(6), 0.0)
        # Proxy on the device, both at rest: no coupling force, the command is g(q) alone.
        np.testing.assert_array_equal(r["T1"], np.zeros(6))
        np.testing.assert_allclose(r["tau"], model.gravity(q), rtol=0, atol=1e-15)
        np.testing.assert_array_equal(r["tau"], r["tau_gravity"])
        np.testing.assert_allclose(r["device_x"], model.forward_kinematics(q)[0], atol=1e-15)
        assert r["contacts"] == 0 and not r["saturated"]


def test_a_bad_tick_reports_its_fault_and_commands_zero_torque(model):
    p = dentsim.Pipeline("fast")
    q = model.home_q
    p.reset(q)
    r = p.tick(q, np.zeros(6), 0.001, T=-1.0)
    assert r["status"] == "tick_bad_length"
    np.testing.assert_array_equal(r["tau"], np.zeros(6))
    r = p.tick(np.full(6, np.nan), np.zeros(6), 0.002)
    assert r["status"] == "tick_bad_sample"


def test_bad_arguments_raise_with_the_message():
    with pytest.raises(dentsim.InputError, match=r"impl 'turbo': expected one of reference, fast"):
        dentsim.Pipeline("turbo")
    with pytest.raises(dentsim.InputError, match=r"scene 'nope' is neither a built-in scene"):
        dentsim.Pipeline("fast", scene="nope")
    with pytest.raises(dentsim.InputError, match=r"either scene or model"):
        dentsim.Pipeline("fast", scene="probe", model="x.json")
    p = dentsim.Pipeline("reference")
    with pytest.raises(ValueError, match=r"Pipeline.tick: q: expected 6 numbers"):
        p.tick([0.0] * 5, None, 0.0)

"""dentsim.PhantomModel: the analytic Phantom model through the bindings.

Checks (docs/tolerance_policy.md): M(q) symmetric positive definite over the joint-limit box;
gravity the gradient of the potential and the Jacobian the derivative of the forward kinematics
(central differences: the bounds below are the truncation h^2 |f'''| plus the round-off
eps |f| / h, stated per check, each at least 100 times below the signal); the bias C(q, qd) qd
equal to the Lagrangian velocity terms dM/dt qd - 1/2 d/dq (qd^T M qd); the model the command
prints (`dentsim device show`) loaded from its file equal to the default bit for bit; bad inputs
raise dentsim.InputError with the C++ message.
"""

import numpy as np
import pytest

import dentsim

SEED = 20  # numpy's default_rng; printed in every failure message below


def configurations(model, n=20, seed=SEED):
    """n configurations drawn uniformly in the joint-limit box (seeded)."""
    rng = np.random.default_rng(seed)
    return model.q_min + rng.random((n, model.dof)) * (model.q_max - model.q_min)


def test_mass_matrix_is_symmetric_positive_definite(model):
    assert model.dof == 6
    for k, q in enumerate(configurations(model)):
        M = model.mass_matrix(q)
        assert M.shape == (6, 6) and M.dtype == np.float64
        # Symmetric to round-off of its sums (policy item 2): c eps |M| n with c = 10, n = 8 bodies.
        np.testing.assert_allclose(M, M.T, rtol=0, atol=10 * 2.2e-16 * np.abs(M).max() * 8,
                                   err_msg=f"seed {SEED}, sample {k}")
        assert np.linalg.eigvalsh(M).min() > 0.0, f"seed {SEED}, sample {k}"


def test_gravity_is_the_gradient_of_the_potential(model):
    h = 1e-5
    for k, q in enumerate(configurations(model)):
        g = model.gravity(q)
        fd = np.array([(model.potential_energy(q + h * e) - model.potential_energy(q - h * e))
                       / (2 * h) for e in np.eye(6)])
        # U ~ 0.1 J, its derivatives ~ 0.1: truncation h^2 0.1 = 1e-11, round-off 1e-16 / h = 1e-11.
        assert np.abs(g - fd).max() <= 1e-9, f"seed {SEED}, sample {k}: {g} vs {fd}"
        assert np.abs(g).max() >= 100 * 1e-9  # signal guard (policy item 5)


def test_jacobian_is_the_derivative_of_the_forward_kinematics(model):
    h = 1e-6
    for k, q in enumerate(configurations(model)):
        J = model.jacobian(q)
        x0, R0 = model.forward_kinematics(q)
        fd = np.zeros((6, 6))
        for j, e in enumerate(np.eye(6)):
            xp, Rp = model.forward_kinematics(q + h * e)
            xm, Rm = model.forward_kinematics(q - h * e)
            fd[:3, j] = (xp - xm) / (2 * h)  # v1 in the world frame
            W = R0.T @ (Rp - Rm) / (2 * h)  # R1^T dR1/dq_j = [w1]x, w1 in the tool's frame
            fd[3:, j] = (W[2, 1], W[0, 2], W[1, 0])
        # |x| ~ 0.3 m, unit rotations: truncation h^2 = 1e-12, round-off 1e-16 / h = 1e-10.
        assert np.abs(J - fd).max() <= 1e-8, f"seed {SEED}, sample {k}"
        assert np.abs(J).max() >= 100 * 1e-8


def test_bias_is_the_lagrangian_velocity_term(model):
    """C qd = dM/dt qd - 1/2 d/dq (qd^T M qd) for every factorisation with dM/dt = C + C^T."""
    rng = np.random.default_rng(SEED + 1)
    h = 1e-6
    for k, q in enumerate(configurations(model, n=10)):
        qd = rng.uniform(-2.0, 2.0, 6)
        dM = [(model.mass_matrix(q + h * e) - model.mass_matrix(q - h * e)) / (2 * h)
              for e in np.eye(6)]
        Mdot = sum(dM[j] * qd[j] for j in range(6))
        expected = Mdot @ qd - 0.5 * np.array([qd @ dM[i] @ qd for i in range(6)])
        b = model.bias(q, qd)
        # |M| ~ 1e-2, |qd| ~ 2: terms ~ 4e-2 |dM/dq|; truncation ~1e-14, round-off 1e-18 / h.
        assert np.abs(b - expected).max() <= 1e-9, f"seed {SEED}, sample {k}"
        assert np.abs(b).max() >= 100 * 1e-9
        np.testing.assert_array_equal(b, model.coriolis_matrix(q, qd) @ qd)


def test_forward_dynamics_inverts_the_equation_of_motion(model):
    rng = np.random.default_rng(SEED + 2)
    for q in configurations(model, n=5):
        qd = rng.uniform(-1.0, 1.0, 6)
        tau = rng.uniform(-0.1, 0.1, 6)
        qdd = model.forward_dynamics(q, qd, tau)
        lhs = model.mass_matrix(q) @ qdd + model.bias(q, qd) + model.gravity(q) + model.friction(qd)
        # A Cholesky solve: round-off c eps cond(M) |tau| with cond(M) <= 1e4 here, c = 100.
        np.testing.assert_allclose(lhs, tau, rtol=0, atol=100 * 2.2e-16 * 1e4 * 0.3)


def test_the_model_file_of_the_command_loads_to_the_same_model(model, cli, tmp_path):
    path = tmp_path / "phantom.json"
    path.write_text(cli("device", "show").stdout)
    loaded = dentsim.PhantomModel(path)  # os.PathLike
    assert loaded.path == str(path)
    assert dentsim.PhantomModel(str(path)).name == model.name
    for q in configurations(model, n=5):
        np.testing.assert_array_equal(loaded.mass_matrix(q), model.mass_matrix(q))
        np.testing.assert_array_equal(loaded.gravity(q), model.gravity(q))
        np.testing.assert_array_equal(loaded.jacobian(q), model.jacobian(q))
    assert model.model_file().strip() == cli("device", "show").stdout.strip()


def test_a_bad_model_file_raises_the_message_of_the_command(cli, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{}")
    with pytest.raises(dentsim.InputError) as e:
        dentsim.PhantomModel(bad)
    assert str(e.value) == cli.error("device", "check", bad)
    assert isinstance(e.value, ValueError)
    with pytest.raises(dentsim.InputError, match="cannot read"):
        dentsim.PhantomModel(tmp_path / "missing.json")


def test_wrong_lengths_raise_naming_the_expected_length(model):
    with pytest.raises(ValueError, match=r"mass_matrix: q: expected 6 numbers .*got shape \(5,\)"):
        model.mass_matrix(np.zeros(5))
    with pytest.raises(ValueError, match=r"jacobian: q: expected 6 numbers .*got shape \(6, 1\)"):
        model.jacobian(np.zeros((6, 1)))
    with pytest.raises(ValueError, match=r"bias: qd: expected 6 numbers"):
        model.bias(np.zeros(6), [0.0] * 7)
    with pytest.raises(ValueError, match=r"gravity: q: expected 6 numbers, got str"):
        model.gravity("abcdef")
    with pytest.raises(ValueError, match=r"expected a str or os.PathLike path"):
        dentsim.PhantomModel(3)
    # Any real array-like of the right length is taken.
    np.testing.assert_array_equal(model.gravity([0, 0.5, 0.25, 0, 0, 0]),
                                  model.gravity(np.array([0, 0.5, 0.25, 0, 0, 0], np.float32)))
    np.testing.assert_array_equal(model.gravity((0, 1, 0, 0, 0, 0)),
                                  model.gravity(np.array([0, 1, 0, 0, 0, 0])))

"""ROS34PW2 (fibersweep/fiber/integrators/rosw.py): order conditions and
measured order of convergence.

The steps below use the kernel's own stage arithmetic (``stage_point``,
``stage_rhs``, ``combine``), its transformed coefficients and its LU, on small
test problems with known or tightly computed solutions, with an exact Jacobian
and with inexact W (a W-method keeps its order for any W).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from fibersweep.fiber.integrators.lu import lu_factor, lu_solve
from fibersweep.fiber.integrators.rosw import (
    ALPHA,
    BHAT,
    GAMMA3,
    GAMMA_MATRIX,
    ROS34PW2,
    B,
    combine,
    stage_point,
    stage_rhs,
    transformed,
    w_order_residuals,
)


def test_order_conditions_hold():
    """The published coefficients satisfy the 8 W-method conditions of order 3 and the
    embedded weights the 3 of order 2, to 1e-14 (16-digit coefficients; a typo in
    the 12th digit of α32 gives residuals ~1e-12 and fails). The embedded weights
    are not third order (their order-3 residuals exceed 1e-2)."""
    assert np.max(np.abs(w_order_residuals(ALPHA, GAMMA_MATRIX, B, 3))) < 1e-14
    assert np.max(np.abs(w_order_residuals(ALPHA, GAMMA_MATRIX, BHAT, 2))) < 1e-14
    assert np.max(np.abs(w_order_residuals(ALPHA, GAMMA_MATRIX, BHAT, 3))) > 1e-2
    typo = ALPHA.copy()
    typo[2, 1] = -1.1299064236397981e-01
    assert np.max(np.abs(w_order_residuals(typo, GAMMA_MATRIX, B, 3))) > 1e-13


def test_ros34pw2_is_l_stable_and_stiffly_accurate():
    """Stability function R(z) = 1 + z mᵀ(I − z a − ... ) evaluated through the
    transformed step on y' = λy with W = λ: |R(z)| <= 1 on the left half plane
    (sampled) and R(-1e8) within 1e-6 of 0 (L-stable). Tolerances as stated."""
    zs = [-1e8, -100.0, -10.0, -1.0, -0.1, 1j * 10.0, -1.0 + 5j, -50.0 + 50j]
    for z in zs:
        r = _stability(z)
        assert abs(r) <= 1.0 + 1e-12, z
    assert abs(_stability(-1e8)) < 1e-6


def _stability(z: complex) -> complex:
    """One step of y' = z y (h = 1, W = z) in complex arithmetic, from the transformed
    coefficients (the same formula as the kernel's helpers)."""
    a, c, m, _ = ROS34PW2
    x = np.zeros(4, dtype=complex)
    for i in range(4):
        arg = 1.0 + a[i, :i] @ x[:i]
        x[i] = (z * arg + c[i, :i] @ x[:i]) / (1.0 - GAMMA3 * z)
    return 1.0 + m @ x


def _step(f, w, q, h):
    """One ROS34PW2 step with the kernel's helpers: (new q, error estimate vector)."""
    a, c, m, e = ROS34PW2
    n = q.shape[0]
    lhs = np.eye(n) - GAMMA3 * h * w
    piv = np.empty(n, dtype=np.int64)
    assert lu_factor(lhs, piv)
    xs = np.zeros((4, n))
    qn = np.empty(n)
    for i in range(4):
        stage_point(q, h, a, xs, i, qn)
        xs[i] = f(qn)
        stage_rhs(c, xs, i, xs[i])
        lu_solve(lhs, piv, xs[i])
    out = np.empty(n)
    combine(q, h, m, xs, out)
    err = np.empty(n)
    combine(np.zeros(n), h, e, xs, err)
    return out, err


def _global_error(f, wfun, y0, t_end, steps, exact):
    y = np.array(y0, dtype=float)
    h = t_end / steps
    for _ in range(steps):
        y, _ = _step(f, wfun(y), y, h)
    return float(np.max(np.abs(y - exact)))


def _slope(errs, steps):
    return float(np.polyfit(np.log(1.0 / np.asarray(steps)), np.log(errs), 1)[0])


LIN = np.array([[-1.0, 2.0, 0.0], [-2.0, -1.0, 0.5], [0.0, 0.0, -20.0]])
RNG_W = np.random.default_rng(7).standard_normal((3, 3))


@pytest.mark.parametrize(
    "wkind",
    ["exact", "perturbed", "zero"],
)
def test_third_order_on_a_linear_problem(wkind):
    """y' = A y (eigenvalues −1 ± 2i and −20), y(1) against expm(A) y0: the global
    error falls with slope 3 ± 0.2 (log–log, 40..320 steps) for W = A, for
    W = A + 0.5 R (R a fixed random matrix) and for W = 0 (the method is then an
    explicit third-order Runge–Kutta method)."""
    w = {"exact": LIN, "perturbed": LIN + 0.5 * RNG_W, "zero": np.zeros((3, 3))}[wkind]
    y0 = np.array([1.0, 0.5, 1.0])
    exact = expm(LIN) @ y0
    steps = [40, 80, 160, 320]
    errs = [_global_error(lambda y: LIN @ y, lambda y: w, y0, 1.0, s, exact) for s in steps]
    assert _slope(errs, steps) == pytest.approx(3.0, abs=0.2), errs


def _brusselator(y):
    u, v = y
    return np.array([1.0 + u * u * v - 4.0 * u, 3.0 * u - u * u * v])


def _brusselator_jac(y):
    u, v = y
    return np.array([[2.0 * u * v - 4.0, u * u], [3.0 - 2.0 * u * v, -u * u]])


@pytest.fixture(scope="module")
def brusselator_reference():
    """y(2) of the Brusselator from (1.5, 3), DOP853 at rtol = atol = 1e-13."""
    sol = solve_ivp(
        lambda t, y: _brusselator(y), (0.0, 2.0), [1.5, 3.0], method="DOP853",
        rtol=1e-13, atol=1e-13,
    )  # fmt: skip
    return sol.y[:, -1]


@pytest.mark.parametrize("wkind", ["exact", "lagged", "perturbed"])
def test_third_order_on_a_nonlinear_problem(brusselator_reference, wkind):
    """Brusselator u' = 1 + u²v − 4u, v' = 3u − u²v on [0, 2]: global error slope
    3 ± 0.2 (160..1280 steps; at 40..80 steps the error is pre-asymptotic) with
    W = J(y_n) (Rosenbrock), W = J(y0) frozen for the whole run (lagged, like the
    fiber's mobility) and W = 0.7 J(y_n) + 0.3 R."""
    y0 = np.array([1.5, 3.0])
    rw = np.random.default_rng(3).standard_normal((2, 2))
    wfun = {
        "exact": _brusselator_jac,
        "lagged": lambda y: _brusselator_jac(y0),
        "perturbed": lambda y: 0.7 * _brusselator_jac(y) + 0.3 * rw,
    }[wkind]
    steps = [160, 320, 640, 1280]
    errs = [_global_error(_brusselator, wfun, y0, 2.0, s, brusselator_reference) for s in steps]
    assert _slope(errs, steps) == pytest.approx(3.0, abs=0.2), errs


@pytest.mark.parametrize("wkind", ["exact", "lagged"])
def test_error_estimate_is_third_order_locally(wkind):
    """The embedded estimate of one Brusselator step from (1.5, 3) scales as h³
    (the local error of the second-order embedded solution): log–log slope 3 ± 0.2
    over h = 0.0125 .. 0.0015625 (larger h are pre-asymptotic), for W = J(y0) and
    W = J(y0) + 0.3 R (inexact)."""
    y0 = np.array([1.5, 3.0])
    w = _brusselator_jac(y0)
    if wkind == "lagged":
        w = w + 0.3 * np.random.default_rng(5).standard_normal((2, 2))
    hs = [0.0125, 0.00625, 0.003125, 0.0015625]
    errs = [float(np.max(np.abs(_step(_brusselator, w, y0, h)[1]))) for h in hs]
    slope = float(np.polyfit(np.log(hs), np.log(errs), 1)[0])
    assert slope == pytest.approx(3.0, abs=0.2), errs


def test_transformed_form_matches_the_hairer_wanner_form():
    """The transformed coefficients give the same step as the untransformed stage
    equations (I − γhW) k_i = f(q + hΣα_ij k_j) + hWΣγ_ij k_j on the Brusselator
    with an inexact W, to 1e-13 relative."""
    y0 = np.array([1.5, 3.0])
    w = _brusselator_jac(y0) + 0.3 * np.random.default_rng(1).standard_normal((2, 2))
    h = 0.05
    k = np.zeros((4, 2))
    lhs = np.eye(2) - GAMMA3 * h * w
    for i in range(4):
        rhs = _brusselator(y0 + h * ALPHA[i, :i] @ k[:i]) + h * w @ (GAMMA_MATRIX[i, :i] @ k[:i])
        k[i] = np.linalg.solve(lhs, rhs)
    ref = y0 + h * B @ k
    ref_err = h * (B - BHAT) @ k
    new, err = _step(_brusselator, w, y0, h)
    assert np.allclose(new, ref, rtol=1e-13, atol=0.0)
    assert np.allclose(err, ref_err, rtol=1e-10, atol=1e-16)
    a, c, m, e = transformed(ALPHA, GAMMA_MATRIX, B, BHAT)
    assert np.allclose(np.tril(a, -1), a) and np.allclose(np.tril(c, -1), c)


def test_fiber_kernel_agrees_with_ros2_in_free_flow(coarse_field):
    """The fiber kernel's ROS34PW2 path (``fiber.integrator: ros34pw2``) against
    ROS2 at a tight tolerance (1e-6 µm, bead error 4e-7 µm against Δt = 2.5e-5 s BDF2
    at t = 0.3 s): E = 1 MPa, L = 0.5 l_obs, free flow to t = 0.2 s (68 ROS34PW2 steps
    against 399). Measured 1.6e-5 µm; tolerance 1e-4 µm on every bead (ROS34PW2's
    own error at its 2 µm displacement bound is ~3e-5 µm over 0.3 s,
    docs/flexible.md)."""
    from fibersweep.config.fiber import FiberSettings
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.run import simulate_for

    start = FiberStart(0.0, 0.45, 0.5)
    out = {}
    for method, tol in (("ros2", 1e-6), ("ros34pw2", 1e-4)):
        st = FiberSettings(
            model="bead-spring", integrator=method, young_modulus=1e6, step={"tolerance": tol}
        )
        traj, _ = simulate_for(coarse_field, st, start, 0.2)
        out[method] = traj.beads[-1]
    assert np.max(np.hypot(*(out["ros34pw2"] - out["ros2"]).T)) < 1e-4


@pytest.mark.parametrize(
    ("method", "reuse", "controller"),
    [("ros2", 10, "i"), ("ros34pw2", 10, "i"), ("ros2", 1, "pi"), ("ros34pw2", 3, "pi")],
)
def test_reused_w_and_pi_controller_keep_the_solution(coarse_field, method, reuse, controller):
    """``fiber.step.jacobian_reuse`` (one W = M J over several steps) and
    ``fiber.step.controller: pi`` change the steps, not the solution: ROS2 and
    ROS34PW2 are W-methods, whose order holds for any W, and the error is still
    controlled per step. Against ROS2 with a fresh W at 1e-6 µm (E = 1 MPa,
    L = 0.5 l_obs, free flow to t = 0.2 s), every bead within 1e-4 µm at tolerance
    1e-4 µm (the bound of the ROS34PW2 test above, same run)."""
    from fibersweep.config.fiber import FiberSettings
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.run import simulate_for

    start = FiberStart(0.0, 0.45, 0.5)

    def beads(integrator, **step):
        st = FiberSettings(
            model="bead-spring", integrator=integrator, young_modulus=1e6, step=step
        )
        traj, _ = simulate_for(coarse_field, st, start, 0.2)
        return traj.beads[-1]

    ref = beads("ros2", tolerance=1e-6)
    got = beads(method, tolerance=1e-4, jacobian_reuse=reuse, controller=controller)
    assert np.max(np.hypot(*(got - ref).T)) < 1e-4


def test_reuse_and_controller_defaults_are_not_written():
    """Configs that do not set the two step options keep their dump (and run ids)."""
    from fibersweep.config.fiber import FiberSettings

    step = FiberSettings().model_dump()["step"]
    assert "jacobian_reuse" not in step and "controller" not in step
    st = FiberSettings(step={"jacobian_reuse": 4, "controller": "pi"}).model_dump()["step"]
    assert st["jacobian_reuse"] == 4 and st["controller"] == "pi"

"""The typed bundles the Numba integrators read, built once per run by :func:`build_kernel`.

Each bundle is a ``typing.NamedTuple``: Numba passes it as a struct and
resolves field access at compile time; reading scalars from it costs what a
float vector or a structured-array record costs (measured equal, ~5 ns per
iteration of a toy loop), and unlike a record it can hold arrays, and its
type can select code (the effect records, :mod:`fibersweep.fiber.kernel.hooks`).
The integrators take one :class:`Kernel` holding them all, unpack it once and
hand their inner functions and the effects' stages only the bundles they need:
a call copies its arguments, and passing the whole Kernel to the per-step
velocity made the rigid kernel ~15 % slower (measured with a contact run).

- :class:`FlowArrays`: the field on its grid;
- :class:`~fibersweep.fiber.contact.pillar.PillarArrays`: the pillar (rough or smooth);
- :class:`BodyArrays`: the straight fiber's rigid-body mobility;
- :class:`Params`: the scalars of stepping, stopping and the bead-spring energy;
- :class:`Work`, :class:`BeadWork`: scratch buffers, allocated here so the
  kernels never allocate (BeadWork is empty for the rigid model);
- ``effects``: the kernel records of the run's active dynamic effects
  (see :mod:`fibersweep.fiber.kernel.hooks`), sorted by effect name and ending with
  :data:`~fibersweep.fiber.kernel.hooks.BASELINE`;
- ``frame``: where copies of the pillar stand and how the field is read
  (:mod:`fibersweep.fiber.frame`: the channel's single pillar, or an array).

:func:`build_kernel` assembles a channel run from its :class:`Setup`; an
array run (:mod:`fibersweep.fiber.rows`) uses the same :func:`make_params` and
:func:`assemble` with its own field, bounds and frame.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fibersweep.config.fiber import ROSENBROCK, FiberSettings
from fibersweep.fiber.contact.pillar import PillarArrays, contact_force_scale
from fibersweep.fiber.frame import CHANNEL
from fibersweep.fiber.hydro.rpy import body_mobility
from fibersweep.fiber.integrators.rosw import METHODS
from fibersweep.fiber.kernel.hooks import BASELINE
from fibersweep.fiber.models.rod import rod
from fibersweep.fiber.models.spacing import exclusion_force_scale, exclusion_gap, spacing_um
from fibersweep.fiber.setup import Setup

__all__ = [
    "DEFAULT_DT",
    "BeadWork",
    "BodyArrays",
    "FlowArrays",
    "Kernel",
    "Params",
    "PillarArrays",
    "Work",
    "assemble",
    "build_kernel",
    "make_params",
]

DEFAULT_DT = 5e-5  # s; bead-spring default step (see tests/validation/test_fiber_beadspring.py)


class FlowArrays(NamedTuple):
    """Background flow: ``ux, uy`` (nx, ny) [µm/s] on nodes ``dx`` [µm] apart."""

    ux: np.ndarray
    uy: np.ndarray
    dx: float


class BodyArrays(NamedTuple):
    """Rigid-body mobility of the straight n-bead fiber (body frame, see mobility.BodyMobility).

    Attributes
    ----------
    s : ndarray, shape (n,)
        Bead offsets along the axis [µm].
    pm, nm, chol : ndarray, shapes (3, 2n), (3, 3), (3, 3)
        P, N and the Cholesky factor of N.
    tip_m : float
        Largest bead mobility of the rigid body [µm/(pN s)].
    """

    s: np.ndarray
    pm: np.ndarray
    nm: np.ndarray
    chol: np.ndarray
    tip_m: float


class Params(NamedTuple):
    """Scalars of a run (lengths µm, times s, speeds µm/s, forces pN).

    Attributes
    ----------
    a, mu : bead radius, viscosity [pN s/µm²]
    max_disp, contact_disp : largest bead move per step far from / near the pillar
        (rigid: step.max_displacement, contact_displacement; ros2, ros34pw2: the
        step.ros2_ ones)
    dt_max : largest step (rigid, ros2, ros34pw2)
    dt : fixed step (bdf2; NaN otherwise unless step.dt is set)
    t_max : give up
    x_stop : mode 0 stops when the rearmost end passes this x
    t_stop : mode 1 stops at this time
    mode : 0 run past the pillar, 1 run until t_stop
    trap_speed, trap_time : a fiber in contact slower than trap_speed for trap_time is trapped
    stopped_implicit : rigid: linearly implicit steps while stopped in contact
    y_lo, y_hi : bead centres must stay between these
    stretch, bend : bead-spring S = EA [pN] and B = EI [pN µm²] of the rod
        (:func:`~fibersweep.fiber.models.rod.rod`)
    tol : ros2, ros34pw2: local error allowed per step [µm] (step.tolerance)
    rosw : the Rosenbrock-W method, 0 ROS2, 1 ROS34PW2
        (:data:`~fibersweep.fiber.integrators.rosw.METHODS`)
    w_reuse : ros2, ros34pw2: accepted steps one W = M J may serve (step.jacobian_reuse)
    pi_control : ros2, ros34pw2: PI step-size controller (step.controller == "pi")
    excl_gap : bead-spring self-exclusion: beads |i − j| >= excl_gap repel (0: off;
        :mod:`fibersweep.fiber.models.exclusion`)
    excl_cut, excl_eq, excl_fref : its cutoff χ·2a [µm], r_eq = 2a [µm] and pair force
        scale [pN]: the pillar contact's F_ref times (b/2a)²
        (:mod:`fibersweep.fiber.models.spacing`)
    half_b : half the bead spacing, b/2 [µm]: the elastic energy's length scale (a for the
        touching chain; :mod:`fibersweep.fiber.models.spacing`)
    """

    a: float
    mu: float
    max_disp: float
    contact_disp: float
    dt_max: float
    dt: float
    t_max: float
    x_stop: float
    t_stop: float
    mode: int
    trap_speed: float
    trap_time: float
    stopped_implicit: bool
    y_lo: float
    y_hi: float
    stretch: float
    bend: float
    tol: float = math.nan
    rosw: int = 0
    w_reuse: int = 1
    pi_control: bool = False
    excl_gap: int = 0
    excl_cut: float = math.nan
    excl_eq: float = math.nan
    excl_fref: float = math.nan
    half_b: float = math.nan


class Work(NamedTuple):
    """Scratch buffers of every integrator (n beads).

    ``x, y`` bead centres [µm], ``u`` (n, 2) background velocities [µm/s],
    ``fx, fy`` forces [pN] (rigid: contact; bead-spring: total), ``st`` contact
    stiffness [pN/µm], ``dist`` distance to the pillar [µm]. (An effect's own
    scratch lives in its kernel record.)
    """

    x: np.ndarray
    y: np.ndarray
    u: np.ndarray
    fx: np.ndarray
    fy: np.ndarray
    st: np.ndarray
    dist: np.ndarray


class BeadWork(NamedTuple):
    """Scratch buffers of the bead-spring integrators (empty for rigid).

    ``cfx, cfy`` contact forces [pN], ``gx, gy`` Jacobian scratch, ``f`` (2n)
    bead velocities [µm/s], ``mob, jac, lhs`` (2n, 2n) mobility, force Jacobian
    and system matrix, ``rhs, qs, v`` (2n) right-hand side, extrapolated
    positions and velocities.
    """

    cfx: np.ndarray
    cfy: np.ndarray
    gx: np.ndarray
    gy: np.ndarray
    f: np.ndarray
    mob: np.ndarray
    jac: np.ndarray
    lhs: np.ndarray
    rhs: np.ndarray
    qs: np.ndarray
    v: np.ndarray


class Kernel(NamedTuple):
    """All inputs of an integrator for one run (``frame``: a :mod:`.frame` record)."""

    flow: FlowArrays
    pillar: PillarArrays
    body: BodyArrays
    params: Params
    work: Work
    bead: BeadWork
    effects: tuple
    frame: tuple = CHANNEL


def _work(n: int) -> Work:
    return Work(
        *(np.zeros(n) for _ in range(2)),
        np.zeros((n, 2)),
        *(np.zeros(n) for _ in range(4)),
    )


def _bead_work(n: int) -> BeadWork:
    """Buffers for n beads (n = 0: the empty set a rigid run carries)."""
    m = 2 * n
    return BeadWork(
        *(np.zeros(n) for _ in range(4)),
        np.zeros(m),
        *(np.zeros((m, m)) for _ in range(3)),
        *(np.zeros(m) for _ in range(3)),
    )


def make_params(
    st: FiberSettings,
    *,
    mu: float,
    u_center: float,
    x_stop: float,
    y_lo: float,
    y_hi: float,
    random: bool,
    mode: int = 0,
    t_stop: float = math.nan,
) -> Params:
    """The scalars of a run from its settings and what its geometry fixes.

    Parameters
    ----------
    st : FiberSettings
    mu : float
        Viscosity [pN s/µm²].
    u_center : float
        Signed centreline speed of the field [µm/s] (sets the trap speed).
    x_stop : float
        Mode 0 stops when the rearmost end passes this x [µm].
    y_lo, y_hi : float
        Bead centres must stay between these [µm] (±inf: no side walls).
    random : bool
        Whether an effect draws random increments (no implicit stopped steps then).
    mode, t_stop : int, float
        See :func:`build_kernel`.
    """
    a = float(st.bead_radius)
    integrator = st.resolved_integrator
    fixed = integrator == "bdf2"
    dt = st.step.dt if st.step.dt is not None else (DEFAULT_DT if fixed else math.nan)
    ros2 = integrator in ROSENBROCK
    excl = st.self_exclusion and st.model == "bead-spring"
    frac = st.bead_spacing
    elastic = rod(st.young_modulus, a)
    return Params(
        a=a,
        mu=mu,
        max_disp=float(st.step.ros2_max_displacement if ros2 else st.step.max_displacement),
        contact_disp=float(
            st.step.ros2_contact_displacement if ros2 else st.step.contact_displacement
        ),
        dt_max=st.classify.trap_time / 20.0,
        dt=float(dt),
        t_max=float(st.step.t_max),
        x_stop=x_stop,
        t_stop=float(t_stop),
        mode=int(mode),
        trap_speed=st.classify.trap_speed * abs(u_center),
        trap_time=float(st.classify.trap_time),
        # Brownian increments scale with the step: keep the short explicit steps then
        stopped_implicit=bool(st.step.stopped_implicit and not random),
        y_lo=y_lo,
        y_hi=y_hi,
        stretch=elastic.stretch,  # EA [pN]: E [Pa == pN/µm²], a [µm]
        bend=elastic.bend,  # EI [pN µm²]
        tol=float(st.step.tolerance),
        rosw=METHODS.get(integrator, 0),
        w_reuse=int(st.step.jacobian_reuse),
        pi_control=st.step.controller == "pi",
        excl_gap=exclusion_gap(frac) if excl else 0,
        excl_cut=st.contact.cutoff(2.0 * a),
        excl_eq=2.0 * a,
        excl_fref=contact_force_scale(st.contact, mu, a, u_center) * exclusion_force_scale(frac),
        half_b=0.5 * spacing_um(a, frac),
    )


def assemble(
    st: FiberSettings,
    n: int,
    flow: FlowArrays,
    pillar: PillarArrays,
    params: Params,
    kernel_effects: tuple,
    frame: tuple = CHANNEL,
) -> Kernel:
    """A Kernel of ``n`` beads: body mobility, work buffers and the effects' tuple added."""
    bm = body_mobility(n, params.a, params.mu)
    body = BodyArrays(bm.offsets.copy(), bm.P.copy(), bm.N.copy(), bm.chol.copy(), bm.tip_mobility)
    beads = st.model == "bead-spring"
    return Kernel(
        flow,
        pillar,
        body,
        params,
        _work(n),
        _bead_work(n if beads else 0),
        kernel_effects + (BASELINE,),
        frame,
    )


def build_kernel(setup: Setup, mode: int = 0, t_stop: float = math.nan) -> Kernel:
    """Every kernel input of a channel run: the one place they are assembled.

    Parameters
    ----------
    setup : Setup
        The validated run (:func:`fibersweep.fiber.setup.prepare`).
    mode : {0, 1}
        0: stop past the pillar; 1: stop at ``t_stop`` [s].
    t_stop : float
        Stop time of mode 1 [s].
    """
    st = setup.settings
    field = setup.field
    geo = field.geometry
    a = float(st.bead_radius)
    params = make_params(
        st,
        mu=float(field.fluid.viscosity),
        u_center=setup.u_center,
        x_stop=setup.pillar.x_max + st.step.x_end,
        y_lo=a,
        y_hi=geo.width - a,
        random=setup.effects.random,
        mode=mode,
        t_stop=t_stop,
    )
    flow = FlowArrays(
        np.ascontiguousarray(field.ux, dtype=np.float64),
        np.ascontiguousarray(field.uy, dtype=np.float64),
        float(field.dx),
    )
    flow = setup.effects.sample_flow(flow, a)
    return assemble(st, setup.n, flow, setup.pillar.arrays(), params, setup.kernel_effects)

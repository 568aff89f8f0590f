"""Kernel hooks of the dynamic effects: compile-time dispatch on the effect's record type.

An effect that acts inside the Numba integrators hands them a small record
(a ``typing.NamedTuple`` of floats, plus any scratch arrays it needs: its
*kernel record*) and implements one or
more of the stages below for that record type with :func:`implements`. The
integrators receive the run's records as a tuple (``Kernel.effects``) and, at
each stage, call its ``each_`` form (``each_background(effects, w, u)``, ...): at
compile time it becomes one call per record, in the tuple's order, each
resolving (through ``numba.extending.overload``) to the record's implementation
or, when it has none, to nothing. So the integrators are
compiled once per *set* of active effects (Numba caches one specialisation per
tuple type, in memory and on disk), and an effect that is off is not in the
tuple: it costs nothing, not even a branch.

Stages (arguments are the run's bundles, :mod:`fibersweep.fiber.kernel.bundles`:
``body`` BodyArrays, ``w`` Work (bead positions ``w.x, w.y``,
background velocities ``w.u``, forces, distances ``w.dist``, scratch), ``bw``
BeadWork (bead-spring buffers)):

``background(e, w, u)``
    Both models, after interpolation and contact: change the beads' background
    velocities ``u`` (n, 2) [µm/s] in place (``w.x, w.y`` hold the bead positions,
    e.g. for a second field read where ``u`` was read).
``rigid_mobility(e, body, w, c, sn, vbx, vby, om, nm_eff)`` -> ``(vbx, vby, om, nm_eff)``
    Rigid model: change the body velocity (body frame) by a change of mobility
    (c, sn: cos and sin of the fiber angle, from the lab frame to the body's);
    return the mobility ``nm_eff`` (3, 3) the later stages must use.
``rigid_contact(e, body, w, c, sn, any_c, vbx, vby, om, nm_eff)`` -> ``(vbx, vby, om)``
    Rigid model: change the body velocity by extra contact forces (``w.fx, fy``
    hold the contact forces; c, sn: cos and sin of the fiber angle).
``rigid_noise(e, body, dt, c, sn, xc, yc, th)`` -> ``(xc, yc, th)``
    Rigid model, after each step of length ``dt`` [s]: random increments.
``bead_forces(e, body, w, bw, any_c)``
    Bead-spring model, before the mobility is applied: add forces to the total
    forces ``w.fx, fy`` [pN] (``bw.cfx, cfy`` hold the contact forces, ``bw.f``
    the background velocities).
``bead_mobility(e, w, bw)``
    Bead-spring model: change the mobility ``bw.mob`` (2n, 2n) and the
    background velocities ``bw.f`` (2n) in place.

Only bundles, never the whole ``Kernel``, go to stages and inner kernels: a
call copies its arguments, and a big bundle costs time on every call (the
stage functions that do nothing are compiled away).

Stage implementations are plain Python functions (Numba compiles them into the
integrator) with the stage's signature.

Numba's disk cache (``cache=True``) checks only the file of the cached
integrator, not the files of what it calls (true of every cross-module call,
e.g. ``contact.pillar_forces``), and its index stores the record types by
module. :mod:`fibersweep.numba_cache` therefore drops the kernel caches
whenever any source file of ``fiber`` or ``flow`` changed (checked on import),
so an edited stage or a renamed effect module is compiled afresh. Kernel records
must still be
defined in ``fibersweep.fiber.effects`` modules, which are always imported.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import NamedTuple

from numba.extending import overload

__all__ = [
    "BASELINE",
    "STAGES",
    "Baseline",
    "background",
    "bead_forces",
    "bead_mobility",
    "each_background",
    "each_bead_forces",
    "each_bead_mobility",
    "each_rigid_contact",
    "each_rigid_mobility",
    "each_rigid_noise",
    "implements",
    "rigid_contact",
    "rigid_mobility",
    "rigid_noise",
    "stages_of",
]

STAGES = (
    "background",
    "rigid_mobility",
    "rigid_contact",
    "rigid_noise",
    "bead_forces",
    "bead_mobility",
)

_IMPLS: dict[tuple[str, type], Callable] = {}
_RECORD_PACKAGE = "fibersweep.fiber.effects."


class Baseline(NamedTuple):
    """The record every effect tuple ends with; it implements no stage."""


BASELINE = Baseline()


def implements(stage: str, record: type) -> Callable[[Callable], Callable]:
    """Decorator: the function is ``stage`` for effects whose kernel record is ``record``."""
    if stage not in STAGES:
        raise ValueError(f"unknown kernel stage {stage!r}; stages: {', '.join(STAGES)}")

    def deco(fn: Callable) -> Callable:
        want = list(inspect.signature(globals()[stage]).parameters)
        got = list(inspect.signature(fn).parameters)
        if got != want:
            raise TypeError(
                f"{fn.__qualname__}: stage {stage!r} takes ({', '.join(want)}), "
                f"got ({', '.join(got)})"
            )
        if not record.__module__.startswith(_RECORD_PACKAGE):
            raise TypeError(
                f"{record.__qualname__}: kernel records must be defined in a module of "
                f"{_RECORD_PACKAGE.rstrip('.')} (Numba's disk cache stores their type by "
                f"module, and an index naming a module that is missing cannot be read)"
            )
        if (stage, record) in _IMPLS and _IMPLS[(stage, record)] is not fn:
            raise TypeError(f"{record.__name__} implements {stage!r} twice")
        _IMPLS[(stage, record)] = fn
        return fn

    return deco


def stages_of(record: type) -> frozenset[str]:
    """The stages implemented for kernel records of type ``record``."""
    return frozenset(stage for stage, rec in _IMPLS if rec is record)


def _impl(stage: str, e, noop: Callable) -> Callable:
    # Numba requires the implementation's argument names to be the stub's.
    return _IMPLS.get((stage, getattr(e, "instance_class", None)), noop)


# Stubs: callable only inside Numba kernels, where they resolve per record type.


def background(e, w, u):
    """Both models: change the background velocities ``u`` (n, 2) in place."""
    raise NotImplementedError("kernel stage: call from a Numba kernel")


def rigid_mobility(e, body, w, c, sn, vbx, vby, om, nm_eff):
    """Rigid model: ``(vbx, vby, om, nm_eff)`` after a change of mobility."""
    raise NotImplementedError("kernel stage: call from a Numba kernel")


def rigid_contact(e, body, w, c, sn, any_c, vbx, vby, om, nm_eff):
    """Rigid model: ``(vbx, vby, om)`` after extra contact forces."""
    raise NotImplementedError("kernel stage: call from a Numba kernel")


def rigid_noise(e, body, dt, c, sn, xc, yc, th):
    """Rigid model: ``(xc, yc, th)`` after the step's random increments."""
    raise NotImplementedError("kernel stage: call from a Numba kernel")


def bead_forces(e, body, w, bw, any_c):
    """Bead-spring model: add forces to ``w.fx, fy``."""
    raise NotImplementedError("kernel stage: call from a Numba kernel")


def bead_mobility(e, w, bw):
    """Bead-spring model: change ``bw.mob`` and ``bw.f`` in place."""
    raise NotImplementedError("kernel stage: call from a Numba kernel")


def _keep_mobility(e, body, w, c, sn, vbx, vby, om, nm_eff):
    return vbx, vby, om, nm_eff


def _keep_velocity(e, body, w, c, sn, any_c, vbx, vby, om, nm_eff):
    return vbx, vby, om


def _keep_pose(e, body, dt, c, sn, xc, yc, th):
    return xc, yc, th


def _keep_background(e, w, u):
    return None


def _keep_beads(e, w, bw):
    return None


def _keep_forces(e, body, w, bw, any_c):
    return None


@overload(background, inline="always")
def _ov_background(e, w, u):
    return _impl("background", e, _keep_background)


@overload(rigid_mobility, inline="always")
def _ov_rigid_mobility(e, body, w, c, sn, vbx, vby, om, nm_eff):
    return _impl("rigid_mobility", e, _keep_mobility)


@overload(rigid_contact, inline="always")
def _ov_rigid_contact(e, body, w, c, sn, any_c, vbx, vby, om, nm_eff):
    return _impl("rigid_contact", e, _keep_velocity)


@overload(rigid_noise, inline="always")
def _ov_rigid_noise(e, body, dt, c, sn, xc, yc, th):
    return _impl("rigid_noise", e, _keep_pose)


@overload(bead_forces, inline="always")
def _ov_bead_forces(e, body, w, bw, any_c):
    return _impl("bead_forces", e, _keep_forces)


@overload(bead_mobility, inline="always")
def _ov_bead_mobility(e, w, bw):
    return _impl("bead_mobility", e, _keep_beads)


# Every stage over the run's whole effect tuple, in order. A loop over the tuple
# (``numba.literal_unroll``) copies each record into the loop variable on every pass, and
# each copy counts a reference to every array the record holds (about 0.5 µs a velocity
# evaluation for a record of nine arrays); the chain below indexes the tuple with
# constants in straight-line code, which Numba's reference-count pruning removes.

#: What each stage hands on to the next record's call (its return value).
_THREADED = {
    "background": (),
    "rigid_mobility": ("vbx", "vby", "om", "nm_eff"),
    "rigid_contact": ("vbx", "vby", "om"),
    "rigid_noise": ("xc", "yc", "th"),
    "bead_forces": (),
    "bead_mobility": (),
}
_CHAINS: dict[tuple[str, int], Callable] = {}


def _chain(stage: str, n: int) -> Callable:
    """``stage`` for effects[0], then effects[1], ... (n of them), its results threaded."""
    key = (stage, n)
    if key not in _CHAINS:
        args = ", ".join(list(inspect.signature(globals()[stage]).parameters)[1:])
        out = ", ".join(_THREADED[stage])
        lines = [f"def chain(effects, {args}):"]
        for i in range(n):
            call = f"{stage}(effects[{i}], {args})"
            lines.append(f"    {out} = {call}" if out else f"    {call}")
        lines.append(f"    return {out}" if out else "    return None")
        scope: dict = {stage: globals()[stage]}
        exec("\n".join(lines), scope)  # noqa: S102 - source built above from stage names only
        _CHAINS[key] = scope["chain"]
    return _CHAINS[key]


def each_background(effects, w, u):
    """:func:`background` of every record of ``effects``, in order."""
    raise NotImplementedError("kernel stage: call from a Numba kernel")


def each_rigid_mobility(effects, body, w, c, sn, vbx, vby, om, nm_eff):
    """:func:`rigid_mobility` of every record, each given the last one's result."""
    raise NotImplementedError("kernel stage: call from a Numba kernel")


def each_rigid_contact(effects, body, w, c, sn, any_c, vbx, vby, om, nm_eff):
    """:func:`rigid_contact` of every record, each given the last one's velocity."""
    raise NotImplementedError("kernel stage: call from a Numba kernel")


def each_rigid_noise(effects, body, dt, c, sn, xc, yc, th):
    """:func:`rigid_noise` of every record, each given the last one's pose."""
    raise NotImplementedError("kernel stage: call from a Numba kernel")


def each_bead_forces(effects, body, w, bw, any_c):
    """:func:`bead_forces` of every record, in order."""
    raise NotImplementedError("kernel stage: call from a Numba kernel")


def each_bead_mobility(effects, w, bw):
    """:func:`bead_mobility` of every record, in order."""
    raise NotImplementedError("kernel stage: call from a Numba kernel")


@overload(each_background, inline="always")
def _ov_each_background(effects, w, u):
    return _chain("background", len(effects))


@overload(each_rigid_mobility, inline="always")
def _ov_each_rigid_mobility(effects, body, w, c, sn, vbx, vby, om, nm_eff):
    return _chain("rigid_mobility", len(effects))


@overload(each_rigid_contact, inline="always")
def _ov_each_rigid_contact(effects, body, w, c, sn, any_c, vbx, vby, om, nm_eff):
    return _chain("rigid_contact", len(effects))


@overload(each_rigid_noise, inline="always")
def _ov_each_rigid_noise(effects, body, dt, c, sn, xc, yc, th):
    return _chain("rigid_noise", len(effects))


@overload(each_bead_forces, inline="always")
def _ov_each_bead_forces(effects, body, w, bw, any_c):
    return _chain("bead_forces", len(effects))


@overload(each_bead_mobility, inline="always")
def _ov_each_bead_mobility(effects, w, bw):
    return _chain("bead_mobility", len(effects))

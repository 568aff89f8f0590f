"""Record or compare reference fiber runs (rigid and bead-spring, each effect on and off).

Usage:
    python scripts/tools/fiber_reference.py record OUT.npz [--cache DIR]
    python scripts/tools/fiber_reference.py compare OUT.npz [--cache DIR]

Runs a fixed handful of fibers on the cached dx = 4 µm test flow field
(``FIBERSWEEP_TEST_CACHE`` or ``.fibersweep-cache/tests``): contact and no
contact, rough and smooth pillar, every registered effect at a non-zero value,
forward, reversible and fixed-duration runs. ``record`` saves each run's
scalar results and its full trajectory (all beads); ``compare`` reruns them and
prints, per case, the class and the largest absolute difference of every
array, then the overall maximum. A refactoring of the kernels must keep the
classes and the trajectories (bit-identical, or equal to float rounding).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate, simulate_for, simulate_reversible

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from common import DEFAULT_CACHE, study_field  # noqa: E402  (scripts/studies/common.py)

REC = {"trajectories": True, "samples": 100_000, "all_beads": True}
VAULT = FiberStart(-3.7, 0.373, 0.82)
TRAP = FiberStart(8.0, 0.351, 0.75)
APEX = FiberStart(5.0, 0.40, 1.0)
SHORT = FiberStart(8.0, 0.351, 0.5)
SOFT = FiberStart(0.0, 0.33, 2.0)
SOFT_LOW = FiberStart(0.0, 0.30, 2.0)
E_SOFT = {"young_modulus": 1e4}
SMOOTH = {"contact": {"pillar": "smooth"}}
ROS3 = {"step": {"rosenbrock": "ros34pw2"}}

# name -> (kind, model, start, settings overrides, rng seed[, duration of a "for" run [s]])
# (the bead-spring models by their legacy names, which every version accepts)
CASES = {
    "rigid_free": ("run", "rigid", FiberStart(0.0, 0.8, 1.0), {}, None),
    "rigid_vault": ("run", "rigid", VAULT, {}, None),
    "rigid_vault_smooth": ("run", "rigid", VAULT, {"contact": {"pillar": "smooth"}}, None),
    "rigid_trap_friction": ("run", "rigid", TRAP, {"effects": {"friction": 0.3}}, None),
    "rigid_vault_friction_smooth": (
        "run",
        "rigid",
        VAULT,
        {"effects": {"friction": 0.3}, "contact": {"pillar": "smooth"}},
        None,
    ),  # fmt: skip
    "rigid_apex_hydro": ("run", "rigid", APEX, {"effects": {"pillar_hydro": 1.0}}, None),
    "rigid_apex_hydro_friction": (
        "run",
        "rigid",
        APEX,
        {"effects": {"pillar_hydro": 1.0, "friction": 0.3}},
        None,
    ),  # fmt: skip
    "rigid_apex_midplane": ("run", "rigid", APEX, {"effects": {"off_midplane": 0.2}}, None),
    "rigid_apex_brownian": ("run", "rigid", APEX, {"effects": {"brownian": 1.0}}, 7),
    "rigid_apex_inlet": ("run", "rigid", APEX, {"effects": {"inlet_speed": 0.1}}, None),
    "rigid_apex_scale": ("run", "rigid", APEX, {"effects": {"pillar_scale": 0.05}}, None),
    "rigid_apex_noise": ("run", "rigid", APEX, {"effects": {"start_noise": 1.0}}, 3),
    "rigid_reversible": ("rev", "rigid", VAULT, {}, None),
    "rigid_for": ("for", "rigid", APEX, {}, None),
    "bs_short_contact": ("run", "bead-spring", SHORT, {"x0": 1100.0}, None),
    "bs_short_friction": (
        "run",
        "bead-spring",
        SHORT,
        {"x0": 1100.0, "effects": {"friction": 0.3}},
        None,
    ),  # fmt: skip
    "bs_short_hydro": (
        "run",
        "bead-spring",
        SHORT,
        {"x0": 1100.0, "effects": {"pillar_hydro": 1.0}},
        None,
    ),  # fmt: skip
    "bs_short_midplane_smooth": (
        "run",
        "bead-spring",
        SHORT,
        {"x0": 1100.0, "effects": {"off_midplane": 0.2}, "contact": {"pillar": "smooth"}},
        None,
    ),  # fmt: skip
    "bs_for": ("for", "bead-spring", APEX, {"x0": 1000.0}, None),
    "ros2_short_hydro_friction": (
        "run",
        "bead-spring-ros2",
        SHORT,
        {"x0": 1100.0, "effects": {"pillar_hydro": 1.0, "friction": 0.3}},
        None,
    ),  # fmt: skip
    "ros34_short_smooth": (
        "run",
        "bead-spring-ros2",
        SHORT,
        {"x0": 1100.0, "contact": {"pillar": "smooth"}, "step": {"rosenbrock": "ros34pw2"}},
        None,
    ),  # fmt: skip
    # A soft fiber (10 kPa, 43 beads) bent over the apex: its self-exclusion pairs act.
    "ros2_soft_rough": ("run", "bead-spring-ros2", SOFT, {"x0": 1060.0, **E_SOFT}, None),
    "ros2_soft_smooth": ("run", "bead-spring-ros2", SOFT, {"x0": 1060.0, **E_SOFT, **SMOOTH}, None),
    "ros2_soft_low": ("run", "bead-spring-ros2", SOFT_LOW, {"x0": 1060.0, **E_SOFT}, None),
    "ros34_soft_rough": ("run", "bead-spring-ros2", SOFT, {"x0": 1060.0, **E_SOFT, **ROS3}, None),
    "ros34_soft_smooth": (
        "run",
        "bead-spring-ros2",
        SOFT,
        {"x0": 1060.0, **E_SOFT, **ROS3, **SMOOTH},
        None,
    ),  # fmt: skip
    "bdf2_soft_rough": ("for", "bead-spring", SOFT, {"x0": 1060.0, **E_SOFT}, None, 0.8),
    "bdf2_soft_smooth": ("for", "bead-spring", SOFT, {"x0": 1060.0, **E_SOFT, **SMOOTH}, None, 0.8),
}
SCALARS = ("delta", "t_end", "x_f", "y_f", "theta_f", "t_contact", "t_pass", "min_clearance")


def run_case(field, kind, model, start, over, seed, duration=0.3) -> dict[str, np.ndarray]:
    """One case's arrays: scalars, class and the full trajectory."""
    st = FiberSettings(model=model, record=REC, **over)
    out: dict[str, np.ndarray] = {}
    if kind == "for":
        tr, reason = simulate_for(field, st, start, duration, rng_seed=seed)
        out["reason"] = np.array(reason)
    else:
        if kind == "rev":
            r, err = simulate_reversible(field, st, start, rng_seed=seed)
            out["return_error"] = np.array(err)
        else:
            r = simulate(field, st, start, rng_seed=seed)
        out["cls"] = np.array(r.cls)
        out["status"] = np.array(r.status)
        out["n_steps"] = np.array(r.n_steps)
        for k in SCALARS:
            out[k] = np.array(getattr(r, k))
        tr = r.trajectory
    for k, v in tr.columns().items():
        out["traj_" + k] = np.asarray(v)
    if tr.beads is not None:
        out["traj_beads"] = tr.beads
        out["min_self_distance"] = np.array(_min_self(tr.beads))
    return out


def _min_self(beads: np.ndarray) -> float:
    """Smallest distance [µm] of beads |i − j| >= 2 apart over the run (pairs act below χ 2a)."""
    i, j = np.triu_indices(beads.shape[1], k=2)
    return float(np.linalg.norm(beads[:, i] - beads[:, j], axis=-1).min()) if i.size else math.inf


def _diff(a: np.ndarray, b: np.ndarray) -> float:
    if a.dtype.kind in "US" or b.dtype.kind in "US":
        return 0.0 if np.array_equal(a, b) else math.inf
    if a.shape != b.shape:
        return math.inf
    a = a.astype(float)
    b = b.astype(float)
    same_nan = np.isnan(a) & np.isnan(b)
    d = np.where(same_nan, 0.0, np.abs(a - b))
    return float(np.nanmax(np.where(np.isnan(d), math.inf, d))) if d.size else 0.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("action", choices=("record", "compare"))
    ap.add_argument("path", type=Path)
    ap.add_argument("--cache", default=DEFAULT_CACHE)
    ap.add_argument("--only", nargs="*", help="case names (default: all)")
    args = ap.parse_args()
    field = study_field(args.cache)
    names = args.only or list(CASES)
    if args.action == "record":
        data = {}
        for name in names:
            for k, v in run_case(field, *CASES[name]).items():
                data[f"{name}/{k}"] = v
            print(f"recorded {name}: {data.get(f'{name}/cls', '')}", flush=True)
        np.savez_compressed(args.path, **data)
        return
    ref = np.load(args.path)
    worst = 0.0
    for name in names:
        got = run_case(field, *CASES[name])
        case_max = 0.0
        worst_key = ""
        for k, v in got.items():
            d = _diff(ref[f"{name}/{k}"], v)
            if d > case_max:
                case_max, worst_key = d, k
        cls = got.get("cls", got.get("reason"))
        same_cls = str(ref.get(f"{name}/cls", ref.get(f"{name}/reason"))) == str(cls)
        beads = (f"  max|Δ beads| {_diff(ref[f'{name}/traj_beads'], got['traj_beads']):.3e}"
                 f" (min self-distance {float(got['min_self_distance']):.2f} µm)"
                 if "traj_beads" in got else "")  # fmt: skip
        print(f"{name:30s} class {cls!s:14s} same={same_cls}  max|diff| {case_max:.3e} "
              f"{worst_key}{beads}")  # fmt: skip
        worst = max(worst, case_max)
    print(f"overall max |difference| = {worst:.3e}")


if __name__ == "__main__":
    main()

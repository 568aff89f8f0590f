"""What moves the separatrix by the source's offset: its numerics, the fiber's thickness.

Every field is the full channel at dx = 4 µm with a dx = 2 µm patch around the
pillar (the source's resolution; flow/patch.py, validated in docs/validation/flow.md),
read from or stored in ``--cache``. Per candidate it prints the far-upstream
separatrix (traced and by flux, h_obs) and its shift from the model's field
(TRT, sub-grid pillar), and with ``--examples`` the classes of the source's two
worked examples at their quoted starts (paper.yaml's fiber settings).

Candidates:

* the source's lattice: BGK, staircase pillar, τ in ``--taus``, and the pillar
  moved by fractions of the 2 µm cell (``--shifts``, µm, across and along the flow);
* the source's plain forcing term w_i f·e_i/c_s² with no half-force shift: for a
  uniform force and Stokes flow it evolves the same populations as the Guo term
  to first order in the force (the two differ by terms of order u·f), and its
  velocity Σ e_i f_i is the physical one minus f/2: the field less f/2 on fluid nodes;
* the fiber's thickness across the depth: the velocity averaged over the bead's
  cross-section (a disk of radius a about the midplane) or over its volume,
  instead of the IB kernel's z-average, from the patch's 3D solution
  (u = c0 − c2 ζ² through the two nodes nearest the midplane).

With ``band`` first, it prints instead where the two worked examples change class:
for each (θ0, L) of the examples, the class per y0/h_obs over ``--y0`` (paper.yaml's
fiber settings) on ``model`` (the patch field, TRT, sub-grid pillar), ``source`` (BGK
τ = 1, staircase pillar), ``source+plain`` (that field as the plain forcing term
reports it), ``model+hydro`` (``fiber.effects.pillar_hydro`` = ``--hydro``, the
source's ~10 % slowing) and, with ``--thickness``, ``model+disk`` (the field averaged
over the bead's cross-section). Its fields come from ``--cache`` (the default mode
stores them there).

Usage: python3 scripts/studies/fidelity/offset_study.py [--taus 0.8 1 1.5] [--shifts 0.5 1]
       [--axes y] [--examples]
       python3 scripts/studies/fidelity/offset_study.py band [--y0 0.30 0.31 ...] [--hydro 0.4]
       [--thickness]
"""

from __future__ import annotations

import argparse
import logging
import sys
import time

import numpy as np

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.analysis import flux_separatrix
from fibersweep.flow.cache import get_flow_field
from fibersweep.flow.field import FlowField
from fibersweep.flow.lbm import solve_nested
from fibersweep.flow.patch import compose, depth_factor, solve_patch_lattice
from fibersweep.flow.solver import field_from_solution
from fibersweep.flow.streamlines import separatrix_y

EXAMPLES = ((-3.7, 0.373, 0.82), (8.0, 0.351, 0.75))  # the source's (θ0, y0/h, L/l_obs)


def settings_of(**kw) -> FlowSettings:
    """Channel dx = 4 µm, patch dx = 2 µm (default margin), with ``kw`` overrides."""
    geo = kw.pop("geometry", {})
    return FlowSettings.model_validate({"dx": 4.0, "patch": {"dx": 2.0}, "geometry": geo, **kw})


def measure(field: FlowField) -> tuple[float, float]:
    return separatrix_y(field), flux_separatrix(field).y_far_over_h


def plain_forcing(field: FlowField) -> FlowField:
    """The field as the plain forcing term reports it: ux − f/2 on fluid nodes."""
    half = 0.5 * field.meta["report"]["force"] * field.meta["scale_um_per_s_per_lattice"]
    ux = np.where(field.solid, field.ux, field.ux - half)
    return FlowField(ux, np.asarray(field.uy), field.dx, field.geometry, field.fluid,
                     field.solid, {**field.meta, "plain_forcing_shift": half})  # fmt: skip


def thickness_fields(settings: FlowSettings, radius: float) -> dict[str, FlowField]:
    """Midplane fields of the model's patch sampled as a point, a disk and a ball of ``radius``."""
    channel = settings.model_copy(update={"patch": None})
    coarse = solve_nested(channel)
    coarse_field = field_from_solution(channel, coarse)
    sol, box, pgeom = solve_patch_lattice(settings, coarse)
    g = sol.grid
    k1 = g.nz_full // 2 - 1  # ζ = 1/2 (lattice units) below the midplane; k1 - 1 at 3/2
    u1, u2 = sol.u[0:2, k1], sol.u[0:2, k1 - 1]
    c0 = (9.0 * u1 - u2) / 8.0  # u = c0 - c2 ζ², ζ in lattice units
    c2 = (u1 - u2) / 2.0
    a = radius / g.dx
    depth = g.nz_full
    scale = coarse_field.meta["scale_um_per_s_per_lattice"]
    out = {}
    # (mean ζ² [lattice²], Hele-Shaw factor of the parabola for the outside)
    for name, zeta2 in (("midplane point", 0.0), (f"disk a={radius:g}", a * a / 4.0),
                        (f"ball a={radius:g}", a * a / 5.0)):  # fmt: skip
        u = (c0 - c2 * zeta2) * scale
        ux, uy = u[0].T.copy(), u[1].T.copy()
        ux[g.solid] = 0.0
        uy[g.solid] = 0.0
        hs = 1.0 - 4.0 * zeta2 / depth**2
        fx, fy, solid = compose(coarse_field, ux, uy, g.solid, box, hs / depth_factor(coarse.grid))
        out[name] = FlowField(fx, fy, box.dx, coarse_field.geometry, coarse_field.fluid, solid,
                              {"source": name})  # fmt: skip
    return out


def examples(field: FlowField, fiber_settings) -> str:
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.run import simulate

    res = [simulate(field, fiber_settings, FiberStart(*s)) for s in EXAMPLES]
    return "; ".join(f"{r.cls}" if r.status == "ok" else f"failed ({r.status})" for r in res)


SHORT = {"Above": "A", "Below": "B", "Trapping": "T", "Pole-vaulting": "PV"}


def band(field, fiber, theta0: float, length: float, y0s: list[float]) -> str:
    """The class of each start (θ0, y0, L) over ``y0s``, abbreviated, in one line."""
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.run import simulate

    out = []
    for y0 in y0s:
        r = simulate(field, fiber, FiberStart(theta0, y0, length))
        out.append(SHORT.get(r.cls, r.cls) if r.status == "ok" else "fail")
    return " ".join(f"{c:>2}" for c in out)


def band_main(argv: list[str]) -> None:
    """``band``: where the worked examples change class, on the model and its candidates."""
    from fibersweep.config.loading import load_config

    ap = argparse.ArgumentParser(prog="offset_study.py band", description=band_main.__doc__)
    default_y0 = [round(0.29 + 0.01 * i, 2) for i in range(10)]
    ap.add_argument("--y0", type=float, nargs="+", default=default_y0)
    ap.add_argument("--hydro", type=float, default=0.4)
    ap.add_argument("--thickness", action="store_true")
    ap.add_argument("--config", default="configs/paper.yaml")
    ap.add_argument("--cache", default=".fibersweep-cache/patch")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    fiber = load_config(args.config).fiber
    hydro = load_config(args.config, [f"fiber.effects.pillar_hydro={args.hydro}"]).fiber
    model, _ = get_flow_field(settings_of(), args.cache)
    src = {"collision": "bgk", "tau": 1.0, "pillar_boundary": "staircase"}
    source, _ = get_flow_field(settings_of(**src), args.cache)
    cases = [("model", model, fiber), ("source", source, fiber),
             ("source+plain", plain_forcing(source), fiber),
             (f"model+hydro {args.hydro:g}", model, hydro)]  # fmt: skip
    if args.thickness:
        disk = [f for n, f in thickness_fields(settings_of(), 2.0).items() if n.startswith("disk")]
        cases.append(("model+disk a=2", disk[0], fiber))
    head = " ".join(f"{y:>4.2f}"[1:] for y in args.y0)
    for theta0, y0q, length in EXAMPLES:
        print(f"theta0 = {theta0:g} deg, L = {length:g} l_obs (source's start y0 = {y0q}); "
              f"class by y0/h:")  # fmt: skip
        print(f"  {'field':<18} {head}")
        for name, field, fs in cases:
            print(f"  {name:<18} {band(field, fs, theta0, length, args.y0)}", flush=True)


def main() -> None:
    if sys.argv[1:2] == ["band"]:
        band_main(sys.argv[2:])
        return
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--taus", type=float, nargs="*", default=[0.8, 1.0, 1.5])
    ap.add_argument("--shifts", type=float, nargs="*", default=[0.5, 1.0, 1.5], help="µm")
    ap.add_argument("--axes", default="y", help="move the pillar along 'x', 'y' or 'xy'")
    ap.add_argument("--radius", type=float, default=2.0, help="bead radius a [µm]")
    ap.add_argument("--no-thickness", action="store_true")
    ap.add_argument("--examples", action="store_true", help="run the two worked examples")
    ap.add_argument("--config", default="configs/paper.yaml", help="fiber settings (examples)")
    ap.add_argument("--cache", default=".fibersweep-cache/patch")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    fiber = None
    if args.examples:
        from fibersweep.config.loading import load_config

        fiber = load_config(args.config).fiber
    base = FlowSettings().geometry.to_geometry().base_center
    source = {"collision": "bgk", "tau": 1.0, "pillar_boundary": "staircase"}
    cands = [("model: TRT, sub-grid pillar", settings_of()),
             ("TRT, staircase", settings_of(pillar_boundary="staircase"))]  # fmt: skip
    for tau in args.taus:
        cands.append((f"BGK tau={tau:g}, staircase", settings_of(**{**source, "tau": tau})))
    for s in args.shifts:
        geo_y = {"pillar_y_base": base[1] + s}
        geo_x = {"pillar_x": base[0] + s}
        if "y" in args.axes:
            cands.append((f"BGK tau=1, staircase, pillar y +{s:g} um",
                          settings_of(**source, geometry=geo_y)))  # fmt: skip
        if "x" in args.axes:
            cands.append((f"BGK tau=1, staircase, pillar x +{s:g} um",
                          settings_of(**source, geometry=geo_x)))  # fmt: skip
    rows = []
    ref = None
    for name, s in cands:
        t0 = time.perf_counter()
        field, _ = get_flow_field(s, args.cache)
        tr, fl = measure(field)
        ex = examples(field, fiber) if fiber is not None else ""
        rows.append((name, tr, fl, time.perf_counter() - t0, ex))
        ref = ref if ref is not None else tr
        print(f"{name:<44} traced {tr:.4f} ({tr - ref:+.4f})  flux {fl:.4f}  {ex}", flush=True)
        if name.startswith("BGK tau=1,") and "pillar" not in name:
            pf = plain_forcing(field)
            tr2, fl2 = measure(pf)
            ex2 = examples(pf, fiber) if fiber is not None else ""
            label = f"  + plain forcing (ux - {pf.meta['plain_forcing_shift']:.3f} um/s)"
            print(f"{label:<44} traced {tr2:.4f} ({tr2 - ref:+.4f})  flux {fl2:.4f}  {ex2}",
                  flush=True)  # fmt: skip
    if not args.no_thickness:
        fields = thickness_fields(settings_of(), args.radius)
        for name, f in fields.items():
            tr, fl = measure(f)
            ex = examples(f, fiber) if fiber is not None else ""
            print(f"{'model, fiber samples ' + name:<44} traced {tr:.4f} ({tr - ref:+.4f})  "
                  f"flux {fl:.4f}  {ex}", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()

"""Grid convergence of the pillar flow: dx = 4, 2, 1 µm, staircase and interpolated pillar.

Two steps, so that the expensive fine solve runs once and on its own:

``solve``  solves one level (nested: coarser grids first, as the CLI does) into the
           content-addressed flow cache and writes ``run-<kind>-dx<dx>.json`` next to
           it: wall time, peak resident memory of the process (getrusage), the load
           average sampled every 10 s while it ran, steps and MLUPS of the finest grid.
``report`` reads the cached levels and prints, per pillar boundary and dx: the
           far-upstream separatrix (traced and by flux), the peak speeds over the
           apex and below the base (/ U_center), the flux below the pillar; then
           the L2 difference of the midplane field between successive levels
           (compared on the coarse nodes, away from the pillar), the observed order
           p = log2(|s4 − s2| / |s2 − s1|) and the Richardson estimate
           s∞ = s1 + (s1 − s2) / (2^p − 1) (and with p = 2, the formal order).

Usage::

    python scripts/studies/flow/convergence.py solve --dx 1 --kind interpolated [--domain small] \
        [--cache DIR]
    python scripts/studies/flow/convergence.py report [--domain small] [--kinds interpolated \
        staircase]

The default cache is ``.fibersweep-cache/convergence`` in the current directory.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import threading
import time
from pathlib import Path

import numpy as np
from scipy.ndimage import binary_dilation

from fibersweep.config.flow import FlowSettings, GeometrySettings
from fibersweep.flow.analysis import (
    flux_below_pillar,
    flux_separatrix,
    peak_speeds,
    stream_function,
)
from fibersweep.flow.cache import cache_key, get_flow_field, load_entry
from fibersweep.flow.streamlines import separatrix_y

DEFAULT_CACHE = Path(".fibersweep-cache/convergence")
LEVELS = (4.0, 2.0, 1.0)


#: Channels: the full one, and a shorter, narrower one (same pillar and depth) whose
#: dx = 1 µm grid (6.4 M cells) is affordable on a shared 2-core machine.
DOMAINS = {
    "spec": GeometrySettings(),
    "small": GeometrySettings(width=400.0, length=800.0),
}


def settings_for(dx: float, kind: str, domain: str = "spec") -> FlowSettings:
    """The ``domain`` channel at ``dx`` with pillar boundary ``kind`` (defaults otherwise)."""
    return FlowSettings(geometry=DOMAINS[domain], dx=dx, pillar_boundary=kind)


def _run_record(cache: Path, dx: float, kind: str, domain: str = "spec") -> Path:
    tag = "" if domain == "spec" else f"{domain}-"
    return cache / f"run-{tag}{kind}-dx{dx:g}.json"


def solve(dx: float, kind: str, cache: Path, domain: str = "spec") -> dict:
    """Solve (or load) one level; record time, memory and load if it was computed."""
    loads: list[float] = []
    stop = threading.Event()

    def sample() -> None:
        while not stop.wait(10.0):
            loads.append(os.getloadavg()[0])

    sampler = threading.Thread(target=sample, daemon=True)
    load0 = os.getloadavg()[0]
    sampler.start()
    t0 = time.perf_counter()
    field, info = get_flow_field(settings_for(dx, kind, domain), cache, mmap=True)
    wall = time.perf_counter() - t0
    stop.set()
    rep = field.meta["report"]
    rec = {
        "dx": dx,
        "kind": kind,
        "domain": domain,
        "hit": info.hit,
        "wall_s": wall,
        "peak_rss_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2,
        "load_start": load0,
        "load_mean": float(np.mean(loads)) if loads else load0,
        "load_max": float(np.max(loads)) if loads else load0,
        "steps": rep["steps"],
        "coarse_steps": rep["coarse_steps"],
        "fine_seconds": rep["seconds"],
        "coarse_seconds": rep["coarse_seconds"],
        "mlups": rep["mlups"],
        "threads": rep["threads"],
        "converged": rep["converged"],
        "residual": rep["residual"],
        "mass_change": rep["mass_change"],
        "cells": int(np.prod(rep["grid"][:3])),
        "cpus": os.cpu_count(),
    }
    if not info.hit:
        _run_record(cache, dx, kind, domain).write_text(json.dumps(rec, indent=1))
    return rec


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("solve")
    s.add_argument("--dx", type=float, required=True)
    s.add_argument("--kind", default="interpolated")
    s.add_argument("--cache", type=Path, default=DEFAULT_CACHE)
    s.add_argument("--domain", choices=sorted(DOMAINS), default="spec")
    r = sub.add_parser("report")
    r.add_argument("--cache", type=Path, default=DEFAULT_CACHE)
    r.add_argument("--kinds", nargs="+", default=["interpolated", "staircase"])
    r.add_argument("--domain", choices=sorted(DOMAINS), default="spec")
    args = ap.parse_args()
    if args.cmd == "solve":
        rec = solve(args.dx, args.kind, args.cache, args.domain)
        print(json.dumps(rec, indent=1))
    else:
        report(args.cache, args.kinds, args.domain)


def measure(field) -> dict:
    """Separatrix (traced, flux), peak speeds, flux fraction below the pillar of one field."""
    above, below = peak_speeds(field)
    psi = stream_function(field)
    i_far = int(np.argmin(np.abs(field.x_nodes - field.geometry.x_far)))
    total = float(psi[i_far, -1])
    return {
        "sep": separatrix_y(field, rounds=5),
        "sep_flux": flux_separatrix(field).y_far_over_h,
        "apex": above,
        "base": below,
        "flux_below": float(flux_below_pillar(field).mean()) / total,
    }


def l2_difference(coarse, fine, margin: int = 2) -> float:
    """Relative L2 difference of (ux, uy) on the coarse nodes, fine averaged 2 x 2 onto them.

    Nodes within ``margin`` coarse nodes of the pillar (where the two grids
    resolve the wall differently by construction) are left out.
    """
    nxc, nyc = coarse.shape
    if fine.shape != (2 * nxc, 2 * nyc):
        raise ValueError(f"levels must differ by 2: {coarse.shape} vs {fine.shape}")

    def restrict(a: np.ndarray) -> np.ndarray:
        return np.asarray(a).reshape(nxc, 2, nyc, 2).mean(axis=(1, 3))

    near = binary_dilation(coarse.solid, np.ones((3, 3), bool), iterations=margin)
    solid_f = restrict(fine.solid.astype(float)) > 0
    keep = ~near & ~solid_f
    du = restrict(fine.ux) - np.asarray(coarse.ux)
    dv = restrict(fine.uy) - np.asarray(coarse.uy)
    num = np.sqrt(np.sum(du[keep] ** 2 + dv[keep] ** 2))
    den = np.sqrt(np.sum(np.asarray(coarse.ux)[keep] ** 2 + np.asarray(coarse.uy)[keep] ** 2))
    return float(num / den)


def richardson(s4: float, s2: float, s1: float) -> tuple[float, float, float]:
    """(observed order p, estimate with p, estimate with p = 2) from three levels (ratio 2).

    p is NaN when the differences change sign (no asymptotic convergence seen).
    """
    d1, d2 = s4 - s2, s2 - s1
    p = math.log2(abs(d1 / d2)) if d1 * d2 > 0 and d2 != 0 else float("nan")
    est_p = s1 + (s1 - s2) / (2.0**p - 1.0) if math.isfinite(p) and p > 0 else float("nan")
    return p, est_p, s1 + (s1 - s2) / 3.0


def report(cache: Path, kinds: list[str], domain: str = "spec") -> None:
    """Print the convergence tables of the cached levels (solves nothing)."""
    rows = {}
    fields = {}
    print(
        f"{'boundary':13s} {'dx':>4s} {'sep/h':>7s} {'flux sep':>8s} {'apex/U':>7s} "
        f"{'base/U':>7s} {'Q below':>8s} {'L2 vs 2dx':>9s} {'steps':>6s} {'wall s':>7s} "
        f"{'load':>5s} {'MLUPS':>6s} {'RSS GB':>6s}"
    )
    for kind in kinds:
        for dx in LEVELS:
            settings = settings_for(dx, kind, domain)
            entry = cache / f"flow-{cache_key(settings)}"
            if not entry.exists():
                print(
                    f"{kind:13s} {dx:4g}  (not computed: python "
                    f"scripts/studies/flow/convergence.py solve --dx {dx:g} --kind {kind} "
                    f"--domain {domain})"
                )
                continue
            field = load_entry(entry, settings, mmap=True, verify=False)
            fields[kind, dx] = field
            m = rows[kind, dx] = measure(field)
            coarse = fields.get((kind, 2 * dx))
            l2 = l2_difference(coarse, field) if coarse is not None else float("nan")
            rec_path = _run_record(cache, dx, kind, domain)
            rec = json.loads(rec_path.read_text()) if rec_path.exists() else {}
            print(
                f"{kind:13s} {dx:4g} {m['sep']:7.4f} {m['sep_flux']:8.4f} {m['apex']:7.4f} "
                f"{m['base']:7.4f} {m['flux_below']:8.5f} {l2:9.2e} "
                f"{field.meta['report']['steps']:6d} {rec.get('wall_s', float('nan')):7.0f} "
                f"{rec.get('load_mean', float('nan')):5.1f} "
                f"{field.meta['report']['mlups']:6.1f} {rec.get('peak_rss_gb', float('nan')):6.2f}",
                flush=True,
            )
    print("observed order p and Richardson estimate (levels 4, 2, 1 µm):")
    for kind in kinds:
        if not all((kind, dx) in rows for dx in LEVELS):
            print(f"{kind:13s} (needs all three levels)")
            continue
        for name in ("sep", "sep_flux", "apex", "base", "flux_below"):
            s4, s2, s1 = (rows[kind, dx][name] for dx in LEVELS)
            p, est_p, est_2 = richardson(s4, s2, s1)
            print(
                f"{kind:13s} {name:10s} p = {p:5.2f}  s_inf(p) = {est_p:.4f}  "
                f"s_inf(p=2) = {est_2:.4f}  |s1 - s_inf(p=2)| = {abs(s1 - est_2):.4f}"
            )


if __name__ == "__main__":
    main()

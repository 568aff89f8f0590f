"""Write the discrepancy report: Markdown, figures, JSON summary and the updated config.

Files written into the output directory (each atomically):

- ``summary.json``: verdict, gaps, ranking, fits, held-out before/after; for scripts;
- ``report.md``: the same for people, with the figures;
- ``phase_before_after.png``: (θ0, y0) phase diagrams of the held-out fibers:
  measured, baseline model, model with the chosen effect;
- ``residual_map.png``: binned per-fiber excess score in (θ0, y0) and (L, y0);
- ``gap_before_after.png``: held-out excess per observable, before and after;
- ``updated_config.yaml`` (named effect) or ``updated_config.<effect>.yaml``
  (each effect of an ambiguous pair): the input config with the effect set.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from fibersweep.atomic import atomic_write
from fibersweep.discrepancy.gap import GapResult, combined_excess
from fibersweep.discrepancy.localise import binned_map
from fibersweep.discrepancy.observables import OBSERVABLES, log_scale, scored
from fibersweep.discrepancy.workflow import DiscrepancyResult
from fibersweep.plots.style import CLASS_STYLE, FAILED_STYLE, save_figure, subplots

__all__ = ["summary", "write_report"]


def _clean(x: Any) -> Any:
    """JSON-safe: NaN/inf -> None, numpy scalars -> Python."""
    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def _gap_dict(g: GapResult | None) -> dict[str, Any]:
    if g is None:
        return {}
    biased = set(g.biased)
    return {
        name: {
            "statistic": o.test.statistic,
            "noise_floor": o.test.null_mean,
            "noise_sd": o.test.null_sd,
            "z": o.test.z,
            "p": o.test.p_value,
            "p_holm": o.p_holm,
            "significant": o.significant,
            "excess": {"mean": o.excess[0], "lo95": o.excess[1], "hi95": o.excess[2]},
            "n": o.test.n,
            "bias_z": list(o.bias_z),
            "bias_p": list(o.bias_p),
            "bias_p_holm": list(o.bias_p_holm),
            "systematic": name in biased,
        }
        for name, o in g.gaps.items()
    }


def summary(res: DiscrepancyResult) -> dict[str, Any]:
    """JSON-ready summary of a workflow result."""
    v = res.verdict
    ho = []
    before = _gap_dict(res.heldout_before)
    for h in res.heldout:
        after = _gap_dict(h.residual)
        shrink = {}
        for name, b in before.items():
            a = after.get(name)
            bm, am = b["excess"]["mean"], a["excess"]["mean"] if a else None
            shrink[name] = (am / bm) if (am is not None and bm is not None and bm > 0) else None
        ho.append(
            {
                "effect": h.name,
                "value": h.value,
                "improvement": dict(zip(("mean", "lo95", "hi95"), h.improvement, strict=True)),
                "p": h.p_value,
                "p_holm": h.p_holm,
                "significant": h.significant,
                "explains": h.explains,
                "gap_after": after,
                "gap_final": _gap_dict(h.final),
                "gap_ratio_after_before": shrink,
            }
        )
    out = {
        "verdict": {
            "kind": v.kind,
            "effects": v.effects,
            "observable": v.observable,
            "region": v.region,
            "text": v.text,
        },
        "n_fibers": len(res.observed),
        "n_heldout": len(res.heldout_rows),
        "observables": list(res.observables),
        "observables_absent": [o for o in scored() if o not in res.observables],
        "alpha": res.settings.alpha,
        "gap": _gap_dict(res.gap),
        "descriptive": res.descriptive,
        "region": {
            "where": res.region.describe(),
            "n": res.region.n,
            "mean_excess": res.region.mean_excess,
            "share": res.region.share,
        },
        "region_by_observable": {k: r.describe() for k, r in res.region_by_observable.items()},
        "signatures": [
            {"effect": s.name, "probe": s.probe, "cosine": s.cosine, "strength": s.strength}
            for s in res.signatures
        ],
        "fits": [
            {
                "effect": f.name,
                "value": f.value,
                "loss": f.loss,
                "loss_baseline": f.loss0,
                "evaluations": [list(e) for e in f.evaluations],
            }
            for f in res.fits
        ],
        "heldout_gap_before": before,
        "heldout": ho,
        "simulations": res.simulations,
        "simulations_planned": res.plan.cost(len(res.observed)),
        "failed_runs": res.failed_runs,
        "seconds": res.seconds,
        "settings": {
            "copies": res.plan.copies,
            "fit_copies": res.plan.fit_copies,
            "candidates": res.plan.candidates,
            "fit_evals": res.plan.fit_evals,
            "seed": res.settings.seed,
            "budget": res.settings.budget,
            "noise": res.settings.noise.as_dict(),
        },
    }
    return _clean(out)


def _fmt(x: Any, spec: str = ".3g") -> str:
    return "–" if x is None else format(x, spec)


def _class_groups(codes: np.ndarray) -> list[tuple[str, dict[str, object], np.ndarray]]:
    """(label, marker style, row mask) per class present, failed runs last (plots/style)."""
    out = []
    for k, name in enumerate(OBSERVABLES["class"].categories):
        mask = codes == k
        if mask.any():
            out.append((name, CLASS_STYLE[name], mask))
    bad = ~np.isfinite(codes)
    if bad.any():
        out.append(("failed", FAILED_STYLE, bad))
    return out


def _figures(res: DiscrepancyResult, out: Path, effect: str | None) -> list[str]:
    import matplotlib
    from matplotlib.lines import Line2D

    made = []
    obs = res.observed
    held = res.heldout_rows
    o_ho = obs.iloc[held].reset_index(drop=True)
    codes = OBSERVABLES["class"].values  # category index, NaN for a failed run
    panels = [
        ("measured", codes(o_ho["class"])),
        ("baseline model", codes(res.baseline_copies[0]["class"])[held]),
    ]
    if effect and effect in res.effect_copies:
        panels.append((f"with {effect}", codes(res.effect_copies[effect][0]["class"])))
    fig, axes = subplots(1, len(panels), figsize=(4.2 * len(panels), 3.8), sharey=True)
    size = (12 + 30 * (o_ho["length"] - 0.4)).to_numpy()
    seen: dict[str, dict[str, object]] = {}
    for ax, (title, codes) in zip(np.atleast_1d(axes), panels, strict=True):
        codes = np.asarray(codes, dtype=np.float64)
        for name, style, mask in _class_groups(codes):
            ax.scatter(
                o_ho["theta0"][mask],
                o_ho["y0"][mask],
                s=size[mask],
                marker=style["marker"],
                color=style["color"],
                edgecolors="0.2" if name != "failed" else None,
                linewidths=0.3,
            )
            seen[name] = style
        ax.set_title(f"{title} (held-out)")
        ax.set_xlabel("θ0 [deg]")
    np.atleast_1d(axes)[0].set_ylabel("y0 / h_obs")
    handles = [
        Line2D([], [], ls="", markersize=6, label=k, **st)  # type: ignore[arg-type]
        for k, st in seen.items()
    ]
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), frameon=False)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    save_figure(fig, out / "phase_before_after.png", dpi=110)
    made.append("phase_before_after.png")

    exc = combined_excess(res.gap, res.weights)
    th, y0, L = (obs[c].to_numpy(dtype=np.float64) for c in ("theta0", "y0", "length"))
    fig, axes = subplots(1, 2, figsize=(9, 3.8))
    for ax, (x, xl) in zip(axes, ((th, "θ0 [deg]"), (L, "L / l_obs")), strict=True):
        xe = np.linspace(np.nanmin(x), np.nanmax(x) + 1e-9, 6)
        ye = np.linspace(np.nanmin(y0), np.nanmax(y0) + 1e-9, 8)
        m, c = binned_map(x, y0, exc, xe, ye)
        lim = np.nanmax(np.abs(m)) if np.isfinite(m).any() else 1.0
        # bins without fibers: grey, not the white of "no excess"
        cmap = matplotlib.colormaps["RdBu_r"].with_extremes(bad="0.85")
        im = ax.pcolormesh(xe, ye, np.ma.masked_invalid(m.T), cmap=cmap, vmin=-lim, vmax=lim)
        ax.set_xlabel(xl)
        ax.set_ylabel("y0 / h_obs")
        fig.colorbar(im, ax=ax, label="mean excess score (weighted)")
    fig.suptitle("Where the measurement sits worse than the model's own copies (grey: no fibers)")
    fig.tight_layout()
    save_figure(fig, out / "residual_map.png", dpi=110)
    made.append("residual_map.png")

    if res.heldout_before is not None and effect:
        h = next((h for h in res.heldout if h.name == effect), None)
        if h is not None:
            names = list(res.heldout_before.gaps)
            # in units of the per-fiber spread of the copies' scores (comparable bars)
            w = [res.weights.get(n, 0.0) for n in names]
            b = [
                np.multiply(res.heldout_before.gaps[n].excess, wn)
                for n, wn in zip(names, w, strict=True)
            ]
            a = [np.multiply(h.residual.gaps[n].excess, wn) for n, wn in zip(names, w, strict=True)]
            x = np.arange(len(names))
            fig, ax = subplots(figsize=(6.5, 3.5))
            for off, vals, lab in ((-0.18, b, "baseline"), (0.18, a, f"with {effect}")):
                mean = np.array([v[0] for v in vals])
                err = np.array([[v[0] - v[1], v[2] - v[0]] for v in vals]).T
                ax.bar(x + off, mean, 0.36, yerr=err, capsize=3, label=lab)
            ax.axhline(0, color="k", lw=0.8)
            ax.set_xticks(x, names)
            ax.set_ylabel("out-of-sample excess score\n/ spread of the copies (95 % CI)")
            ax.legend(frameon=False)
            fig.tight_layout()
            save_figure(fig, out / "gap_before_after.png", dpi=110)
            made.append("gap_before_after.png")
    return made


def _score_text() -> str:
    """How each observable is scored, from the registry."""
    cat = [n for n in scored() if OBSERVABLES[n].categorical]
    logs = [n for n in scored() if OBSERVABLES[n].transform is log_scale]
    on_log = f"; {', '.join(logs)} on a log scale" if logs else ""
    return (
        f"Score: log-loss ({', '.join(cat)}) or fair CRPS (continuous{on_log}) of "
        "each observation against the model's jittered copies. Noise floor: the same score of "
        "the model's own copies (permutation test, Holm-corrected)."
    )


def _markdown(s: dict[str, Any], figures: list[str], configs: list[str]) -> str:
    v = s["verdict"]
    lines = [
        "# Discrepancy report",
        "",
        f"**Verdict: {v['kind']}.** {v['text']}",
        "",
        f"{s['n_fibers']} measured fibers ({s['n_heldout']} scored out of sample: each half "
        "with the effect value fitted on the other half); "
        f"{s['simulations']} simulations ({s['failed_runs']} failed, kept as failures) "
        f"in {s['seconds']:.0f} s; family-wise alpha = {s['alpha']}.",
        "",
        f"Observables used: {', '.join(s['observables'])}. "
        + (
            f"Absent from the measured data, so not tested: {', '.join(s['observables_absent'])}."
            if s["observables_absent"]
            else "Every observable the workflow knows was measured."
        ),
        "",
        "## Gap per observable (all fibers, baseline model)",
        "",
        _score_text(),
        "",
        "| observable | n | score | noise floor | z | p (Holm) | significant | excess [95 % CI] "
        "| signed residual z |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, g in s["gap"].items():
        e = g["excess"]
        lines.append(
            f"| {name} | {g['n']} | {_fmt(g['statistic'], '.4g')} "
            f"| {_fmt(g['noise_floor'], '.4g')} | {_fmt(g['z'], '.2f')} "
            f"| {_fmt(g['p_holm'], '.3g')} | "
            f"{'**yes**' if g['significant'] else 'no'} | {_fmt(e['mean'], '.3g')} "
            f"[{_fmt(e['lo95'], '.3g')}, {_fmt(e['hi95'], '.3g')}] "
            f"| {', '.join(_fmt(z, '.1f') for z in g['bias_z'])}"
            f"{' (**systematic**)' if g['systematic'] else ''} |"
        )
    d = s["descriptive"]
    lines += ["", "Descriptive measures (observed vs the model's copies):", ""]
    if "confusion" in d:
        labels = d["confusion"]["labels"]
        lines += [
            "| observed \\ model | " + " | ".join(labels) + " |",
            "|---" * (len(labels) + 1) + "|",
        ]
        for lab, row in zip(labels, d["confusion"]["counts"], strict=True):
            lines.append(f"| {lab} | " + " | ".join(str(c) for c in row) + " |")
        lines.append("")
    for k, val in d.items():
        if k != "confusion":
            lines.append(f"- {k}: {json.dumps(val)}")
    lines += [
        "",
        "## Where the gap lives",
        "",
        f"Shallow regression tree on the per-fiber excess: largest mean excess in "
        f"**{s['region']['where']}** ({s['region']['n']} fibers, "
        f"{_fmt(100 * (s['region']['share'] or 0), '.0f')} % of the positive excess).",
    ]
    for obs, where in s["region_by_observable"].items():
        lines.append(f"- {obs}: {where}")
    if s["signatures"]:
        lines += [
            "",
            "## Effects ranked by signature",
            "",
            "| effect | probe | cosine with the gap | signature strength |",
            "|---|---|---|---|",
        ]
        for r in s["signatures"]:
            lines.append(
                f"| {r['effect']} | {r['probe']:g} | {r['cosine']:.2f} | {r['strength']:.1f} |"
            )
        lines += [
            "",
            "## Fits (per half) and out-of-sample decision",
            "",
            "| effect | fitted value | held-out improvement [95 % CI] | p (Holm) | explains |",
            "|---|---|---|---|---|",
        ]
        for h in s["heldout"]:
            im = h["improvement"]
            lines.append(
                f"| {h['effect']} | {h['value']:.4g} | {_fmt(im['mean'])} [{_fmt(im['lo95'])}, "
                f"{_fmt(im['hi95'])}] | {_fmt(h['p_holm'])} | {'yes' if h['explains'] else 'no'} |"
            )
        for h in s["heldout"]:
            if h["effect"] not in v["effects"]:
                continue
            lines += [
                "",
                f"### Held-out gap before / after {h['effect']}",
                "",
                "| observable | before [95 % CI] | after [95 % CI] | after/before |",
                "|---|---|---|---|",
            ]
            for name, b in s["heldout_gap_before"].items():
                a = h["gap_after"].get(name, {}).get("excess", {})
                be = b["excess"]
                lines.append(
                    f"| {name} | {_fmt(be['mean'])} [{_fmt(be['lo95'])}, {_fmt(be['hi95'])}] | "
                    f"{_fmt(a.get('mean'))} [{_fmt(a.get('lo95'))}, {_fmt(a.get('hi95'))}] | "
                    f"{_fmt(h['gap_ratio_after_before'].get(name))} |"
                )
    if figures:
        lines += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figures]
    if configs:
        lines += ["", "## Updated model", ""] + [f"- `{c}`" for c in configs]
    return "\n".join(lines) + "\n"


def write_report(
    res: DiscrepancyResult, out_dir: str | Path, config_data: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Write every report file into ``out_dir``; returns the JSON summary.

    Parameters
    ----------
    config_data : dict, optional
        The input config as a plain mapping (``Config.model_dump(mode='json')``);
        the updated config(s) are this with ``fiber.effects`` set.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    s = summary(res)
    v = res.verdict
    effect = next(iter(v.effects), None) if v.effects else None
    if effect is None and res.heldout:
        effect = max(res.heldout, key=lambda h: h.improvement[0]).name
    figures = _figures(res, out, effect)
    configs = []
    if config_data is not None and v.kind in ("named", "ambiguous"):
        for name, value in v.effects.items():
            data = json.loads(json.dumps(config_data))
            fiber = data.setdefault("fiber", {})
            fiber["effects"] = {**(fiber.get("effects") or {}), name: float(value)}
            fname = "updated_config.yaml" if v.kind == "named" else f"updated_config.{name}.yaml"
            atomic_write(out / fname, yaml.safe_dump(data, sort_keys=False))
            configs.append(fname)
    s["updated_configs"] = configs
    atomic_write(out / "summary.json", json.dumps(s, indent=2))
    atomic_write(out / "report.md", _markdown(s, figures, configs))
    return s

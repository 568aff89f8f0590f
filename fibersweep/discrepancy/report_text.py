"""The Markdown of the discrepancy report, from the JSON summary (:func:`.report.summary`).

Two layers. First a page for a researcher, in words (:mod:`.report_first_page`):
what differs, what explains it and by how much, what cannot be excluded, what
to measure next. Then the statistical detail, opened by a short glossary: the
analysis sections written here (gap, where it lives, ranking, fits and the
held-out decision, sets, before / after) and the follow-up sections of
:mod:`.report_followup`. A section about where a gap lives appears only with a
gap. Numbers are rounded to what they can tell (:mod:`.report_format`); the gap
is in one unit everywhere (copy-spread units), every residual in its
observable's unit, every z with what it is about.
"""

from __future__ import annotations

import json
from typing import Any

from fibersweep.discrepancy.observables import (
    OBSERVABLES,
    geometry_of,
    has_tracks,
    log_scale,
    scored,
)
from fibersweep.discrepancy.report_first_page import first_page, z_labels
from fibersweep.discrepancy.report_followup import next_lines, power_lines, settle_lines
from fibersweep.discrepancy.report_format import ci_text, num
from fibersweep.discrepancy.settings import TIE_COSINE

__all__ = ["GLOSSARY", "markdown"]

#: The words of the statistical detail, in plain words (the report's glossary).
GLOSSARY = (
    ("copy", "one simulation of a measured fiber by the model, its start and outcome "
     "jittered by the measurement noise; the model's copies show what the model predicts "
     "and how much that varies"),
    ("fair Brier score, fair CRPS", "how far a measured value sits from the model's copies "
     "(the Brier score for a class or yes/no, the CRPS for a number); lower is better, "
     "'fair' corrects for the finite number of copies"),
    ("gap [copy-spread units]", "how much worse the measured fibers score than a copy "
     "scores against the other copies, divided by the spread of the copies' own scores: "
     "0 is as good as the model's own copies, 1 one spread worse per fiber"),
    ("shift z", "the signed residual (measured minus the copies' mean) over its noise: "
     "positive means measured more often in that class, or larger; |z| above about 2 "
     "stands out of the noise"),
    ("p, Holm", "p: how often noise alone gives a result this far out. Holm: the "
     "p-values of every test of a table adjusted together, so the chance of any false "
     "alarm stays at alpha"),
    ("held out, out of sample", "a value fitted on one half of the fibers and judged on "
     "the other half: an effect is named only if it helps fibers it was not fitted to"),
    ("95 % interval", "the values the data cannot tell from the fitted one"),
    ("detection limit", "the smallest size of an effect the tests would see with "
     "probability 0.8 with this many fibers"),
)


def _score_text(observed: list[str] | tuple[str, ...] = ()) -> str:
    # the track observables only when tracks were measured
    names = scored(tracks=has_tracks(observed), geometry=geometry_of(observed))
    cat = [n for n in names if OBSERVABLES[n].categorical]
    logs = [n for n in names if OBSERVABLES[n].transform is log_scale]
    on_log = f"; {', '.join(logs)} on a log scale" if logs else ""
    return (
        f"Score: fair Brier score ({', '.join(cat)}) or fair CRPS (continuous{on_log}) of each "
        "observation against the model's jittered copies. Two tests per observable, one Holm "
        "family: the score (does the measurement sit worse than a copy?) and the signed "
        "residual (is it shifted?). Gap: the excess score over the copies' own, divided by the "
        "spread of the copies' scores (copy-spread units; 0 = as good as the model's copies)."
    )


def _header(s: dict[str, Any]) -> list[str]:
    fails = s["failed_runs"]
    under = {k: n for k, n in s["failed_runs_by_stage"].items() if k != "baseline" and n}
    under_txt = (
        "; runs under a probed or fitted effect that failed (e.g. the time limit with strong "
        "Brownian motion) count as that effect's outcomes, not as failures of the analysis: "
        + ", ".join(f"{k} {n}" for k, n in under.items())
        if under
        else ""
    )
    return [
        f"{s['n_fibers']} measured fibers"
        + (", every one scored out of sample (each half with the value fitted on the other "
           "half)" if s.get("heldout") else "")
        + f"; {s['simulations']} simulations, {fails} failed runs "
        f"of the baseline model (kept as failures){under_txt}; {s['seconds']:.0f} s; "
        f"family-wise alpha = {s['alpha']}.",
        "",
        f"Observables used: {', '.join(s['observables'])}. "
        + (
            f"Absent from the measured data, so not tested: {', '.join(s['observables_absent'])}."
            if s["observables_absent"]
            else "Every observable the workflow knows was measured."
        ),
    ]


def _glossary() -> list[str]:
    return ["", "## Words used below", ""] + [f"- **{k}**: {v}." for k, v in GLOSSARY]


def _z_text(name: str, zs: list[float | None]) -> str:
    """Each shift z with what it is about ('Below −2.1, Above 2.1'; 'shift 0.3')."""
    return ", ".join(f"{lab} {num(z, '+.1f')}" for lab, z in
                     zip(z_labels(name, len(zs)), zs, strict=True))  # fmt: skip


def _unit(name: str) -> str:
    o = OBSERVABLES.get(name)
    return o.unit if o is not None else ""


def _descriptive(d: dict[str, Any]) -> list[str]:
    """The descriptive measures in words, each in its observable's unit."""
    out = []
    for k, val in d.items():
        if k == "confusion" or val is None:
            continue
        name, _, what = k.rpartition("_")
        if k.endswith("_confusion"):
            continue
        u = _unit(name)
        us = f" {u}" if u else ""
        if what == "residual" and isinstance(val, dict):
            if val.get("mean") is None:
                continue
            out.append(f"- {name}: measured minus the model's mean {num(val['mean'], '+.3g')}{us} "
                       f"on average, sd {num(val.get('sd'), '.3g')}{us} over {val.get('n')} "
                       "fibers")  # fmt: skip
        elif what == "wasserstein":
            out.append(f"- {name}: distance between the measured and model distributions "
                       f"(Wasserstein) {num(val, '.3g')}{us}")  # fmt: skip
        elif what == "ratio":
            out.append(f"- {name}: median ratio measured / model {num(val, '.3g')}")
        elif what == "agreement":
            out.append(f"- {name}: {100 * val:.0f} % of fibers in the class the model finds "
                       "most often")  # fmt: skip
        elif what == "mismatch":
            out.append(f"- {name}: {100 * val:.0f} % of fibers differ from the model's usual "
                       "outcome")  # fmt: skip
        else:
            out.append(f"- {k}: {json.dumps(val)}")
    return out


def _gap_table(s: dict[str, Any]) -> list[str]:
    lines = [
        "",
        "## Gap per observable (all fibers, baseline model)",
        "",
        _score_text(s["observables"]),
        "",
        "| observable | n | gap [copy-spread units, 95 % CI] | p score (Holm) | p shift (Holm) "
        "| shift z, per class or of the value | significant |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, g in s["gap"].items():
        sig = "**score**" if g["significant"] else ""
        if g["systematic"]:
            sig = (sig + " **shift**").strip()
        lines.append(
            f"| {name} | {g['n']} | {ci_text(g['gap'])} | {num(g['p_holm'], '.2g')} "
            f"| {num(g['signed_p_holm'], '.2g')} "
            f"| {_z_text(name, g['bias_z'])} | {sig or 'no'} |"
        )
    disp = s.get("dispersion") or {}
    if disp.get("baseline", {}).get("n"):
        b = disp["baseline"]
        after = "; ".join(
            f"with {k} at its value: {num(x['mean_score'], '.2f')} (p {num(x['p'], '.2g')})"
            for k, x in disp.items()
            if k != "baseline" and x.get("n")
        )
        lines += [
            "",
            "Dispersion (where each observation falls among its copies, continuous "
            f"observables; 1 = as spread as a copy, larger = more widely spread): "
            f"{num(b['mean_score'], '.2f')}, p {num(b['p'], '.2g')} (one-sided, outside the "
            "Holm family)" + (f"; {after}" if after else "") + ".",
        ]
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

    lines += _descriptive(d)
    if not any(g["significant"] or g["systematic"] for g in s["gap"].values()):
        return lines  # no gap: nothing lives anywhere
    varying = s["start_axes_varying"]
    lines += [
        "",
        "## Where the gap lives",
        "",
        f"Shallow regression tree on the per-fiber gap over the start axes that vary "
        f"({', '.join(varying) or 'none'}) and the observed contact: largest mean gap in "
        f"**{s['region']['where']}** ({s['region']['n']} fibers, "
        f"{num(100 * (s['region']['share'] or 0), '.0f')} % of the positive gap).",
    ]
    for obs, where in s["region_by_observable"].items():
        lines.append(f"- {obs}: {where}")
    return lines


def _chosen_text(settings: dict[str, Any]) -> list[str]:
    """Which of the ranked effects were fitted, and a blank line (``settings``: the
    summary's; nothing when it does not say)."""
    if "candidates" not in settings:
        return []
    k, tied = settings["candidates"], settings.get("tied", 0)
    more = (
        f", and up to {tied} more whose cosine is within {TIE_COSINE:g} of the best one's "
        "(look-alike effects that the noise may have put out of order)"
        if tied
        else ""
    )
    return [f"The {k} best matches with a positive cosine are fitted{more}.", ""]


def _fits(s: dict[str, Any]) -> list[str]:
    if not s["signatures"]:
        return []
    lines = [
        "",
        "## Effects ranked by signature",
        "",
        *_chosen_text(s.get("settings", {})),
        "| effect | probe | cosine with the gap | signature strength |",
        "|---|---|---|---|",
    ]
    for r in s["signatures"]:
        lines.append(
            f"| {r['effect']} | {r['probe']:g} | {r['cosine']:.2f} | {r['strength']:.2g} |"
        )
    lines += [
        "",
        "## Fits per half and the out-of-sample decision",
        "",
        "Each half is scored with the value fitted on the other half. Every value is the one "
        "the fit's score test is most compatible with (the zero of its mean loss slope; for a "
        "random effect, where the data are as spread as its copies). Final: the value "
        "refitted on all fibers (significant candidates), with its 95 % interval: where the "
        "minimum of the fibers' mean loss falls when the fibers are resampled (a bootstrap "
        "over the fibers; it includes the copies' Monte Carlo noise). '≤' / '≥' mark an "
        "end where the resampled minima pile up at the last evaluated value (the effect's "
        "range end, or where a small budget stopped the refit). Candidates "
        "whose fit kept the "
        "baseline (0) on both halves are left out.",
        "",
        "| effect | half A | half B | spread | final [95 % CI] | held-out improvement "
        "[copy-spread units, 95 % CI] | p | p (Holm) | explains |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for h in s["heldout"]:
        a, b = (h["halves"] or [None, None])[:2]
        spread = abs(a - b) if a is not None and b is not None else None
        ci = h.get("interval95")
        op = h.get("interval95_open") or [False, False]
        final = num(h["value"]) + _bracket(ci, op)
        lines.append(
            f"| {h['effect']} | {num(a)} | {num(b)} | {num(spread, '.2g')} | {final} "
            f"| {ci_text(h['improvement'])} | {num(h['p'], '.2g')} | {num(h['p_holm'], '.2g')} "
            f"| {'yes' if h['explains'] else 'no'} |"
        )
    lines += _spread_lines(s["heldout"])
    lines += _declared_lines(s)
    if s["sets"]:
        lines += [
            "",
            "### Two effects together (forward selection)",
            "",
            "Contribution of a member: held-out improvement of the set over the set without "
            "it; p-values Holm-adjusted over every member of every set. A significant set's "
            "values are each member refitted on all fibers with the other at its pair value, "
            "with its 95 % interval (the score test of a single effect's final value; it "
            "does not carry the other member's uncertainty).",
            "",
            "| set | values [95 % CI] (half A, half B) | contributions [copy-spread units] "
            "| p (Holm) | explains |",
            "|---|---|---|---|---|",
        ]
        for st in s["sets"]:
            vals = "; ".join(
                f"{k} = {num(v)}{_interval_text(st, k)} "
                f"({num(st['halves'][k][0])}, {num(st['halves'][k][1])})"
                for k, v in st["values"].items()
            )
            gains = "; ".join(f"{k} {ci_text(g)}" for k, g in st["gains"].items())
            ps = "; ".join(f"{k} {num(p, '.2g')}" for k, p in st["p_holm"].items())
            lines.append(
                f"| {st['set']} | {vals} | {gains} | {ps} | {'yes' if st['explains'] else 'no'} |"
            )
    return lines


def _declared_lines(s: dict[str, Any]) -> list[str]:
    """Declared candidates: what each is, and its fitted value in the setting's unit."""
    if not s.get("declared"):
        return []
    lines = [
        "",
        "### Candidates declared from the config's settings",
        "",
        "A declared candidate is fitted on its own scale (0: the config's value; a stiffness "
        "with a model switch: 0 is the rigid model, larger is softer); the table above shows "
        "that scale, this one the setting itself.",
        "",
        "| candidate | what | final value [95 % CI], in the setting's unit |",
        "|---|---|---|",
    ]
    held = {h["effect"]: h for h in s["heldout"]}
    for c in s["declared"]:
        h = held.get(c["name"])
        if h is None:
            value = "not fitted (signature did not match)"
        else:
            value = h["setting"]
            ci = h.get("interval95_setting")
            if ci:
                value += f" [{num(ci[0])}, {num(ci[1])}]"
        switch = ", ".join(f"{k} = {v}" for k, v in c["switch"].items())
        what = c["note"] + (f" (with {switch})" if switch else "")
        lines.append(f"| {c['name']} | {what} | {value} |")
    return lines


def _bracket(ci: list[float] | None, op: list[bool] | None) -> str:
    """' [lo, hi]' of a 95 % interval, '≤' / '≥' at an end the evaluated values cut."""
    if not ci:
        return ""
    op = op or [False, False]
    return f" [{'≤ ' if op[0] else ''}{num(ci[0])}, {'≥ ' if op[1] else ''}{num(ci[1])}]"


def _interval_text(st: dict[str, Any], name: str) -> str:
    """The bracketed interval of a set member's value ('' when it was not refitted)."""
    ci = (st.get("interval95") or {}).get(name)
    return _bracket(ci, (st.get("interval95_open") or {}).get(name))


def _before_after(s: dict[str, Any]) -> list[str]:
    named = s["verdict"]["effects"]
    rows = [h for h in s["heldout"] if h["effect"] in named and len(named) == 1]
    rows += [st for st in s["sets"] if set(st["values"]) == set(named)]
    lines = []
    for h in rows:
        label = h.get("effect") or h.get("set")
        lines += [
            "",
            f"### Held-out gap before / after {label} [copy-spread units]",
            "",
            "| observable | before [95 % CI] | after [95 % CI] | share removed |",
            "|---|---|---|---|",
        ]
        for name, b in s["heldout_gap_before"].items():
            a = h["gap_after"].get(name, {}).get("gap")
            r = h["gap_removed"].get(name)
            lines.append(
                f"| {name} | {ci_text(b['gap'])} | {ci_text(a)} | "
                f"{num(None if r is None else 100 * r, '.0f')}{' %' if r is not None else ''} |"
            )
    return lines


def markdown(s: dict[str, Any], figures: list[str], configs: list[str]) -> str:
    """The report for people (see the module docstring)."""
    v = s["verdict"]
    lines = [
        "# Discrepancy report",
        "",
        f"**Verdict: {v['kind']}.** {v['text']}",
        "",
        "## In short",
        "",
        *first_page(s),
        "",
        "---",
        "",
        "# Statistical detail",
        "",
        *_header(s),
        *_glossary(),
    ]
    lines += _gap_table(s) + _fits(s) + _before_after(s)
    if s["advice"]:
        lines += ["", "## Advice", ""] + [f"- {a}" for a in s["advice"]]
    lines += power_lines(s) + next_lines(s) + settle_lines(s)
    if figures:
        lines += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figures]
    if configs:
        lines += ["", "## Updated model", ""] + [f"- `{c}`" for c in configs]
    return "\n".join(lines) + "\n"


def _spread_lines(heldout: list[dict[str, Any]]) -> list[str]:
    """One line per random effect: its held-out spread test (the second naming route)."""
    out = []
    for h in heldout:
        sp = h.get("spread")
        if not sp:
            continue
        fd = sp.get("final_dispersion_p")
        out.append(
            f"- {h['effect']}, held-out spread: mean dispersion score {sp['base_mean']:.2f} "
            f"against the baseline, {sp['effect_mean']:.2f} with the effect (1: as spread as a "
            f"copy); p {num(sp['p'], '.2g')} (Holm {num(sp['p_holm'], '.2g')}), held-out "
            f"dispersion p {num(sp['heldout_dispersion_p'], '.2g')}, shift p "
            f"{num(sp['shift_p'], '.2g')}"
            + (f", final dispersion p {num(fd, '.2g')}" if fd is not None else "")
            + f": {'significant' if sp['significant'] else 'not significant'}."
        )
    return [""] + out if out else []

"""The Markdown of the discrepancy report, from the JSON summary (:func:`report.summary`).

Numbers are rounded to what they can tell (3 significant digits for values, 2
for p-values and gaps); the gap is in one unit everywhere (copy-spread units).
"""

from __future__ import annotations

import json
from typing import Any

from fibersweep.discrepancy.observables import OBSERVABLES, has_tracks, log_scale, scored
from fibersweep.discrepancy.settings import TIE_COSINE

__all__ = ["markdown"]


def _f(x: Any, spec: str = ".3g") -> str:
    return "–" if x is None else format(x, spec)


def _ci(d: dict[str, Any] | None, spec: str = ".2g") -> str:
    if not d:
        return "–"
    return f"{_f(d.get('mean'), spec)} [{_f(d.get('lo95'), spec)}, {_f(d.get('hi95'), spec)}]"


def _score_text(observed: list[str] | tuple[str, ...] = ()) -> str:
    # the track observables only when tracks were measured
    names = scored(tracks=has_tracks(observed))
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
    v = s["verdict"]
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
        "# Discrepancy report",
        "",
        f"**Verdict: {v['kind']}.** {v['text']}",
        "",
        f"{s['n_fibers']} measured fibers, every one scored out of sample (each half with the "
        f"value fitted on the other half); {s['simulations']} simulations, {fails} failed runs "
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


def _gap_table(s: dict[str, Any]) -> list[str]:
    lines = [
        "",
        "## Gap per observable (all fibers, baseline model)",
        "",
        _score_text(s["observables"]),
        "",
        "| observable | n | gap [copy-spread units, 95 % CI] | p score (Holm) | p signed (Holm) "
        "| signed residual z | significant |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, g in s["gap"].items():
        sig = "**score**" if g["significant"] else ""
        if g["systematic"]:
            sig = (sig + " **shift**").strip()
        lines.append(
            f"| {name} | {g['n']} | {_ci(g['gap'])} | {_f(g['p_holm'], '.2g')} "
            f"| {_f(g['signed_p_holm'], '.2g')} "
            f"| {', '.join(_f(z, '.1f') for z in g['bias_z'])} | {sig or 'no'} |"
        )
    disp = s.get("dispersion") or {}
    if disp.get("baseline", {}).get("n"):
        b = disp["baseline"]
        after = "; ".join(
            f"with {k} at its value: {_f(x['mean_score'], '.2f')} (p {_f(x['p'], '.2g')})"
            for k, x in disp.items()
            if k != "baseline" and x.get("n")
        )
        lines += [
            "",
            "Dispersion (where each observation falls among its copies, continuous "
            f"observables; 1 = as spread as a copy, larger = more widely spread): "
            f"{_f(b['mean_score'], '.2f')}, p {_f(b['p'], '.2g')} (one-sided, outside the "
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

    def rnd(x: Any) -> Any:
        if isinstance(x, float):
            return float(f"{x:.3g}")
        if isinstance(x, dict):
            return {k: rnd(v) for k, v in x.items()}
        return x

    for k, val in d.items():
        if k != "confusion":
            lines.append(f"- {k}: {json.dumps(rnd(val))}")
    varying = s["start_axes_varying"]
    lines += [
        "",
        "## Where the gap lives",
        "",
        f"Shallow regression tree on the per-fiber gap over the start axes that vary "
        f"({', '.join(varying) or 'none'}) and the observed contact: largest mean gap in "
        f"**{s['region']['where']}** ({s['region']['n']} fibers, "
        f"{_f(100 * (s['region']['share'] or 0), '.0f')} % of the positive gap).",
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
        "refitted on all fibers (significant candidates), with its 95 % interval: the values "
        "where the fibers' mean loss slope is not significantly different from zero (a score "
        "test over the fibers; it includes the copies' Monte Carlo noise, and its critical "
        "value is calibrated on simulated data sets). '≤' / '≥' mark an "
        "end where the evaluated values stopped before the test rejected (the effect's range "
        "end, or where a small budget stopped the refit). Candidates "
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
        final = _f(h["value"]) + _bracket(ci, op)
        lines.append(
            f"| {h['effect']} | {_f(a)} | {_f(b)} | {_f(spread, '.2g')} | {final} "
            f"| {_ci(h['improvement'])} | {_f(h['p'], '.2g')} | {_f(h['p_holm'], '.2g')} "
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
                f"{k} = {_f(v)}{_interval_text(st, k)} "
                f"({_f(st['halves'][k][0])}, {_f(st['halves'][k][1])})"
                for k, v in st["values"].items()
            )
            gains = "; ".join(f"{k} {_ci(g)}" for k, g in st["gains"].items())
            ps = "; ".join(f"{k} {_f(p, '.2g')}" for k, p in st["p_holm"].items())
            lines.append(
                f"| {st['set']} | {vals} | {gains} | {ps} | {'yes' if st['explains'] else 'no'} |"
            )
    return lines


def _shown(h: dict[str, Any]) -> str:
    """``effect = value`` of a held-out or leading entry; a declared candidate's value in
    its setting's unit (its ``setting`` text)."""
    return h.get("setting") or f"{h['effect']} = {h['value']:.3g}"


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
                value += f" [{_f(ci[0])}, {_f(ci[1])}]"
        switch = ", ".join(f"{k} = {v}" for k, v in c["switch"].items())
        what = c["note"] + (f" (with {switch})" if switch else "")
        lines.append(f"| {c['name']} | {what} | {value} |")
    return lines


def _bracket(ci: list[float] | None, op: list[bool] | None) -> str:
    """' [lo, hi]' of a 95 % interval, '≤' / '≥' at an end the evaluated values cut."""
    if not ci:
        return ""
    op = op or [False, False]
    return f" [{'≤ ' if op[0] else ''}{_f(ci[0])}, {'≥ ' if op[1] else ''}{_f(ci[1])}]"


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
                f"| {name} | {_ci(b['gap'])} | {_ci(a)} | "
                f"{_f(None if r is None else 100 * r, '.0f')}{' %' if r is not None else ''} |"
            )
    return lines


def _fibers_ci(ci: Any) -> str:
    """' (95 % over the simulated starts: lo to hi)', or '' when not computed."""
    if not ci:
        return ""
    lo, hi = (_f(x, "d") if x is not None else "more than 100000" for x in ci)
    return f" (95 % over the simulated starts: {lo} to {hi})"


def _power(s: dict[str, Any]) -> list[str]:
    pw = s["power"]
    if pw is None:
        return (
            ["", "## What it cannot see", "", f"Not run: {s['power_skipped']}."]
            if s.get("power_skipped")
            else []
        )
    lines = [
        "",
        "## What it cannot see (power analysis)",
        "",
        f"By simulation on {pw['n_simulated']} of the measured starts, scaled to "
        f"{pw['n']} fibers: the smallest magnitude of each effect that the gap tests would "
        f"detect with probability {pw['power']:g} (alpha = {pw['alpha']:g}); an effect "
        "below it may be present without being seen. To *name* an effect takes more: "
        "half of the fibers fit it, the other half must confirm it. Each limit comes from "
        "one set of simulated starts; the interval beside it (95 %, a bootstrap over "
        "those starts) is how far another set of starts could move it, and its upper end "
        "is the size below which an effect may be present unseen.",
        "",
        "| effect | direction | detected from | 95 % over the starts "
        "| realistic magnitude | fibers to detect it |",
        "|---|---|---|---|---|---|",
    ]
    for e in pw["effects"]:
        lim = _f(e["limit"]) if e["limit"] is not None else "not within its range"
        ci = e.get("limit_ci")
        ci_txt = (
            "–"
            if ci is None
            else f"[{_f(ci[0]) if ci[0] is not None else 'out of range'}, "
            f"{_f(ci[1]) if ci[1] is not None else 'out of range'}]"
        )
        if e.get("setting"):  # a declared candidate: its limit in the setting's unit
            lim = e["setting"]
            ci_txt = "–"
        lines.append(
            f"| {e['effect']} | {e['direction']} | {lim} | {ci_txt} | {_f(e['realistic'])} "
            f"| {_f(e['fibers_for_realistic'], 'd') if e['fibers_for_realistic'] else '> 100000'} |"
        )
    again = [e for e in pw["effects"] if e.get("read_at") is not None]
    disp = [e for e in pw["effects"] if e.get("dispersion_limit") is not None]
    for lead, items in (
        (
            "Read again where they lie (the probes were far from them, and a power law "
            "read there would misplace them; the effect was simulated again at the limit): ",
            [f"{e['effect']} {e['direction']} at {_f(e['read_at'])}" for e in again],
        ),
        (
            "The dispersion test alone (one-sided at alpha, outside the gap family) would "
            "detect with the same probability: ",
            [f"{e['effect']} from {_f(e['dispersion_limit'])}" for e in disp],
        ),
    ):
        if items:
            lines += ["", lead + ", ".join(items) + "."]
    if pw["lookalikes"]:
        lines += [
            "",
            "Look-alikes (per-fiber effects nearly parallel, |cosine| >= 0.9: these "
            "observables cannot tell them apart): "
            + ", ".join(f"{x['a']} ~ {x['b']} ({x['cosine']:.2f})" for x in pw["lookalikes"])
            + ".",
        ]
    lead = pw.get("leading")
    if lead:
        lines += [
            "",
            f"Leading candidate {_shown(lead)}: about "
            f"{_f(lead['fibers_to_detect'], 'd')} fibers would detect a gap of this size"
            f"{_fibers_ci(lead.get('fibers_to_detect_ci'))}; "
            f"about {_f(lead['fibers_to_name'], 'd')} would make its held-out improvement "
            "significant (from the spread of the per-fiber improvement measured here).",
        ]
    return lines


def _window(w: list[float] | None) -> str:
    """Where the fibers should start: spread over the window around each start, or at it."""
    if not w:
        return "at these starts"
    return (
        f"with starts spread over θ0 ±{w[0]:.2g}°, y0 ±{w[1]:.2g} h_obs, L ±{w[2]:.2g} l_obs "
        "around these starts"
    )


def _next(s: dict[str, Any]) -> list[str]:
    nx = s["next"]
    if nx is None:
        return (
            ["", "## What to measure next", "", f"Not run: {s['next_skipped']}."]
            if s.get("next_skipped")
            else []
        )
    a, b = nx["hypotheses"]
    lines = [
        "",
        "## What to measure next",
        "",
        f"Why: {nx['reason']}. To separate **{a}** from **{b}**, measure fibers "
        f"{_window(nx.get('window'))} (separation per fiber: the two predictions' "
        "difference over the noise of one measured fiber, summed over the observables):",
        "",
        "| θ0 [deg] | y0 [h_obs] | L [l_obs] | separation per fiber | observable | "
        "prediction A | prediction B |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in nx["best"]:
        lines.append(
            f"| {r['theta0']:.1f} | {r['y0']:.2f} | {r['length']:.2f} | {r['d']:.2g} "
            f"| {r['observable']} | {r['a']:.3g} | {r['b']:.3g} |"
        )
    lines += [
        "",
        f"About {_f(nx['fibers_needed'], 'd')} fibers there, shared over these starts, "
        "would settle it with power 0.8 (a rough figure at the measured starts: "
        f"{_f(nx['fibers_needed_at_measured_starts'], 'd')})"
        + (". The count and the follow-up test assume starts scattered over the window, "
           "not aimed at one point" if nx.get("window") else "")
        + ". Once measured, give them to the same command with `--followup`, once: they "
        "are put to the two hypotheses directly (docs/discrepancy.md, *Settling it*).",
    ]
    return lines


def _settle(s: dict[str, Any]) -> list[str]:
    st = s.get("settle")
    if st is None:
        skipped = s.get("settle_skipped")
        return ["", "## Follow-up fibers", "", f"Not tested: {skipped}."] if skipped else []
    a, b = st["hypotheses"]
    pa, pb = st["p_values"]
    first = st.get("verdict_first") or {}
    lines = [
        "",
        "## Follow-up fibers",
        "",
        f"Why: {st['reason']}. {st['fibers']} fibers measured after the first analysis test "
        f"**{a}** (A) against **{b}** (B) on {', '.join(st['observables'])}: the sum of their "
        "log-likelihood ratios of A over B, against its distribution under each hypothesis "
        "from simulated copies (one-sided tests); the winner is then checked for a gap left "
        "on these fibers.",
        "",
        "| | A | B |",
        "|---|---|---|",
        f"| expected sum (sd) | {st['expected'][0]:.3g} ({st['sd'][0]:.2g}) "
        f"| {st['expected'][1]:.3g} ({st['sd'][1]:.2g}) |",
        f"| p of this hypothesis | {_f(pa, '.2g')} | {_f(pb, '.2g')} |",
        "",
        f"Measured sum: {st['statistic']:.3g}. Outcome: {st['text']}.",
    ]
    if st.get("failed_copies"):
        lines += ["", f"{st['failed_copies']} copies failed and were left out of the test."]
    if first:
        lines += ["", f"Verdict on the first fibers alone: {first['kind']}: {first['text']}"]
    return lines


def markdown(s: dict[str, Any], figures: list[str], configs: list[str]) -> str:
    """The report for people (see the module docstring)."""
    lines = _header(s) + _gap_table(s) + _fits(s) + _before_after(s)
    if s["advice"]:
        lines += ["", "## Advice", ""] + [f"- {a}" for a in s["advice"]]
    lines += _power(s) + _next(s) + _settle(s)
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
            f"copy); p {_f(sp['p'], '.2g')} (Holm {_f(sp['p_holm'], '.2g')}), held-out "
            f"dispersion p {_f(sp['heldout_dispersion_p'], '.2g')}, shift p "
            f"{_f(sp['shift_p'], '.2g')}"
            + (f", final dispersion p {_f(fd, '.2g')}" if fd is not None else "")
            + f": {'significant' if sp['significant'] else 'not significant'}."
        )
    return [""] + out if out else []

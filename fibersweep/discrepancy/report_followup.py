"""Markdown of the report's follow-up sections: what it cannot see, what to measure next, settling.

From the JSON summary (:func:`.report.summary`): the power analysis, what to
measure next, and the follow-up fibers' test of the verdict's two hypotheses.
"""

from __future__ import annotations

from typing import Any

from fibersweep.discrepancy.array_report import start_units
from fibersweep.discrepancy.report_format import num

__all__ = ["next_lines", "power_lines", "settle_lines"]


def _shown(h: dict[str, Any]) -> str:
    """``effect = value`` of a held-out or leading entry; a declared candidate's value in
    its setting's unit (its ``setting`` text)."""
    return h.get("setting") or f"{h['effect']} = {h['value']:.3g}"


def _fibers_ci(ci: Any) -> str:
    """' (95 % over the simulated starts: lo to hi)', or '' when not computed."""
    if not ci:
        return ""
    lo, hi = (num(x, "d") if x is not None else "more than 100000" for x in ci)
    return f" (95 % over the simulated starts: {lo} to {hi})"


def power_lines(s: dict[str, Any]) -> list[str]:
    """'What it cannot see': the power analysis, or why it did not run (nothing if neither)."""
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
        lim = num(e["limit"]) if e["limit"] is not None else "not within its range"
        ci = e.get("limit_ci")
        ci_txt = (
            "–"
            if ci is None
            else f"[{num(ci[0]) if ci[0] is not None else 'out of range'}, "
            f"{num(ci[1]) if ci[1] is not None else 'out of range'}]"
        )
        if e.get("setting"):  # a declared candidate: its limit in the setting's unit
            lim = e["setting"]
            ci_txt = "–"
        need = e["fibers_for_realistic"]
        lines.append(
            f"| {e['effect']} | {e['direction']} | {lim} | {ci_txt} | {num(e['realistic'])} "
            f"| {num(need, 'd') if need else '> 100000'} |"
        )
    again = [e for e in pw["effects"] if e.get("read_at") is not None]
    disp = [e for e in pw["effects"] if e.get("dispersion_limit") is not None]
    for lead, items in (
        (
            "Read again where they lie (the probes were far from them, and a power law "
            "read there would misplace them; the effect was simulated again at the limit): ",
            [f"{e['effect']} {e['direction']} at {num(e['read_at'])}" for e in again],
        ),
        (
            "The dispersion test alone (one-sided at alpha, outside the gap family) would "
            "detect with the same probability: ",
            [f"{e['effect']} from {num(e['dispersion_limit'])}" for e in disp],
        ),
    ):
        if items:
            lines += ["", lead + ", ".join(items) + "."]
    if s.get("power_unread"):
        lines += ["", "Not read again for the budget (each limit stays as read from its last two "
                  "magnitudes, less accurate): " + ", ".join(s["power_unread"]) + "."]  # fmt: skip
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
            f"{num(lead['fibers_to_detect'], 'd')} fibers would detect a gap of this size"
            f"{_fibers_ci(lead.get('fibers_to_detect_ci'))}; "
            f"about {num(lead['fibers_to_name'], 'd')} would make its held-out improvement "
            "significant (from the spread of the per-fiber improvement measured here).",
        ]
    return lines


def _window(w: list[float] | None, units: tuple[str, str] = ("h_obs", "l_obs")) -> str:
    """Where the fibers should start: spread over the window around each start, or at it."""
    if not w:
        return "at these starts"
    return (
        f"with starts spread over θ0 ±{w[0]:.2g}°, y0 ±{w[1]:.2g} {units[0]}, "
        f"L ±{w[2]:.2g} {units[1]} around these starts"
    )


def next_lines(s: dict[str, Any]) -> list[str]:
    """'What to measure next', or why it did not run (nothing if neither)."""
    nx = s["next"]
    if nx is None:
        return (
            ["", "## What to measure next", "", f"Not run: {s['next_skipped']}."]
            if s.get("next_skipped")
            else []
        )
    a, b = nx["hypotheses"]
    units = start_units(s.get("observables", ()))
    lines = [
        "",
        "## What to measure next",
        "",
        f"Why: {nx['reason']}. To separate **{a}** from **{b}**, measure fibers "
        f"{_window(nx.get('window'), units)} (separation per fiber: the two predictions' "
        "difference over the noise of one measured fiber, summed over the observables):",
        "",
        f"| θ0 [deg] | y0 [{units[0]}] | L [{units[1]}] | separation per fiber | observable | "
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
        f"About {num(nx['fibers_needed'], 'd')} fibers there, shared over these starts, "
        "would settle it with power 0.8 (a rough figure at the measured starts: "
        f"{num(nx['fibers_needed_at_measured_starts'], 'd')})"
        + (". The count and the follow-up test assume starts scattered over the window, "
           "not aimed at one point" if nx.get("window") else "")
        + ". Once measured, give them to the same command with `--followup`, once: they "
        "are put to the two hypotheses directly (docs/discrepancy.md, *Settling it*).",
    ]
    return lines


def settle_lines(s: dict[str, Any]) -> list[str]:
    """'Follow-up fibers': their test of the two hypotheses, or why it did not run."""
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
        f"| p of this hypothesis | {num(pa, '.2g')} | {num(pb, '.2g')} |",
        "",
        f"Measured sum: {st['statistic']:.3g}. Outcome: {st['text']}.",
    ]
    if st.get("failed_copies"):
        lines += ["", f"{st['failed_copies']} copies failed and were left out of the test."]
    if first:
        lines += ["", f"Verdict on the first fibers alone: {first['kind']}: {first['text']}"]
    return lines

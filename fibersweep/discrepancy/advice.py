"""Advice of the report: what to try, and the measurement that would most reduce the doubt.

Pure functions of the report's JSON summary (:func:`.report.summary`).
:func:`advice_lines` says, for an unexplained gap, which candidates helped out of
sample and by how much, what to try next, and, when the gap is unexplained or
not seen, which effects may be present unseen (the power analysis).

The doubt of an "unexplained" verdict is whether the candidate that helped most
out of sample is there. Two numbers answer *how many more fibers* and one table
*which starts* (:func:`next_measurement`):

- at the starts where its prediction and the model's part most (what to measure
  next, :mod:`.next_measure`), the fibers that would confirm or rule it out;
- at starts like the measured ones, from the power curve (:mod:`.power`), the
  fibers that would detect a gap of its size, with the 95 % interval over the
  simulated starts, and the fibers that would make its held-out improvement
  significant (from the spread of the per-fiber improvement measured).

Without a candidate that moved the predictions (nothing helped out of sample),
the starts are where the gap is largest (the localisation).
"""

from __future__ import annotations

from typing import Any

from fibersweep.discrepancy.gap import GAP_UNIT

__all__ = ["advice_lines", "next_measurement"]


def _n(x: Any) -> str:
    return "more than 100000" if x is None else f"{int(x)}"


def _range(ci: Any) -> str:
    if not ci:
        return ""
    lo, hi = ci
    return f" (95 % over the simulated starts: {_n(lo)} to {_n(hi)})"


def _shown(h: dict[str, Any]) -> str:
    """``effect = value`` of a held-out or leading entry; a declared candidate's value in
    its setting's unit (its ``setting`` text)."""
    return h.get("setting") or f"{h['effect']} = {h['value']:.3g}"


def next_measurement(s: dict[str, Any]) -> list[str]:
    """Advice lines naming the starts and the number of fibers (see the module docstring).

    Parameters
    ----------
    s : dict
        The summary; uses ``verdict``, ``n_fibers``, ``region``, ``next`` and
        ``power`` (its ``leading`` entry).

    Returns
    -------
    list of str
        Empty unless the verdict is "unexplained".
    """
    if s["verdict"]["kind"] != "unexplained":
        return []
    out = []
    n = int(s.get("n_fibers") or 0)
    nx = s.get("next")
    if nx and nx.get("fibers_needed") is not None and nx.get("best"):
        b = nx["best"][0]
        out.append(
            f"The measurement that would most reduce the doubt ({nx['reason']}): about "
            f"{nx['fibers_needed']} more fibers at the starts under 'What to measure "
            f"next' (best: θ0 {b['theta0']:.1f}°, y0 {b['y0']:.2f}, L {b['length']:.2f}, "
            f"through {b['observable']}); a rough figure at starts like the measured "
            f"ones: {nx.get('fibers_needed_at_measured_starts') or 'many'}."
        )
    else:
        r = s.get("region") or {}
        share = r.get("share")
        where = r.get("where") or "the region of the gap table"
        out.append(
            "No candidate's prediction was compared with the model's there (none helped "
            "out of sample or the budget was spent): the measurement that would most reduce "
            f"the doubt is more fibers where the gap is largest, {where}"
            + (
                f" ({r.get('n')} of the {n} fibers, {100 * share:.0f} % of the gap)"
                if share is not None and r.get("n") is not None
                else ""
            )
            + "."
        )
    lead = (s.get("power") or {}).get("leading")
    if lead:
        det, name = lead.get("fibers_to_detect"), lead.get("fibers_to_name")
        parts = [
            f"about {_n(det)} fibers would detect a gap of its size"
            + _range(lead.get("fibers_to_detect_ci"))
        ]
        if name is not None:
            more = f", {max(int(name) - n, 0)} more than the {n} measured" if n else ""
            parts.append(
                f"about {int(name)} would name it (held-out improvement significant{more})"
            )
        out.append(
            f"From the power curve, at starts like the measured ones, for {_shown(lead)}: "
            + "; ".join(parts)
            + "."
        )
    return out


def advice_lines(s: dict[str, Any]) -> list[str]:
    """What to try when the gap is unexplained (or not seen), one sentence per line.

    Parameters
    ----------
    s : dict
        The summary (:func:`.report.summary`, JSON-safe); uses ``verdict``,
        ``heldout``, ``sets``, ``power`` and what :func:`next_measurement` uses.
    """
    v = s["verdict"]
    out = []
    if v["kind"] == "unexplained":
        helped = [h for h in s["heldout"] if h["significant"]]
        for h in helped:
            parts = [
                f"{o} {100 * r:.0f} %"
                for o, r in h["gap_removed"].items()
                if r is not None and r > 0.1
            ]
            out.append(
                f"{_shown(h)} helped out of sample (improvement "
                f"{h['improvement']['mean']:.2g} {GAP_UNIT} per fiber, p Holm "
                f"{h['p_holm']:.2g}) and removed "
                + (", ".join(parts) if parts else "no observable's gap by more than 10 %")
                + " of the gap, but leaves a significant gap."
            )
        for st in s["sets"]:
            out.append(
                f"{st['set']} was tried together: contributions "
                + ", ".join(
                    f"{m} {st['gains'][m]['mean']:.2g} (p Holm {st['p_holm'][m]:.2g})"
                    for m in st["values"]
                )
                + ("; it still leaves a significant gap." if st["significant"] else ".")
            )
        declared = [c["name"] for c in s.get("declared") or []]
        if not helped:
            out.append(
                "No library effect"
                + (f" nor declared candidate ({', '.join(declared)})" if declared else "")
                + " improved the held-out fibers significantly."
            )
        beyond = "the library and the declared candidates" if declared else "the library"
        out.append(
            f"Try: an effect or setting outside {beyond} (the region and observable above "
            "say where to look; any setting can be declared with --candidate), a check of "
            "the measurement-noise model (a wrong noise level shows as a gap everywhere), "
            "or more fibers (see the power analysis)."
        )
        out += next_measurement(s)
    if v["kind"] in ("unexplained", "no significant gap") and s.get("power"):
        hidden = [
            e["unseen"]
            if e.get("unseen")
            else f"{e['effect']} ({e['direction']}) up to {e['limit_ci'][1]:.3g}"
            for e in s["power"]["effects"]
            if e.get("unseen") or (e.get("limit_ci") and e["limit_ci"][1] is not None)
        ]
        if hidden:
            out.append(
                "May be present unseen (the upper end of each detection limit's 95 % "
                "interval over the simulated starts): " + ", ".join(hidden) + "."
            )
    return out

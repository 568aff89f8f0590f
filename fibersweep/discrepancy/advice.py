"""Advice of the report: what to try, and the measurement that would most reduce the doubt.

Pure functions of the report's JSON summary (:func:`.report.summary`).
:func:`advice_lines` says, for an unexplained gap, which candidates helped out of
sample and by how much, what to try next, and, when the gap is unexplained or
not seen, which effects cannot be excluded (:func:`cannot_exclude`: the power
analysis would miss them at a realistic magnitude) and below which sizes the
others may still be present.

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

__all__ = ["advice_lines", "cannot_exclude", "exclusion_lines", "next_measurement"]


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
        out += exclusion_lines(s)
    return out


def _far(e: dict[str, Any]) -> float | None:
    """The upper end of a limit's 95 % interval (None: out of range), or the limit itself
    when no interval was computed."""
    ci = e.get("limit_ci")
    return ci[1] if ci else e.get("limit")


def cannot_exclude(s: dict[str, Any]) -> list[dict[str, Any]]:
    """The effects the power analysis cannot rule out at a realistic magnitude.

    An effect is listed when its detection limit, or the upper end of the limit's
    95 % interval over the simulated starts, lies above its realistic magnitude
    or out of its range (None): these fibers could carry it at that magnitude
    and the tests would not see it. A declared candidate (no realistic
    magnitude) is listed when its limit or that upper end is out of its range,
    and an alternative when it was not detected.

    Parameters
    ----------
    s : dict
        The summary; uses ``power`` (its ``effects``, :func:`.report.summary`).

    Returns
    -------
    list of dict
        Per listed effect: ``effect``, ``direction``, ``limit`` and ``upper``
        (None: out of range), ``realistic`` (None for a declared candidate),
        ``fibers`` (the fibers that would detect it at the realistic magnitude
        with the analysis's power; None: more than 100 000 or not known),
        ``fibers_ci`` (their 95 % interval over the simulated starts, or None)
        and ``text`` (one phrase for the report).
    """
    pw = s.get("power") or {}
    out = []
    for e in pw.get("effects", []):
        lim, far, real = e.get("limit"), _far(e), e.get("realistic")
        if real is None:  # a declared candidate: judged against its range
            if lim is not None and far is not None:
                continue
        elif lim is not None and far is not None and max(abs(lim), abs(far)) <= abs(real):
            continue  # would have been seen at the realistic magnitude
        seen = (f"detected only from {lim:.3g}" if lim is not None
                else "not detected within its range")  # fmt: skip
        if lim is not None and e.get("limit_ci"):
            seen += (f" (another set of starts could put that at {far:.3g})" if far is not None
                     else " (another set of starts could put that beyond its range)")  # fmt: skip
        if e.get("setting"):
            seen = e["setting"]
        need, need_ci = e.get("fibers_for_realistic"), e.get("fibers_for_realistic_ci")
        if real is not None:
            fibers = (f"about {int(need)} fibers would detect {real:.3g}" if need
                      else f"more than 100000 fibers would be needed at {real:.3g}")  # fmt: skip
            if need and need_ci:
                fibers += _range(need_ci)
        else:
            fibers = "the fibers to detect it are not known from this analysis"
        out.append({
            "effect": e["effect"], "direction": e.get("direction", ""), "limit": lim,
            "upper": far, "realistic": real, "fibers": need if real is not None else None,
            "fibers_ci": e.get("fibers_for_realistic_ci") if real is not None else None,
            "text": f"{e['effect']} ({e.get('direction', '')}): {seen}; {fibers}",
        })  # fmt: skip
    return out


def exclusion_lines(s: dict[str, Any]) -> list[str]:
    """What the power analysis cannot exclude, and what it excludes down to which size.

    One line listing every effect of :func:`cannot_exclude` (with the fibers that
    would settle it), one for the others (seen at a realistic magnitude; each may
    still be present below the upper end of its interval). Nothing without a
    power analysis.
    """
    pw = s.get("power")
    if not pw:
        return []
    listed = cannot_exclude(s)
    names = {(c["effect"], c["direction"]) for c in listed}
    out = []
    if listed:
        n = pw.get("n", s.get("n_fibers"))
        out.append(
            f"Cannot be excluded with these {n} fibers (at a realistic magnitude the "
            "tests would miss it; the detection limit or the upper end of its 95 % interval "
            "lies above that magnitude or out of range): "
            + "; ".join(c["text"] for c in listed) + "."
        )
    rest = []
    for e in pw["effects"]:
        if (e["effect"], e.get("direction", "")) in names:
            continue
        far = _far(e)
        rest.append(e.get("unseen") or f"{e['effect']} ({e.get('direction', '')}) up to "
                    f"{far:.3g}")  # fmt: skip
    if rest:
        out.append(
            "Would have been seen at a realistic magnitude, yet may be present below the "
            "upper end of its detection limit's 95 % interval: " + ", ".join(rest) + "."
        )
    return out


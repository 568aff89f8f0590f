"""The report's first page, for a researcher, in words (:func:`first_page`).

What differs (each observable in its unit), what explains it and by how much
(the value in its unit, with its 95 % interval), what cannot be excluded
(:func:`.advice.cannot_exclude`), what to measure next, and what did not run
for the budget. A pure function of the JSON summary (:func:`.report.summary`);
the statistical detail follows it (:mod:`.report_text`).
"""

from __future__ import annotations

from typing import Any

from fibersweep.discrepancy.advice import cannot_exclude
from fibersweep.discrepancy.array_report import start_units
from fibersweep.discrepancy.candidates import LIBRARY
from fibersweep.discrepancy.observables import OBSERVABLES

__all__ = ["first_page", "z_labels"]


def _n(x: Any) -> str:
    return "more than 100000" if x is None else f"{int(x)}"


def z_labels(name: str, n: int) -> list[str]:
    """What each signed-residual z of an observable is about: its categories, or its shift."""
    o = OBSERVABLES.get(name)
    if o is not None and o.categorical and len(o.categories) == n:
        return list(o.categories)
    return ["shift"] if n == 1 else [f"component {k + 1}" for k in range(n)]


def _difference(name: str, g: dict[str, Any], d: dict[str, Any]) -> str:
    """One observable's difference in words, in its unit (``g``: its gap entry, ``d``: the
    descriptive measures)."""
    o = OBSERVABLES[name]
    gap = g.get("gap") or {}
    # the gap in words: copy-spread units are spreads of the model's own copies
    tail = (f" (it fits {gap['mean']:.2g} spreads of the model's own copies worse per fiber, "
            f"95 % {gap['lo95']:.2g} to {gap['hi95']:.2g})"
            if gap.get("mean") is not None and gap.get("lo95") is not None else "")  # fmt: skip
    if o.categorical:
        shifts = [
            f"{'more' if z > 0 else 'fewer'} {lab}"
            for lab, z in zip(z_labels(name, len(g.get("bias_z", []))), g.get("bias_z", []),
                              strict=True)
            if z is not None and abs(z) >= 2 and not (o.kind == "binary" and z < 0)
        ]  # fmt: skip
        agree = d.get(f"{name}_agreement")
        miss = d.get(f"{name}_mismatch")
        parts = []
        if shifts:
            parts.append(", ".join(shifts) + " than the model predicts")
        if agree is not None:
            parts.append(f"{100 * agree:.0f} % of fibers in the class the model finds most often")
        if miss is not None:
            parts.append(f"{100 * miss:.0f} % of fibers disagree with the model's usual outcome")
        return f"{name} ({o.description}): " + ("; ".join(parts) or "scores worse") + tail
    r = d.get(f"{name}_residual") or {}
    unit = f" {o.unit}" if o.unit else ""
    if r.get("mean") is None:
        return f"{name} ({o.description}): scores worse than the model's copies{tail}"
    side = "above" if r["mean"] > 0 else "below"
    text = (f"{name} ({o.description}): measured {abs(r['mean']):.2g}{unit} {side} the "
            f"model's on average (per fiber sd {r['sd']:.2g}{unit}")  # fmt: skip
    ratio = d.get(f"{name}_ratio")
    text += f"; median ratio measured / model {ratio:.3g})" if ratio is not None else ")"
    return text + tail


def _value_text(name: str, value: float, entry: dict[str, Any] | None, ci: Any = None,
                op: Any = None, rigid: bool = False, switch: str = "") -> str:  # fmt: skip
    """``name = value, 95 % interval lo to hi (what it is)`` in the candidate's unit
    (``rigid``: a declared stiffness, whose setting runs backwards on its fitted scale)."""
    op = op or [False, False]
    if entry is not None and entry.get("setting"):
        text, ci = entry["setting"], entry.get("interval95_setting")
        op = op[::-1] if rigid else op  # a stiffness runs backwards: its ends swap
    else:
        text = f"{name} = {value:.3g}"
    if ci and ci[0] is not None and ci[1] is not None:
        # an open end: the fit's evaluated values stopped before the test rejected
        text += (f", 95 % interval {ci[0]:.3g}{' or less' if op[0] else ''} to "
                 f"{ci[1]:.3g}{' or more' if op[1] else ''}")  # fmt: skip
    if name in LIBRARY:
        text += f" ({LIBRARY[name].note}, no unit)"
    elif switch:
        text += f" (with {switch})"
    return text


def _explained(s: dict[str, Any]) -> list[str]:
    """Which effect explains the difference and by how much, in words."""
    v = s["verdict"]
    held = {h["effect"]: h for h in s["heldout"]}
    sets = {st["set"]: st for st in s["sets"]}
    declared = s.get("declared") or []
    rigid = {c["name"] for c in declared if c.get("scale") == "rigid"}
    switch = {c["name"]: ", ".join(f"{k} = {v}" for k, v in (c.get("switch") or {}).items())
              for c in declared}  # fmt: skip
    if v["kind"] == "no significant gap":
        return ["Nothing to explain: the model as it is agrees with these fibers within the "
                "measurement noise and its own run-to-run spread."]  # fmt: skip
    if v["kind"] in ("named", "ambiguous"):
        alts = v["alternatives"] or [v["effects"]]
        out = []
        for alt in alts:
            key = " + ".join(alt)
            st = sets.get(key)
            parts = []
            for k, val in alt.items():
                h = held.get(k) if st is None else None
                if st is None:
                    ci, op = (h or {}).get("interval95"), (h or {}).get("interval95_open")
                else:
                    ci = (st.get("interval95") or {}).get(k)
                    op = (st.get("interval95_open") or {}).get(k)
                parts.append(_value_text(k, val, h, ci, op, k in rigid, switch.get(k, "")))
            out.append(" together with ".join(parts))
        if v["kind"] == "named":
            return [f"Explained by {out[0]}: fitted on one half of the fibers, it removes the "
                    "difference on the other half, and leaves none significant."]  # fmt: skip
        return ["Two explanations fit equally well, and these fibers cannot tell them apart: "
                + "; or ".join(out) + " (what to measure next separates them)."]  # fmt: skip
    helped = sorted((h for h in s["heldout"] if h["significant"]),
                    key=lambda h: -h["improvement"]["mean"])  # fmt: skip
    if not helped:
        return ["Not explained: no candidate tried (the library"
                + (" and the declared settings" if s.get("declared") else "")
                + ") made the held-out fibers fit better."]
    h = helped[0]
    best = _value_text(h["effect"], h["value"], h, h.get("interval95"), h.get("interval95_open"),
                       h["effect"] in rigid, switch.get(h["effect"], ""))
    removed = [f"{o} {100 * r:.0f} %" for o, r in (h.get("gap_removed") or {}).items()
               if r is not None and r > 0.1]  # fmt: skip
    return [
        f"Not fully explained: the best candidate, {best}, makes the held-out fibers fit better"
        + (f" (removes {', '.join(removed)} of the gap)" if removed else "")
        + f", but a significant difference is left{_where(v)}."
    ]


def _where(v: dict[str, Any]) -> str:
    """' in OBSERVABLE' of a verdict that names one (else '')."""
    return f" in {v['observable']}" if v.get("observable") else ""


def first_page(s: dict[str, Any]) -> list[str]:
    """The report's first page for a researcher, in words: what differs, what explains it
    and by how much, what cannot be excluded, what to measure next, what did not run.

    Parameters
    ----------
    s : dict
        The summary (:func:`.report.summary`, JSON-safe).

    Returns
    -------
    list of str
        Markdown lines (no heading of the page itself).
    """
    gaps = {k: g for k, g in s["gap"].items() if g["significant"] or g["systematic"]}
    out = ["### What differs", ""]
    if not gaps:
        out.append(f"Nothing beyond noise: none of {', '.join(s['observables'])} differs "
                   f"between the {s['n_fibers']} measured fibers and the model by more than "
                   "the measurement noise and the model's run-to-run spread allow.")  # fmt: skip
    else:
        out += [f"- {_difference(k, g, s['descriptive'])}" for k, g in gaps.items()]
        r = s.get("region") or {}
        if r.get("where") and r.get("share") is not None:
            out += ["", f"Most of it ({100 * r['share']:.0f} %) comes from the fibers with "
                    f"{r['where']} ({r.get('n')} of {s['n_fibers']})."]  # fmt: skip
    out += ["", "### What explains it", "", *_explained(s)]
    out += ["", "### What cannot be excluded", ""]
    pw = s.get("power")
    listed = s.get("cannot_exclude")
    if listed is None:
        listed = cannot_exclude(s)
    if pw is None:
        why = s.get("power_skipped") or ""
        if why.startswith("skipped: budget"):
            why = f"was skipped for the budget ({why.removeprefix('skipped: budget').strip(' ()')})"
        out.append("Not analysed: the power analysis "
                   + (why or "runs only when nothing is named, and only if asked") + ".")
    elif listed:
        out.append(f"With {pw['n']} fibers these could be present at a realistic size and "
                   "go unseen:")  # fmt: skip
        out += [f"- {c['text']}" for c in listed]
    else:
        out.append(f"Every effect analysed would have been seen at a realistic size with "
                   f"{pw['n']} fibers (smaller sizes may still hide: see the power analysis).")
    out += ["", "### What to measure next", ""]
    out += _next_words(s)
    skipped = {k: w for k, w in (s.get("stages_skipped") or {}).items()
               if w.startswith("skipped: budget")}  # fmt: skip
    if skipped:
        out += ["", "### Not run for the budget", ""]
        out += [f"- {k}: {w.removeprefix('skipped: budget').strip(' ()')}"
                for k, w in skipped.items()]  # fmt: skip
    return out


def _next_words(s: dict[str, Any]) -> list[str]:
    """What to measure next, in words (the first page's last question)."""
    nx = s.get("next")
    if nx and nx.get("best"):
        b = nx["best"][0]
        a, c = nx["hypotheses"]
        need = nx.get("fibers_needed")
        yu, lu = start_units(s.get("observables", ()))
        return [f"To tell **{a}** from **{c}**: about {_n(need)} fibers near θ0 "
                f"{b['theta0']:.1f}°, y0 {b['y0']:.2f} {yu}, L {b['length']:.2f} {lu} "
                "(the other starts in the table 'What to measure next' below)."]  # fmt: skip
    listed = s.get("cannot_exclude") or []
    n = int(s.get("n_fibers") or 0)
    # the upper end of the fibers' 95 % range settles it whichever set of starts is right
    ends = [((c.get("fibers_ci") or [None, c["fibers"]])[1], c) for c in listed if c.get("fibers")]
    settle = sorted((kc for kc in ends if kc[0]), key=lambda kc: kc[0])
    if settle:
        parts = [f"{c['effect']} at {c['realistic']:.3g}: {k} fibers in all"
                 + (f" ({k - n} more than the {n} measured)" if k > n else "")
                 for k, c in settle[:3]]  # fmt: skip
        return ["More fibers at starts like these would settle what cannot be excluded ("
                "the upper end of each number's 95 % range): " + "; ".join(parts) + "."]
    if s["verdict"]["kind"] == "named":
        return ["Nothing needed to decide: the updated config holds the named effect."]
    if s.get("next_skipped"):
        return [f"Not computed: {s['next_skipped']}."]
    if s["verdict"]["kind"] == "no significant gap":
        return ["Nothing to decide between. Smaller effects than these fibers can see need "
                "more fibers (the power analysis says which and how many)."]  # fmt: skip
    return ["Nothing specific: no two explanations are left to separate."]

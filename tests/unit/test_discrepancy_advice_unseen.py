"""The advice never hides an effect the power analysis cannot exclude (no simulations).

An effect is "cannot be excluded" when its detection limit, or the upper end of
the limit's 95 % interval over the simulated starts, lies above its realistic
magnitude or out of its range: these fibers could carry it at that magnitude
unseen. The case of the issue: 40 fibers, friction detected only from 0.667 with
the upper end of its interval out of range, realistic 0.5.
"""

from __future__ import annotations

from fibersweep.discrepancy.advice import advice_lines, cannot_exclude
from fibersweep.discrepancy.report_first_page import first_page


def _effect(name, limit, ci, real, need, need_ci=None, direction="+"):
    return {"effect": name, "direction": direction, "limit": limit, "limit_ci": ci,
            "realistic": real, "fibers_for_realistic": need,
            "fibers_for_realistic_ci": need_ci}  # fmt: skip


def _summary(kind: str = "no significant gap") -> dict:
    effects = [
        _effect("friction", 0.667, [0.4, None], 0.5, 70, [35, None]),  # upper end out of range
        _effect("inlet_speed", 0.02, [0.015, 0.03], 0.05, 12, direction="-"),  # seen
        _effect("pillar_hydro", 1.4, [0.9, 2.5], 1.0, 90),  # limit above realistic
        _effect("off_midplane", None, None, 0.15, None),  # not within its range
        _effect("pillar_scale", 0.05, [0.03, 0.12], 0.1, 20),  # upper end above realistic
    ]
    power = {"n": 40, "n_simulated": 40, "alpha": 0.05, "power": 0.8, "effects": effects,
             "lookalikes": [], "leading": None, "simulations": 1}  # fmt: skip
    return {"verdict": {"kind": kind, "text": "t", "effects": {}, "alternatives": [],
                        "observable": ""},
            "heldout": [], "sets": [], "power": power, "next": None, "n_fibers": 40,
            "gap": {}, "observables": ["class"], "descriptive": {}, "region": {},
            "stages_skipped": {}}  # fmt: skip


def test_an_out_of_range_upper_end_is_listed_as_cannot_be_excluded():
    listed = {c["effect"]: c for c in cannot_exclude(_summary())}
    # exactly the four whose limit or upper end exceeds the realistic size (or its range)
    assert set(listed) == {"friction", "pillar_hydro", "off_midplane", "pillar_scale"}
    assert listed["friction"]["upper"] is None and listed["friction"]["fibers"] == 70
    assert "about 70 fibers would detect 0.5" in listed["friction"]["text"]
    assert "35 to more than 100000" in listed["friction"]["text"]
    assert "more than 100000 fibers" in listed["off_midplane"]["text"]
    adv = " ".join(advice_lines(_summary()))
    cannot, seen = adv.split("Cannot be excluded")[1].split("Would have been seen")
    assert ("friction (+): detected only from 0.667 (another set of starts could put that "
            "beyond its range)") in cannot
    assert "inlet_speed" not in cannot and "inlet_speed (-) up to 0.03" in seen


def test_the_first_page_lists_what_cannot_be_excluded():
    s = _summary()
    s["cannot_exclude"] = cannot_exclude(s)
    page = "\n".join(first_page(s))
    part = page.split("### What cannot be excluded")[1].split("###")[0]
    assert "friction (+)" in part and "pillar_hydro (+)" in part and "inlet_speed" not in part
    # the next measurement: the fibers that settle each, by the upper end of their range
    nxt = page.split("### What to measure next")[1]
    assert "pillar_scale at 0.1: 20 fibers in all;" in nxt  # no range: its estimate
    assert "pillar_hydro at 1: 90 fibers in all (50 more than the 40 measured)" in nxt
    assert "friction" not in nxt  # its range's upper end: more than 100 000


def test_a_declared_candidate_open_at_its_range_end_is_not_excluded():
    s = _summary()
    s["power"]["effects"] = [
        {"effect": "fiber.young_modulus", "direction": "+", "limit": 0.9, "limit_ci": [0.7, None],
         "realistic": None, "fibers_for_realistic": None,
         "setting": "flexibility detected for fiber.young_modulus <= 5e+05 Pa [1e5, out of range]",
         "unseen": "flexibility of fiber.young_modulus anywhere in its range"},
        {"effect": "fiber.contact.chi=2.5", "direction": "+", "limit": 1.0, "limit_ci": None,
         "realistic": None, "fibers_for_realistic": None,
         "setting": "detected with fiber.contact.chi = 2.5", "unseen": None},
    ]  # fmt: skip
    listed = cannot_exclude(s)
    assert [c["effect"] for c in listed] == ["fiber.young_modulus"]
    assert listed[0]["text"].startswith("fiber.young_modulus (+): flexibility detected for")

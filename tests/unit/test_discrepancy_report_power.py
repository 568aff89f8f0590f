"""The report's power table and advice with each limit's interval (no simulations)."""

from __future__ import annotations

from fibersweep.discrepancy.advice import advice_lines as _advice
from fibersweep.discrepancy.report_followup import power_lines


def _summary(kind: str) -> dict:
    effects = [
        {"effect": "friction", "direction": "+", "limit": 0.11, "limit_ci": [0.08, 0.2],
         "realistic": 0.4, "fibers_for_realistic": 12},
        {"effect": "pillar_hydro", "direction": "+", "limit": 0.3, "limit_ci": [0.1, None],
         "realistic": 0.5, "fibers_for_realistic": 80, "read_at": 0.25},
        {"effect": "start_noise", "direction": "+", "limit": 1.6, "limit_ci": None,
         "realistic": 2.0, "fibers_for_realistic": 60, "dispersion_limit": 1.3},
    ]  # fmt: skip
    power = {"n": 100, "n_simulated": 40, "alpha": 0.05, "power": 0.8, "effects": effects,
             "lookalikes": [], "leading": None, "simulations": 1}  # fmt: skip
    nxt = {"reason": "the gap is unexplained; friction = 0.2 helped most", "fibers_needed": 23,
           "fibers_needed_at_measured_starts": 140,
           "best": [{"theta0": 4.0, "y0": 0.3, "length": 1.1, "observable": "class"}]}  # fmt: skip
    return {"verdict": {"kind": kind}, "heldout": [], "sets": [], "power": power, "next": nxt}


def test_power_table_shows_each_limit_with_its_interval():
    text = "\n".join(power_lines(_summary("unexplained")))
    assert "| friction | + | 0.11 | [0.08, 0.2] |" in text
    # an upper end beyond the effect's range in more than 2.5 % of the resamples
    assert "| pillar_hydro | + | 0.3 | [0.1, out of range] |" in text
    assert "| start_noise | + | 1.6 | – |" in text
    assert "dispersion test alone" in text and "start_noise from 1.3" in text
    # a limit read again where it lies says where; the others (read at the probes) do not
    again = next(x for x in text.split("\n") if x.startswith("Read again"))
    assert again.endswith("pillar_hydro + at 0.25.") and "friction" not in again


def test_advice_of_an_unexplained_gap_names_the_next_measurement_and_the_unseen_sizes():
    adv = " ".join(_advice(_summary("unexplained")))
    assert "about 23 more fibers" in adv and "like the measured ones: 140" in adv
    seen, cannot = adv.split("Would have been seen")[1], adv.split("Cannot be excluded")[1]
    assert "friction (+) up to 0.2" in seen
    # an interval's upper end out of range: not excluded, with the fibers that would settle it
    assert "pillar_hydro" not in seen and "pillar_hydro (+)" in cannot.split("Would")[0]
    assert "about 80 fibers would detect 0.5" in cannot
    # no gap: only what is and is not excluded, no next measurement
    adv = " ".join(_advice(_summary("no significant gap")))
    assert "Would have been seen" in adv and "more fibers at" not in adv


def test_unexplained_without_a_candidate_sends_the_fibers_where_the_gap_is_largest():
    from fibersweep.discrepancy.advice import next_measurement

    s = _summary("unexplained")
    s.update(next=None, n_fibers=100,
             region={"where": "y0 > 0.31 and θ0 <= 4.5", "n": 22, "share": 0.61})  # fmt: skip
    adv = " ".join(next_measurement(s))
    assert "more fibers where the gap is largest, y0 > 0.31 and θ0 <= 4.5" in adv
    assert "(22 of the 100 fibers, 61 % of the gap)" in adv
    assert next_measurement(_summary("named")) == []


def test_power_curve_numbers_for_the_leading_candidate_carry_their_interval():
    from fibersweep.discrepancy.advice import next_measurement
    from fibersweep.discrepancy.report_followup import power_lines

    s = _summary("unexplained")
    s["n_fibers"] = 100
    s["power"]["leading"] = {"effect": "friction", "value": 0.21, "fibers_to_detect": 140,
                             "fibers_to_detect_ci": [90, None], "fibers_to_name": 260}  # fmt: skip
    adv = " ".join(next_measurement(s))
    assert "about 23 more fibers at the starts" in adv  # the next-measure starts first
    assert "for friction = 0.21: about 140 fibers would detect a gap of its size" in adv
    assert "(95 % over the simulated starts: 90 to more than 100000)" in adv
    assert "about 260 would name it (held-out improvement significant, 160 more than the 100" in adv
    text = "\n".join(power_lines(s))
    assert (
        "about 140 fibers would detect a gap of this size (95 % over the simulated "
        "starts: 90 to more than 100000)" in text
    )


def test_what_to_measure_next_asks_for_starts_spread_over_the_window():
    """The count and the follow-up test assume starts scattered over the window, and
    one test of the fibers: the report says both; without a window, the starts only."""
    from fibersweep.discrepancy.report_followup import next_lines

    s = _summary("ambiguous")
    s["next"] |= {"hypotheses": ["a = 1", "b = 2"],
                  "best": [{"theta0": 4.0, "y0": 0.3, "length": 1.1, "d": 0.4,
                            "observable": "t_pass", "a": 0.5, "b": 0.6}]}  # fmt: skip
    text = "\n".join(next_lines(s | {"next": s["next"] | {"window": [3.0, 0.03, 0.03]}}))
    assert "with starts spread over θ0 ±3°, y0 ±0.03 h_obs, L ±0.03 l_obs" in text
    assert "not aimed at one point" in text and "`--followup`, once" in text
    assert "About 23 fibers there" in text
    assert "measure fibers at these starts" in "\n".join(next_lines(s))

"""The report in two layers: a first page in words, then the statistical detail with a
glossary, labelled z's and units; gap-only sections only with a gap (no simulations)."""

from __future__ import annotations

import numpy as np

from fibersweep.discrepancy.report_figures import bin_z
from fibersweep.discrepancy.report_text import markdown


def _gap(sig: bool, bias_z: list[float], mean: float = 0.1) -> dict:
    return {"n": 40, "gap": {"mean": mean, "lo95": mean - 0.2, "hi95": mean + 0.2},
            "p_holm": 0.001 if sig else 1.0, "signed_p_holm": 0.002 if sig else 1.0,
            "bias_z": bias_z, "significant": sig, "systematic": sig}  # fmt: skip


def _summary(with_gap: bool) -> dict:
    verdict = (
        {"kind": "named", "effects": {"friction": 0.48}, "alternatives": [{"friction": 0.48}],
         "observable": "delta", "region": "R", "text": "friction explains it"}
        if with_gap else
        {"kind": "no significant gap", "effects": {}, "alternatives": [], "observable": "",
         "region": "", "text": "nothing beyond noise"}
    )  # fmt: skip
    heldout = []
    if with_gap:
        heldout = [{"effect": "friction", "value": 0.48, "halves": [0.45, 0.5],
                    "interval95": [0.31, 0.66], "interval95_open": [False, False],
                    "improvement": {"mean": 0.4, "lo95": 0.2, "hi95": 0.6}, "p": 0.001,
                    "p_holm": 0.002, "significant": True, "explains": True,
                    "gap_after": {}, "gap_removed": {"delta": 0.8}, "spread": None}]  # fmt: skip
    return {
        "verdict": verdict, "n_fibers": 40, "observables": ["class", "delta"],
        "observables_absent": [], "start_axes_varying": ["theta0", "y0"], "alpha": 0.05,
        "gap": {"class": _gap(False, [0.0, -2.1, -0.4, 2.1]),
                "delta": _gap(with_gap, [3.4 if with_gap else 0.3], 1.2 if with_gap else 0.1)},
        "descriptive": {"class_agreement": 0.9,
                        "delta_residual": {"mean": 0.012, "sd": 0.02, "n": 40}},
        "region": {"where": "y0 > 0.31", "n": 12, "share": 0.7}, "region_by_observable": {},
        "signatures": [], "heldout": heldout, "sets": [], "heldout_gap_before": {},
        "power": None, "power_skipped": None, "next": None, "next_skipped": None,
        "settle": None, "stages_skipped": {}, "simulations": 320, "seconds": 10.0,
        "failed_runs": 0, "failed_runs_by_stage": {}, "settings": {}, "advice": [],
        "dispersion": {}, "declared": [],
    }  # fmt: skip


def test_without_a_gap_the_report_says_so_in_words_and_shows_no_gap_sections():
    md = markdown(_summary(False), ["phase_before_after.png"], [])
    first, detail = md.split("# Statistical detail")
    assert first.index("## In short") < first.index("### What differs")
    assert "Nothing beyond noise" in first and "Nothing to explain" in first
    assert "Where the gap lives" not in md
    assert "## Words used below" in detail and "**fair Brier score, fair CRPS**" in detail
    # every z with what it is about; every residual in its observable's unit
    assert "| Below +0.0, Above -2.1, Pole-vaulting -0.4, Trapping +2.1 |" in detail
    assert "| shift +0.3 |" in detail
    assert "delta: measured minus the model's mean +0.012 h_obs on average, sd 0.02 h_obs" in detail
    assert "class: 90 % of fibers in the class the model finds most often" in detail


def test_a_named_effect_is_given_in_words_with_its_value_and_interval():
    md = markdown(_summary(True), [], [])
    first = md.split("# Statistical detail")[0]
    assert ("Explained by friction = 0.48, 95 % interval 0.31 to 0.66 (Coulomb coefficient on "
            "the pillar, no unit)") in first  # fmt: skip
    assert "delta (lateral displacement y_f - y0 far downstream): measured 0.012 h_obs" in first
    assert "Most of it (70 %) comes from the fibers with y0 > 0.31 (12 of 40)" in first
    assert "## Where the gap lives" in md


def test_a_bins_z_is_its_mean_over_the_noise_of_a_mean_of_its_fibers():
    mean = np.array([[0.5, np.nan], [-1.0, 0.2]])
    count = np.array([[4, 0], [9, 1]])
    z = bin_z(mean, count, sd=1.0)
    # 0.5 * sqrt(4) = 1, -1 * sqrt(9) = -3, 0.2 * 1: exact arithmetic (1e-12)
    assert np.allclose(z[[0, 1, 1], [0, 0, 1]], [1.0, -3.0, 0.2], rtol=0, atol=1e-12)
    assert np.isnan(z[0, 1])  # no fibers: no z
    assert np.isnan(bin_z(mean, count, sd=0.0)).all()


def test_the_residual_map_is_drawn_only_with_a_gap_and_over_sampled_axes(tmp_path):
    """An L spread by the start noise alone (sd 0.01 l_obs) is no axis of the map."""
    from types import SimpleNamespace

    import pandas as pd

    from fibersweep.discrepancy.copies import NoiseModel
    from fibersweep.discrepancy.report_figures import _residual_map, _sampled_axes

    rng = np.random.default_rng(0)
    n = 60
    obs = pd.DataFrame({"theta0": rng.uniform(-8, 8, n), "y0": rng.uniform(0.05, 0.9, n),
                        "length": 1.0 + 0.01 * rng.standard_normal(n)})  # fmt: skip
    res = SimpleNamespace(gap=SimpleNamespace(any=True), observed=obs,
                          gap_per_fiber=rng.standard_normal(n),
                          settings=SimpleNamespace(noise=NoiseModel()))  # fmt: skip
    assert _sampled_axes(res) == ["theta0", "y0"]
    assert _residual_map(res, tmp_path) == "residual_map.png"
    res.gap = SimpleNamespace(any=False)
    assert _residual_map(res, tmp_path / "none") is None


def test_an_unexplained_gap_names_the_best_candidate_and_what_it_left():
    s = _summary(True)
    s["verdict"] = {"kind": "unexplained", "effects": {}, "alternatives": [],
                    "observable": "delta", "region": "R", "text": "t"}  # fmt: skip
    s["heldout"][0]["explains"] = False
    first = markdown(s, [], []).split("# Statistical detail")[0]
    assert ("Not fully explained: the best candidate, friction = 0.48, 95 % interval 0.31 to "
            "0.66 (Coulomb coefficient on the pillar, no unit), makes the held-out fibers fit "
            "better (removes delta 80 % of the gap), but a significant difference is left in "
            "delta.") in first  # fmt: skip

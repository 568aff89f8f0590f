"""Every pole-vaulting rule against the labelled set (tests/data/vault_labels).

100 runs (the ``design`` set) and 40 more drawn apart (``holdout``) from the contact band
of the default field (configs/quick.yaml), each labelled by eye from its
chronophotograph (docs/figures/vault-labels); the trajectories are stored, so the rules
are judged without solving anything. The bounds are the measured agreement
(docs/validation/fiber-models.md, ``python scripts/studies/fidelity/vault_labels.py compare``) less
about two binomial standard errors (sqrt(p(1-p)/100) <= 0.05 on the design set), so a
rule change that costs a few runs fails here and is looked at again. The default rule was
chosen on the design set and is confirmed on the holdout set, which no rule or setting was
chosen on.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from fibersweep.analysis.classify import RULES
from fibersweep.analysis.labelled import confusion, load_trajectories, rule_labels
from fibersweep.analysis.trajectory import CLASSES
from fibersweep.config.loading import load_config

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data" / "vault_labels"


def _judge(name: str):
    cfg = load_config(REPO / "configs" / "quick.yaml")
    starts = pd.read_csv(DATA / "labels.csv")
    done = starts[starts["set"] == name]
    trajs = load_trajectories(DATA / "trajectories.npz")
    got = rule_labels(
        done, trajs, cfg.flow.geometry.to_geometry(), cfg.flow.fluid.u_center,
        cfg.fiber.classify, RULES,
    )  # fmt: skip
    return done, got


@pytest.fixture(scope="module")
def judged():
    return _judge("design")


@pytest.fixture(scope="module")
def holdout():
    return _judge("holdout")


def test_the_set_is_complete():
    starts = pd.read_csv(DATA / "labels.csv")
    design = starts[starts["set"] == "design"]
    assert len(design) >= 60  # the issue asks for at least 60 pictures
    assert design["label"].notna().all() and design["reason"].str.len().gt(10).all()
    assert set(design["id"]) <= set(load_trajectories(DATA / "trajectories.npz"))


# measured agreement (of 100): head-speed 53, pivot 58, switch 88, corner 48
@pytest.mark.parametrize(
    ("rule", "low", "high"),
    [("head-speed", 0.43, 0.63), ("pivot", 0.48, 0.68), ("switch", 0.81, 0.95),
     ("corner", 0.38, 0.58)],
)  # fmt: skip
def test_agreement_of_every_rule_with_the_labels(judged, rule, low, high):
    done, got = judged
    agree = float((got[rule] == done["label"]).mean())
    assert low <= agree <= high, confusion(done["label"], got[rule]).to_string()


def test_every_rule_agrees_on_runs_without_a_swap(judged):
    # the rules only differ on swapped runs: Below, Above and Trapping by eye are never
    # called Pole-vaulting by head-speed, pivot or corner
    done, got = judged
    plain = done["label"] != "Pole-vaulting"
    for rule in ("head-speed", "pivot", "corner"):
        assert (got.loc[plain, rule] == done.loc[plain, "label"]).all(), rule


def test_the_default_rule_is_confirmed_on_the_holdout_set(holdout):
    """Measured on the 40 held-out runs: switch 39, head-speed 22 (docs/validation/fiber-models.md).

    Bounds: switch at least 0.90 (0.975 less three standard errors, sqrt(.975*.025/40)
    = 0.025); head-speed at most 0.70 (0.55 plus two, sqrt(.25/40) = 0.079); the default
    beats the source's rule by at least 0.25 (measured 0.425).
    """
    from fibersweep.config.fiber import ClassifySettings

    done, got = holdout
    assert len(done) == 40 and done["label"].isin(CLASSES).all()
    assert ClassifySettings().rule == "switch"
    agree = {r: float((got[r] == done["label"]).mean()) for r in RULES}
    assert agree["switch"] >= 0.90, confusion(done["label"], got["switch"]).to_string()
    assert agree["head-speed"] <= 0.70, confusion(done["label"], got["head-speed"]).to_string()
    assert agree["switch"] - agree["head-speed"] >= 0.25, agree
    assert max(agree, key=agree.get) == "switch", agree


def test_every_registered_rule_is_judged():
    assert set(RULES) == {"head-speed", "pivot", "switch", "corner"}

"""The validated-range rules: each fires where its page says the model is not converged
or not checked, stays quiet inside, names the setting to change and its page."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from fibersweep.sweep import validity as v

REPO = Path(__file__).resolve().parents[2]

#: A combination inside every rule's range: a rigid fiber through 20 rows at ε = 0.1.
INSIDE = v.Facts("", "rigid", 26e6, 1.0, True, True, 0.1, 20, trapped=1, runs=12)
SOFT = dataclasses.replace(INSIDE, model="bead-spring", young_modulus=1e4)

#: Per rule: a combination it fires on, and one just inside its range.
CASES = {
    "touching-soft": (SOFT, dataclasses.replace(SOFT, bead_spacing=0.5)),
    "touching-unchecked": (
        dataclasses.replace(SOFT, young_modulus=1e5),
        dataclasses.replace(SOFT, young_modulus=1e6),
    ),
    "trapped-spacing": (
        dataclasses.replace(SOFT, bead_spacing=0.5),
        dataclasses.replace(SOFT, bead_spacing=0.25),
    ),
    "self-exclusion": (
        dataclasses.replace(SOFT, self_exclusion=False),
        dataclasses.replace(SOFT, self_exclusion=False, young_modulus=1e6),
    ),
    "rows-periods": (
        dataclasses.replace(INSIDE, array_rows=19),
        dataclasses.replace(INSIDE, array_rows=20),
    ),
    "device-rows": (
        dataclasses.replace(INSIDE, device_rows=5),
        dataclasses.replace(INSIDE, device_rows=10),
    ),
}


def test_every_rule_is_tested_and_names_a_page_that_exists():
    assert set(CASES) == set(v.RULES)
    for rule in v.RULES.values():
        for part in rule.source.split(";"):
            page = part.strip().split(",")[0]
            assert (REPO / page).is_file(), (rule.name, page)


@pytest.mark.parametrize("name", sorted(v.RULES))
def test_each_rule_fires_outside_its_range_only(name):
    rule = v.RULES[name]
    out, inside = CASES[name]
    assert rule.applies(out) and not rule.applies(inside)
    assert not rule.applies(INSIDE)
    (text,) = v.warnings_for([out], {name: rule})
    assert rule.setting.split()[-1] in text  # the setting (or option) to change
    assert text.endswith(f"[{rule.source}]")
    assert v.warnings_for([inside], {name: rule}) == ()


def test_the_thresholds_are_the_pages():
    """31.6 kPa is not converged with touching beads (bandpass.md section 4); b = a is the
    spacing to set for f, b = a/2 for trapped shares; two zigzag periods of rows."""
    at = dataclasses.replace(SOFT, young_modulus=31.6e3)
    assert v.RULES["touching-soft"].applies(at)
    text = v.RULES["touching-soft"].says([at])
    assert "not converged" in text and "fiber.bead_spacing to 0.5 (b = a)" in text
    trap = v.RULES["trapped-spacing"].says([dataclasses.replace(SOFT, bead_spacing=0.5)])
    assert "trapped shares need b = a/2" in trap and "fiber.bead_spacing to 0.25" in trap
    rows = v.RULES["rows-periods"].says([dataclasses.replace(INSIDE, array_rows=3)])
    assert "3 rows are 0.3 zigzag periods" in rows and "at least 20 rows" in rows
    dev = v.RULES["device-rows"].says([dataclasses.replace(INSIDE, device_rows=5)])
    assert "cannot complete one period" in dev and "--rows 10" in dev
    # no trapped run, no trapped share to doubt
    assert not v.RULES["trapped-spacing"].applies(dataclasses.replace(SOFT, trapped=0))


def test_one_line_per_rule_naming_the_combinations_it_concerns():
    combos = [
        dataclasses.replace(SOFT, label="young_modulus=10000.0"),
        dataclasses.replace(SOFT, label="young_modulus=31600.0", young_modulus=3.16e4),
        dataclasses.replace(SOFT, label="young_modulus=1000000.0", young_modulus=1e6),
    ]
    found = v.warnings_for(combos)
    soft = [w for w in found if "touching beads are not converged" in w]
    assert len(soft) == 1
    assert "young_modulus=10000.0; young_modulus=31600.0" in soft[0]
    assert "E = 10 kPa, 31.6 kPa" in soft[0] and "1000000" not in soft[0]
    # a rule every combination breaks names none of them
    rows = v.warnings_for([dataclasses.replace(c, array_rows=3) for c in combos])
    assert any("zigzag periods at ε = 0.1 (1/ε = 10 rows), too few" in w for w in rows)


def test_the_shipped_configs(tmp_path):
    """The flexible array config (touching beads at 1 MPa, 0.1 MPa and 10 kPa) is warned
    on; the rigid one is not."""
    from fibersweep.api import load_config
    from fibersweep.sweep.plan import sweep_settings

    flex = load_config("configs/array-flexible.yaml")
    found = v.warnings_for(v.combination_facts(sweep_settings(flex)))
    names = " ".join(found)
    assert "E = 10 kPa with touching beads (b = 2a)" in names
    assert "E = 100 kPa with touching beads (b = 2a) in an array" in names
    assert "trapped shares" in names  # not known before the runs: warned
    assert (
        v.warnings_for(v.combination_facts(sweep_settings(load_config("configs/array.yaml")))) == ()
    )
    short = load_config("configs/array.yaml", "fiber.array_rows=5")
    (rows,) = v.warnings_for(v.combination_facts(sweep_settings(short)))
    assert "5 rows are 0.5 zigzag periods" in rows


def test_facts_from_a_stored_config_fill_the_defaults_and_apply_the_swept_values():
    stored = {"model": "bead-spring", "bead_radius": 2.0}  # a manifest leaves defaults out
    f = v.facts_from_dict(stored, {"shift": 0.1}, {"fiber.young_modulus": 1e4}, "E")
    assert (f.young_modulus, f.bead_spacing, f.self_exclusion, f.array_rows) == (1e4, 1.0, True,
                                                                                 20)  # fmt: skip
    assert f.array and f.shift == 0.1 and f.label == "E"

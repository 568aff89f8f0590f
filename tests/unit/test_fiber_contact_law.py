"""The contact law's range: the source's chi law and the surfaces' gap law (contact.law)."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from fibersweep.config.fiber import ContactSettings, FiberSettings
from fibersweep.fiber.contact.pillar import contact_forces, make_pillar
from fibersweep.units import Geometry


def test_default_is_the_source_law_and_its_dump_is_unchanged():
    """law chi is the default; its dump holds neither law, gap_um nor curvature (so run ids
    of configs that do not set them are as before)."""
    c = ContactSettings()
    assert c.law == "chi" and c.curvature == "plane"
    dump = c.model_dump()
    assert "law" not in dump and "gap_um" not in dump and "curvature" not in dump
    assert set(FiberSettings().model_dump()["contact"]) == {
        "pillar", "obstacle_bead_radius", "chi", "f_ref", "corner_radius",
    }  # fmt: skip
    g = ContactSettings(law="gap", gap_um=0.3, curvature="local")
    assert g.model_dump()["law"] == "gap" and g.model_dump()["gap_um"] == 0.3
    assert ContactSettings.model_validate(g.model_dump()) == g


def test_cutoffs_of_the_two_laws():
    """chi: R = chi r_eq (bit for bit the former product); gap: R = r_eq + gap for any r_eq."""
    c = ContactSettings(chi=1.07)
    for r_eq in (2.6, 7.6, 15.6):
        assert c.cutoff(r_eq) == 1.07 * r_eq
        assert ContactSettings(law="gap", gap_um=0.4).cutoff(r_eq) == pytest.approx(r_eq + 0.4)


def test_gap_is_refused_with_the_chi_law_and_out_of_range():
    with pytest.raises(ValidationError, match="gap_um"):
        ContactSettings(gap_um=0.3)
    with pytest.raises(ValidationError):
        ContactSettings(law="gap", gap_um=0.0)
    with pytest.raises(ValidationError):
        ContactSettings(law="gap", gap_um=6.0)
    with pytest.raises(ValidationError):
        ContactSettings(law="roughness")


@pytest.mark.parametrize("pillar", ["rough", "smooth"])
def test_the_gap_law_touches_at_the_same_surface_gap_for_every_bead(pillar):
    """A bead of radius a below the middle of the base: with the gap law the force starts at
    the same surface gap δ_r (bead surface to pillar bead surface, rough; to the outline,
    smooth) for a = 1, 5, 12 µm; with the chi law the range grows with a."""
    geo = Geometry()
    xb = geo.shape.vertices[:, 0].mean()
    yb = geo.shape.vertices[:, 1].min()
    gap = 0.3
    ranges = []
    for a in (1.0, 5.0, 12.0):
        for law, kw in (("gap", {"gap_um": gap}), ("chi", {})):
            st = ContactSettings(pillar=pillar, law=law, **kw)
            pil = make_pillar(geo, st, a, 1.0)
            r_eq = pil.r_eq
            surface = r_eq - a if pillar == "rough" else 0.0  # a_obs of the rough beads
            # just inside and just outside the range (below the base, on a pillar bead)
            in_f, _ = contact_forces(pil, np.array([[xb, yb - (pil.r_cut - 1e-6)]]))
            out_f, _ = contact_forces(pil, np.array([[xb, yb - (pil.r_cut + 1e-6)]]))
            assert np.abs(out_f).max() == 0.0
            assert in_f[0, 1] < 0.0  # pushed away, down
            if law == "gap":
                assert pil.r_cut - a - surface == pytest.approx(gap, abs=1e-12)
            else:
                ranges.append(pil.r_cut - a - surface)
    assert ranges[0] < ranges[1] < ranges[2]

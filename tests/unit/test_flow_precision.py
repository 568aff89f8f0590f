"""flow.precision: cache keys, the float32 tolerance floor, dtype-specialised kernels."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest
from pydantic import ValidationError

from fibersweep.config.flow import FlowSettings, GeometrySettings
from fibersweep.flow.cache import cache_key
from fibersweep.flow.lattice import make_grid
from fibersweep.flow.lbm import SOLVER_VERSION
from fibersweep.flow.steppers import make_stepper
from fibersweep.units import Geometry

TINY = FlowSettings(
    geometry=GeometrySettings(width=48, depth=16, length=96, pillar_height=20), dx=2.0
)


def _key_without_precision(settings: FlowSettings) -> str:
    """The key as computed before ``precision`` (and the pillar shapes, and the patch) existed."""
    dump = settings.model_dump(mode="json")
    dump.pop("precision")
    dump.pop("patch")
    for name in ("pillar_shape", "pillar_rotation", "pillar_vertices"):  # default triangle
        dump["geometry"].pop(name)
    blob = json.dumps({"settings": dump, "solver": SOLVER_VERSION}, sort_keys=True,
                      separators=(",", ":")).encode()  # fmt: skip
    return hashlib.sha256(blob).hexdigest()[:24]


def test_default_precision_keeps_existing_cache_keys():
    # fields cached before the key existed are found again: the default (float32,
    # what was always computed) leaves the key as it was
    for s in (TINY, FlowSettings(), TINY.model_copy(update={"pillar_boundary": "interpolated"})):
        assert s.precision == "float32"
        assert cache_key(s) == _key_without_precision(s)


def test_float64_has_its_own_cache_key():
    s64 = TINY.model_copy(update={"precision": "float64"})
    assert cache_key(s64) != cache_key(TINY)
    assert cache_key(s64) == cache_key(FlowSettings.model_validate(s64.model_dump()))


def test_float32_rejects_tolerance_below_its_floor():
    with pytest.raises(ValidationError, match="tolerance = 1e-08.*precision: float64"):
        FlowSettings(tolerance=1e-8)
    assert FlowSettings(tolerance=1e-8, precision="float64").tolerance == 1e-8
    with pytest.raises(ValidationError, match="precision"):
        FlowSettings(precision="float16")


@pytest.mark.parametrize("kernel", ["aa", "pull"])
def test_stepper_keeps_and_specialises_on_its_dtype(kernel):
    # the same start stepped in both precisions: storage keeps its dtype and the
    # states agree to float32 rounding (tolerance 1e-5 of the largest population)
    geom = Geometry(width=48, depth=16, length=96, pillar_height=20)
    grid = make_grid(geom, 2.0, symmetry=True)
    shape = (grid.nz, grid.ny, grid.nx)
    u0 = np.zeros((3, *shape))
    u0[0] = 1e-5
    out = {}
    for dt in (np.float32, np.float64):
        st = make_stepper(
            kernel, grid, u0, np.zeros(shape), np.zeros((3, 3, *shape)), 1e-7, 1.1, 1.2, dtype=dt
        )
        st.advance(4)
        assert st.g.dtype == dt
        mom = np.zeros((4, *shape))
        st.moments(mom)
        out[dt] = mom
    scale = np.abs(out[np.float64][1]).max()
    assert np.abs(out[np.float32] - out[np.float64]).max() < 1e-5 * scale
    with pytest.raises(ValueError, match="float16.*float32"):
        make_stepper(kernel, grid, u0, np.zeros(shape), np.zeros((3, 3, *shape)), 1e-7, 1.1, 1.2,
                     dtype=np.float16)  # fmt: skip

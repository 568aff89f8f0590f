"""The far-upstream separatrix of a field with an estimate of its error.

Two independent measures of how well the separatrix y_s/h_obs of a lattice
field is known:

* **model spread** |y_traced − y_flux|: the streamline traced through the
  z-averaged midplane field (what a fiber follows,
  :func:`fibersweep.flow.streamlines.separatrix_y`) against the stream line
  that carries the flux passing below the pillar
  (:func:`fibersweep.flow.analysis.flux_separatrix`). They would agree for an
  exactly 2D divergence-free field; the difference measures how far the
  midplane field is from one, and is an error of the *definition* more than of
  the grid.
* **grid error** by Richardson extrapolation with the formal order p = 2 of the
  solver, from the same problem at a spacing twice or half as large when it is
  in the cache: for the fine value of a pair (s_f, s_c) the error is
  (s_f − s_c)/3, for the coarse value 4 (s_c − s_f)/3. Nothing is solved here.

The reported ``error`` is the sum of the two (a conservative bound, in h_obs).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.analysis import flux_separatrix
from fibersweep.flow.cache import CorruptCacheError, cache_key, load_entry
from fibersweep.flow.field import FlowField
from fibersweep.flow.streamlines import separatrix_y

__all__ = ["SeparatrixEstimate", "separatrix_estimate", "other_level"]

log = logging.getLogger(__name__)

ORDER = 2.0  # formal order of the TRT solver with half-way / interpolated walls


@dataclass(frozen=True)
class SeparatrixEstimate:
    """Separatrix y_s/h_obs far upstream with its error parts (all in h_obs).

    Attributes
    ----------
    traced : float
        Canonical value (streamline traced through the midplane field).
    flux : float
        Value from the flux passing below the pillar.
    model_spread : float
        |traced − flux|.
    other_dx : float or None
        Spacing [µm] of the cached level used for the grid error; None if none.
    other_traced : float or None
        Traced separatrix on that level.
    grid_error : float or None
        Richardson (p = 2) estimate of |traced − converged value|; None without a level.
    extrapolated : float or None
        Richardson estimate of the converged traced separatrix.
    """

    traced: float
    flux: float
    model_spread: float
    other_dx: float | None = None
    other_traced: float | None = None
    grid_error: float | None = None
    extrapolated: float | None = None

    @property
    def error(self) -> float:
        """model_spread + grid_error (grid error 0 when no other level is cached)."""
        return self.model_spread + (self.grid_error or 0.0)


def other_level(
    settings: FlowSettings, cache_dir: str | Path
) -> tuple[FlowSettings, FlowField] | None:
    """A cached field of the same problem at 2 Δx or Δx/2 (finer preferred); None if neither.

    With a patch the levels are the patch's spacing halved or doubled in the same
    channel (doubled up to the channel's own spacing, which is the channel alone).

    Only loads (never solves).
    """
    for factor in (0.5, 2.0):
        try:
            dump = settings.model_dump()
            if settings.patch is None:
                dump["dx"] = settings.dx * factor
            elif settings.patch.dx * factor >= settings.dx - 1e-9:
                dump["patch"] = None  # the patch's coarser level is the channel itself
            else:  # the patch levels: the same channel, the patch at 2 or 1/2 its spacing
                dump["patch"] = {**dump["patch"], "dx": settings.patch.dx * factor}
            other = FlowSettings.model_validate(dump)
            if other.field_dx != settings.field_dx * factor:
                continue
        except ValueError:
            continue
        path = Path(cache_dir) / f"flow-{cache_key(other)}"
        if path.exists():
            try:
                return other, load_entry(path, other, mmap=True)
            except CorruptCacheError as exc:
                log.warning("ignoring cached level %s: %s", path, exc)
    return None


def separatrix_estimate(field: FlowField, other: FlowField | None = None) -> SeparatrixEstimate:
    """Separatrix of ``field`` with its model spread and, given ``other``, its grid error.

    Parameters
    ----------
    field : FlowField
    other : FlowField, optional
        The same problem solved at twice or half the spacing.

    Raises
    ------
    ValueError
        If ``other`` is not at 2 Δx or Δx/2.
    """
    traced = separatrix_y(field)
    flux = flux_separatrix(field).y_far_over_h
    est = SeparatrixEstimate(traced=traced, flux=flux, model_spread=abs(traced - flux))
    if other is None:
        return est
    ratio = other.dx / field.dx
    s_other = separatrix_y(other)
    r = 2.0**ORDER - 1.0
    if abs(ratio - 2.0) < 1e-9:  # other is coarser: field is the fine value
        extrapolated = traced + (traced - s_other) / r
    elif abs(ratio - 0.5) < 1e-9:  # other is finer
        extrapolated = s_other + (s_other - traced) / r
    else:
        raise ValueError(f"other level must be at 2 dx or dx/2, got dx {other.dx} vs {field.dx}")
    return SeparatrixEstimate(
        traced=traced,
        flux=flux,
        model_spread=abs(traced - flux),
        other_dx=other.dx,
        other_traced=s_other,
        grid_error=abs(traced - extrapolated),
        extrapolated=extrapolated,
    )

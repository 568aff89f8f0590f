"""What one refinement round proposes, whichever proposer made it.

The channel's grid bisects class brackets (:func:`fibersweep.sweep.refine.propose`);
a pillar array's random starts bisect the critical length
(:func:`fibersweep.sorting.lengths.propose_lengths`). Both return a
:class:`Proposal`, and the refinement rounds (:mod:`fibersweep.sweep.refine`)
read only that.
"""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

__all__ = ["Proposal"]


@dataclass(frozen=True)
class Proposal:
    """The next round of a refinement.

    Attributes
    ----------
    new : DataFrame
        Points to run: columns ``group``, ``theta0``, ``y0``, ``length`` (at most
        the budget; the widest brackets, relative to their tolerance, first).
    brackets : DataFrame
        Every bracket of the known points
        (:data:`fibersweep.analysis.boundaries.BRACKET_COLUMNS`) with a ``state``:
        'located' (within tolerance), 'open' (to bisect: its midpoint is in ``new``
        or was left out by the budget) or 'stuck' (its midpoint is known but has
        no class: a failed or missing run).
    """

    new: pd.DataFrame
    brackets: pd.DataFrame


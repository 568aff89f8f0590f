"""Observable components on their scoring scale: the matrices of copies, their names.

An observable has one component (continuous: its value on the scoring scale,
:func:`.scores.transform`, e.g. log t_pass) or one per category (categorical:
one-hot). The power analysis, what-to-measure-next and the follow-up test compare
copies component by component in this space.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from fibersweep.discrepancy.observables import OBSERVABLES
from fibersweep.discrepancy.scores import transform

__all__ = ["component_names", "copy_values", "standardised_values"]


def standardised_values(
    copies: Sequence[pd.DataFrame], observables: Sequence[str]
) -> list[np.ndarray]:
    """Each copy as an (n, c) matrix of observable components on their scoring scale.

    Continuous observables: ``transform`` (e.g. log t_pass); categorical: one-hot
    per category. NaN where undefined. Columns in registry order.
    """
    out = []
    for df in copies:
        cols = []
        for name in (o for o in OBSERVABLES if o in observables and OBSERVABLES[o].scored):
            o = OBSERVABLES[name]
            v = o.values(df[name])
            if o.categorical:
                for c in range(o.width):
                    cols.append(np.where(np.isfinite(v), (v == c).astype(float), np.nan))
            else:
                cols.append(transform(name, v))
        out.append(np.column_stack(cols))
    return out


def component_names(observables: Sequence[str]) -> list[str]:
    """Names of the columns of :func:`standardised_values` (e.g. 'class=Above')."""
    out = []
    for name in (o for o in OBSERVABLES if o in observables and OBSERVABLES[o].scored):
        o = OBSERVABLES[name]
        out += [f"{name}={c}" for c in o.categories] if o.categorical else [name]
    return out


def copy_values(
    cps: Sequence[pd.DataFrame], observables: Sequence[str]
) -> tuple[np.ndarray, np.ndarray]:
    """Copies on the scoring scale, with the runs that failed marked.

    Parameters
    ----------
    cps : sequence of DataFrame
        k copies of n fibers (:meth:`.copies.CopyMaker.copies`).

    Returns
    -------
    values : ndarray, shape (k, n, c)
        :func:`standardised_values`; a failed run's row is NaN.
    ok : ndarray of bool, shape (k, n)
        The run did not fail (``status == 'ok'``). A failed run is no outcome; an
        outcome undefined by its observable's rule (no contact) is one.
    """
    vals = np.stack(standardised_values(list(cps), observables))
    ok = np.stack([(c["status"] == "ok").to_numpy() if "status" in c
                   else np.ones(len(c), bool) for c in cps])  # fmt: skip
    vals[~ok] = np.nan
    return vals, ok

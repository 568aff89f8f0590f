"""Where the gap lives: a shallow regression tree and binned maps of per-fiber excess.

The tree is a plain CART on a handful of features (θ0, y0, L, observed
contact): each split minimises the summed squared error of the per-fiber excess
score, down to ``depth`` levels with at least ``min_leaf`` fibers per leaf.
The *region* is the leaf with the largest mean excess, described by the
inequalities along its path.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Region", "find_region", "binned_map"]

FEATURES = ("theta0", "y0", "length", "contact")


@dataclass(frozen=True)
class Region:
    """A box in feature space.

    Attributes
    ----------
    bounds : dict name -> (lo, hi)
        Inclusive-exclusive bounds; ±inf where unbounded.
    n : int
        Fibers inside.
    mean_excess : float
        Mean excess score inside.
    share : float
        Fraction of the total positive excess found inside.
    """

    bounds: dict[str, tuple[float, float]]
    n: int
    mean_excess: float
    share: float

    def describe(self) -> str:
        """Human-readable inequalities, e.g. ``0.31 <= y0 < 0.48, contact``."""
        parts = []
        for name, (lo, hi) in self.bounds.items():
            if name == "contact":
                if lo > 0.5:
                    parts.append("with contact")
                elif hi <= 0.5:
                    parts.append("without contact")
                continue
            if np.isfinite(lo) and np.isfinite(hi):
                parts.append(f"{lo:.3g} <= {name} < {hi:.3g}")
            elif np.isfinite(lo):
                parts.append(f"{name} >= {lo:.3g}")
            elif np.isfinite(hi):
                parts.append(f"{name} < {hi:.3g}")
        return ", ".join(parts) if parts else "everywhere"

    def contains(self, X: np.ndarray, names: tuple[str, ...] = FEATURES) -> np.ndarray:
        """Mask of rows of X (shape (n, len(names))) inside the box."""
        m = np.ones(len(X), dtype=bool)
        for k, name in enumerate(names):
            lo, hi = self.bounds.get(name, (-np.inf, np.inf))
            m &= (X[:, k] >= lo) & (X[:, k] < hi)
        return m


def _best_split(X: np.ndarray, y: np.ndarray, min_leaf: int) -> tuple[int, float, float] | None:
    """(feature, threshold, sse reduction) of the best split, or None."""
    n = len(y)
    base = float(((y - y.mean()) ** 2).sum())
    best = None
    for f in range(X.shape[1]):
        order = np.argsort(X[:, f], kind="stable")
        xs, ys = X[order, f], y[order]
        cs, cs2 = np.cumsum(ys), np.cumsum(ys**2)
        for k in range(min_leaf, n - min_leaf + 1):
            if xs[k - 1] == xs[k]:
                continue
            nl, nr = k, n - k
            sl, sr = cs[k - 1], cs[-1] - cs[k - 1]
            sse = (cs2[k - 1] - sl**2 / nl) + (cs2[-1] - cs2[k - 1] - sr**2 / nr)
            gain = base - sse
            if best is None or gain > best[2]:
                best = (f, 0.5 * (xs[k - 1] + xs[k]), gain)
    return best


def find_region(
    X: np.ndarray,
    excess: np.ndarray,
    depth: int = 2,
    min_leaf: int | None = None,
    names: tuple[str, ...] = FEATURES,
) -> Region:
    """Leaf of a shallow regression tree with the largest mean excess.

    Parameters
    ----------
    X : ndarray, shape (n, f)
        Features per fiber (columns named by ``names``).
    excess : ndarray, shape (n,)
        Per-fiber excess score (NaN rows are ignored).
    depth : int
        Levels of splits.
    min_leaf : int, optional
        Fewest fibers per leaf; default max(5, n // 8).
    """
    ok = np.isfinite(excess) & np.all(np.isfinite(X), axis=1)
    X, y = np.asarray(X, dtype=np.float64)[ok], np.asarray(excess, dtype=np.float64)[ok]
    total_pos = float(np.clip(y, 0, None).sum()) or 1.0
    if min_leaf is None:
        min_leaf = max(5, len(y) // 8)
    leaves: list[tuple[np.ndarray, dict[str, tuple[float, float]]]] = []

    def grow(idx: np.ndarray, bounds: dict[str, tuple[float, float]], level: int) -> None:
        split = None
        if level < depth and len(idx) >= 2 * min_leaf:
            split = _best_split(X[idx], y[idx], min_leaf)
        if split is None or split[2] <= 0:
            leaves.append((idx, bounds))
            return
        f, thr, _ = split
        name = names[f]
        lo, hi = bounds.get(name, (-np.inf, np.inf))
        left = idx[X[idx, f] < thr]
        right = idx[X[idx, f] >= thr]
        grow(left, {**bounds, name: (lo, min(hi, thr))}, level + 1)
        grow(right, {**bounds, name: (max(lo, thr), hi)}, level + 1)

    if len(y) == 0:
        return Region({}, 0, float("nan"), 0.0)
    grow(np.arange(len(y)), {}, 0)
    idx, bounds = max(leaves, key=lambda lb: float(y[lb[0]].mean()))
    return Region(
        bounds=bounds,
        n=int(len(idx)),
        mean_excess=float(y[idx].mean()),
        share=float(np.clip(y[idx], 0, None).sum() / total_pos),
    )


def binned_map(
    x: np.ndarray, y: np.ndarray, v: np.ndarray, x_edges: np.ndarray, y_edges: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Mean of ``v`` and the count in each (x, y) bin.

    Returns
    -------
    mean, count : ndarray, shape (len(x_edges) - 1, len(y_edges) - 1)
        NaN mean where a bin is empty.
    """
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(v)
    s, _, _ = np.histogram2d(x[ok], y[ok], bins=[x_edges, y_edges], weights=v[ok])
    c, _, _ = np.histogram2d(x[ok], y[ok], bins=[x_edges, y_edges])
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(c > 0, s / np.maximum(c, 1), np.nan)
    return mean, c.astype(int)

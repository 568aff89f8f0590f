"""Content-addressed run ids and the settings that change a run's result.

A run's id is the hash of everything that determines its outcome: its start
(θ0, y0/h, L/l_obs), the fiber settings that change the physics, and the key of
the flow field it moves in. What only changes bookkeeping (workers, output
directory) or the labelling of a finished trajectory (classification
thresholds, which ``fibersweep classify`` re-applies without simulating) is
left out, so changing it never forces a re-run.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterable
from typing import Any

from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.result import FiberStart

__all__ = [
    "ID_LENGTH",
    "canonical_json",
    "diff_settings",
    "fiber_result_settings",
    "run_id",
    "run_ids",
    "settings_id",
    "stable_hash",
]

#: Hex digits kept of the sha256 (64 bits: collisions negligible for 1e6 runs).
ID_LENGTH = 16

# Fiber settings that change labels or bookkeeping but not the simulated path.
_NOT_IN_ID = ("classify",)


def canonical_json(obj: Any) -> str:
    """JSON with sorted keys and floats written with ``repr`` (round-trips exactly)."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)


def stable_hash(obj: Any, length: int = ID_LENGTH) -> str:
    """Hex sha256 of the canonical JSON of ``obj``, truncated to ``length`` digits."""
    return hashlib.sha256(canonical_json(obj).encode()).hexdigest()[:length]


def fiber_result_settings(fiber: FiberSettings) -> dict[str, Any]:
    """The part of the fiber settings that changes a run's result (plain JSON types)."""
    d = fiber.model_dump(mode="json")
    for k in _NOT_IN_ID:
        d.pop(k, None)
    return d


def _norm(x: float) -> float:
    # 12 significant digits: 0.1 + 0.2 and 0.3 give the same id.
    return float(f"{float(x):.12g}") + 0.0


def run_id(start: FiberStart, fiber: FiberSettings | dict[str, Any], flow_key: str) -> str:
    """Content-addressed id of one run.

    Parameters
    ----------
    start : FiberStart
        θ0 [deg], y0/h_obs, L/l_obs.
    fiber : FiberSettings or dict
        Fiber settings (or the dict from :func:`fiber_result_settings`).
    flow_key : str
        Hash of the flow field (``CacheInfo.key``).

    Returns
    -------
    str
        ``ID_LENGTH`` hex digits: the sha256 of the canonical JSON of
        ``{"start": [θ0, y0, L], "fiber": ..., "flow": flow_key}``.
    """
    return run_ids([start.theta0], [start.y0], [start.length], fiber, flow_key)[0]


def run_ids(
    theta0: Iterable[float],
    y0: Iterable[float],
    length: Iterable[float],
    fiber: FiberSettings | dict[str, Any],
    flow_key: str,
) -> list[str]:
    """Content-addressed ids of many runs with the same settings (see :func:`run_id`).

    The canonical JSON puts the start last (keys sorted: fiber, flow, start), so
    the settings part is hashed once and each id only hashes its three numbers:
    200 000 ids take well under a second.

    Parameters
    ----------
    theta0, y0, length : iterables of float, same length n
        Starts: θ0 [deg], y0/h_obs, L/l_obs.
    fiber : FiberSettings or dict
    flow_key : str

    Returns
    -------
    list of str, length n
    """
    fs = fiber if isinstance(fiber, dict) else fiber_result_settings(fiber)
    head = canonical_json({"fiber": fs, "flow": flow_key, "start": []})
    assert head.endswith('"start":[]}')  # the start must come last for the shared prefix
    base = hashlib.sha256(head[:-2].encode())
    out = []
    for t, y, L in zip(theta0, y0, length, strict=True):
        h = base.copy()
        # json writes a float as its repr; _norm gives 12 significant digits
        h.update(f"{_norm(t)!r},{_norm(y)!r},{_norm(L)!r}]}}".encode())
        out.append(h.hexdigest()[:ID_LENGTH])
    return out


def settings_id(fiber: FiberSettings | dict[str, Any], flow_key: str) -> str:
    """Id of a run's settings: the hash of its fiber result settings and flow key.

    The runs of one setting combination share it (the ``settings`` column), and
    a run's id is the hash of it with the start added (:func:`run_id`).
    """
    fs = fiber if isinstance(fiber, dict) else fiber_result_settings(fiber)
    return stable_hash({"fiber": fs, "flow": flow_key})


def diff_settings(old: Any, new: Any, prefix: str = "") -> list[str]:
    """Human-readable differences between two nested settings dicts.

    Returns
    -------
    list of str
        One ``"path: old -> new"`` line per changed leaf.
    """
    if isinstance(old, dict) and isinstance(new, dict):
        out: list[str] = []
        for k in sorted(set(old) | set(new), key=str):
            path = f"{prefix}.{k}" if prefix else str(k)
            if k not in old:
                out.append(f"{path}: (absent) -> {new[k]!r}")
            elif k not in new:
                out.append(f"{path}: {old[k]!r} -> (absent)")
            else:
                out.extend(diff_settings(old[k], new[k], path))
        return out
    return [] if old == new else [f"{prefix or '<value>'}: {old!r} -> {new!r}"]

"""Shared look of the figures: class markers and colours, fonts, sizes."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import matplotlib as mpl
from matplotlib.figure import Figure

from fibersweep.atomic import atomic_path

__all__ = [
    "CLASS_STYLE",
    "MODE_STYLE",
    "STYLE_FILE",
    "FAILED_STYLE",
    "UNCLASSIFIED_STYLE",
    "new_figure",
    "paper_style",
    "save_figure",
    "subplots",
]

# Okabe-Ito colours (colour-blind safe); marker shapes carry the class without colour too.
CLASS_STYLE: dict[str, dict[str, object]] = {
    "Below": {"marker": "o", "color": "#0072B2"},
    "Above": {"marker": "s", "color": "#E69F00"},
    "Pole-vaulting": {"marker": "^", "color": "#009E73"},
    "Trapping": {"marker": "D", "color": "#D55E00"},
}
# Transport modes of a pillar array (fibersweep.analysis.modes.MODES), same palette idea.
MODE_STYLE: dict[str, dict[str, object]] = {
    "zigzag": {"marker": "o", "color": "#0072B2"},
    "displacement": {"marker": "s", "color": "#D55E00"},
    "wrap-and-jump": {"marker": "^", "color": "#CC79A7"},
    "trapped": {"marker": "D", "color": "0.35"},
    "mixed": {"marker": "v", "color": "#E69F00"},
}
FAILED_STYLE: dict[str, object] = {"marker": "x", "color": "0.45"}
UNCLASSIFIED_STYLE: dict[str, object] = {"marker": "P", "color": "0.6"}


#: The package's matplotlib style file, applied to every figure by :func:`paper_style`.
STYLE_FILE = Path(__file__).with_name("fibersweep.mplstyle")


@contextmanager
def paper_style() -> Iterator[None]:
    """Matplotlib settings of every fibersweep figure (``fibersweep.mplstyle``).

    Print-sized text for a 7 in wide page, Okabe-Ito colours, mathtext labels,
    constrained layout, 200 dpi PNG. Settings made inside the block win.
    """
    with mpl.rc_context(fname=str(STYLE_FILE)):
        yield


def save_figure(fig: Any, path: str | Path, **savefig_kw: Any) -> Path:
    """Write ``fig`` to ``path`` atomically (temporary file, then rename) and close it.

    The format is the path's suffix unless ``format=`` is given; other keywords
    go to ``Figure.savefig``.
    """
    out = Path(path)
    savefig_kw.setdefault("format", out.suffix.lstrip(".").lower() or None)
    try:
        with atomic_path(out) as tmp:
            fig.savefig(tmp, **savefig_kw)
    finally:
        if getattr(fig.canvas, "manager", None) is not None:  # made through pyplot
            import matplotlib.pyplot as plt

            plt.close(fig)
    return out


def new_figure(**kw: Any) -> Figure:
    """A figure that belongs to no window or backend (files only, any thread).

    Keywords go to :class:`matplotlib.figure.Figure` (``figsize`` [in], ``layout``).
    Unlike ``pyplot.figure`` it selects no backend and registers nothing globally,
    so importing or using the plots never changes matplotlib's state.
    """
    return Figure(**kw)


def subplots(nrows: int = 1, ncols: int = 1, *, figsize: tuple[float, float], **kw: Any) -> Any:
    """``(figure, axes)`` like ``pyplot.subplots``, on a :func:`new_figure`.

    ``layout`` goes to the figure; other keywords (``sharex``, ``squeeze``...) to
    :meth:`Figure.subplots`.
    """
    fig = new_figure(figsize=figsize, layout=kw.pop("layout", None))
    return fig, fig.subplots(nrows, ncols, **kw)

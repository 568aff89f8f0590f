"""fibersweep.plots: figures of sweeps, runs and flow fields (matplotlib, files only).

Modules: :mod:`.phase` (phase diagram, δ and contact maps of a runs table),
:mod:`.chrono` (chronophotograph of one run), :mod:`.flow` (a flow field),
:mod:`.style` (the shared look and the atomic figure writer).
"""

__all__ = ["FORMATS"]

#: Figure formats every plot command writes (matplotlib back ends without a display).
FORMATS = ("png", "pdf", "svg")

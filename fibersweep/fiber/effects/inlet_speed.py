"""``inlet_speed``: calibration error of the flow speed (value = ε, speed x (1 + ε)).

A nuisance effect: the real flow is (1 + ε) times the nominal one. Stokes flow
is linear in the driving force, so the field is scaled as a whole
(:meth:`FlowField.scaled`, which also rescales U_center and with it the
contact force scale F_ref = 6πμaU_center): paths stay the same and every
time divides by 1 + ε. It therefore masquerades as anything that slows the
fiber uniformly (compare ``off_midplane``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from fibersweep.fiber.effects.base import Effect
from fibersweep.fiber.effects.registry import register

if TYPE_CHECKING:  # pragma: no cover
    from fibersweep.flow.field import FlowField


@register
@dataclass(frozen=True)
class InletSpeed(Effect):
    name = "inlet_speed"
    unit = "relative speed error ε, flow x (1 + ε), in (-1, 1)"

    def validate(self) -> None:
        self._require(-1.0 < self.value < 1.0, "must be in (-1, 1)")

    def transform_field(self, field: FlowField) -> FlowField:
        return field.scaled(1.0 + self.value)

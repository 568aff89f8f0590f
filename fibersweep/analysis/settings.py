"""Thresholds and rule of the classification (a pure function of the trajectory)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field, field_validator

__all__ = ["ClassifySettings"]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class ClassifySettings(_Strict):
    """Thresholds of the classification (a pure function of the trajectory)."""

    head_blocked_speed: float = Field(
        0.01, gt=0, description="head counts as blocked below this fraction of U_center"
    )
    trap_time: float = Field(
        2.0, gt=0, description="in contact and stopped for this long [s] -> Trapping"
    )
    trap_speed: float = Field(
        0.01, gt=0, description="'stopped' means COM speed below this fraction of U_center"
    )
    rule: str = Field(
        "switch",
        description=(
            "pole-vaulting rule: switch (default: agrees best with a person's eye, "
            "docs/fidelity.md), head-speed (the source's), pivot or corner"
        ),
    )
    pivot_fraction: float = Field(
        0.5, gt=0, description="pivot rule: the head moves less than this x L while turning 90°"
    )
    corner_fraction: float = Field(
        0.3,
        gt=0,
        le=1,
        description="corner rule: the head stays within this x L of a pillar corner ...",
    )
    corner_turn: float = Field(
        90.0, gt=0, le=180, description="corner rule: ... while the fiber turns this much [deg]"
    )

    @field_validator("rule")
    @classmethod
    def _known_rule(cls, name: str) -> str:
        from fibersweep.analysis.classify import RULES  # the registry decides

        if name not in RULES:
            raise ValueError(f"unknown rule; valid: {', '.join(RULES)}")
        return name

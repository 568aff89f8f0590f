"""Validated settings of one fiber run: model, contact, stepping, classification, recording."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_serializer

from fibersweep.analysis.classify import ClassifySettings

__all__ = [
    "ContactSettings",
    "StepSettings",
    "ClassifySettings",
    "RecordSettings",
    "FiberSettings",
    "ARRAY_ROWS",
]

#: Rows a fiber crosses in a pillar array unless ``fiber.array_rows`` says otherwise.
ARRAY_ROWS = 20
#: Step settings left out of a dump at these (default) values (see StepSettings).
_STEP_DEFAULTS_NOT_WRITTEN = {"jacobian_reuse": 1, "controller": "i"}


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class ContactSettings(_Strict):
    """Fiber-pillar repulsion (docs/model.md)."""

    pillar: Literal["rough", "smooth"] = Field("rough", description="pillar surface model")
    obstacle_bead_radius: float = Field(0.6, gt=0, description="a_obs of the rough pillar [µm]")
    chi: float = Field(1.1, gt=1.0, description="cutoff R_ref = chi (a + a_obs) (smooth: chi a)")
    f_ref: float | None = Field(
        None, gt=0, description="force scale [pN]; None means 6 pi mu a U_center"
    )
    corner_radius: float = Field(
        2.0, ge=0, description="rounding of the smooth pillar's corners (Bezier) [µm]"
    )


class StepSettings(_Strict):
    """Time stepping and stopping of a run."""

    dt: float | None = Field(
        None, gt=0, description="bead-spring step [s]; None: the model's validated default"
    )
    max_displacement: float = Field(
        0.5, gt=0, description="rigid: largest bead move per step far from contact [µm]"
    )
    contact_displacement: float = Field(
        0.02, gt=0, description="rigid: largest bead move per step near the pillar [µm]"
    )
    t_max: float = Field(30.0, gt=0, description="give up after this time [s] (status failed)")
    stopped_implicit: bool = Field(
        True,
        description="rigid: while stopped in contact, linearly implicit steps bound by the "
        "displacement (false: explicit steps bound by the contact stiffness)",
    )
    tolerance: float = Field(
        0.01, gt=0, description="bead-spring-ros2: local error allowed per step [µm]"
    )
    ros2_max_displacement: float = Field(
        2.0, gt=0, description="bead-spring-ros2: largest bead move per step [µm]"
    )
    ros2_contact_displacement: float = Field(
        0.1,
        gt=0,
        description="bead-spring-ros2: smallest step bound approaching the pillar [µm]",
    )
    rosenbrock: Literal["ros2", "ros34pw2"] = Field(
        "ros2",
        description="bead-spring-ros2: the Rosenbrock-W method, two-stage second order (ros2) "
        "or four-stage third order with one LU per step (ros34pw2; docs/flexible.md)",
    )
    jacobian_reuse: int = Field(
        1,
        ge=1,
        le=1000,
        description="bead-spring-ros2: accepted steps one W = M J and its LU may serve "
        "(1: a fresh W every step; more: W is refreshed after a rejected step, when the "
        "beads in contact change, or after this many steps; docs/flexible.md)",
    )
    controller: Literal["i", "pi"] = Field(
        "i",
        description="bead-spring-ros2: step-size controller, integral (i) or "
        "proportional-integral (pi, Gustafsson's 0.7/0.4)",
    )

    @model_serializer(mode="wrap")
    def _new_fields_when_set(self, handler: Any) -> dict[str, Any]:
        """``jacobian_reuse`` and ``controller`` are written only away from their
        defaults, so the run ids of configs that do not set them stay as before."""
        data = handler(self)
        if isinstance(data, dict):
            for key, default in _STEP_DEFAULTS_NOT_WRITTEN.items():
                if data.get(key) == default:
                    data.pop(key, None)
        return data
    x_end: float = Field(
        300.0, gt=0, description="stop when the rearmost bead is this far past the pillar [µm]"
    )


class RecordSettings(_Strict):
    """What a run keeps of its trajectory."""

    trajectories: bool = Field(False, description="store trajectories")
    samples: int = Field(200, ge=2, description="samples kept per trajectory")
    all_beads: bool = Field(False, description="keep every bead's position, not only COM/angle")


class FiberSettings(_Strict):
    """One fiber run apart from its start (theta0, y0, L)."""

    model: Literal["rigid", "bead-spring", "bead-spring-ros2"] = Field(
        "rigid", description="fiber model (docs/flexible.md)"
    )
    bead_radius: float = Field(2.0, gt=0, description="bead radius a [µm]")
    young_modulus: float = Field(26e6, gt=0, description="E [Pa] (bead-spring models only)")
    x0: float | None = Field(None, description="start x of the centre of mass [µm]; None: L_ch/4")
    contact: ContactSettings = ContactSettings()
    step: StepSettings = StepSettings()
    classify: ClassifySettings = ClassifySettings()
    record: RecordSettings = RecordSettings()
    effects: dict[str, float] = Field(
        default_factory=dict, description="extra physical effects, name -> strength (0 = off)"
    )
    array_rows: int = Field(
        ARRAY_ROWS,
        ge=1,
        description="pillar arrays (flow.array): rows of pillars a run crosses before it ends",
    )
    self_exclusion: bool = Field(
        True,
        description="bead-spring models: non-neighbouring beads repel with the pillar's "
        "contact law, so a fiber cannot pass through itself (docs/flexible.md)",
    )

    @model_serializer(mode="wrap")
    def _defaults_left_out(self, handler: Any) -> dict[str, Any]:
        """``array_rows`` and ``self_exclusion`` are written only away from their defaults,
        so the dump, the run ids and the manifest of every config that does not set them
        stay as before they existed."""
        data = handler(self)
        if isinstance(data, dict):
            for key, default in _HIDDEN_DEFAULTS.items():
                if key in data and data[key] == default:
                    data.pop(key)
        return data


#: Settings left out of a dump at these values (see ``FiberSettings._defaults_left_out``).
_HIDDEN_DEFAULTS: dict[str, Any] = {"array_rows": ARRAY_ROWS, "self_exclusion": True}

"""Validated settings of one fiber run: model and integrator, contact, stepping, classification,
recording.

The model (``fiber.model``) is the fiber's physics, the integrator
(``fiber.integrator``) how it is stepped in time; :data:`INTEGRATORS` names
each model's integrators, and :mod:`fibersweep.fiber.models.registry` implements exactly
these pairs. The former model name ``bead-spring-ros2`` (the bead-spring model
stepped by Rosenbrock-W, its method in ``fiber.step.rosenbrock``) is still read,
with a logged deprecation, as ``model: bead-spring`` with that integrator.
"""

from __future__ import annotations

import logging
from typing import Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationInfo,
    field_validator,
    model_serializer,
    model_validator,
)

from fibersweep.analysis.classify import ClassifySettings

__all__ = [
    "ContactSettings",
    "StepSettings",
    "ClassifySettings",
    "RecordSettings",
    "FiberSettings",
    "ARRAY_ROWS",
    "INTEGRATORS",
    "LEGACY_MODELS",
    "ROSENBROCK",
    "valid_pairs",
]

log = logging.getLogger(__name__)

#: Each fiber model's integrators (``fiber.integrator``); the first is the model's default.
#: The bead-spring model defaults to its reference, BDF2, the method ``model: bead-spring``
#: has always named; sweeps of flexible fibers choose ``ros2``.
INTEGRATORS: dict[str, tuple[str, ...]] = {
    "rigid": ("midpoint",),
    "bead-spring": ("bdf2", "ros2", "ros34pw2"),
}
#: The adaptive Rosenbrock-W integrators (their step settings: ``tolerance``, ``ros2_*``,
#: ``jacobian_reuse``, ``controller``).
ROSENBROCK = ("ros2", "ros34pw2")
#: Former model names, still read (with a logged deprecation), and the model they name;
#: the integrator is ``fiber.step.rosenbrock``.
LEGACY_MODELS = {"bead-spring-ros2": "bead-spring"}

#: Rows a fiber crosses in a pillar array unless ``fiber.array_rows`` says otherwise.
ARRAY_ROWS = 20
#: Step settings left out of a dump at these (default) values (see StepSettings).
_STEP_DEFAULTS_NOT_WRITTEN = {"jacobian_reuse": 1, "controller": "i"}


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


#: Contact settings left out of a dump at these values (see ``ContactSettings``), so the
#: run ids of configs that do not set them stay as before they existed.
_CONTACT_DEFAULTS_NOT_WRITTEN: dict[str, Any] = {"law": "chi", "gap_um": 0.26, "curvature": "plane"}


class ContactSettings(_Strict):
    """Fiber-pillar repulsion (docs/model.md)."""

    pillar: Literal["rough", "smooth"] = Field("rough", description="pillar surface model")
    obstacle_bead_radius: float = Field(0.6, gt=0, description="a_obs of the rough pillar [µm]")
    chi: float = Field(
        1.1,
        gt=1.0,
        description="law chi: cutoff R_ref = chi (a + a_obs) (smooth: chi a); the source's law, "
        "whose range grows with the bead",
    )
    law: Literal["chi", "gap"] = Field(
        "chi",
        description="range of the repulsion: chi (the source's, R_ref = chi r_eq, a range "
        "(chi - 1) r_eq that grows with the bead radius) or gap (R_ref = r_eq + gap_um: the "
        "surfaces' roughness, the same gap for every bead size; docs/validation/near-contact.md). "
        "r_eq is a + a_obs (rough), a (smooth), 2a (a fiber's self-exclusion)",
    )
    gap_um: float = Field(
        0.26,
        gt=0.0,
        le=5.0,
        description="law gap: the surface gap delta_r [µm] at which the repulsion starts, for "
        "every bead size (0.26: the chi law's range for a = 2 µm, a_obs = 0.6 µm)",
    )
    f_ref: float | None = Field(
        None, gt=0, description="force scale [pN]; None means 6 pi mu a U_center"
    )
    corner_radius: float = Field(
        2.0,
        ge=0,
        description="corner radius r_c of the pillar [µm]: the smooth pillar's rounded "
        "(Bezier) outline; with curvature: local also the near-wall hydrodynamics' radius at "
        "every polygon corner (rough pillar: its contact beads stay on the sharp outline)",
    )
    curvature: Literal["plane", "local"] = Field(
        "plane",
        description="near_wall effect: the bead sees the pillar's surface as its tangent plane "
        "(plane) or with its local curvature (local: the normal lubrication resistance times "
        "2 q^1.5/(1 + q), q = R/(a + R), R a circle's radius, corner_radius at a polygon's "
        "corners, a plane on its faces; docs/validation/near-contact.md)",
    )

    @model_validator(mode="after")
    def _gap_needs_the_gap_law(self) -> ContactSettings:
        """``gap_um`` means something only with ``law: gap``: refuse it set beside ``chi``."""
        if self.law == "chi" and "gap_um" in self.model_fields_set:
            raise ValueError(
                f"fiber.contact.gap_um: {self.gap_um!r} is read only with fiber.contact.law: gap "
                "(law chi sets the range by fiber.contact.chi)"
            )
        return self

    def cutoff(self, r_eq: float) -> float:
        """R_ref [µm] of a pair whose force is F_ref at ``r_eq`` [µm]: chi r_eq or r_eq + gap."""
        if self.law == "gap":
            return float(r_eq) + float(self.gap_um)
        return float(self.chi) * float(r_eq)

    @model_serializer(mode="wrap")
    def _law_when_set(self, handler: Any) -> dict[str, Any]:
        """``law``, ``gap_um`` and ``curvature`` are written only away from their defaults
        (chi, an unused gap, plane), so the dump and run ids of every config that does not set
        them stay as before."""
        data = handler(self)
        if isinstance(data, dict):
            if data.get("law") == "chi":
                data.pop("law", None)
                data.pop("gap_um", None)
            if data.get("curvature") == "plane":
                data.pop("curvature", None)
        return data


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
        0.01, gt=0, description="ros2, ros34pw2 integrators: local error allowed per step [µm]"
    )
    ros2_max_displacement: float = Field(
        2.0, gt=0, description="ros2, ros34pw2 integrators: largest bead move per step [µm]"
    )
    ros2_contact_displacement: float = Field(
        0.1,
        gt=0,
        description="ros2, ros34pw2 integrators: smallest step bound approaching the pillar [µm]",
    )
    rosenbrock: Literal["ros2", "ros34pw2"] = Field(
        "ros2",
        description="deprecated: the integrator of the former model name bead-spring-ros2 "
        "(read as fiber.integrator; set that instead)",
    )
    jacobian_reuse: int = Field(
        1,
        ge=1,
        le=1000,
        description="ros2, ros34pw2 integrators: accepted steps one W = M J and its LU may "
        "serve (1: a fresh W every step; more: W is refreshed after a rejected step, when the "
        "beads in contact change, or after this many steps; docs/flexible.md)",
    )
    controller: Literal["i", "pi"] = Field(
        "i",
        description="ros2, ros34pw2 integrators: step-size controller, integral (i) or "
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

    model: Literal["rigid", "bead-spring"] = Field(
        "rigid",
        description="fiber model: rigid or bead-spring (docs/flexible.md); the former "
        "bead-spring-ros2 is read as bead-spring with integrator fiber.step.rosenbrock",
    )
    integrator: Literal["midpoint", "bdf2", "ros2", "ros34pw2"] | None = Field(
        None,
        description="time integrator of the model; unset: its default. rigid: midpoint; "
        "bead-spring: bdf2 (fixed step, the reference; the default), ros2 or ros34pw2 "
        "(adaptive Rosenbrock-W, for sweeps; docs/flexible.md)",
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
    bead_spacing: float = Field(
        1.0,
        gt=0.0,
        le=1.0,
        description="bead-spring model: distance between bead centres as a fraction of the "
        "bead diameter 2a (1: touching beads, the source's chain; 0.5: b = a). Same radius, "
        "S and B at every spacing; contact and self-exclusion scaled per bead "
        "(docs/flexible.md)",
    )

    @model_validator(mode="before")
    @classmethod
    def _legacy_names(cls, data: Any) -> Any:
        """Read the former spelling: ``model: bead-spring-ros2``, its method in ``step.rosenbrock``.

        That pair becomes (bead-spring, the method), and ``step.rosenbrock`` is dropped
        whenever a Rosenbrock integrator is set (it must then name the same one), so both
        spellings give equal settings and run ids. With the rigid model or BDF2 it keeps
        its old meaning: none.
        """
        if not isinstance(data, dict):
            return data
        legacy = data.get("model") in LEGACY_MODELS
        integrator = data.get("integrator")
        step = data.get("step")
        if isinstance(step, BaseModel):
            given, step = step.model_fields_set, step.model_dump()
        else:
            step = dict(step or {})
            given = set(step)
        if not legacy and (integrator not in ROSENBROCK or "rosenbrock" not in given):
            return data
        method = step.pop("rosenbrock", None) if "rosenbrock" in given else None
        step.pop("rosenbrock", None)
        if legacy:
            integrator = integrator or method or "ros2"
            name = data["model"]
            if integrator not in ROSENBROCK:
                raise ValueError(
                    f"fiber.integrator: {integrator!r} contradicts fiber.model: {name}, the former "
                    f"name of bead-spring with a Rosenbrock integrator: {', '.join(ROSENBROCK)}"
                )
            log.warning(
                "fiber.model: %s is deprecated; read as model: %s, integrator: %s",
                name,
                LEGACY_MODELS[name],
                integrator,
            )
            data = {**data, "model": LEGACY_MODELS[name]}
        if method not in (None, integrator):
            raise ValueError(
                f"fiber.step.rosenbrock: {method!r} contradicts fiber.integrator: {integrator!r} "
                "(step.rosenbrock is the deprecated way to name a Rosenbrock integrator; write "
                "only fiber.integrator)"
            )
        return {**data, "integrator": integrator, "step": step}

    @field_validator("integrator")
    @classmethod
    def _integrator_of_the_model(cls, value: str | None, info: ValidationInfo) -> str | None:
        """An integrator of the model (stored as None when it is the model's default)."""
        model = info.data.get("model")
        if value is None or model not in INTEGRATORS:
            return value
        if value not in INTEGRATORS[model]:
            raise ValueError(
                f"{value!r} is not an integrator of the {model} model; valid pairs "
                f"(model: integrator): {valid_pairs()}"
            )
        return None if value == INTEGRATORS[model][0] else value

    @field_validator("bead_spacing")
    @classmethod
    def _spacing_of_a_chain(cls, value: float, info: ValidationInfo) -> float:
        """A bead spacing other than 2a is a bead-spring chain's: the rigid model's beads
        touch (its body mobility is validated for that chain)."""
        if value != 1.0 and info.data.get("model") == "rigid":
            raise ValueError(
                f"{value!r}: a bead spacing other than 1 (touching beads) needs "
                "fiber.model: bead-spring; the rigid model's beads are 2a apart"
            )
        return value

    @model_validator(mode="after")
    def _spacing_without_effects(self) -> FiberSettings:
        """The effects' per-bead forces and mobilities are written for touching beads; a
        finer chain runs without them until each is scaled and validated per bead."""
        active = sorted(k for k, v in self.effects.items() if v != 0.0)
        if self.bead_spacing != 1.0 and active:
            raise ValueError(
                f"fiber.bead_spacing: {self.bead_spacing!r} with the effect(s) "
                f"{', '.join(active)}: effects act per bead and are validated for touching "
                "beads only; set bead_spacing: 1 or turn the effects off"
            )
        return self

    @property
    def resolved_integrator(self) -> str:
        """The integrator that runs: ``integrator``, or the model's default when unset."""
        return self.integrator or INTEGRATORS[self.model][0]

    @model_serializer(mode="wrap")
    def _defaults_left_out(self, handler: Any) -> dict[str, Any]:
        """``array_rows``, ``self_exclusion``, ``bead_spacing`` and an unset ``integrator`` are
        written only away from their defaults, so the dump, the run ids and the manifest of
        every config that does not set them stay as before they existed."""
        data = handler(self)
        if isinstance(data, dict):
            for key, default in _HIDDEN_DEFAULTS.items():
                if key in data and data[key] == default:
                    data.pop(key)
        return data


#: Settings left out of a dump at these values (see ``FiberSettings._defaults_left_out``).
_HIDDEN_DEFAULTS: dict[str, Any] = {
    "array_rows": ARRAY_ROWS,
    "self_exclusion": True,
    "integrator": None,
    "bead_spacing": 1.0,
}


def valid_pairs() -> str:
    """The valid (model: integrator) pairs, as one line, each model's default first."""
    return "; ".join(f"{m}: {', '.join(i)}" for m, i in INTEGRATORS.items())

"""Command-line choices come from the registries (a new entry is offered at once)."""

from __future__ import annotations

from fibersweep.analysis.classify import RULES
from fibersweep.cli import fiber, sweep
from fibersweep.config.fiber import LEGACY_MODELS
from fibersweep.fiber.models.registry import MODELS
from fibersweep.sweep.executors import EXECUTORS


def test_choices_match_the_registries():
    assert [e.value for e in sweep.Executor] == list(EXECUTORS)
    assert [e.value for e in sweep.Rule] == list(RULES)
    assert {e.value for e in fiber.Model} == set(MODELS) | set(LEGACY_MODELS)
    assert [e.value for e in sweep.Format] == ["png", "pdf", "svg"]

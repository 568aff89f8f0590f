"""Settings in words with units: every axis, legend and title names a setting as a reader
would, never by its config key."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.plots.labels import (
    SETTINGS,
    axis_label,
    describe,
    display_values,
    is_decades,
    value_text,
    values_text,
)


def test_registered_settings_read_as_words_with_units():
    assert axis_label("fiber.young_modulus") == "Young's modulus E [kPa]"
    assert axis_label("flow.array.shift") == "row shift ε"
    assert axis_label("fiber.bead_radius") == "bead radius a [µm]"
    assert axis_label("length", array=True) == "fiber length L [µm]"
    assert "l_{obs}" in axis_label("length") and "µm" not in axis_label("length")
    assert value_text("fiber.young_modulus", 1.0e4) == "E = 10 kPa"
    assert value_text("fiber.young_modulus", 1.0e6) == "E = 1 MPa"
    assert value_text("flow.array.shift", 0.125) == "ε = 0.125"
    assert value_text("length", 80.0, array=True) == "L = 80 µm"
    assert value_text("fiber.contact.pillar", "rough") == "pillar surface = rough"
    assert display_values("fiber.young_modulus", [1.0e4, 1.0e5]).tolist() == [10.0, 100.0]
    labels = describe([{"values": {"fiber.young_modulus": 1.0e5, "flow.array.shift": 0.1}}])
    assert labels == {0: "E = 100 kPa, ε = 0.1"}


@pytest.mark.parametrize(
    "key", [*[k for k in SETTINGS if "." in k], "fiber.step.t_max", "flow.fluid.viscosity",
            "fiber.record.samples", "flow.array.mean_flow", "fiber.classify.trap_speed"],
)  # fmt: skip
def test_no_label_is_a_dotted_config_key(key):
    """The registry, and the schema's field descriptions for any other key."""
    for text in (axis_label(key), axis_label(key, array=True), values_text({key: 2.0})):
        assert key not in text and "." not in text.replace("2.0", "").split("=")[0], text
        assert "_" not in text.split("$")[0], text  # no snake_case outside mathtext


def test_schema_units_come_with_unregistered_keys():
    assert axis_label("fiber.step.t_max").endswith("[s]")
    assert axis_label("flow.fluid.viscosity").endswith("[Pa s]")


def test_log_axis_for_a_setting_over_decades_only():
    assert is_decades("fiber.young_modulus", [1.0e4, 1.0e5])
    assert is_decades("fiber.young_modulus", [1.0e4, 3.0e4])  # a stiffness: always
    assert is_decades("flow.array.pillar_size", [2.0, 20.0, 40.0])
    assert not is_decades("flow.array.shift", [0.1, 0.125, 0.2])
    assert not is_decades("fiber.effects.friction", [0.0, 0.3, 3.0])  # a zero
    assert not is_decades("length", [4.0, 160.0])  # the start axes stay linear
    assert not is_decades("fiber.young_modulus", np.array([1.0e4]))

"""Pillar-shape settings: config errors name the field; each shape its own flow-field key."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.cache import GEOMETRY_ADDED, cache_key


def _flow(**geometry) -> FlowSettings:
    return FlowSettings.model_validate({"geometry": geometry})


def test_default_triangle_keeps_the_key_of_fields_solved_before_shapes():
    """The shape keys stay out of the hashed payload for the unrotated triangle, so the
    default key is the hash of exactly the settings that existed before."""
    default = FlowSettings()
    assert cache_key(default) == cache_key(_flow(pillar_shape="triangle", pillar_rotation=0.0))
    keys = {
        cache_key(s)
        for s in (
            default,
            _flow(pillar_shape="circle"),
            _flow(pillar_shape="square"),
            _flow(pillar_shape="square", pillar_rotation=45.0),
            _flow(pillar_shape="triangle", pillar_rotation=180.0),
            _flow(pillar_shape="polygon", pillar_vertices=[[0, 0], [1, 0], [1, 1], [0, 1]]),
        )
    }
    assert len(keys) == 6
    assert all(name in default.geometry.model_dump() for name in GEOMETRY_ADDED)


@pytest.mark.parametrize(
    "geometry, field, text",
    [
        ({"pillar_shape": "cirle"}, "pillar_shape", "did you mean 'circle'"),
        ({"pillar_shape": "blob"}, "pillar_shape", "triangle, circle, square, polygon"),
        ({"pillar_shape": "polygon"}, "pillar_vertices", "needs its vertices"),
        ({"pillar_vertices": [[0, 0], [1, 0], [0, 1]]}, "pillar_vertices", "only used with"),
        (
            {
                "pillar_shape": "polygon",
                "pillar_vertices": [[0, 0], [2, 0], [1, 0.5], [2, 2], [0, 2]],
            },
            "pillar_vertices",
            "convex",
        ),
        ({"pillar_rotation": float("nan")}, "pillar_rotation", "finite"),
        ({"pillar_shape": "circle", "pillar_height": 900.0}, "", "does not fit"),
    ],
)
def test_bad_shape_settings_name_the_field(geometry, field, text):
    with pytest.raises(ValidationError) as err:
        _flow(**geometry)
    msg = str(err.value)
    assert text in msg and field in msg

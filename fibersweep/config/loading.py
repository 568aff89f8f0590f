"""Reading a config: YAML with line numbers, overrides, and messages that name each field.

:func:`load_config` turns every validation problem into a :class:`ConfigError`
that names the full path of the field, what was expected, what was given, the
YAML line (or the command-line override), and a did-you-mean for misspelled keys.
"""

from __future__ import annotations

import copy
import difflib
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from pydantic import (
    BaseModel,
    ValidationError,
)

from fibersweep.config.errors import ConfigError, FieldError, error_parts, expand
from fibersweep.config.schema import Config, _unwrap
from fibersweep.config.sweep_axes import PhysicsChecks


@dataclass(frozen=True)
class _Located:
    data: Any
    lines: dict[tuple, int]


class _Loader(yaml.SafeLoader):
    """Safe loader (no tags run) that reads ``3e-1`` and ``1e5`` as numbers, as YAML 1.2 does.

    YAML 1.1 (PyYAML's default) needs a dot in a float, so ``y0: 3e-1`` was a string
    while the same in a list was coerced: one rule for every number here.
    """


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


def _yaml_with_lines(text: str) -> _Located:
    """Parse YAML and record the 1-based line of every key path.

    Raises
    ------
    ConfigError
        A key written twice in one mapping (YAML would silently keep the last).
    """
    lines: dict[tuple, int] = {}
    duplicates: list[str] = []

    def walk(node: yaml.Node, path: tuple) -> None:
        lines.setdefault(path, node.start_mark.line + 1)
        if isinstance(node, yaml.MappingNode):
            first: dict[Any, int] = {}
            for k, v in node.value:
                key = (*path, k.value)
                line = k.start_mark.line + 1
                if k.value in first:
                    dotted = ".".join(str(p) for p in key)
                    duplicates.append(
                        f"{dotted}: key written twice (lines {first[k.value]} and {line}); keep one"
                    )
                    continue
                first[k.value] = line
                lines[key] = line
                walk(v, key)
        elif isinstance(node, yaml.SequenceNode):
            for i, v in enumerate(node.value):
                walk(v, (*path, i))

    root = yaml.compose(text, Loader=_Loader)
    if root is not None:
        walk(root, ())
    if duplicates:
        raise ConfigError(duplicates)
    return _Located(yaml.load(text, Loader=_Loader), lines)


def _model_at(path: tuple) -> type[BaseModel] | None:
    """The pydantic model that owns the mapping at ``path`` (for did-you-mean)."""
    model: type[BaseModel] | None = Config
    for part in path:
        if model is None or not isinstance(part, str) or part not in model.model_fields:
            return None
        ann = _unwrap(model.model_fields[part].annotation)  # an optional section too
        model = ann if isinstance(ann, type) and issubclass(ann, BaseModel) else None
    return model


def _describe(err: dict, lines: dict[tuple, int]) -> str:
    loc, msg, given = error_parts(err)
    dotted = ".".join(str(p) for p in loc) or "<top level>"
    line = None
    for k in range(len(loc), -1, -1):
        if loc[:k] in lines:
            line = lines[loc[:k]]
            break
    # a YAML line number, or the label of a command-line override
    where = f" (line {line})" if isinstance(line, int) else (f" ({line})" if line else "")
    if err["type"] == "extra_forbidden":
        parent = _model_at(loc[:-1])
        hint = ""
        if parent is not None:
            close = difflib.get_close_matches(
                str(loc[-1]), list(parent.model_fields), n=1, cutoff=0.5
            )
            hint = f"; did you mean '{close[0]}'?" if close else "."
            valid = ", ".join(parent.model_fields)
            hint += f" Valid keys here: {valid}"
        return f"{dotted}{where}: unknown key{hint}"
    raised = (err.get("ctx") or {}).get("error")
    given_s = (
        "" if isinstance(given, dict) or isinstance(raised, FieldError) else f"; given {given!r}"
    )
    return f"{dotted}{where}: {msg}{given_s}"


def parse_config(
    data: Any,
    lines: dict[tuple, int | str] | None = None,
    source: str = "config",
    *,
    executors: Mapping[str, type] | None = None,
    physics: PhysicsChecks | None = None,
) -> Config:
    """Validate a config mapping.

    ``executors`` (name -> executor class, e.g. the sweep's ``EXECUTORS``) checks
    ``run.executor`` and ``run.options`` against the registry; ``physics`` (the
    sweep's :data:`~fibersweep.sweep.starts.PHYSICS`) checks the start points and
    the swept effects against the fiber model. The config package imports neither
    the sweep nor the fiber, so the caller hands them in.

    Raises
    ------
    ConfigError
        With one message per problem, naming each field.
    """
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError([f"<top level>: expected a mapping, got {type(data).__name__}"], source)
    context = {"executors": executors, "physics": physics}
    try:
        return Config.model_validate(data, context=context)
    except ValidationError as exc:
        errors = [*exc.errors(), *_whole_config_errors(data, exc.errors(), context)]
        seen: list[str] = []
        for err in errors:
            for one in expand(err):  # a model's several failed checks, each at its field
                msg = _describe(one, lines or {})
                if msg not in seen:
                    seen.append(msg)
        raise ConfigError(seen, source) from None


def _whole_config_errors(data: dict, errors: list, context: dict[str, Any]) -> list:
    """The whole config's checks that a section's problem kept from running.

    Pydantic runs a model's own checks only when all its fields are valid, so a
    misspelled key in one section would hide, say, a start point on the pillar
    (checked with flow, fiber and sweep). The config is validated again with the
    failed sections (and unknown top-level keys) left at their defaults, and each
    whole-config check runs when the sections it reads are valid
    (:meth:`Config._whole_config`); its problems are reported with the sections'.
    """
    if any(not err["loc"] for err in errors):  # the whole config's checks ran already
        return []
    failed = {err["loc"][0] for err in errors}
    kept = {k: v for k, v in data.items() if k in Config.model_fields and k not in failed}
    try:
        Config.model_validate(kept, context={**context, "failed_sections": failed})
    except ValidationError as exc:
        return [err for err in exc.errors() if not err["loc"]]
    return []


def apply_overrides(
    data: dict[str, Any], lines: dict[tuple, int | str], overrides: Sequence[str]
) -> dict[str, Any]:
    """Apply ``KEY=VALUE`` overrides (dotted keys, YAML values) to a config mapping.

    Parameters
    ----------
    data : dict
        The config as read from YAML (not modified).
    lines : dict
        Key path -> YAML line; each overridden path is relabelled with its
        override, so a problem with it is reported as ``(override KEY=VALUE)``.
    overrides : sequence of str
        E.g. ``fiber.contact.chi=1.2``, ``sweep.y0=[0.3, 0.4]``, ``flow.dx=2``.
        Values are YAML: numbers, booleans, strings, ``[lists]`` and ``{maps}``.

    Returns
    -------
    dict
        A new mapping with the overrides applied, in order (a later one wins).

    Raises
    ------
    ConfigError
        Malformed overrides, each named (the schema then checks keys and values).
    """
    out: dict[str, Any] = copy.deepcopy(data)
    problems = []
    for item in overrides:
        key, sep, raw = item.partition("=")
        path = tuple(p.strip() for p in key.split("."))
        if len(path) > 2 and path[0] == "sweep" and path[1] not in ("refine", "random"):
            # a swept setting is one dotted key inside sweep (or inside sweep.zip);
            # sweep.refine and sweep.random are sections of their own
            cut = 3 if path[1] == "zip" and len(path) > 3 else 2
            path = (*path[: cut - 1], ".".join(path[cut - 1 :]))
        if not sep or not all(path):
            problems.append(
                f"override {item!r}: expected KEY=VALUE with a dotted key, "
                "e.g. fiber.contact.chi=1.2"
            )
            continue
        try:
            value = yaml.load(raw, Loader=_Loader) if raw.strip() else None
        except yaml.YAMLError as exc:
            problems.append(f"override {item!r}: the value is not valid YAML ({exc})")
            continue
        node = out
        for depth, part in enumerate(path[:-1]):
            child = node.setdefault(part, {})
            if child is None:
                child = node[part] = {}
            if not isinstance(child, dict):
                where = ".".join(path[: depth + 1])
                problems.append(f"override {item!r}: {where} is a value, not a section")
                break
            node = child
        else:
            node[path[-1]] = value
            label = f"override {item}"
            for stale in [k for k in lines if len(k) > len(path) and k[: len(path)] == path]:
                del lines[stale]  # the file's lines inside a replaced value
            lines[path] = label
            for k in range(1, len(path)):
                lines.setdefault(path[:k], label)
    if problems:
        raise ConfigError(problems)
    return out


def load_config(
    path: str | Path,
    overrides: Sequence[str] = (),
    *,
    max_points: int | None = None,
    executors: Mapping[str, type] | None = None,
    physics: PhysicsChecks | None = None,
) -> Config:
    """Read and validate a YAML config file, with command-line overrides.

    ``overrides`` are ``KEY=VALUE`` strings (:func:`apply_overrides`), validated by
    the same schema with the same messages. ``max_points`` (the command line's
    ``--max-points``) replaces ``run.max_points`` before validation, so a large
    sweep can be allowed without editing the file. ``executors`` checks the
    executor's name and options, ``physics`` the starts and swept effects (see
    :func:`parse_config`).

    Raises
    ------
    ConfigError
        Unreadable file, invalid YAML, bad overrides or invalid settings (each named).
    """
    p = Path(path)
    try:
        text = p.read_text()
    except OSError as exc:
        raise ConfigError([f"cannot read config: {exc.strerror}"], str(p)) from None
    try:
        located = _yaml_with_lines(text)
    except yaml.YAMLError as exc:
        for mark in (getattr(exc, "context_mark", None), getattr(exc, "problem_mark", None)):
            if mark is not None:  # name the file, not "<unicode string>"
                mark.name = str(p)
        raise ConfigError([f"invalid YAML: {exc}"], str(p)) from None
    except ConfigError as exc:
        raise ConfigError(exc.problems, str(p)) from None
    data = located.data
    if data is None:  # an empty file (or only comments) is a mistake, not "all defaults"
        raise ConfigError(
            ["the file holds no settings (empty or only comments); `fibersweep init` writes "
             "a commented starter config"],
            str(p),
        )  # fmt: skip
    if overrides and isinstance(data, dict):
        try:
            data = apply_overrides(data, located.lines, overrides)
        except ConfigError as exc:
            raise ConfigError(exc.problems, str(p)) from None
    if max_points is not None and isinstance(data, dict):
        run = data.get("run") if isinstance(data.get("run"), dict) else {}
        data = {**data, "run": {**run, "max_points": max_points}}
    return parse_config(data, located.lines, str(p), executors=executors, physics=physics)

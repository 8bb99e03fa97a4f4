"""Configuration: frozen dataclasses and the one TOML-to-dataclass loader.

Every file surveil reads as configuration (run configs, scenario files, ``recording.toml``,
rule files) goes through :func:`from_table`, which rejects unknown keys and out-of-range values
with a :class:`ConfigError` naming the file, the dotted key, what is allowed and what was
given, e.g. ``run.toml: tracking.n_particles must be >= 50, got 3``.

Fields declare their constraints with :func:`setting`::

    @dataclass(frozen=True)
    class EvalConfig:
        gate_m: float = setting(0.25, "match gate for targets, metres", min=0.0)
"""

from __future__ import annotations

import dataclasses
import tomllib
import types
import typing
from pathlib import Path
from typing import Any, TypeVar

from surveil.errors import ConfigError

T = TypeVar("T")


def setting(
    default: Any = dataclasses.MISSING,
    doc: str = "",
    *,
    min: float | None = None,
    max: float | None = None,
    choices: tuple | None = None,
    default_factory: Any = dataclasses.MISSING,
) -> Any:
    """A dataclass field with a one-line description and an allowed range or set."""
    meta = {"doc": doc, "min": min, "max": max, "choices": choices}
    if default_factory is not dataclasses.MISSING:
        return dataclasses.field(default_factory=default_factory, metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def read_toml(path: Path) -> dict[str, Any]:
    """Parse a TOML file; a syntax error becomes a ConfigError naming the file and line."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{path}: file not found")
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: invalid TOML: {exc}") from None


def _type_name(tp: Any) -> str:
    return getattr(tp, "__name__", str(tp))


def _convert(value: Any, tp: Any, where: str) -> Any:
    """Check/convert one TOML value against a field type annotation."""
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if tp is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        errors = []
        for arg in args:
            if arg is type(None):
                continue
            try:
                return _convert(value, arg, where)
            except ConfigError as exc:
                errors.append(str(exc))
        raise ConfigError(
            errors[0]
            if len(errors) == 1
            else f"{where} must be one of {', '.join(_type_name(a) for a in args)}, got {value!r}"
        )
    if origin is tuple:
        if not isinstance(value, list | tuple):
            raise ConfigError(f"{where} must be a list, got {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(v, args[0], f"{where}[{i}]") for i, v in enumerate(value))
        if len(value) != len(args):
            raise ConfigError(f"{where} must be a list of {len(args)} values, got {value!r}")
        return tuple(
            _convert(v, a, f"{where}[{i}]")
            for i, (v, a) in enumerate(zip(value, args, strict=False))
        )
    if origin is dict:
        if not isinstance(value, dict):
            raise ConfigError(f"{where} must be a table, got {value!r}")
        return {k: _convert(v, args[1], f"{where}.{k}") for k, v in value.items()}
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, dict):
            raise ConfigError(f"{where} must be a table, got {value!r}")
        return from_table(tp, value, where)
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(f"{where} must be a number, got {value!r}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{where} must be an integer, got {value!r}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{where} must be true or false, got {value!r}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(f"{where} must be a string, got {value!r}")
        return value
    raise TypeError(f"unsupported config type {tp!r} at {where}")  # programming error


def from_table(cls: type[T], table: dict[str, Any], where: str) -> T:
    """Build dataclass ``cls`` from a TOML table, validating keys, types and ranges.

    ``where`` prefixes every message: ``"run.toml: tracking"`` gives keys such as
    ``run.toml: tracking.n_particles``.

    >>> @dataclasses.dataclass(frozen=True)
    ... class C:
    ...     n: int = setting(100, "particles", min=50)
    >>> from_table(C, {"n": 3}, "run.toml: tracking")
    Traceback (most recent call last):
    ...
    surveil.errors.ConfigError: run.toml: tracking.n must be >= 50, got 3
    """
    if not isinstance(table, dict):
        raise ConfigError(f"{where} must be a table, got {table!r}")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    sep = "" if where.endswith(": ") else "."
    unknown = sorted(set(table) - set(fields))
    if unknown:
        raise ConfigError(
            f"{where}{sep}{unknown[0]} is not a known key; valid keys: {', '.join(sorted(fields))}"
        )
    kwargs = {}
    for name, f in fields.items():
        key = f"{where}{sep}{name}"
        if name not in table:
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                raise ConfigError(f"{key} is required ({f.metadata.get('doc', '')})")
            continue
        value = _convert(table[name], hints[name], key)
        lo, hi, choices = (f.metadata.get(k) for k in ("min", "max", "choices"))
        if lo is not None and value < lo:
            raise ConfigError(f"{key} must be >= {lo}, got {value!r}")
        if hi is not None and value > hi:
            raise ConfigError(f"{key} must be <= {hi}, got {value!r}")
        if choices is not None and value not in choices:
            raise ConfigError(
                f"{key} must be one of {', '.join(map(repr, choices))}, got {value!r}"
            )
        kwargs[name] = value
    try:
        return cls(**kwargs)
    except (ValueError, TypeError) as exc:
        raise ConfigError(f"{where}: {exc}") from None


def to_table(obj: Any) -> dict[str, Any]:
    """A dataclass as a plain dict (for storing the effective config as metadata)."""
    return dataclasses.asdict(obj)

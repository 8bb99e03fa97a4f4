"""Argument checks for public boundaries. Messages name the argument, what was expected and
what was received."""

from __future__ import annotations

import numpy as np


def require_shape(
    name: str, arr: object, shape: tuple[int | None, ...], kind: type = np.number
) -> None:
    """Raise unless ``arr`` is an ndarray of the given shape (None = any) and dtype kind.

    >>> require_shape("points_m", np.zeros((4, 3)), (None, 3), np.floating)
    >>> require_shape("points_m", np.zeros((4, 2)), (None, 3), np.floating)
    Traceback (most recent call last):
    ...
    ValueError: points_m must have shape (None, 3) (None = any), got (4, 2)
    """
    if not isinstance(arr, np.ndarray):
        raise TypeError(f"{name} must be a numpy array, got {type(arr).__name__}")
    got = arr.shape
    if len(got) != len(shape) or any(
        s is not None and s != a for s, a in zip(shape, got, strict=True)
    ):
        raise ValueError(f"{name} must have shape {shape} (None = any), got {got}")
    # called ~100 times per frame set on the hot path: np.issubdtype costs more than the
    # rest of the check, and the (dtype, kind) pairs seen are few
    key = (arr.dtype, kind)
    ok = _KIND_OK.get(key)
    if ok is None:
        ok = _KIND_OK[key] = bool(np.issubdtype(arr.dtype, kind))
    if not ok:
        raise TypeError(f"{name} must have a {kind.__name__} dtype, got {arr.dtype}")


_KIND_OK: dict[tuple[np.dtype, type], bool] = {}


def require_finite(name: str, arr: np.ndarray) -> None:
    """Raise ValueError if ``arr`` holds NaN or infinity, saying how many and where first."""
    bad = ~np.isfinite(arr)
    if bad.any():
        first = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(
            f"{name} must be finite, got {int(bad.sum())} non-finite values "
            f"(first at index {first})"
        )


def readonly(*arrays: np.ndarray) -> None:
    """Mark arrays read-only so that data passed between stages cannot be changed in place."""
    for arr in arrays:
        arr.flags.writeable = False

"""Checks of settings' numbers, one message form for all: what, which value, what it got.

Every settings dataclass validates in ``__post_init__`` through these, so a bad value is
a :class:`~footfall.errors.ConfigError` that names the setting and its owner, and NaN never
slips past a comparison (``nan > 0`` is False, so "not > 0" catches it; ``nan < 0`` is also
False, so a plain "< 0" would not).
"""

from __future__ import annotations

import math
import numbers

from footfall.errors import ConfigError


def _number(value: object) -> float | None:
    """The value as a finite float, or None when it is not a finite real number."""
    if not isinstance(value, numbers.Real):
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def require_positive(owner: str, **values: object) -> None:
    """Each value is a finite number > 0.

    Args:
        owner: What the values belong to ("gait", "height map"), for the message.
        values: The settings by name.

    Raises:
        ConfigError: Naming the first value that is not.
    """
    for name, value in values.items():
        number = _number(value)
        if number is None or not number > 0:
            raise ConfigError(f"{owner} {name} must be positive, got {value!r}")


def require_non_negative(owner: str, **values: object) -> None:
    """Each value is a finite number >= 0.

    Raises:
        ConfigError: Naming the first value that is not.
    """
    for name, value in values.items():
        number = _number(value)
        if number is None or not number >= 0:
            raise ConfigError(f"{owner} {name} must be a number >= 0, got {value!r}")


def require_finite(owner: str, **values: object) -> None:
    """Each value is a finite number.

    Raises:
        ConfigError: Naming the first value that is not.
    """
    for name, value in values.items():
        if _number(value) is None:
            raise ConfigError(f"{owner} {name} must be a finite number, got {value!r}")

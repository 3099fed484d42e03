"""The settings' number checks: they pass exactly the numbers they promise, and name the
setting and its owner otherwise."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from footfall.checks import require_finite, require_non_negative, require_positive
from footfall.errors import ConfigError

VALUES = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(),
    st.none(),
    st.text(alphabet="0123456789.-e", max_size=4),  # numbers as text are not numbers
)


def _number(value: object) -> float | None:
    if isinstance(value, (int, float)) and math.isfinite(value):
        return float(value)
    return None


@given(VALUES)
def test_each_check_passes_exactly_its_numbers(value):
    """Positive: finite and > 0; non-negative: finite and >= 0; finite: any finite number.
    NaN, infinities and what is not a number never pass; a refusal names the setting."""
    number = _number(value)
    for check, accepts in (
        (require_positive, number is not None and number > 0),
        (require_non_negative, number is not None and number >= 0),
        (require_finite, number is not None),
    ):
        if accepts:
            check("gait", stride_length=value)
        else:
            with pytest.raises(ConfigError, match="gait stride_length must be"):
                check("gait", stride_length=value)


def test_the_first_bad_value_is_named():
    """Several values: the first refused one is in the message, with what it got."""
    with pytest.raises(ConfigError, match=r"camera height must be positive, got 0"):
        require_positive("camera", width=320, height=0, rate_hz=-1.0)

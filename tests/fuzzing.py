"""What the fuzz tests share: how many examples, and the count of examples per target.

The normal suite runs a few dozen examples per target; ``FOOTFALL_FUZZ=long`` runs
``LONG_EXAMPLES`` (``benchmarks/fuzz.py`` does). With ``FOOTFALL_FUZZ_REPORT=FILE`` the
examples run per target are written there when the session ends (``conftest.py``).
"""

from __future__ import annotations

import json
import os
from collections import Counter
from pathlib import Path

from hypothesis import HealthCheck, settings

from footfall.errors import FootfallError

LONG = os.environ.get("FOOTFALL_FUZZ") == "long"
LONG_EXAMPLES = 1200


def fuzz_settings(examples: int) -> settings:
    """Hypothesis settings: ``examples`` normally, ``LONG_EXAMPLES`` in the long run."""
    return settings(
        max_examples=LONG_EXAMPLES if LONG else examples,
        deadline=None,
        suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
    )


COUNTS: Counter[str] = Counter()


def fails_cleanly(target: str, call) -> object:
    """Run ``call``; a FootfallError must say something, anything else fails the test."""
    COUNTS[target] += 1
    try:
        return call()
    except FootfallError as exc:
        assert str(exc).strip(), f"{target}: a FootfallError without a message"
        return None


def write_report() -> None:
    """Add this session's counts to the report file, when one is asked for."""
    out = os.environ.get("FOOTFALL_FUZZ_REPORT")
    if not out or not COUNTS:
        return
    path = Path(out)
    counts = json.loads(path.read_text()) if path.exists() else {}
    for target, n in COUNTS.items():
        counts[target] = counts.get(target, 0) + n
    path.write_text(json.dumps(counts, indent=2, sort_keys=True) + "\n")

"""The long fuzz run: every reader and entry point, LONG_EXAMPLES examples each.

    uv run python benchmarks/fuzz.py [--out footfall-out/fuzz]

Runs ``tests/test_fuzz.py`` and ``tests/test_reader_fuzz.py`` with ``FOOTFALL_FUZZ=long``
and writes the examples run per target to ``fuzz.json`` (and prints them); the exit status
is pytest's (0: no input ended in anything but a FootfallError).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("footfall-out/fuzz"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    report = (args.out / "fuzz.json").resolve()
    report.unlink(missing_ok=True)
    env = {**os.environ, "FOOTFALL_FUZZ": "long", "FOOTFALL_FUZZ_REPORT": str(report)}
    tests = [str(ROOT / "tests" / "test_fuzz.py"), str(ROOT / "tests" / "test_reader_fuzz.py")]
    status = subprocess.call(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *tests], env=env
    )
    counts = json.loads(report.read_text()) if report.exists() else {}
    counts["total"] = sum(counts.values())
    report.write_text(json.dumps(counts, indent=2, sort_keys=True) + "\n")
    width = max(map(len, counts))
    for target, n in counts.items():
        print(f"{target:<{width}}  {n:>7,}")
    print(f"wrote {report}")
    return status


if __name__ == "__main__":
    sys.exit(main())

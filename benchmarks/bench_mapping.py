"""Time the map update and the scorer against plain NumPy, as `footfall bench mapping` does.

Run with ``uv run python benchmarks/bench_mapping.py``; it prints the figures and writes
``benchmarks/results/mapping.json``.
"""

from __future__ import annotations

import json
from pathlib import Path

from footfall.benchmarking import run_mapping_benchmark


def main() -> dict[str, float]:
    results = run_mapping_benchmark(repeats=50)
    width = max(len(k) for k in results)
    for key, value in results.items():
        print(f"{key:<{width}}  {value:14,.3f}")
    out = Path(__file__).parent / "results"
    out.mkdir(exist_ok=True)
    (out / "mapping.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


if __name__ == "__main__":
    main()

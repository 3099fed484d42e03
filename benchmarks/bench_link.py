"""The robot's link to its station over an emulated radio: latency and bandwidth per topic.

For each profile (``runtime/radio.py``: "good-wifi" 50 Mbit/s, 5 ms, 0.1 % loss; "poor-wifi"
10 Mbit/s, 40 ms +- 10 ms, 2 % loss) the robot walks the stairs in a network namespace of
its own behind the emulated radio, this process its station (``runtime/link_trial.py``).
Two runs per profile: walking for ``--seconds`` (bandwidth, rate and age per topic at the
station, command to joint targets), and a cut of ``--cut`` seconds (when the robot stood,
how soon the station had a whole map again). Needs root (network namespaces); says why
not otherwise.

    uv run python benchmarks/bench_link.py [--seconds 20] [--cut 3] [--profiles poor-wifi]

Writes ``benchmarks/results/link.json``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from footfall.runtime.link_trial import cut_run, walking_run
from footfall.runtime.radio import PROFILES, EmulatedLink, NamespaceError


def main() -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="walking time measured")
    parser.add_argument("--cut", type=float, default=3.0, help="how long the link is cut [s]")
    parser.add_argument("--profiles", default="good-wifi,poor-wifi", help="comma-separated")
    args = parser.parse_args()
    results: dict[str, dict] = {}
    for name in args.profiles.split(","):
        profile = PROFILES[name]
        try:
            with EmulatedLink(profile, seed=1) as link:
                walking = walking_run(link, args.seconds)
            with EmulatedLink(profile, seed=2) as link:
                cut = cut_run(link, args.cut)
        except NamespaceError as exc:
            print(f"cannot emulate the link here: {exc}")
            return {}
        results[name] = {"profile": profile.__dict__, "walking": walking, "cut": cut}
        print(json.dumps({name: results[name]}, indent=2))
    path = Path(__file__).parent / "results"
    path.mkdir(exist_ok=True)
    (path / "link.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


if __name__ == "__main__":
    main()

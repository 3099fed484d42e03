"""What each ``footfall`` command runs: a request in, a report out (``to_json()``, ``write()``).

The command line only parses into a request, calls the ``run_*`` function and prints the
report; the rules (default speed, terrain parameters, ground truth for plots) live here.
"""

import json
from pathlib import Path


def write_json(path: Path, data: dict[str, object]) -> Path:
    """Write ``data`` as indented JSON to ``path``; returns the path."""
    path.write_text(json.dumps(data, indent=2) + "\n")
    return path

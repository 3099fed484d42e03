"""What each ``footfall`` command runs: a request in, a report out (``to_json()``, ``write()``).

The command line only parses into a request, calls the ``run_*`` function and prints the
report; the rules (default speed, terrain parameters, ground truth for plots) live here.
"""

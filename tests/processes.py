"""Reading from and stopping the footfall processes a test starts, and saying where one is stuck."""

from __future__ import annotations

import select
import signal
import subprocess
import time


def read_until(process: subprocess.Popen, text: str, timeout_s: float = 60.0) -> str:
    """What ``process`` says on its stdout (a text pipe) up to the first line holding ``text``.

    Fails, with what it said, when it says nothing more for ``timeout_s`` or ends first: a
    process that hangs before it is ready fails the test instead of hanging it.
    """
    said = ""
    end = time.monotonic() + timeout_s
    while text not in said:
        ready, _, _ = select.select([process.stdout], [], [], max(end - time.monotonic(), 0.0))
        line = process.stdout.readline() if ready else None
        if not line:
            state = "said nothing more" if line is None else f"ended ({process.wait(10)})"
            raise AssertionError(f"{process.args} {state} before {text!r}; it said: {said!r}")
        said += line
    return said


def stop(process: subprocess.Popen, timeout_s: float = 30.0) -> int:
    """SIGINT ``process`` and wait for it to end; its return code.

    A process still running after ``timeout_s`` is asked for its threads' stacks (SIGUSR1:
    the footfall command prints them on its stderr, which the test's report shows), then
    killed, and the test fails naming it.
    """
    if process.poll() is None:
        process.send_signal(signal.SIGINT)
    try:
        return process.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        masks = _signal_masks(process.pid)
        process.send_signal(signal.SIGUSR1)
        time.sleep(2.0)
        process.kill()
        process.wait(timeout=10)
        raise AssertionError(
            f"{' '.join(map(str, process.args))} did not stop {timeout_s:.0f} s after SIGINT; "
            f"its threads' stacks are in the captured stderr; its signal masks: {masks}"
        ) from None


def _signal_masks(pid: int) -> str:
    """The pending, blocked, ignored and caught signal masks of a process (Linux)."""
    try:
        with open(f"/proc/{pid}/status") as status:
            return " ".join(line.strip() for line in status if line.startswith("Sig"))
    except OSError as exc:
        return f"not readable ({exc})"

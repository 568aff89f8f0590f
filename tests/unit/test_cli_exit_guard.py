"""A finished command always ends its process, with its exit code, even when shutdown stalls."""

from __future__ import annotations

import subprocess
import sys

# A non-daemon thread that never ends stalls interpreter shutdown for ever, as a
# process pool's manager thread stuck on a dead worker would.
STALLED = """
import sys, threading
from fibersweep.cli._app import _leave_anyway
threading.Thread(target=threading.Event().wait).start()
print("work saved", flush=True)
_leave_anyway({code}, grace=1.0)
sys.exit({code})
"""


def test_stalled_shutdown_still_exits_with_the_commands_code():
    proc = subprocess.run(
        [sys.executable, "-c", STALLED.format(code=3)], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 3
    assert proc.stdout == "work saved\n"
    assert "shutdown stalled" in proc.stderr


def test_normal_exit_is_not_delayed_by_the_guard():
    code = "from fibersweep.cli._app import _leave_anyway; _leave_anyway(0, grace=600.0)"
    # the guard is a daemon thread: a clean shutdown does not wait the 600 s
    proc = subprocess.run([sys.executable, "-c", code], timeout=120)
    assert proc.returncode == 0


def test_the_console_script_goes_through_the_guard():
    from importlib.metadata import entry_points

    (ep,) = [e for e in entry_points(group="console_scripts") if e.name == "fibersweep"]
    assert ep.value == "fibersweep.cli:entry"

"""Hooks for every pytest run under tests/.

LEGSIM_NO_SKIP=1 (set by tools/test.sh): a skipped test, or a module skipped at
collection, is reported as a failure with the skip's reason. tools/setup.sh installs
every dependency the tests need, so in that run a skip (say, a peer engine that does
not import, or no vcan0) means the set-up is broken, not that the test may be left
out. Expected failures (xfail) are not skips and stay as they are; tests that do not
belong in a run are deselected (--ignore, -k, -m), not skipped.
"""
from __future__ import annotations

import os

import pytest

NO_SKIP = os.environ.get("LEGSIM_NO_SKIP") == "1"


def _skip_reason(longrepr) -> str:
    # A skip's longrepr is (path, line, "Skipped: reason").
    if isinstance(longrepr, tuple) and len(longrepr) == 3:
        path, line, reason = longrepr
        return f"{reason} ({path}:{line})"
    return str(longrepr)


def _as_failure(report, what: str) -> None:
    reason = _skip_reason(report.longrepr)
    report.outcome = "failed"
    report.longrepr = (f"{what} was skipped, and LEGSIM_NO_SKIP=1 makes a skip a failure "
                       f"(tools/setup.sh should have installed what it needs): {reason}")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if NO_SKIP and report.skipped and not hasattr(report, "wasxfail"):
        _as_failure(report, "this test")


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector):
    outcome = yield
    report = outcome.get_result()
    if NO_SKIP and report.skipped:
        _as_failure(report, f"{collector.nodeid or 'this module'} (at collection)")


def pytest_report_header(config):
    if NO_SKIP:
        return "LEGSIM_NO_SKIP=1: skips count as failures"
    return None


# A line at least every LEGSIM_TEST_TICK seconds (default 20) while one test runs, so
# that a long test (a SocketCAN scene in the VM, a peer engine's convergence run) is
# not a silence of minutes in the log. The line goes to the terminal's own file
# descriptor, which pytest's output capture saved before it redirected stdout.
TICK_S = float(os.environ.get("LEGSIM_TEST_TICK", "20"))


def _terminal_fd(config):
    capman = config.pluginmanager.getplugin("capturemanager")
    capturing = getattr(capman, "_global_capturing", None)
    out = getattr(capturing, "out", None)
    return getattr(out, "targetfd_save", None)  # None when capture is off (-s): use stdout


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_call(item):
    import threading
    import time

    if TICK_S <= 0:
        yield
        return
    fd = _terminal_fd(item.config)
    done = threading.Event()
    t0 = time.monotonic()

    def tick():
        first = True
        while not done.wait(TICK_S):
            # The first line starts a new one: pytest -v has written the test's name.
            line = (("\n" if first else "") +
                    f"    ... {item.nodeid}: still running, {time.monotonic() - t0:.0f} s\n")
            first = False
            try:
                os.write(fd if fd is not None else 1, line.encode())
            except OSError:
                return

    thread = threading.Thread(target=tick, name="legsim-test-tick", daemon=True)
    thread.start()
    try:
        yield
    finally:
        done.set()
        thread.join()

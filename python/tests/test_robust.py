"""What the bindings do with input that is not a scene and with Ctrl-C: an exception, never a
crash (before: SIGSEGV on a dict that holds itself or nests 10,000 deep; Ctrl-C ignored until
the run ended, then a PanicException; ``sweep(jobs=10**6)`` started a million threads)."""

import _thread
import signal
import threading
import time

import pytest

import absorber


def test_a_dict_that_holds_itself_raises():
    scene = {"beam": {}}
    scene["beam"]["again"] = scene
    with pytest.raises(absorber.AbsorberError, match="nests deeper") as e:
        absorber.static(scene)
    assert e.value.field.startswith("beam.again"), e.value.field


def test_a_dict_nested_ten_thousand_deep_raises():
    scene = {}
    inner = scene
    for _ in range(10_000):
        inner["x"] = {}
        inner = inner["x"]
    with pytest.raises(absorber.AbsorberError, match="nests deeper"):
        absorber.static(scene)
    deep_list = []
    for _ in range(10_000):
        deep_list = [deep_list]
    with pytest.raises(absorber.AbsorberError, match="nests deeper"):
        absorber.static({"beam": {"length": deep_list}})


@pytest.fixture
def python_handles_sigint():
    """Python's own Ctrl-C handler for the test's duration. A background job of a
    non-interactive shell starts with SIGINT ignored (POSIX), Python then installs no handler
    and `interrupt_main` does nothing, so without this the test would measure how it was
    launched, not what the bindings do with a KeyboardInterrupt."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def test_ctrl_c_interrupts_a_long_run_within_a_second(python_handles_sigint):
    # 10^5 s of the paper scene takes a minute or more; Ctrl-C (simulated) after 0.5 s.
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    timer = threading.Timer(0.5, _thread.interrupt_main)
    start = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            absorber.run("paper", duration=1e5, every=1000)
    finally:
        timer.cancel()
    elapsed = time.monotonic() - start
    assert elapsed < 1.5, elapsed
    # The next call runs normally.
    r = absorber.run("paper", duration=0.3)
    assert len(r["t"]) == 101


def test_sweep_jobs_are_capped_at_the_points_and_the_cores():
    start = time.monotonic()
    points = absorber.sweep("paper", [4.0, 4.1], last=0.5, jobs=10**6, duration=1.0)
    assert list(points["frequency"]) == [4.0, 4.1]
    assert time.monotonic() - start < 60


def test_bad_arguments_name_the_argument_its_value_and_the_range():
    # Before: count=0 and freqs=[] returned empty results, every=-1 raised an OverflowError,
    # freqs=["a"] a bare ValueError naming nothing.
    cases = [
        (lambda: absorber.modes("paper", count=0), ["`count`", "0", "at least 1"]),
        (lambda: absorber.modes("paper", count=-1), ["`count`", "-1", "at least 1"]),
        (lambda: absorber.run("paper", every=-1, duration=0.2), ["`every`", "-1", "at least 1"]),
        (lambda: absorber.sweep("paper", freqs=[], duration=0.5), ["`freqs`", "[]", "at least one"]),
        (lambda: absorber.sweep("paper", freqs=["a"], duration=0.5), ["`freqs`", "'a'", "numbers"]),
        (
            lambda: absorber.sweep("paper", freqs=[4.1], jobs=-2, duration=0.5),
            ["`jobs`", "-2", "at least 1"],
        ),
        (
            lambda: absorber.static({"beam": {"length": object()}}),
            ["`beam.length`", "`object`", "allowed: numbers"],
        ),
    ]
    for call, words in cases:
        with pytest.raises(absorber.AbsorberError) as e:
            call()
        for w in words:
            assert w in str(e.value), (w, str(e.value))

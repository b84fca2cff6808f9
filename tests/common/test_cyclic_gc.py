"""The collector pause around a comparison (common.cyclic_gc) ends with the last
thread that took it, also on an error, and leaves a collector that was off, off."""

import gc
import threading

import pytest

from common import cyclic_gc


@pytest.fixture(autouse=True)
def collector_restored():
    was = gc.isenabled()
    yield
    (gc.enable if was else gc.disable)()


def test_the_collector_runs_again_after_the_last_of_two_threads():
    gc.enable()
    first_in, second_done, first_may_leave = threading.Event(), threading.Event(), threading.Event()
    seen = {}

    def first():
        with cyclic_gc.paused():
            first_in.set()
            first_may_leave.wait(10)
            seen["first leaving"] = gc.isenabled()

    def second():
        first_in.wait(10)
        with cyclic_gc.paused():
            seen["second inside"] = gc.isenabled()
        seen["second left"] = gc.isenabled()
        second_done.set()

    threads = [threading.Thread(target=first), threading.Thread(target=second)]
    for t in threads:
        t.start()
    assert second_done.wait(10)
    first_may_leave.set()
    for t in threads:
        t.join(10)
    # Off while either ran; still off when the second left before the first.
    assert seen == {"second inside": False, "second left": False, "first leaving": False}
    assert gc.isenabled()


def test_an_error_inside_ends_the_pause_and_a_collector_that_was_off_stays_off():
    gc.enable()
    with pytest.raises(ValueError), cyclic_gc.paused():
        raise ValueError("no comparison")
    assert gc.isenabled()

    gc.disable()
    with cyclic_gc.paused():
        pass
    assert not gc.isenabled()


def test_a_decorated_function_pauses_it_on_every_call():
    gc.enable()

    @cyclic_gc.paused()
    def comparison():
        return gc.isenabled()

    assert [comparison(), comparison()] == [False, False]
    assert gc.isenabled()

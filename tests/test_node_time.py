"""Time values, Rate and Timer (no master needed: they do not touch the graph)."""
from __future__ import annotations

import threading

import pytest

from orchestra.node import Duration, Time, Timer

pytestmark = pytest.mark.timeout(30)


def test_periodic_timer_ticks_on_a_fixed_schedule_until_shutdown():
    events = []
    enough = threading.Event()

    def tick(event):
        events.append(event)
        if len(events) >= 3:
            enough.set()

    timer = Timer(Duration.from_sec(0.02), tick)
    assert enough.wait(10)
    timer.shutdown()
    first, second = events[0], events[1]
    assert first.last_expected is None and second.last_expected == first.current_expected
    assert second.current_expected - first.current_expected == Duration.from_sec(0.02)
    assert all(e.current_real >= e.current_expected for e in events)


def test_oneshot_timer_fires_once_and_a_failing_callback_is_contained():
    calls = []
    done = threading.Event()

    def boom(event):
        calls.append(event)
        done.set()
        raise RuntimeError("callback failure")

    timer = Timer(0.01, boom, oneshot=True)
    assert done.wait(10)
    timer.join(10)
    assert not timer.is_alive() and len(calls) == 1


def test_timer_rejects_a_non_positive_period():
    with pytest.raises(ValueError):
        Timer(0, lambda e: None)


def test_time_and_duration_arithmetic_and_normalisation():
    assert Time(1, 1_500_000_000) == Time(2, 500_000_000)
    assert (Time(3) - Time(1, 500_000_000)) == Duration(1, 500_000_000)
    assert Duration(-1, 500_000_000).to_sec() == -0.5
    assert Time.from_sec(1.25).nsecs == 250_000_000
    assert (Time(1) + Duration(2)).secs == 3
    with pytest.raises(ValueError):
        Time(-1)

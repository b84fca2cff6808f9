"""A switch is placed at the robot's time; lost fixes are counted from the stamps."""

from datetime import UTC, datetime, timedelta

import pytest

from rosbridge_app.collector.losses import LossCounter
from rosbridge_app.collector.mode_timing import ModeClock

T0 = datetime(2026, 5, 1, 12, 0, tzinfo=UTC)


def s(seconds: float) -> datetime:
    return T0 + timedelta(seconds=seconds)


def test_a_stamped_switch_starts_at_its_stamp_however_late_it_arrives():
    clock = ModeClock()
    assert clock.place("auto", s(0), s(0), s(0.1)) == (s(0), s(0), 0.0)
    assert clock.place("ito", s(10), s(10.01), s(13.5)) == (s(10), s(10), 0.0)


def test_an_unstamped_switch_starts_when_sent_within_the_interval_since_the_last_message():
    clock = ModeClock()
    clock.place("auto", None, s(9), s(9.1))
    assert clock.place("ito", None, s(10), s(12.0)) == (s(10), s(10), 1.0)
    # Without a send time either: the receive time, its error unknown.
    assert ModeClock().place("auto", None, None, s(5)) == (s(5), None, None)


def test_a_second_copy_of_a_message_is_not_placed_again():
    clock = ModeClock()
    clock.place("auto", s(1), s(1), s(1.1))
    assert clock.place("auto", s(1), s(1), s(1.2)) is None  # the latched subscription's copy
    assert clock.place("auto", s(0.5), None, s(1.3)) is None  # an older one
    # A publisher whose stamp stands still: a new value is not taken for a copy.
    assert clock.place("ito", s(1), None, s(1.4)) == (s(1), s(1), 0.0)


def test_a_clock_far_from_the_receive_time_is_not_believed():
    clock = ModeClock()
    assert clock.place("auto", s(3600), None, s(0)) == (s(0), None, None)


def test_gaps_in_the_stamps_are_counted_against_the_measured_rate():
    counter = LossCounter()
    stamps = [i * 0.1 for i in range(60)]
    del stamps[40:43]  # three fixes not sent
    del stamps[30]  # and one more
    for stamp in stamps:
        counter.seen(1000 + stamp)
    # Without sequence numbers nothing says the collector dropped them.
    assert counter.report() == {"dropped": 0, "publisher_gaps": 4, "rate": 10.0}


def test_sequence_numbers_tell_the_publishers_gaps_from_messages_dropped():
    counter = LossCounter()
    sent = list(range(60))  # (sequence number, stamp in tenths): one per beat
    skipped = {20, 21, 22}  # beats the loaded publisher's timer missed: never sent
    sequence = 0
    received = []
    for beat in sent:
        if beat in skipped:
            continue
        sequence += 1
        received.append((sequence, beat))
    del received[40:45]  # five sent ones the collector's queue overwrote
    for number, beat in received:
        counter.seen(1000 + beat * 0.1, number)
    assert counter.report() == {"dropped": 5, "publisher_gaps": 3, "rate": 10.0}
    # A restarted publisher numbers from 1 again: no drop, no gap.
    counter.seen(1000 + 60 * 0.1, 1)
    assert (counter.dropped, counter.gaps) == (5, 3)


def test_two_publishers_on_one_topic_are_not_taken_for_drops():
    counter = LossCounter()
    # A driver that has run for a while and a second one just started, interleaved.
    for i in range(100):
        counter.seen(None, 5000 + i)
        counter.seen(None, 1 + i)
    assert counter.dropped == 0
    counter.seen(None, 5000 + 102)  # the first one's next two never arrived
    assert counter.dropped == 2


def test_a_pause_of_the_publisher_is_not_a_loss():
    counter = LossCounter()
    for stamp in [i * 0.1 for i in range(10)] + [30 + i * 0.1 for i in range(10)]:
        counter.seen(1000 + stamp)
    assert counter.report()["publisher_gaps"] == 0


def test_a_jittery_publisher_that_loses_nothing_has_no_gaps():
    counter = LossCounter()
    # A loaded robot's timer: every third message 40 ms late, the next one early.
    late = [0.04 if i % 3 == 1 else -0.04 if i % 3 == 2 else 0 for i in range(300)]
    for i, shift in enumerate(late):
        counter.seen(1000 + i * 0.1 + shift)
    assert counter.gaps == 0
    assert counter.report()["rate"] == pytest.approx(10, abs=0.2)

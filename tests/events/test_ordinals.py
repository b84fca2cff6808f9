"""People see Shift 3 and Leg 2; those numbers must not move."""

from events.services import deletion, logs


def test_numbers_count_up_per_parent(test_event, vehicle, other_vehicle):
    first = logs.create_shift(test_event=test_event, vehicle=vehicle)
    second = logs.create_shift(test_event=test_event, vehicle=other_vehicle)
    assert (first.number, second.number) == (1, 2)
    assert [logs.create_leg(shift=second).number for _ in range(3)] == [1, 2, 3]


def test_deleting_a_sibling_never_reuses_a_number(test_event, vehicle):
    shifts = [logs.create_shift(test_event=test_event, vehicle=vehicle) for _ in range(3)]
    deletion.delete(shifts[1])
    assert logs.create_shift(test_event=test_event, vehicle=vehicle).number == 4
    deletion.delete(shifts[2])
    # Number 3 is gone now, but 4 exists, so the next is 5.
    assert logs.create_shift(test_event=test_event, vehicle=vehicle).number == 5

"""The segment state machine of one leg."""

from datetime import timedelta

import pytest
from django.utils import timezone

from common.errors import RuleViolation
from events.models import Segment
from events.services import segments
from events.services.segments import GpsPosition, LocalPosition
from tests.support.modes import start_auto


def masters(leg):
    return list(Segment.objects.filter(leg=leg, parent__isnull=True).order_by("start", "id"))


def test_mode_change_closes_the_master_and_opens_one_of_the_new_type(leg):
    auto = start_auto(leg)
    ito = segments.report_mode(leg, "ito").master
    auto.refresh_from_db()
    assert auto.end == ito.start
    assert [m.segment_type_id for m in masters(leg)] == ["auto", "ito"]
    assert ito.is_open


def test_new_ito_master_gets_an_unassigned_child_at_once(leg):
    ito = segments.report_mode(leg, "ito").master
    child = ito.children.get()
    assert child.ito_reason_id == "unassigned"
    assert child.start == ito.start
    assert child.is_open


def test_a_reason_belongs_to_its_master_and_a_master_to_itself(leg):
    ito = segments.report_mode(leg, "ito").master
    child = Segment.objects.select_related("parent").get(parent=ito)
    assert (child.master, child.master_id) == (ito, ito.pk)
    assert (ito.master, ito.master_id) == (ito, ito.pk)


def test_reporting_the_open_mode_again_changes_nothing(leg):
    first = segments.report_mode(leg, "auto")
    again = segments.report_mode(leg, "auto")
    assert first.changed and not again.changed
    assert again.master == first.master
    assert Segment.objects.filter(leg=leg).count() == 1


def test_unknown_mode_is_refused_with_a_field_message(leg):
    with pytest.raises(RuleViolation) as exc:
        segments.report_mode(leg, "teleop")
    assert "mode" in exc.value.message_dict


def test_operator_adds_a_second_reason_to_an_open_ito_master(leg):
    ito = segments.report_mode(leg, "ito").master
    second = segments.new_manual_segment(leg, reason="planner")
    assert second.parent == ito
    assert sorted(ito.children.values_list("ito_reason", flat=True)) == ["planner", "unassigned"]


def test_manual_segment_while_auto_runs_switches_to_ito(leg):
    auto = start_auto(leg)
    child = segments.new_manual_segment(leg, reason="safety")
    auto.refresh_from_db()
    assert not auto.is_open
    assert child.ito_reason_id == "safety"
    assert child.parent.segment_type_id == "ito"
    assert child.parent.is_open


def test_closing_a_child_closes_only_the_child(leg):
    ito = segments.report_mode(leg, "ito").master
    child = ito.children.get()
    segments.close_segment(child)
    ito.refresh_from_db()
    child.refresh_from_db()
    assert not child.is_open and ito.is_open


def test_closing_a_master_closes_its_children(leg):
    ito = segments.report_mode(leg, "ito").master
    segments.new_manual_segment(leg, reason="planner")
    segments.close_segment(ito)
    assert not Segment.objects.filter(leg=leg, end__isnull=True).exists()


def test_reasons_belong_to_ito_children_not_auto(leg):
    auto = start_auto(leg)
    with pytest.raises(RuleViolation, match="AUTO"):
        segments.annotate_segment(auto, obstacle="tree")


def test_annotating_a_child_and_clearing_a_field(leg):
    child = segments.report_mode(leg, "ito").master.children.get()
    segments.annotate_segment(child, ito_reason="safety", obstacle="Baum 🌳", slope="10°")
    segments.annotate_segment(child, obstacle="")
    child.refresh_from_db()
    assert (child.ito_reason_id, child.obstacle, child.slope) == ("safety", "", "10°")


def test_unknown_reason_is_refused(leg):
    child = segments.report_mode(leg, "ito").master.children.get()
    with pytest.raises(RuleViolation) as exc:
        segments.annotate_segment(child, ito_reason="lunch")
    assert "ito_reason" in exc.value.message_dict


def test_zero_is_a_valid_position(leg):
    master = segments.report_mode(
        leg, "auto", gps=GpsPosition(0.0, 0.0), local=LocalPosition(0.0, 5.0, "map")
    ).master
    master.refresh_from_db()
    assert (master.start_position.x, master.start_position.y) == (0.0, 0.0)
    assert (master.start_local_x, master.start_local_y) == (0.0, 5.0)


def test_a_switch_without_position_is_still_recorded(leg):
    master = segments.report_mode(leg, "ito").master
    assert master.start_position is None and master.start_local_x is None


@pytest.mark.parametrize(
    "lon,lat,field",
    [(181, 0, "longitude"), (0, -91, "latitude"), (float("nan"), 0, "longitude")],
)
def test_impossible_positions_are_refused(lon, lat, field):
    with pytest.raises(RuleViolation) as exc:
        GpsPosition(lon, lat)
    assert field in exc.value.message_dict


def test_robot_stamp_is_kept_beside_server_time(leg):
    stamp = timezone.now() - timedelta(hours=1, microseconds=5)
    master = segments.report_mode(leg, "auto", robot_stamp=stamp).master
    master.refresh_from_db()
    assert master.robot_stamp == stamp
    assert master.start > stamp


def test_state_machine_is_scoped_to_one_leg(test_event, vehicle, other_vehicle):
    from events.services import logs

    leg_a = logs.create_leg(shift=logs.create_shift(test_event=test_event, vehicle=vehicle))
    leg_b = logs.create_leg(shift=logs.create_shift(test_event=test_event, vehicle=other_vehicle))
    a = start_auto(leg_a)
    segments.report_mode(leg_b, "ito")
    a.refresh_from_db()
    assert a.is_open


def test_retried_report_with_the_same_uid_is_a_no_op(leg):
    import uuid

    uid = uuid.uuid4()
    first = segments.report_mode(leg, "ito", uid=uid)
    segments.report_mode(leg, "auto")
    retry = segments.report_mode(leg, "ito", uid=uid)
    assert retry.master == first.master and not retry.changed
    assert Segment.objects.filter(leg=leg, parent__isnull=True).count() == 2


def test_close_open_master_when_logging_stops(leg):
    segments.report_mode(leg, "ito")
    closed = segments.close_open_master(leg)
    assert closed is not None
    assert not Segment.objects.filter(leg=leg, end__isnull=True).exists()
    assert segments.close_open_master(leg) is None

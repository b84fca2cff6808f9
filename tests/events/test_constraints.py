"""The database itself refuses states the services never create."""

import pytest
from django.db import IntegrityError, connection, transaction
from django.db.migrations.executor import MigrationExecutor
from django.utils import timezone

from events.models import Leg, Segment, Shift
from events.services import segments
from tests.support.modes import start_auto


def test_second_open_shift_for_a_vehicle_is_refused_by_the_database(shift):
    with pytest.raises(IntegrityError), transaction.atomic():
        Shift.objects.create(
            test_event=shift.test_event, vehicle=shift.vehicle, number=99, start=timezone.now()
        )


def test_second_open_leg_in_a_shift_is_refused_by_the_database(leg):
    with pytest.raises(IntegrityError), transaction.atomic():
        Leg.objects.create(shift=leg.shift, number=99, start=timezone.now())


def test_second_open_master_in_a_leg_is_refused_by_the_database(leg):
    segments.report_mode(leg, "auto")
    with pytest.raises(IntegrityError), transaction.atomic():
        Segment.objects.create(leg=leg, segment_type_id="ito", start=timezone.now())


def test_auto_children_and_annotated_masters_are_refused_by_the_database(leg):
    master = start_auto(leg)
    with pytest.raises(IntegrityError), transaction.atomic():
        Segment.objects.create(leg=leg, parent=master, segment_type_id="auto", start=master.start)
    with pytest.raises(IntegrityError), transaction.atomic():
        Segment.objects.filter(pk=master.pk).update(obstacle="rock")


@pytest.mark.parametrize(
    "annotation",
    [{"initiator": "remote_operator"}, {"severity": "critical"}, {"location_type": "road"}],
)
def test_a_master_with_a_reasons_regulator_fields_is_refused_by_the_database(leg, annotation):
    master = start_auto(leg)
    with pytest.raises(IntegrityError), transaction.atomic():
        Segment.objects.filter(pk=master.pk).update(**annotation)
    reason = segments.add_ito_child(segments.report_mode(leg, "ito").master, reason="unassigned")
    Segment.objects.filter(pk=reason.pk).update(**annotation)


@pytest.mark.django_db(transaction=True)
def test_the_upgrade_clears_what_a_master_held_of_a_reasons_fields(leg):
    master = start_auto(leg)
    executor = MigrationExecutor(connection)
    executor.migrate([("events", "0027_history_source")])
    Segment.objects.filter(pk=master.pk).update(initiator="other", location_type="yard")
    executor.loader.build_graph()
    executor.migrate(executor.loader.graph.leaf_nodes())
    master.refresh_from_db()
    assert (master.initiator, master.location_type) == ("safety_driver", "")


def test_end_before_start_is_refused_by_the_database(leg):
    with pytest.raises(IntegrityError), transaction.atomic():
        Leg.objects.filter(pk=leg.pk).update(end=leg.start - timezone.timedelta(seconds=1))

"""A pose batch is checked by pydantic when it can be and by DRF otherwise: same answer."""

import uuid

import pytest
from rest_framework import serializers

from telemetry.api.serializers import (
    PoseItemSerializer,
    PoseListSerializer,
    PoseSerializer,
    gps_fix,
    sent_pose,
)

UID = str(uuid.uuid4())
GOOD = {"longitude": 7.1, "latitude": 50.2}

ITEMS = [
    GOOD,
    {**GOOD, "uid": UID, "altitude": 120.5, "fix_status": 2, "horizontal_accuracy": 0.02},
    {**GOOD, "robot_stamp": "2026-05-04T10:00:01Z"},
    {**GOOD, "robot_stamp": "2026-05-04T12:00:01.250+02:00"},
    {**GOOD, "altitude": None, "robot_stamp": None, "ignored": "x"},
    {"longitude": "7.5", "latitude": "-3"},
    {**GOOD, "uid": UID.replace("-", "")},
    # Taken by DRF but not by pydantic: the fallback answers.
    {**GOOD, "robot_stamp": "2026-05-04T10:00:01"},
    {**GOOD, "fix_status": "1"},
    {**GOOD, "uid": 12345},
    # Refused by both, with DRF's messages.
    {**GOOD, "uid": None},
    {**GOOD, "latitude": 200},
    {**GOOD, "longitude": "east"},
    {**GOOD, "fix_status": 7},
    {**GOOD, "fix_status": True},
    {**GOOD, "robot_stamp": 1767600000},
    {**GOOD, "robot_stamp": "1767600000"},
    {"latitude": 50.0},
]


def drf_only(items):
    checked = serializers.ListSerializer(child=PoseItemSerializer(), data=items)
    return checked.is_valid(), checked.validated_data if checked.is_valid() else checked.errors


def both_ways(items):
    checked = PoseItemSerializer(many=True, data=items)
    assert isinstance(checked, PoseListSerializer)
    ok = checked.is_valid()
    return ok, checked.validated_data if ok else checked.errors


@pytest.mark.parametrize("item", ITEMS, ids=[str(i) for i in range(len(ITEMS))])
def test_each_item_gets_the_answer_drf_gives(item):
    fast, expected = both_ways([GOOD, item]), drf_only([GOOD, item])
    assert fast[0] == expected[0]
    if fast[0]:
        assert [dict(d) for d in fast[1]] == [dict(d) for d in expected[1]]
    else:
        assert fast[1] == expected[1]


def test_a_whole_batch_of_good_items_passes_the_fast_way(monkeypatch):
    good = [item for item in ITEMS[:7]] * 100
    # Were DRF asked, this would fail the test.
    monkeypatch.setattr(serializers.ListSerializer, "to_internal_value", None)
    ok, data = both_ways(good)
    assert ok and len(data) == 700
    assert data[1]["point"] == {"x": 7.1, "y": 50.2} and data[1]["fix_status"] == 2


@pytest.mark.parametrize("item", ITEMS, ids=[str(i) for i in range(len(ITEMS))])
def test_a_single_pose_is_taken_the_quick_way_only_as_drf_takes_it(item, auto_master):
    """The quick check of one pose (telemetry.api.single_pose) takes the first
    items above with the values DRF reads, and leaves every other to the view's
    serializer, which answers."""
    sent = {**item, "segment": auto_master.pk}
    quick = sent_pose(sent)
    if item not in ITEMS[:7]:
        assert quick is None
    else:
        full = PoseSerializer(data=sent)
        assert full.is_valid(), full.errors
        segment_id, fix, source_id = quick
        expected = gps_fix(full.validated_data)
        if "uid" not in item:
            expected.uid = fix.uid  # each gets a new one
        assert (segment_id, fix, source_id) == (auto_master.pk, expected, None)

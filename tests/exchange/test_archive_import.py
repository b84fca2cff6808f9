"""Export and import through an archive within one installation."""

import json
import uuid
import zipfile
from datetime import timedelta

import pytest

from events.models import Leg, Segment, Shift, TestEvent
from events.services import logs, notes, segments
from exchange.archive import ArchiveError, open_archive
from exchange.export import export_events, select_events
from exchange.importer import ImportRefused, import_bundle
from telemetry.models import Image, MapImage, Pose
from tests.support.archives import members_of, replace_record, signed_archive
from tests.support.field_day import T0, configuration, field_day
from tests.support.snapshot import snapshot

pytestmark = pytest.mark.django_db(transaction=False)


def export_all(path):
    return export_events(path, select_events())


def load(path, **kwargs):
    with open_archive(path) as bundle:
        return import_bundle(bundle, **kwargs)


@pytest.fixture
def day(media_root):
    return field_day()


def test_import_into_empty_installation_restores_everything(day, tmp_path, wipe):
    before = snapshot()
    export_all(tmp_path / "day.zip")
    wipe()
    plan = load(tmp_path / "day.zip")
    assert snapshot() == before
    assert plan.counts["poses"]["added"] == 15
    assert plan.counts["segments"]["added"] == 5  # 3 masters + 2 ITO children
    assert plan.counts["images"]["added"] == 1 and plan.counts["maps"]["added"] == 1


def test_second_import_of_same_archive_changes_nothing(day, tmp_path, wipe):
    export_all(tmp_path / "day.zip")
    wipe()
    load(tmp_path / "day.zip")
    after_first = snapshot()
    plan = load(tmp_path / "day.zip")
    assert plan.changes() == 0
    assert plan.counts["poses"]["unchanged"] == 15
    assert plan.counts["vehicles"]["reused"] == 1
    assert snapshot() == after_first
    assert Image.objects.count() == 1 and MapImage.objects.count() == 1


def test_importing_into_the_source_itself_is_a_no_op(day, tmp_path):
    before = snapshot()
    export_all(tmp_path / "day.zip")
    assert load(tmp_path / "day.zip").changes() == 0
    assert snapshot() == before


def test_newer_archive_adds_new_rows_and_updates_changed_ones(media_root, tmp_path, wipe):
    event = field_day(close=False)
    export_all(tmp_path / "early.zip")
    # The robot goes on logging: an annotation changes, the leg ends, a second leg starts.
    leg = Leg.objects.get()
    child = Segment.objects.filter(parent__isnull=False).order_by("start").first()
    segments.annotate_segment(child, obstacle="ditch", lighting="dusk")
    note = notes.add_note(child, text="first note")
    second = logs.create_leg(shift=leg.shift, at=T0 + timedelta(minutes=30))
    segments.report_mode(second, "auto", at=T0 + timedelta(minutes=31))
    notes.edit_note(note, text="edited note")
    logs.close_test_event(event, at=T0 + timedelta(minutes=40))
    final = snapshot()
    export_all(tmp_path / "late.zip")

    wipe()
    load(tmp_path / "early.zip")
    assert Leg.objects.count() == 1 and TestEvent.objects.get().end is None
    plan = load(tmp_path / "late.zip")
    assert snapshot() == final
    assert plan.counts["legs"] == {"updated": 1, "added": 1}
    assert plan.counts["test_events"]["updated"] == 1
    assert plan.counts["notes"]["added"] == 1
    assert plan.counts["poses"]["added"] == 0


def test_old_archive_never_reopens_what_was_closed_here(media_root, tmp_path):
    event = field_day(close=False)
    export_all(tmp_path / "open.zip")
    logs.close_test_event(event, at=T0 + timedelta(minutes=50))
    closed = snapshot()
    assert load(tmp_path / "open.zip").changes() == 0
    assert snapshot() == closed


def test_new_open_leg_under_a_shift_closed_here_is_refused(media_root, tmp_path):
    event = field_day(close=False)
    export_all(tmp_path / "open.zip")
    shift = event.shifts.get()
    logs.close_shift(shift, at=T0 + timedelta(minutes=50))
    shift.legs.all().delete()  # unknown here again, so the archive would add it open
    before = snapshot()
    with pytest.raises(ImportRefused, match=r"Leg .* would stay open inside Shift 1"):
        load(tmp_path / "open.zip")
    assert snapshot() == before


def test_archive_closing_an_event_whose_shift_runs_here_is_refused(media_root, tmp_path):
    vehicle, *_ = configuration()
    event = logs.create_test_event(at=T0, location="Wachtberg")
    logs.close_test_event(event, at=T0 + timedelta(minutes=5))
    export_all(tmp_path / "closed.zip")
    logs.reopen_test_event(event)
    logs.create_shift(test_event=event, vehicle=vehicle, at=T0 + timedelta(minutes=10))
    # As if the other installation had closed the event after our re-opening.
    TestEvent.objects.filter(pk=event.pk).update(modified=T0)
    before = snapshot()
    with pytest.raises(ImportRefused, match="would stay open inside"):
        load(tmp_path / "closed.zip")
    assert snapshot() == before


def test_a_stale_archive_does_not_undo_a_later_change(media_root, tmp_path):
    vehicle, *_ = configuration()
    event = logs.create_test_event(at=T0, location="Wachtberg")
    shift = logs.create_shift(test_event=event, vehicle=vehicle, at=T0 + timedelta(minutes=1))
    export_all(tmp_path / "before.zip")
    logs.update_test_event(event, location="Wachtberg, north field")
    logs.update_shift(shift, workspace="meadow")
    plan = load(tmp_path / "before.zip")
    assert plan.changes() == 0
    assert TestEvent.objects.get().location == "Wachtberg, north field"
    assert Shift.objects.get().workspace == "meadow"


def test_notes_keep_the_later_edit_whichever_side_made_it(day, tmp_path):
    from events.models import Note

    note = Note.objects.get()
    export_all(tmp_path / "before-edit.zip")
    notes.edit_note(note, text="edited here after the export")
    plan = load(tmp_path / "before-edit.zip")
    assert plan.counts["notes"] == {"unchanged": 1}
    assert Note.objects.get().text == "edited here after the export"

    export_all(tmp_path / "after-edit.zip")
    Note.objects.filter(pk=note.pk).update(text="stale", edited=note.created)
    plan = load(tmp_path / "after-edit.zip")
    assert plan.counts["notes"] == {"updated": 1}
    assert Note.objects.get().text == "edited here after the export"


def test_image_description_is_the_only_image_field_an_import_changes(day, tmp_path):
    image = Image.objects.get()
    stored = image.image.name
    export_all(tmp_path / "day.zip")
    Image.objects.filter(pk=image.pk).update(description="changed here")
    plan = load(tmp_path / "day.zip")
    assert plan.counts["images"] == {"updated": 1}
    image.refresh_from_db()
    assert image.description != "changed here" and image.image.name == stored


def test_dry_run_reports_the_plan_and_writes_nothing(day, tmp_path, wipe, media_root):
    export_all(tmp_path / "day.zip")
    wipe()
    files = set(media_root.rglob("*.*"))
    plan = load(tmp_path / "day.zip", dry_run=True)
    assert plan.counts["shifts"]["added"] == 1 and plan.counts["poses"]["added"] == 15
    assert not any(snapshot().values())
    assert set(media_root.rglob("*.*")) == files


def test_configuration_matching_ignores_case_and_keeps_local_rows(day, tmp_path, wipe):
    export_all(tmp_path / "day.zip")
    wipe()
    vehicle, _, performer, person = configuration()
    performer.institution = "FRAUNHOFER fkie"
    performer.save()
    person.name = "jörg müller "
    person.save()
    plan = load(tmp_path / "day.zip")
    assert plan.counts["performers"] == {"reused": 1}
    assert plan.counts["personnel"] == {"reused": 1}
    shift = Shift.objects.get()
    assert shift.performer == performer and shift.robot_operator == person
    assert shift.vehicle == vehicle


def test_number_taken_by_another_shift_is_refused(day, tmp_path, wipe):
    export_all(tmp_path / "day.zip")
    event_uid = TestEvent.objects.get().uid
    wipe()
    vehicle, *_ = configuration("jackal")
    event = logs.create_test_event(uid=event_uid, at=T0, location="Wachtberg")
    logs.create_shift(test_event=event, vehicle=vehicle, at=T0 + timedelta(seconds=5))
    before = snapshot()
    with pytest.raises(ImportRefused, match="Shift 1 of this test event already exists"):
        load(tmp_path / "day.zip")
    assert snapshot() == before


def test_second_open_shift_of_a_vehicle_is_refused(media_root, tmp_path, wipe):
    field_day(close=False)
    export_all(tmp_path / "open.zip")
    wipe()
    vehicle, *_ = configuration()
    event = logs.create_test_event(at=T0)
    logs.create_shift(test_event=event, vehicle=vehicle, at=T0)
    before, files = snapshot(), set(media_root.rglob("*.*"))
    with pytest.raises(ImportRefused, match="'husky' already has an open shift"):
        load(tmp_path / "open.zip")
    assert snapshot() == before
    assert set(media_root.rglob("*.*")) == files


def _rewrite(source, target, change):
    with zipfile.ZipFile(source) as old, zipfile.ZipFile(target, "w") as new:
        for info in old.infolist():
            data = change(info.filename, old.read(info.filename))
            if data is not None:
                new.writestr(info.filename, data)


@pytest.mark.parametrize(
    "change, message",
    [
        (
            lambda n, d: d.replace(b"Wachtberg", b"Wachtburg") if "test_events" in n else d,
            "does not match its checksum",
        ),
        (lambda n, d: None if n.startswith("files/images") else d, "incomplete"),
        (
            lambda n, d: (
                d.replace(b'"format": "ftt-archive"', b'"format": "other"')
                if n == "manifest.json"
                else d
            ),
            "not an FTT archive",
        ),
        (
            lambda n, d: d.replace(b'"version": 1', b'"version": 7') if n == "manifest.json" else d,
            "newer FTT",
        ),
        (lambda n, d: None if n == "manifest.json" else d, "no manifest.json"),
    ],
    ids=["changed-data", "missing-file", "foreign-manifest", "newer-version", "no-manifest"],
)
def test_damaged_or_foreign_archive_is_refused_before_anything_changes(
    day, tmp_path, wipe, change, message
):
    export_all(tmp_path / "day.zip")
    wipe()
    _rewrite(tmp_path / "day.zip", tmp_path / "bad.zip", change)
    with pytest.raises(ArchiveError, match=message):
        load(tmp_path / "bad.zip")
    assert not any(snapshot().values())


def test_truncated_and_non_zip_files_are_refused(day, tmp_path):
    export_all(tmp_path / "day.zip")
    data = (tmp_path / "day.zip").read_bytes()
    (tmp_path / "cut.zip").write_bytes(data[: len(data) // 2])
    (tmp_path / "notes.txt").write_text("hello")
    for name in ("cut.zip", "notes.txt"):
        with pytest.raises(ArchiveError, match="not an FTT archive|damaged"):
            load(tmp_path / name)


def test_record_that_breaks_a_rule_rolls_back_the_whole_import(day, tmp_path, wipe):
    def bad_pose(name, data):
        if name == "data/poses.jsonl":
            lines = data.splitlines(keepends=True)
            lines[-1] = lines[-1].replace(b'"point": [', b'"point": [999, ')
            return b"".join(lines)
        return data

    export_all(tmp_path / "day.zip")
    wipe()
    _rewrite(tmp_path / "day.zip", tmp_path / "bad.zip", bad_pose)
    # Re-sign the changed member so only the rule check can catch it.
    import hashlib
    import json

    with zipfile.ZipFile(tmp_path / "bad.zip") as z:
        manifest = json.loads(z.read("manifest.json"))
        members = {n: z.read(n) for n in z.namelist()}
    body = members["data/poses.jsonl"]
    manifest["members"]["data/poses.jsonl"] = {
        "sha256": hashlib.sha256(body).hexdigest(),
        "size": len(body),
    }
    members["manifest.json"] = json.dumps(manifest).encode()
    with zipfile.ZipFile(tmp_path / "resigned.zip", "w") as z:
        for name, content in members.items():
            z.writestr(name, content)
    with pytest.raises(ImportRefused, match="poses record .*Nothing was imported"):
        load(tmp_path / "resigned.zip")
    assert not any(snapshot().values())
    assert not list(Pose.objects.all())


def test_since_archive_carries_only_new_telemetry_but_completes_the_event(
    media_root, tmp_path, wipe
):
    from django.utils import timezone

    from tests.support.field_day import more_logging

    field_day(close=False)
    export_all(tmp_path / "full.zip")
    cut = timezone.now()
    more_logging()
    final = snapshot()
    result = export_events(tmp_path / "since.zip", select_events(since=cut), since=cut)
    assert result.counts["poses"] == 6 and result.counts["images"] == 0
    assert result.counts["legs"] == 2  # log entries always complete

    wipe()
    load(tmp_path / "full.zip")
    plan = load(tmp_path / "since.zip")
    assert plan.counts["poses"] == {"added": 6}
    assert snapshot() == final


def test_since_selects_a_closed_event_whose_entries_were_edited_since(media_root, tmp_path):
    from django.utils import timezone

    field_day()  # closed
    quiet = field_day(T0 + timedelta(days=1), vehicle_key="jackal")
    cut = timezone.now()
    assert select_events(since=cut) == []
    segments.annotate_segment(
        Segment.objects.filter(leg__shift__test_event=quiet, parent__isnull=False).first(),
        obstacle="a puddle noticed in the video afterwards",
    )
    assert select_events(since=cut) == [quiet]


def test_commands_export_chosen_events_and_print_the_plan(day, tmp_path, wipe):
    import io

    from django.core.management import CommandError, call_command

    other = field_day(T0 + timedelta(days=1), vehicle_key="jackal")
    out = io.StringIO()
    call_command("ftt_export", str(tmp_path / "one.zip"), "--event", str(other.uid), stdout=out)
    assert "1 test event(s)" in out.getvalue()
    with pytest.raises(CommandError, match="No test event with id or uid 'nope'"):
        call_command("ftt_export", str(tmp_path / "x.zip"), "--event", "nope")
    wipe()
    out = io.StringIO()
    call_command("ftt_import", str(tmp_path / "one.zip"), "--dry-run", stdout=out)
    assert "Would change" in out.getvalue() and not TestEvent.objects.exists()
    call_command("ftt_import", str(tmp_path / "one.zip"), stdout=io.StringIO())
    assert list(TestEvent.objects.values_list("uid", flat=True)) == [other.uid]
    with pytest.raises(CommandError, match="does not exist"):
        call_command("ftt_import", str(tmp_path / "x.zip"))


@pytest.mark.parametrize(
    "table, model", [("notes", "Note"), ("poses", "Pose"), ("images", "Image")]
)
def test_a_record_whose_uid_is_another_segments_row_here_is_refused(day, tmp_path, table, model):
    """Issue 42: a uid is one row everywhere; an archive that hangs a known uid
    under another segment than here names another row, and nothing is imported."""
    from events.models import Note

    rows = {"Note": Note, "Pose": Pose, "Image": Image}[model].objects
    first = rows.order_by("id").first()
    master = Segment.objects.get(pk=first.segment_id).master
    elsewhere = Segment.objects.filter(parent__isnull=True).exclude(pk=master.pk).first()
    export_all(tmp_path / "day.zip")
    members = members_of((tmp_path / "day.zip").read_bytes())

    def moved(record):
        if record["uid"] == str(first.uid):
            return {**record, "segment": str(elsewhere.uid)}
        return record

    (tmp_path / "moved.zip").write_bytes(signed_archive(replace_record(members, table, moved)))
    before = snapshot()

    with pytest.raises(ImportRefused, match=f"{table} record {first.uid}: .*another row"):
        load(tmp_path / "moved.zip")

    assert snapshot() == before


def test_an_archive_adds_nothing_to_a_test_event_final_here(day, tmp_path):
    """Issue 46: an archive brings no poses into a test event finalised here."""
    from events.services import finality

    finality.finalise_test_event(TestEvent.objects.get())
    export_all(tmp_path / "day.zip")
    members = members_of((tmp_path / "day.zip").read_bytes())
    poses = [json.loads(line) for line in members["data/poses.jsonl"].splitlines()]
    late = {**poses[-1], "uid": str(uuid.uuid4()), "point": [7.2, 50.7]}
    members["data/poses.jsonl"] += (json.dumps(late) + "\n").encode()
    (tmp_path / "late.zip").write_bytes(signed_archive(members))
    before = snapshot()

    with pytest.raises(ImportRefused, match="final since .*Nothing was imported"):
        load(tmp_path / "late.zip")

    assert snapshot() == before


def test_an_archive_of_a_final_event_new_here_brings_all_of_it(day, tmp_path, wipe):
    from events.services import finality

    finality.finalise_test_event(TestEvent.objects.get())
    export_all(tmp_path / "day.zip")
    before = snapshot()
    wipe()

    load(tmp_path / "day.zip")

    assert snapshot() == before


def test_an_archive_lists_poses_in_driving_order_unstamped_last(leg, tmp_path, media_root):
    """Issue 42, defect 3: the same order on PostgreSQL and SpatiaLite."""
    from events.models import SegmentType
    from telemetry.services import pose_writes

    master = segments.report_mode(leg, SegmentType.AUTO).master
    stamps = [None, T0 + timedelta(seconds=2), None, T0 + timedelta(seconds=1)]
    pose_writes.store_poses(
        master,
        [pose_writes.GpsFix(7.0 + i / 1e4, 50.6, robot_stamp=s) for i, s in enumerate(stamps)],
    )
    pose_writes.store_local_poses(
        master,
        [pose_writes.MapPose(float(i), 0.0, "map", robot_stamp=s) for i, s in enumerate(stamps)],
    )
    export_all(tmp_path / "order.zip")
    members = members_of((tmp_path / "order.zip").read_bytes())

    def sent(table, position):
        return [position(json.loads(line)) for line in members[f"data/{table}.jsonl"].splitlines()]

    assert sent("poses", lambda r: round((r["point"][0] - 7.0) * 1e4)) == [3, 1, 0, 2]
    assert sent("local_poses", lambda r: int(r["x"])) == [3, 1, 0, 2]

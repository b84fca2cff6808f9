"""What the steps of one import share: the archive, the rows met so far and the
files written, with the lookups that find a row named by a record."""

from collections import Counter, defaultdict

from django.utils.translation import gettext

from common.retries import AnotherOwner, stored_uids
from events.models import Performer, PoseSource, Segment, Vehicle
from exchange.importer.plan import ImportRefused, MalformedRecord, Plan


def fold(text) -> str:
    """A name compared ignoring case and blanks; in Python, not SQL, because
    SQLite's case folding stops at ASCII ("Müller")."""
    return " ".join((text or "").split()).casefold()


class ImportSession:
    def __init__(self, bundle, dry_run: bool):
        self.bundle = bundle
        self.dry_run = dry_run
        self.plan = Plan(dry_run=dry_run)
        self.written: list = []  # (storage, name) of files saved so far
        self.where = ""
        # Configuration rows by the archive's key (personnel by its ref).
        self.vehicles: dict[str, Vehicle] = {}
        self.pose_sources: dict[str, PoseSource] = {}
        self.performers: dict[str, Performer] = {}
        self.people: dict = {}
        # Log entries by uid: their id here (segments: the row, for its master and leg).
        self.events: dict[str, int] = {}
        self.shifts: dict[str, int] = {}
        self.legs: dict[str, int] = {}
        self.segments: dict[str, Segment] = {}
        self.masters: dict[str, Segment] = {}  # segment uid: its master (id only)
        # For the change feed: rows added or changed, and new track points per master.
        self.changed: list = []
        self.track_points: Counter = Counter()
        # Test events this archive makes final here (events.services.finality).
        self.arriving: set = set()
        # The uids of every row the archive carries, by table: its history may
        # speak only of them.
        self.carried: dict[str, set[str]] = defaultdict(set)
        # The installation that wrote the archive (its manifest); an older FTT's
        # archive or the original FTT's database does not say.
        manifest = getattr(bundle, "manifest", None) or {}
        source = manifest.get("installation") if isinstance(manifest, dict) else None
        self.source = (source if isinstance(source, str) and source.strip() else "?")[:150]

    def records(self, table: str):
        for record in self.bundle.records(table):
            self.where = f"{table} record {record.get('uid') or record.get('key') or ''}".strip()
            for name in ("uid", "key"):
                if name in record and not isinstance(record[name], str):
                    raise MalformedRecord(
                        gettext("%(where)s: its %(field)s must be a string.")
                        % {"where": self.where, "field": name}
                    )
            if "uid" in record:
                self.carried[table].add(record["uid"])
            yield record

    def refuse(self, message: str):
        raise ImportRefused(message)

    def known(self, table: str, model, uids, **owner) -> set:
        """Those of ``uids`` stored here under the same owner; a uid of another
        owner's row refuses the archive (common.retries)."""
        try:
            return stored_uids(model, uids, **owner)
        except AnotherOwner as exc:
            self.refuse(
                gettext("%(table)s record %(uid)s: %(reason)s")
                % {"table": table, "uid": exc.uid, "reason": " ".join(exc.messages)}
            )

    def stored(self, table: str, model, uid, **owner):
        """The row stored here under ``uid`` and the same owner, or None (:meth:`known`)."""
        return model.objects.get(uid=uid) if self.known(table, model, [uid], **owner) else None

    def config_row(self, cache: dict, model, key, label: str):
        """A configuration row named by a record; looked up here if the archive lacks it."""
        if key is None:
            return None
        if key not in cache:
            if model is Performer:
                row = next(
                    (p for p in Performer.objects.all() if fold(p.institution) == fold(key)),
                    None,
                )
            else:
                row = model.objects.filter(key=key).first()
            if row is None:
                self.refuse(f"{self.where}: unknown {label} '{key}'.")
            cache[key] = row
        return cache[key]

    def person_id(self, ref) -> int | None:
        if ref is None:
            return None
        if ref not in self.people:
            self.refuse(f"{self.where}: refers to person '{ref}' the archive does not list.")
        return self.people[ref].pk

    def entry_id(self, cache: dict, model, uid, label: str) -> int:
        """The id here of the log entry ``uid``, from the archive or this database."""
        if uid not in cache:
            pk = model.objects.filter(uid=uid).values_list("pk", flat=True).first()
            if pk is None:
                self.refuse(f"{self.where}: its {label} {uid} is neither in the archive nor here.")
            cache[uid] = pk
        return cache[uid]

    def segment(self, uid) -> Segment:
        """The segment ``uid`` with its id, parent and leg."""
        if uid not in self.segments:
            row = Segment.objects.only("pk", "parent_id", "leg_id").filter(uid=uid).first()
            if row is None:
                self.refuse(f"{self.where}: segment {uid} is neither in the archive nor here.")
            self.segments[uid] = row
        return self.segments[uid]

    def master(self, uid) -> Segment:
        """The master of segment ``uid`` (id only): data sent for an ITO reason is
        stored on its master, as the live services store it."""
        if uid not in self.masters:
            self.masters[uid] = Segment(pk=self.segment(uid).master_id)
        return self.masters[uid]

    def discard_files(self):
        for storage, name in self.written:
            storage.delete(name)
        self.written.clear()

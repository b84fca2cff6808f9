"""Bringing archived rows into this installation: all or nothing, and idempotent.

Rules (docs/data-exchange.md explains them for administrators):

* Log entries, notes and telemetry are matched by ``uid``.  A known uid is
  updated where the archive differs and its copy changed later than ours
  (``modified``; the later change wins, and a segment's annotation by its own
  stamp ``annotated``), otherwise left alone; an unknown one is
  added with the archive's uid, times and ordinal number.  Numbers are never
  changed: if the number is taken by another entry of the same parent the
  import is refused.
* An import never re-opens what is closed here, because an older archive of a
  still running shift must not undo the end someone recorded since.
* An open entry that would meet another open one (a second open shift of a
  vehicle, a second open leg of a shift, a second open master of a leg) is
  refused; close one of them and import again.
* Notes change only when the archive's copy was edited later than ours.
  Track points and maps never change once stored; of an image only the
  description can.
* A leg's missed fixes take the larger count.  A test case that exists here
  (test event and key) is kept; a judgement follows the later verdict.
* A history entry is added unless this installation has one of the same
  record, time and kind.
* Configuration rows are reused when they match: catalogues, vehicles and pose
  sources by key, performers by institution, personnel by name and institution
  (both ignoring case and surrounding blanks).  Otherwise they are added.
  Reused rows keep their local descriptions.

The historical rows are written directly (the services only open entries "now"),
inside one transaction, after ``full_clean`` and the checks above, which ask
the same rule functions as the services (:mod:`events.rules`, the map checks
of :func:`telemetry.services.map_images.check_map_placement`); the database
constraints stay the last guard.  Files written before a failure are removed.
What changed is announced in the change feed in the same transaction.

The modules: ``bundle`` runs the steps in one transaction and turns failures
into :class:`ImportRefused`; ``session`` holds what the steps share (the rows
met so far, lookups, files written); ``configuration``, ``logbook`` and
``plans``, ``telemetry`` and ``history`` import those kinds of rows;
``plan`` counts the outcome.
"""

from exchange.importer.bundle import import_bundle
from exchange.importer.plan import ImportRefused, MalformedRecord, Plan

__all__ = ["ImportRefused", "MalformedRecord", "Plan", "import_bundle"]

from django.core.exceptions import PermissionDenied, ValidationError
from django.db import transaction
from django.utils import timezone
from django.utils.translation import gettext as _

from common import roles
from common.retries import stored_row
from events.feed import announce_and_return, announce_row
from events.models import Note, Personnel, Segment
from events.services.finality import require_amendable, require_amendable_row

# ``by`` is the signed-in user a request acts for; None is FTT itself (imports,
# seeds, the simulator), which writes what it was given.


def _clean_text(text: str) -> str:
    if not isinstance(text, str) or not text.strip():
        # A bad value, not a state conflict: callers answer 400, not 409.
        raise ValidationError({"text": [_("A note needs some text.")]})
    return text


def _person_of(user) -> Personnel | None:
    return Personnel.objects.filter(user=user).first() if user is not None else None


def may_change_note(user, note: Note) -> bool:
    """A note is edited and deleted by its author and by administrators."""
    if roles.has_role(user, roles.ADMINISTRATOR):
        return True
    person = _person_of(user)
    return person is not None and note.author_id == person.pk


def _check_may_change(by, note: Note) -> None:
    if by is not None and not may_change_note(by, note):
        raise PermissionDenied(_("Only its author and administrators may change or delete a note."))


@transaction.atomic
def add_note(
    segment: Segment, *, text: str, author: Personnel | None = None, uid=None, by=None
) -> Note:
    """The author is the person of ``by``; only administrators name someone else."""
    if existing := stored_row(Note, uid, segment_id=segment.pk):
        return existing
    require_amendable(shifts__legs__segments=segment.pk)
    if by is not None:
        own = _person_of(by)
        if author is not None and author != own and not roles.has_role(by, roles.ADMINISTRATOR):
            raise PermissionDenied(
                _("Only administrators may write a note in someone else's name.")
            )
        author = author or own
    now = timezone.now()
    note = Note(segment=segment, author=author, text=_clean_text(text), created=now, edited=now)
    if uid is not None:
        note.uid = uid
    note.save()
    return announce_and_return(note)


@transaction.atomic
def edit_note(note: Note, *, text: str, by=None) -> Note:
    # The author stays who wrote it; the original tool re-attributed notes to
    # whoever edited them last.
    note = Note.objects.select_for_update().get(pk=note.pk)
    _check_may_change(by, note)
    require_amendable_row(note)
    note.text = _clean_text(text)
    note.edited = timezone.now()
    note.save(update_fields=["text", "edited"])
    return announce_and_return(note)


@transaction.atomic
def delete_note(note: Note, *, by=None) -> None:
    _check_may_change(by, note)
    require_amendable_row(note)
    announce_row(note, deleted=True)
    note.delete()

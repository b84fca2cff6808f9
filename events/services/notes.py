from django.core.exceptions import ValidationError
from django.db import transaction
from django.utils import timezone

from events.models import Note, Personnel, Segment
from rosbridge_app.live import announce_row, announced


def _clean_text(text: str) -> str:
    if not isinstance(text, str) or not text.strip():
        # A bad value, not a state conflict: callers answer 400, not 409.
        raise ValidationError({"text": ["A note needs some text."]})
    return text


@transaction.atomic
def add_note(segment: Segment, *, text: str, author: Personnel | None = None, uid=None) -> Note:
    if uid is not None and (existing := Note.objects.filter(uid=uid).first()):
        return existing
    now = timezone.now()
    note = Note(segment=segment, author=author, text=_clean_text(text), created=now, edited=now)
    if uid is not None:
        note.uid = uid
    note.save()
    return announced(note)


@transaction.atomic
def edit_note(note: Note, *, text: str) -> Note:
    # The author stays who wrote it; the original tool re-attributed notes to
    # whoever edited them last.
    note = Note.objects.select_for_update().get(pk=note.pk)
    note.text = _clean_text(text)
    note.edited = timezone.now()
    note.save(update_fields=["text", "edited"])
    return announced(note)


@transaction.atomic
def delete_note(note: Note) -> None:
    announce_row(note, deleted=True)
    note.delete()

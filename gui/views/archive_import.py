"""The administrators' page for bringing an FTT archive into this installation.

A preview (dry run) is shown at once. An import is checked the same way, then
queued as a job; the page lists the recent imports with their outcome, so a
reload (or coming back later) shows how it went.
"""

from django import forms
from django.core.exceptions import PermissionDenied
from django.shortcuts import redirect, render
from django.utils.translation import gettext as _
from django.utils.translation import gettext_lazy

from common import roles
from exchange.archive import ArchiveError
from exchange.importer import ImportRefused
from exchange.models import ArchiveImport
from exchange.uploads import import_upload, queue_import

RECENT = 10


class ArchiveImportForm(forms.Form):
    archive = forms.FileField(label=gettext_lazy("FTT archive (.zip)"))
    dry_run = forms.BooleanField(
        label=gettext_lazy("Only show what would change"), required=False, initial=True
    )


def archive_import(request):
    if not roles.has_role(request.user, roles.ADMINISTRATOR):
        raise PermissionDenied
    plan = error = None
    form = ArchiveImportForm(request.POST or None, request.FILES or None)
    if request.method == "POST" and form.is_valid():
        upload = form.cleaned_data["archive"]
        try:
            if form.cleaned_data["dry_run"]:
                plan = import_upload(upload, dry_run=True, by=request.user)
            else:
                queue_import(upload, user=request.user)
                # After a POST, a reload must not send the archive again.
                return redirect("gui-archive-import")
        except (ArchiveError, ImportRefused) as exc:
            error = _("Nothing was imported: %(reason)s") % {"reason": exc}
    imports = list(ArchiveImport.objects.all()[:RECENT])
    return render(
        request,
        "gui/archive_import.html",
        {
            "form": form,
            "plan": plan,
            "error": error,
            "imports": imports,
            "pending": any(not job.is_finished for job in imports),
        },
    )

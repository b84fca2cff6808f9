"""The administrators' page for bringing an FTT archive into this installation."""

from django import forms
from django.core.exceptions import PermissionDenied
from django.shortcuts import render

from common import roles
from exchange.archive import ArchiveError
from exchange.importer import ImportRefused
from exchange.uploads import import_upload


class ArchiveImportForm(forms.Form):
    archive = forms.FileField(label="FTT archive (.zip)")
    dry_run = forms.BooleanField(label="Only show what would change", required=False, initial=True)


def archive_import(request):
    if not roles.has_role(request.user, roles.ADMINISTRATOR):
        raise PermissionDenied
    plan = error = None
    form = ArchiveImportForm(request.POST or None, request.FILES or None)
    if request.method == "POST" and form.is_valid():
        try:
            plan = import_upload(form.cleaned_data["archive"], dry_run=form.cleaned_data["dry_run"])
        except (ArchiveError, ImportRefused) as exc:
            error = f"Nothing was imported: {exc}"
    return render(
        request,
        "gui/archive_import.html",
        {"form": form, "plan": plan, "error": error},
    )

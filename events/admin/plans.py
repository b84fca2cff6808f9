"""Admin pages of test plans: test cases with their criteria (events/admin/ loads it)."""

from django import forms
from django.contrib import admin
from leaflet.admin import LeafletGeoAdminMixin

from events.admin.shared import AmendmentAdmin
from events.models import Criterion, Judgement, TestCase


class CriterionForm(forms.ModelForm):
    """The model checks value and text (``Criterion.clean``); the reasons are set
    after the row is saved, so they are checked here on what the form holds."""

    def clean(self):
        data = super().clean()
        if data.get("kind") and not data.get("DELETE"):
            try:
                Criterion.check_reasons(data["kind"], data.get("reasons"))
            except forms.ValidationError as exc:
                self.add_error(None, exc)
        return data


class CriterionInline(admin.StackedInline):
    model = Criterion
    form = CriterionForm
    extra = 1
    filter_horizontal = ["reasons"]
    fields = ["kind", "value", "reasons", "text"]


@admin.register(TestCase)
class TestCaseAdmin(LeafletGeoAdminMixin, admin.ModelAdmin):
    list_display = ["key", "title", "test_event", "planned_runs"]
    list_filter = ["test_event"]
    search_fields = ["key", "title", "description"]
    fields = ["test_event", "key", "title", "description", "planned_runs", "area", "route"]
    inlines = [CriterionInline]


@admin.register(Judgement)
class JudgementAdmin(AmendmentAdmin, admin.ModelAdmin):
    list_display = ["criterion", "leg", "passed", "by", "at"]
    readonly_fields = ["by", "at"]

    def save_model(self, request, obj, form, change):
        obj.by = request.user
        super().save_model(request, obj, form, change)

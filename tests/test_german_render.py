"""Every page, the JSON the cockpit shows and the PDF report, rendered in German,
hold none of FTT's own English words (tests/support/english.py): a string never
marked for translation is caught here, not only a translation left out."""

import pytest
from django.contrib import admin
from django.core.management import call_command
from django.urls import reverse

from events.models import Note, Personnel, Segment, TestEvent
from ftt_site.admin_site import LIBRARY_APPS
from reports import formatting as fmt
from tests.support.english import english_in, json_text, page_text, without_django_words
from tests.support.pdf import flat, pdf_text
from tests.support.scenario import build_scenario

pytestmark = pytest.mark.django_db
GERMAN = {"HTTP_ACCEPT_LANGUAGE": "de"}
# What the test data names (people, places, vehicles), not FTT's words.
DATA = {"Zürich"}
# The libraries' own: django-tasks' app name "Tasks Database Backend", the alt
# text of Django admin's search icon ("Search"), a GeoJSON field's WKT ("POINT").
LIBRARIES = {"Tasks", "Database", "Backend", "Search", "POINT"}
# A catalogue's admin pages show what is stored, the text an administrator edits;
# every other page shows a seeded entry in the reader's language.
STORED = ("/admin/events/weather/", "/admin/events/itoreason/", "/admin/events/segmenttype/")


@pytest.fixture
def german_scenario(vehicle, other_vehicle, performer, media_root, settings, tmp_path):
    """The hand-checkable test event, its texts in German as a German team writes them."""
    settings.FTT_TILE_CACHE = tmp_path / "tiles"
    scenario = build_scenario(vehicle, other_vehicle, performer, text="Zürich")
    Personnel.objects.update(name="Jörg Müller")
    Note.objects.update(text="Schotter")
    TestEvent.objects.update(location="Gelände Zürich")
    scenario.event.language = "de"
    scenario.event.save(update_fields=["language"])
    return scenario


@pytest.fixture
def admin_client(client, django_user_model):
    client.force_login(django_user_model.objects.create_superuser("ada", password="pw-Xy7-long"))
    return client


def _pages(scenario) -> list[str]:
    event = scenario.event
    shift, leg = scenario.shifts[0], scenario.shifts[0].legs.first()
    pages = [
        "/",
        f"/?event={event.pk}&shift={shift.pk}&leg={leg.pk}",
        "/?view=fleet",
        "/compare/",
        "/import/",
        "/admin/",
    ]
    admin.autodiscover()  # as the URLs do (ftt_site.admin_site.FttAdminConfig)
    for model in admin.site._registry:
        if model._meta.app_label in LIBRARY_APPS | {"django_tasks_database"}:
            continue  # the libraries' own records, in their words
        if reverse(f"admin:{model._meta.app_label}_{model._meta.model_name}_changelist") in STORED:
            continue
        meta = model._meta
        pages.append(reverse(f"admin:{meta.app_label}_{meta.model_name}_changelist"))
        pages.append(reverse(f"admin:{meta.app_label}_{meta.model_name}_add"))
        row = model._default_manager.order_by("pk").first()
        if row is not None:
            pages.append(reverse(f"admin:{meta.app_label}_{meta.model_name}_change", args=[row.pk]))
    return pages


def _answers(scenario) -> list[str]:
    """The JSON reads whose words the cockpit, its dialogs and the compare page show."""
    event, shift = scenario.event, scenario.shifts[0]
    leg, master = shift.legs.first(), scenario.masters["I1"]
    return [
        "/gui/api/forms/",
        f"/gui/api/forms/?test_event={event.pk}",
        f"/gui/api/legs/{leg.pk}/segments/",
        "/gui/api/fleet/",
        f"/gui/api/collectors/?vehicle={shift.vehicle_id}&leg={leg.pk}",
        f"/gui/api/segments/{master.pk}/attachments/",
        f"/api/segments/{master.pk}/",
        f"/api/segments/{master.pk}/history/",
        f"/api/reports/test-plan/{event.pk}/",
    ]


def _found_on(client, url: str) -> list[str]:
    answer = client.get(url, **GERMAN)
    if answer.status_code == 403 and url.startswith("/admin/"):
        return []  # an admin page of rows only FTT writes (their add page)
    assert answer.status_code == 200, (url, answer.status_code)
    if answer["Content-Type"].startswith("application/json"):
        text = json_text(answer.json())
    else:
        text = without_django_words(page_text(answer.content.decode()))
    return [f"{url}: {word}" for word in english_in(text, DATA | LIBRARIES)]


def test_german_pages_and_the_cockpits_answers_hold_no_english(admin_client, german_scenario):
    urls = _pages(german_scenario) + _answers(german_scenario)
    found = [line for url in urls for line in _found_on(admin_client, url)]
    assert found == []


def test_the_catalogues_the_cockpit_shows_are_german(admin_client, german_scenario):
    """The cockpit shows a catalogue entry's ``label`` (the stored text is the
    administrator's, for the API and admin)."""
    found = []
    for url in ("/api/ito-reasons/", "/api/weather/", "/api/segment-types/"):
        rows = admin_client.get(url, **GERMAN).json()
        assert rows, url
        found += english_in(" ".join(r["label"] for r in rows))
    assert found == []
    assert {r["label"] for r in admin_client.get("/api/weather/", **GERMAN).json()} >= {
        "sonnig",
        "regnerisch",
    }


def test_the_sign_in_page_holds_no_english(client):
    assert _found_on(client, "/login/") == []


def test_a_german_report_holds_no_english(german_scenario, tmp_path):
    out = tmp_path / "report.pdf"
    call_command(
        "ftt_report", "--test-event", str(german_scenario.event.pk), "--no-tiles", "-o", str(out)
    )
    text = flat(pdf_text(out.read_bytes(), tmp_path))
    assert english_in(text, DATA) == []


def test_the_check_finds_a_string_never_marked(admin_client, german_scenario, monkeypatch):
    """A choice label left unmarked reaches the German segment dialog."""
    unmarked = ("robot", "stopped by the vehicle")
    monkeypatch.setattr(Segment, "INITIATORS", (*Segment.INITIATORS, unmarked))
    found = _found_on(admin_client, "/")
    assert any("'stopped' in …" in line for line in found), found


def test_german_figures_above_999_have_a_thousands_separator():
    with fmt.written_in("de"):
        german = fmt.metres(1227.474), fmt.decimal(12345.678, 1), fmt.number(1500.0)
    with fmt.written_in("en"):
        english = fmt.metres(1227.474)
    assert german == ("1.227,47 m", "12.345,7", "1.500")
    assert english == "1227.47 m"

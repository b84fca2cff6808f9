"""Every user-facing string of FTT has a German translation, and German is what a
German browser or account gets."""

import ast
import logging
import re
import subprocess
from pathlib import Path

import pytest
from django.conf import settings
from django.core.management import call_command
from django.utils import translation

from common.models import AccountPreference
from rosbridge_app.collector.hearing import RESUBSCRIBE, Hearing
from tests.support.typst_words import TypstWords

ROOT = Path(settings.BASE_DIR)
CATALOGUES = ROOT / "locale" / "de" / "LC_MESSAGES"
# What scripts/messages.sh leaves out, as makemessages ignore patterns.
IGNORED = [".venv", "node_modules", "data", "tests", "tmp", "benchmarks", "test-artifacts"]


@pytest.fixture(scope="module")
def fresh_catalogues(tmp_path_factory):
    """makemessages over the source into a temporary locale/, the real one untouched:
    the source folders are linked into a temporary tree, so makemessages writes
    beside them."""
    tree = tmp_path_factory.mktemp("messages")
    for entry in ROOT.iterdir():
        if entry.name not in {"locale", *IGNORED} and not entry.name.startswith("."):
            (tree / entry.name).symlink_to(entry)
    (tree / "locale").mkdir()
    mp = pytest.MonkeyPatch()
    mp.chdir(tree)
    mp.setattr(settings, "LOCALE_PATHS", [tree / "locale"])
    try:
        for domain in ("django", "djangojs"):
            call_command(
                "makemessages",
                locale=["de"],
                domain=domain,
                symlinks=True,
                ignore_patterns=[*IGNORED, "eslint.config.js"],
                verbosity=0,
            )
    finally:
        mp.undo()
    return tree / "locale" / "de" / "LC_MESSAGES"


def gettext_tool(*args) -> subprocess.CompletedProcess:
    return subprocess.run(args, capture_output=True, text=True, check=False)


@pytest.mark.parametrize("domain", ["django", "djangojs"])
def test_every_string_in_the_source_has_a_german_translation(fresh_catalogues, domain):
    committed, fresh = CATALOGUES / f"{domain}.po", fresh_catalogues / f"{domain}.po"
    assert fresh.exists(), f"makemessages found no {domain} strings"
    # msgcmp: every msgid of the source is in the catalogue, translated and not fuzzy.
    compared = gettext_tool("msgcmp", str(committed), str(fresh))
    assert compared.returncode == 0, (
        "strings without German translation (run bash scripts/messages.sh, translate, "
        f"see README 'Translations'):\n{compared.stderr}"
    )
    untranslated = gettext_tool("msgattrib", "--untranslated", "--no-obsolete", str(committed))
    assert untranslated.stdout.count("msgid ") <= 1, untranslated.stdout  # the header only
    fuzzy = gettext_tool("msgattrib", "--only-fuzzy", "--no-obsolete", str(committed))
    assert "msgid " not in fuzzy.stdout, fuzzy.stdout
    # Placeholders of each translation match the English ones.
    checked = gettext_tool("msgfmt", "--check", "-o", "/dev/null", str(committed))
    assert checked.returncode == 0, checked.stderr


@pytest.mark.django_db
def test_a_german_browser_gets_german_pages(client):
    page = client.get("/login/", HTTP_ACCEPT_LANGUAGE="de-DE,de;q=0.9,en;q=0.5")
    text = page.content.decode()
    assert '<html lang="de">' in text
    assert "Benutzername" in text and "Anmelden" in text
    english = client.get("/login/", HTTP_ACCEPT_LANGUAGE="en-GB").content.decode()
    assert "User name" in english and "Benutzername" not in english


@pytest.mark.django_db
def test_the_accounts_language_outranks_the_browser(client, django_user_model):
    user = django_user_model.objects.create_user("anna", password="pw-Xy7-long")
    client.force_login(user)
    chosen = client.post("/language/", {"language": "de", "next": "/"})
    assert chosen.status_code == 302 and chosen["Location"] == "/"
    assert AccountPreference.objects.get(user=user).language == "de"
    # Another browser that asks for English: the account's German wins after sign-in.
    client.logout()
    client.cookies.clear()
    client.force_login(user)
    page = client.get("/", HTTP_ACCEPT_LANGUAGE="en-US,en;q=0.9").content.decode()
    assert '<html lang="de">' in page and "Abmelden" in page
    refused = client.post("/language/", {"language": "xx"})
    assert refused.status_code == 400


def test_the_collectors_words_follow_the_sites_language(caplog):
    """What an operator reads from the collector (its log, its hearing text in the
    GUI) is in FTT_LANGUAGE (settings.LANGUAGE_CODE), German here."""
    with translation.override("de"), caplog.at_level(logging.WARNING):
        hearing = Hearing(0.0)
        step = hearing.check(10.0, 0, 5.0, True, lambda: ["/fix"])
    assert step == RESUBSCRIBE
    assert (
        hearing.text
        == "Roboter sendet, Collector empfängt nichts (/fix) seit 5 s: Abonnements neu angelegt"
    )
    assert hearing.text in caplog.text


@pytest.mark.django_db
def test_dialog_and_admin_labels_come_from_the_models_in_german(client, django_user_model):
    user = django_user_model.objects.create_superuser("ada", password="pw-Xy7-long")
    client.force_login(user)
    german = {"HTTP_ACCEPT_LANGUAGE": "de"}
    forms = client.get("/gui/api/forms/", **german).json()
    labels = {f["name"]: f["label"] for f in forms["event"]["fields"]}
    assert labels["time_zone"] == "Zeitzone" and labels["location"] == "Ort"
    admin = client.get("/admin/", **german).content.decode()
    assert "Testveranstaltungen" in admin and "Etappen" in admin and "Konfiguration" in admin


# Words that stay as they are in every language.
UNTRANSLATED = {"Field Test Tool", "GPS", "ITO", "AUTO", "MDBI", "MTBI"}


def _template_words(text: str) -> list[str]:
    """Words a template shows outside {% translate %} and {% blocktranslate %}."""
    text = re.sub(r"{%\s*blocktranslate.*?endblocktranslate\s*%}", "", text, flags=re.S)
    text = re.sub(r"{%.*?%}|{{.*?}}|{#.*?#}", "", text, flags=re.S)
    text = re.sub(r"<(script|style)\b.*?</\1>", "", text, flags=re.S)
    shown = re.findall(r">([^<]+)<", text)
    shown += re.findall(r'\b(?:title|aria-label|placeholder|alt)="([^"]*)"', text)
    words = [s.strip() for s in shown if re.search(r"[A-Za-z]{2}", s)]
    return [w for w in words if w not in UNTRANSLATED and not w.startswith("https://")]


def test_templates_show_no_words_outside_translate_tags():
    found = {
        str(path.relative_to(ROOT)): words
        for path in sorted((ROOT / "templates").rglob("*.html"))
        if (words := _template_words(path.read_text()))
    }
    assert found == {}


# A literal sentence handed to the page by the GUI's scripts without _().
SCRIPT_WORDS = re.compile(
    r"""(?:\.(?:textContent|title|alt|placeholder)\s*=\s*|"""
    r"""\b(?:notice|say|ApiError|confirmDialog|noTiles|setStatus)\(\s*)["'`][A-Za-z]"""
)


def test_the_gui_scripts_hand_no_untranslated_words_to_the_page():
    found = [
        f"{path.name}:{number}: {line.strip()}"
        for path in sorted((ROOT / "static" / "gui").glob("*.js"))
        for number, line in enumerate(path.read_text().splitlines(), 1)
        if SCRIPT_WORDS.search(line)
    ]
    assert found == []


# The apps of FTT whose modules a user's messages come from.
PACKAGES = [
    "basemaps",
    "common",
    "events",
    "exchange",
    "ftt_site",
    "gui",
    "reports",
    "rosbridge_app",
    "telemetry",
]
# Errors whose message a person reads: as an API or form field message, the
# command line's error, an archive's or report's refusal.
SHOWN_ERRORS = {
    "ValidationError", "RuleViolation", "NotFound", "ParseError", "CommandError",
    "ReportError", "ArchiveError", "AreaError", "BagImportError", "ExportError",
    "ImportRefused", "RecordError", "NotAGeoTiff", "TooManyWaiting",
}  # fmt: skip
GETTEXT = {"_", "gettext", "gettext_lazy", "ngettext", "ngettext_lazy", "pgettext"}


def _words_outside_gettext(node: ast.AST) -> list[ast.AST]:
    """Literal text with words in an error's message: a string, an f-string's
    text parts, or such in a dict or list of field messages."""
    if isinstance(node, ast.Dict):
        return [found for value in node.values for found in _words_outside_gettext(value)]
    if isinstance(node, ast.List | ast.Tuple):
        return [found for item in node.elts for found in _words_outside_gettext(item)]
    if isinstance(node, ast.BinOp):
        return _words_outside_gettext(node.left)
    parts = node.values if isinstance(node, ast.JoinedStr) else [node]
    text = " ".join(
        p.value for p in parts if isinstance(p, ast.Constant) and isinstance(p.value, str)
    )
    return [node] if re.search(r"[A-Za-z]{3,}", text) else []


def _untranslated_errors(source: str, name: str) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(source)):
        if not (isinstance(node, ast.Call) and node.args):
            continue
        called = getattr(node.func, "id", None) or getattr(node.func, "attr", None)
        if called in SHOWN_ERRORS:
            found += [
                f"{name}:{text.lineno}: {ast.unparse(text)[:80]}"
                for text in _words_outside_gettext(node.args[0])
            ]
    return found


def test_the_errors_a_person_reads_are_marked_for_translation():
    modules = [
        path
        for package in PACKAGES
        for path in sorted((ROOT / package).rglob("*.py"))
        if "migrations" not in path.parts
    ]
    assert len(modules) > 100
    found = [
        line
        for path in modules
        for line in _untranslated_errors(path.read_text(), str(path.relative_to(ROOT)))
    ]
    assert found == []
    # The check sees an error's words outside gettext, in a field message too.
    sample = (
        'raise CommandError(f"No leg {n}.")\n'
        'raise ValidationError({"leg": [_("No leg %(n)s.") % {"n": n}, "Give a leg."]})\n'
    )
    assert _untranslated_errors(sample, "sample.py") == [
        "sample.py:1: f'No leg {n}.'",
        "sample.py:2: 'Give a leg.'",
    ]


def test_the_report_templates_take_every_word_from_the_data():
    """The typst templates place words only from ``d.text`` (reports/documents/wording.py,
    translated): no quoted text and no markup text of their own."""
    templates = sorted((ROOT / "reports" / "templates_typst").glob("*.typ"))
    assert len(templates) == 2
    found = {path.name: TypstWords(path.read_text()).found for path in templates}
    assert found == {path.name: [] for path in templates}
    # The check sees text where a template has its own.
    assert TypstWords('#if x [Legs outside] else { text("Check with:") }').found == [
        "Check with:",
        "Legs",
        "outside",
    ]

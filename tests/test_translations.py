"""Every user-facing string of FTT has a German translation, and German is what a
German browser or account gets."""

import ast
import io
import logging
import os
import re
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest
from django.conf import settings
from django.core.management import call_command
from django.utils import translation

from common.models import AccountPreference
from rosbridge_app.collector import conversions, params
from rosbridge_app.collector.deaf_watch import RESUBSCRIBE, DeafWatch
from rosbridge_app.collector.disk_guard import DiskGuard
from tests.support.sites import APPS
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
        watch = DeafWatch(0.0)
        step = watch.check(10.0, 0, 5.0, True, lambda: ["/fix"])
    assert step == RESUBSCRIBE
    assert (
        watch.text
        == "Roboter sendet, Collector empfängt nichts (/fix) seit 5 s: Abonnements neu angelegt"
    )
    assert watch.text in caplog.text


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
PACKAGES = APPS
# Errors whose message a person reads: as an API or form field message, the
# command line's error, an archive's or report's refusal.
SHOWN_ERRORS = {
    "ValidationError", "RuleViolation", "NotFound", "ParseError", "CommandError",
    "ReportError", "ArchiveError", "AreaError", "BagImportError", "ExportError",
    "ImportRefused", "RecordError", "NotAGeoTiff", "TooManyWaiting",
    # Read on a command line, in the collector's log or the GUI's collector panel.
    "BackupError", "FetchError", "InvalidModeSources", "InvalidParameter", "LegacyError",
    "MalformedRecord", "SnapshotError", "UnsupportedImage", "SystemExit",
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


def _assigned(scope: ast.AST) -> dict[str, list[ast.AST]]:
    """What each name of ``scope`` is given: ``x = ...``, ``x[k] = ...``,
    ``x.append(...)``, ``x.update(...)``, ``x.setdefault(k, ...)``, so that a
    message built in a variable is read where it is made."""
    given: dict[str, list[ast.AST]] = {}
    for node in ast.walk(scope):
        if isinstance(node, ast.Assign | ast.AnnAssign | ast.AugAssign) and node.value:
            for target in getattr(node, "targets", None) or [node.target]:
                while isinstance(target, ast.Subscript | ast.Attribute):
                    target = target.value
                if isinstance(target, ast.Name):
                    given.setdefault(target.id, []).append(node.value)
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and isinstance(node.func.value, ast.Name)
            and node.func.attr in {"append", "extend", "update", "setdefault", "insert"}
        ):
            given.setdefault(node.func.value.id, []).extend(node.args[-1:])
    return given


def _sentence(node: ast.AST) -> bool:
    """Words for a reader, not a code ("csv", "bbox_zoom") or a value ("… UTC")."""
    parts = node.values if isinstance(node, ast.JoinedStr) else [node]
    text = "".join(p.value for p in parts if isinstance(p, ast.Constant))
    return " " in text.strip() and re.search(r"[a-z]{3,}", text) is not None


def _message_words(node: ast.AST, given: dict, seen: frozenset = frozenset()) -> list[ast.AST]:
    """Literal words in a message, and sentences in what the names it uses were given."""
    found = _words(node) if not seen else [w for w in _words(node) if _sentence(w)]
    for name in {n.id for n in ast.walk(node) if isinstance(n, ast.Name)} - seen:
        for value in given.get(name, []):
            found += _message_words(value, given, seen | {name})
    return found


def _untranslated_errors(source: str, name: str) -> list[str]:
    found = []
    tree = ast.parse(source)
    module = _assigned(ast.Module(body=[n for n in tree.body if isinstance(n, ast.Assign)]))
    scopes = [n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)]
    for scope in [tree, *scopes]:
        given = {**module, **_assigned(scope)} if scope is not tree else module
        calls = ast.walk(scope) if scope is not tree else _outside_functions(tree)
        for node in calls:
            if not (isinstance(node, ast.Call) and node.args):
                continue
            called = getattr(node.func, "id", None) or getattr(node.func, "attr", None)
            if called in SHOWN_ERRORS:
                found += [
                    f"{name}:{text.lineno}: {ast.unparse(text)[:80]}"
                    for text in _message_words(node.args[0], given)
                ]
    return sorted(set(found), key=lambda line: int(line.split(":")[1]))


def _outside_functions(tree: ast.AST):
    """The nodes of a module that no function holds."""
    todo = list(tree.body)
    while todo:
        node = todo.pop()
        if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            yield node
            todo.extend(ast.iter_child_nodes(node))


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
    # The check sees an error's words outside gettext, in a field message too,
    # and in a message built in a variable first.
    sample = (
        'raise CommandError(f"No leg {n}.")\n'
        'raise ValidationError({"leg": [_("No leg %(n)s.") % {"n": n}, "Give a leg."]})\n'
        "def check(value):\n"
        "    errors = {}\n"
        '    errors["x"] = ["Must be a finite number."]\n'
        '    message = _("Fine.") if value else "Not fine."\n'
        "    raise ValidationError(errors or message)\n"
    )
    assert _untranslated_errors(sample, "sample.py") == [
        "sample.py:1: f'No leg {n}.'",
        "sample.py:2: 'Give a leg.'",
        "sample.py:5: 'Must be a finite number.'",
        "sample.py:6: 'Not fine.'",
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


def _modules(*patterns: str) -> list[Path]:
    found = sorted({path for pattern in patterns for path in ROOT.glob(pattern)})
    assert found, patterns
    return found


def _found(paths, check) -> list[str]:
    return [
        f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)[:80]}"
        for path in paths
        for node in check(ast.parse(path.read_text()))
    ]


def _words(node) -> list[ast.AST]:
    """Literal words in ``node``; both branches of ``a if c else b``."""
    if isinstance(node, ast.IfExp):
        return _words(node.body) + _words(node.orelse)
    return _words_outside_gettext(node)


def _command_words(tree: ast.AST) -> list[ast.AST]:
    """A command's help (its own, its options'), what it writes and how it exits."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef):
            for item in node.body:
                if isinstance(item, ast.Assign) and any(
                    getattr(t, "id", None) == "help" for t in item.targets
                ):
                    found += _words(item.value)
        elif isinstance(node, ast.Call):
            found += [w for k in node.keywords if k.arg == "help" for w in _words(k.value)]
            f = node.func
            if (
                isinstance(f, ast.Attribute)
                and f.attr == "write"
                and getattr(f.value, "attr", None) in {"stdout", "stderr"}
                and node.args
            ):
                found += _words(node.args[0])
    return found


COMMANDS = "*/management/commands/ftt_*.py"


def test_the_commands_help_and_output_are_marked_for_translation():
    """Their argparse help and what they print; argparse's and Django's own words
    (usage:, --verbosity) are theirs and stay English (docs/architecture.md)."""
    assert _found(_modules(COMMANDS), _command_words) == []
    sample = ast.parse(
        'class Command:\n    help = "Make the report."\n'
        'p.add_argument("--x", help="The width.")\n'
        'self.stdout.write(f"wrote {n}")\n'
        'self.stderr.write(("Fine" if ok else _("bad")))\n'
        'p.add_argument("--y", help=_("The height."))\n'
    )
    assert sorted(ast.unparse(n) for n in _command_words(sample)) == [
        "'Fine'", "'Make the report.'", "'The width.'", "f'wrote {n}'",
    ]  # fmt: skip


# Loggers whose lines an operator reads (the collector's console, the report's tile
# source); log.debug and log.exception (with its traceback) are for engineers.
OPERATOR_LOGS = ["rosbridge_app/collector/*.py", COMMANDS, "reports/charts/tiles.py"]
READ_LEVELS = {"info", "warning", "error", "critical"}


def _log_words(tree: ast.AST) -> list[ast.AST]:
    found = []
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)):
            continue
        owner = node.func.value
        logger = getattr(owner, "id", None) in {"log", "logger"} or (
            isinstance(owner, ast.Call) and getattr(owner.func, "attr", "") == "get_logger"
        )
        if logger and node.func.attr in READ_LEVELS and node.args:
            found += _words(node.args[0])
        # A collector's answer to a command from the GUI or ROS: (ok, words).
    for node in ast.walk(tree):
        if isinstance(node, ast.Return) and isinstance(node.value, ast.Tuple):
            first, *rest = node.value.elts or [None]
            if isinstance(first, ast.Constant) and isinstance(first.value, bool) and rest:
                found += _words(rest[0])
    return found


def _parameter_words(tree: ast.AST) -> list[ast.AST]:
    """A collector parameter's description (the GUI's parameter editor shows it)."""
    return [
        found
        for node in ast.walk(tree)
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "Spec"
        for found in _words(node.args[1])
    ]


def test_the_log_lines_an_operator_reads_are_marked_for_translation():
    assert _found(_modules(*OPERATOR_LOGS), _log_words) == []
    assert _found(_modules("rosbridge_app/collector/params.py"), _parameter_words) == []
    sample = ast.parse(
        'log.warning("disk full: %s", x)\nlog.info("%s", text)\n'
        'node.get_logger().error(f"lost {n}")\nlog.exception("crash")\n'
        'def f():\n    return False, "No file."\n'
    )
    assert [ast.unparse(n) for n in _log_words(sample)] == [
        "'disk full: %s'", "f'lost {n}'", "'No file.'",
    ]  # fmt: skip


# A figure written with a decimal mark: f"{x:.2f}", f"{x:g}".
DECIMALS = re.compile(r"^(\.[1-9]\d*)?[gGeE]$|^\.[1-9]\d*[f%]$")
FIGURE_MAKERS = {"plt.subplots", "plt.figure", "add_axes", "add_subplot"}


def _chart_words(tree: ast.AST) -> list[ast.AST]:
    """Figures formatted without the report's or the command's language
    (reports.formatting, django.utils.formats.number_format), and figures made
    without the tick formatter of reports/charts/style.py."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.FormattedValue) and isinstance(node.format_spec, ast.JoinedStr):
            spec = "".join(p.value for p in node.format_spec.values if isinstance(p, ast.Constant))
            if DECIMALS.match(spec):
                found.append(node)
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            if {node.func.attr, ast.unparse(node.func)} & FIGURE_MAKERS:
                found.append(node)
    return found


def test_charts_are_written_in_the_readers_language():
    """Report figures and charts (the PDF is in the report's language) and what the
    commands print: every decimal through the language's formatting."""
    modules = [
        p
        for p in _modules("reports/charts/*.py", "reports/documents/*.py", COMMANDS)
        if p.name != "style.py"
    ]
    assert _found(modules, _chart_words) == []
    sample = ast.parse('f"{x:.2f} m"\nf"{n:.0f} m"\nf"{x:g}"\nplt.subplots(figsize=s)\n')
    assert sorted(ast.unparse(n) for n in _chart_words(sample)) == [
        "plt.subplots(figsize=s)", "{x:.2f}", "{x:g}",
    ]  # fmt: skip


# Where a background job writes its row: its step and failure are kept as words
# (common.deferred_text.deferred_fields), so that each reader gets them in their language.
JOB_WRITERS = ["reports/services/generation.py", "exchange/uploads.py", "common/jobs.py"]


KEPT = {"message", "error", "verdict"}


def _job_words(tree: ast.AST) -> list[ast.AST]:
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            found += [w for k in node.keywords if k.arg in KEPT for w in _words(k.value)]
        elif isinstance(node, ast.Assign):
            if any(getattr(t, "attr", None) in KEPT for t in node.targets):
                found += _words(node.value)
    return found


def test_job_rows_keep_words_not_sentences():
    assert _found(_modules(*JOB_WRITERS), _job_words) == []
    sample = ast.parse(
        'Report.objects.update(message="done")\nrow.error = f"failed: {e}"\n'
        'Report.objects.update(**deferred_fields("message", deferred(gettext_noop("done"))))\n'
    )
    assert sorted(ast.unparse(n) for n in _job_words(sample)) == ["'done'", "f'failed: {e}'"]


@pytest.mark.django_db
def test_commands_and_the_collector_answer_in_german(tmp_path, django_user_model):
    """What an operator reads from a command and from the collector, in German."""
    django_user_model.objects.create_user("anna", password="pw-Xy7-long")
    out = io.StringIO()
    with translation.override("de"):
        call_command("ftt_credentials", "save", str(tmp_path / "sign-ins"), stdout=out)
        with pytest.raises(params.InvalidParameter) as refused:
            params.check("snapshot.write_timeout", 0.5)
        with pytest.raises(conversions.UnsupportedImage) as image:
            conversions.compressed_image(SimpleNamespace(data=b"BM..", format="bmp"))
        disk = DiskGuard(tmp_path / "spool")
        disk.count("frames", 3)
        summary = disk.summary()
    assert out.getvalue().startswith("Anmeldedaten von 1 Konto/Konten in ")
    assert str(refused.value) == "snapshot.write_timeout muss >= 1 sein"
    assert str(image.value) == "nicht unterstütztes komprimiertes Format 'bmp'"
    assert summary == "seit -: 3 Kamerabilder verworfen"


def test_a_commands_help_is_in_the_sites_language():
    """argparse help of FTT's own options in FTT_LANGUAGE (Django's own stay English)."""
    helped = subprocess.run(
        [sys.executable, "manage.py", "ftt_report", "--help"],
        cwd=ROOT,
        env={**os.environ, "FTT_LANGUAGE": "de", "COLUMNS": "200"},
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert "Den PDF-Feldtestbericht einer Testveranstaltung erstellen" in helped
    assert "Nur diese Schicht berichten (ID)." in helped


# Answers for machines stay English: health checks and metrics for monitoring, the
# lean pose route and the original FTT's robot API for robots (README, Translations).
FOR_MACHINES = {
    "ftt_site/monitoring/health.py",
    "ftt_site/monitoring/metrics.py",
    "ftt_site/inbound/pose_route.py",
}


def _answer_words(tree: ast.AST) -> list[ast.AST]:
    """An answer's ``detail`` (API, websocket, GUI data) or a plain-text response."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            found += [
                w
                for key, value in zip(node.keys, node.values, strict=True)
                if isinstance(key, ast.Constant) and key.value == "detail"
                for w in _words(value)
            ]
        elif isinstance(node, ast.Call) and getattr(node.func, "id", None) == "HttpResponse":
            found += _words(node.args[0]) if node.args else []
    return found


def test_answers_a_person_reads_are_marked_for_translation():
    modules = [
        path
        for package in PACKAGES
        for path in sorted((ROOT / package).rglob("*.py"))
        if "migrations" not in path.parts
        and "legacy_api" not in path.parts
        and str(path.relative_to(ROOT)) not in FOR_MACHINES
    ]
    assert _found(modules, _answer_words) == []
    sample = ast.parse(
        'Response({"detail": f"Queued as job {n}."})\nHttpResponse("Sign in first.")\n'
        'send({"type": "error", "detail": gettext("Unknown message.")})\n'
    )
    assert sorted(ast.unparse(n) for n in _answer_words(sample)) == [
        "'Sign in first.'",
        "f'Queued as job {n}.'",
    ]


@pytest.mark.django_db
def test_a_language_chosen_on_the_sign_in_page_is_kept_on_the_account(client, django_user_model):
    user = django_user_model.objects.create_user("berta", password="pw-Xy7-long")
    client.get("/login/")
    client.post("/language/", {"language": "de", "next": "/login/"})
    signed_in = client.post("/login/", {"username": "berta", "password": "pw-Xy7-long"})
    assert signed_in.status_code == 302
    page = client.get("/", HTTP_ACCEPT_LANGUAGE="en-US").content.decode()
    assert '<html lang="de">' in page
    assert AccountPreference.objects.get(user=user).language == "de"
    # Another browser, in English, signs in to the account's German.
    client.logout()
    client.cookies.clear()
    client.force_login(user)
    assert '<html lang="de">' in client.get("/", HTTP_ACCEPT_LANGUAGE="en-US").content.decode()

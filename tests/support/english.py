"""FTT's own English words, to find them where a German reader reads: the words
of every msgid of the German catalogues that no German translation uses.

A word both languages write ("Status", "Name", "GPS") is no sign of English,
so a word of any msgstr is left out; what remains is a word only FTT's English
texts have, and seeing it on a German page means a string was never marked (or
is shown without its translation)."""

import functools
import gettext
import html
import re
import subprocess
import tempfile
from pathlib import Path

import django
from django.conf import settings
from django.utils import translation

CATALOGUES = Path(settings.BASE_DIR) / "locale" / "de" / "LC_MESSAGES"
# A whole word: letters between neither letters nor digits, so that a digest
# ("…b7bad09c…") in a report is no "bad".
WORD = re.compile(r"\b[^\W\d_]{3,}\b")
# Names and units that are words of English too, and the placeholders' names.
ALLOWED = {
    "husky", "jackal", "fkie", "fraunhofer", "rtk", "tokyo", "asia", "europe", "berlin",
    "utc", "png", "jpeg", "pdf", "csv", "json", "geojson", "mcap", "ros", "rosbag",
    "sqlite", "postgresql", "spatialite", "openstreetmap", "osm", "ldap", "api", "http",
    "https", "url", "uid", "uuid", "wkt", "gdal", "typst", "django", "redis", "ftt",
    "field", "test", "tool",  # "Field Test Tool", the name
    "ito", "auto", "mdbi", "mtbi", "mcbi", "gps", "local",  # the glossary's terms
}  # fmt: skip


def _catalogue(domain: str) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        mo = Path(tmp) / f"{domain}.mo"
        po = CATALOGUES / f"{domain}.po"
        subprocess.run(["msgfmt", "-o", str(mo), str(po)], check=True)
        with mo.open("rb") as f:
            return gettext.GNUTranslations(f)._catalog


# Words a German text names as a value or an option, not as German.
# Options and settings (``--leg``, ``–verify``, ``level = full``) are names too.
NAMED = re.compile(r"\w+ = [^;]*|\S*/\S+|%\(\w+\)\w|\{\w*\}|%\w|(?:--|–)[\w-]+|\w*_\w*|'\w+'")
CODES = {"unknown", "default"}


def _words(text: str) -> set[str]:
    return {w.lower() for w in WORD.findall(NAMED.sub(" ", text))}


@functools.cache
def ftt_english() -> frozenset[str]:
    english, german = set(), set()
    for domain in ("django", "djangojs"):
        for msgid, msgstr in _catalogue(domain).items():
            # A plural's key is (msgid, index); a context is "context\x04msgid".
            text = msgid[0] if isinstance(msgid, tuple) else msgid
            if text:  # not the header
                english |= _words(text.split("\x04")[-1])
                german |= _words(msgstr)
    return frozenset(english - (german - CODES) - ALLOWED)


def english_in(text: str, allowed: set[str] = frozenset()) -> list[str]:
    """The words of ``text`` (a page's or a PDF's text) that are FTT's English,
    each with a little of what surrounds it."""
    words = ftt_english() - {w.lower() for w in allowed}
    found = []
    text = NAMED.sub(lambda m: " " * len(m.group()), text)
    for match in WORD.finditer(text):
        if match.group().lower() in words:
            around = text[max(0, match.start() - 30) : match.end() + 30]
            found.append(f"{match.group()!r} in …{' '.join(around.split())}…")
    return found


def page_text(markup: str) -> str:
    """What a reader of an HTML page sees: its text and the attributes a browser
    shows (titles, labels, placeholders, options), without scripts and styles."""
    markup = re.sub(r"<(script|style)\b.*?</\1>", " ", markup, flags=re.S | re.I)
    markup = re.sub(r"<!--.*?-->", " ", markup, flags=re.S)
    # Django stores a permission's name in English when it makes it (migrate).
    markup = re.sub(
        r'<select[^>]*name="(?:user_)?permissions".*?</select>', " ", markup, flags=re.S
    )
    shown = re.findall(r'\b(?:title|aria-label|placeholder|alt)="([^"]*)"', markup)
    text = re.sub(r"<[^>]+>", " ", markup)
    return html.unescape(" ".join([text, *shown]))


# A value for programs: a code ("open", "safety_driver"), a path, a zone name.
CODE = re.compile(r"^[a-z0-9_.:-]*$|^\S*[/_]\S*$")


def json_text(value) -> str:
    """The string values of a JSON answer a page shows: its keys, and values
    written as codes (and GeoJSON's ``type``), are names for programs."""
    if isinstance(value, dict):
        return " ".join(json_text(v) for k, v in value.items() if k != "type")
    if isinstance(value, list):
        return " ".join(json_text(v) for v in value)
    return value if isinstance(value, str) and not CODE.match(value) else ""


def _msgids(po: Path) -> list[str]:
    found = re.findall(r'^msgid ((?:".*"\n)+)', po.read_text(), flags=re.M)
    return ["".join(re.findall(r'"(.*)"', block)).replace('\\"', '"') for block in found]


@functools.cache
def _django_untranslated() -> tuple[str, ...]:
    """Django's own texts its German catalogue leaves English (new in a release)."""
    found = set()
    with translation.override("de"):
        for po in Path(django.__file__).parent.rglob("locale/en/LC_MESSAGES/django.po"):
            for msgid in _msgids(po):
                if "%" not in msgid and WORD.search(msgid) and translation.gettext(msgid) == msgid:
                    found.add(msgid)
    return tuple(sorted(found, key=len, reverse=True))


def without_django_words(text: str) -> str:
    """``text`` without the sentences Django itself shows untranslated."""
    pattern = "|".join(rf"\b{re.escape(sentence)}(?!\w)" for sentence in _django_untranslated())
    return re.sub(pattern, " ", text)

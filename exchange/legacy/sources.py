"""Reading the tables of an original FTT database: live through a PostgreSQL
connection, or from its plain SQL dump (the file its "download data" button
saves), whose COPY blocks are parsed directly, so no PostgreSQL server is
needed for a dump.  Both give each table's rows as dicts ordered by id."""

import re
from pathlib import Path

import psycopg2
from django.utils.translation import gettext

# The original's tables that are read, in the order they are converted.
TABLES = (
    "weather",
    "segment_type",
    "ito_reason",
    "personnel",
    "performer",
    "vehicle",
    "pose_source",
    "test_event",
    "shift",
    "leg",
    "segment",
    "note",
    "pose",
    "local_pose",
    "map_image",
    "image",
)


class LegacyError(Exception):
    """The original database cannot be read or converted; the message says why."""


class PostgresSource:
    """A live original database; geometry arrives as hex EWKB text, bytea as bytes."""

    def __init__(self, conninfo: str):
        try:
            self.connection = psycopg2.connect(conninfo)
        except psycopg2.Error as exc:
            raise LegacyError(
                gettext("Cannot connect to the original database: %(exc)s") % {"exc": exc}
            ) from None
        self.connection.set_session(readonly=True)
        self.name = self.connection.dsn

    def rows(self, table: str) -> list[dict]:
        with self.connection.cursor() as cursor:
            try:
                cursor.execute(f'SELECT * FROM public."{table}" ORDER BY id')  # noqa: S608
            except psycopg2.Error as exc:
                raise LegacyError(
                    gettext(
                        "The database has no usable table %(table)s; is it an original FTT "
                        "database? (%(exc)s)"
                    )
                    % {"table": table, "exc": str(exc).strip()}
                ) from None
            names = [c.name for c in cursor.description]
            return [
                {
                    n: bytes(v) if isinstance(v, memoryview) else v
                    for n, v in zip(names, row, strict=True)
                }
                for row in cursor.fetchall()
            ]

    def close(self):
        self.connection.close()


_COPY = re.compile(r"^COPY (?:public\.)?\"?(\w+)\"? \(([^)]*)\) FROM stdin;$")
_ESCAPES = {"b": "\b", "f": "\f", "n": "\n", "r": "\r", "t": "\t", "v": "\v", "\\": "\\"}
_ESCAPE = re.compile(r"\\(x[0-9a-fA-F]{1,2}|[0-7]{1,3}|.)")


def _copy_value(text: str):
    if text == r"\N":
        return None
    value = _ESCAPE.sub(_unescape, text)
    if value.startswith("\\x") and re.fullmatch(r"\\x[0-9a-fA-F]*", value):
        return bytes.fromhex(value[2:])  # bytea, hex output format
    return value


def _unescape(match: re.Match) -> str:
    token = match.group(1)
    if token in _ESCAPES:
        return _ESCAPES[token]
    if token[0] == "x" and len(token) > 1:
        return chr(int(token[1:], 16))
    if token.isdigit():
        return chr(int(token, 8))
    return token


class DumpSource:
    """A plain-format ``pg_dump`` of an original database (COPY blocks)."""

    def __init__(self, path: str | Path):
        self.name = str(path)
        self.tables: dict[str, list[dict]] = {}
        try:
            with open(path, encoding="utf-8") as handle:
                self._parse(handle)
        except (OSError, UnicodeDecodeError) as exc:
            raise LegacyError(
                gettext("Cannot read %(path)s: %(exc)s") % {"path": path, "exc": exc}
            ) from None
        if "test_event" not in self.tables:
            raise LegacyError(
                gettext(
                    "%(path)s holds no COPY data for test_event: it is not a plain pg_dump of "
                    "an original FTT database (a custom-format dump must be restored with "
                    "pg_restore first and read through a connection string)."
                )
                % {"path": path}
            )

    def _parse(self, handle):
        table = columns = None
        for line in handle:
            line = line.rstrip("\n")
            if table is None:
                match = _COPY.match(line)
                if match:
                    table = match.group(1)
                    columns = [c.strip().strip('"') for c in match.group(2).split(",")]
                    self.tables[table] = []
                continue
            if line == "\\.":
                table = None
                continue
            values = [_copy_value(v) for v in line.split("\t")]
            self.tables[table].append(dict(zip(columns, values, strict=True)))

    def rows(self, table: str) -> list[dict]:
        return sorted(self.tables.get(table, []), key=lambda r: int(r["id"]))

    def close(self):
        pass


def open_source(source: str):
    """A path to an existing file is a dump; anything else a connection string."""
    if Path(source).is_file():
        return DumpSource(source)
    return PostgresSource(source)

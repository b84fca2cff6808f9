"""Taking over a database of the original FTT (fkie/field_test_tool).

``sources`` reads the original's tables (a live database or a plain dump),
``values`` converts single column values, ``bundle`` turns the tables into
archive records, which the same importer as an FTT archive brings in
(exchange.importer), with the same rules.
"""

from exchange.legacy.bundle import LegacyBundle
from exchange.legacy.sources import DumpSource, LegacyError, PostgresSource, open_source

__all__ = ["DumpSource", "LegacyBundle", "LegacyError", "PostgresSource", "open_source"]

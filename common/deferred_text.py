"""Text a row keeps for later readers (a job's step, why it failed): the English
text with its values, translated into the reader's language when read.

The text is a msgid, marked with ``gettext_noop`` where it is written, so the
catalogue has it; a value may be another ``DeferredText`` (a reason inside a sentence).
The row also keeps the English sentence itself (``message``, ``error``), for the
admin, logs and rows written before.
"""

from dataclasses import dataclass, field

from django.utils.translation import gettext


@dataclass(frozen=True)
class DeferredText:
    text: str
    values: dict = field(default_factory=dict)

    def __str__(self) -> str:
        """In the active language."""
        return self._render(gettext)

    def english(self) -> str:
        return self._render(str)

    def _render(self, translate) -> str:
        if not self.values:
            return translate(self.text)
        values = {
            k: v._render(translate) if isinstance(v, DeferredText) else v
            for k, v in self.values.items()
        }
        return translate(self.text) % values

    def as_json(self) -> dict:
        values = {
            k: v.as_json() if isinstance(v, DeferredText) else v for k, v in self.values.items()
        }
        return {"text": self.text, "values": values}

    @classmethod
    def from_json(cls, data: dict) -> "DeferredText":
        values = {
            k: cls.from_json(v) if isinstance(v, dict) and "text" in v else v
            for k, v in (data.get("values") or {}).items()
        }
        return cls(data["text"], values)


def deferred(text: str, **values) -> DeferredText:
    return DeferredText(text, values)


def deferred_fields(column: str, text: "DeferredText | str", limit: int | None = None) -> dict:
    """The fields of a job row that keep ``text`` in ``column`` (message, error, verdict):
    the English sentence and, for a ``DeferredText``, its text and values."""
    if isinstance(text, str):
        return {column: text[:limit], f"{column}_said": {}}
    return {column: text.english()[:limit], f"{column}_said": text.as_json()}


def in_reader_language(english: str, stored: dict | None) -> str:
    """What a reader sees: the kept text in the active language, else the sentence."""
    return str(DeferredText.from_json(stored)) if stored else english

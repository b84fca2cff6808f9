"""Words a row keeps for later readers (a job's step, why it failed): the English
text with its values, said in the reader's language when shown.

The text is a msgid, marked with ``gettext_noop`` where it is written, so the
catalogue has it; a value may be another ``Said`` (a reason inside a sentence).
The row also keeps the English sentence itself (``message``, ``error``), for the
admin, logs and rows written before.
"""

from dataclasses import dataclass, field

from django.utils.translation import gettext


@dataclass(frozen=True)
class Said:
    text: str
    values: dict = field(default_factory=dict)

    def __str__(self) -> str:
        """In the active language."""
        return self._said(gettext)

    def english(self) -> str:
        return self._said(str)

    def _said(self, translate) -> str:
        if not self.values:
            return translate(self.text)
        values = {
            k: v._said(translate) if isinstance(v, Said) else v for k, v in self.values.items()
        }
        return translate(self.text) % values

    def as_json(self) -> dict:
        values = {k: v.as_json() if isinstance(v, Said) else v for k, v in self.values.items()}
        return {"text": self.text, "values": values}

    @classmethod
    def from_json(cls, data: dict) -> "Said":
        values = {
            k: cls.from_json(v) if isinstance(v, dict) and "text" in v else v
            for k, v in (data.get("values") or {}).items()
        }
        return cls(data["text"], values)


def said(text: str, **values) -> Said:
    return Said(text, values)


def said_fields(column: str, words: "Said | str", limit: int | None = None) -> dict:
    """The fields of a job row that keep ``words`` in ``column`` (message, error, verdict):
    the English sentence and, for a ``Said``, its text and values."""
    if isinstance(words, str):
        return {column: words[:limit], f"{column}_said": {}}
    return {column: words.english()[:limit], f"{column}_said": words.as_json()}


def shown(english: str, kept_said: dict | None) -> str:
    """What a reader sees: the kept words in the active language, else the sentence."""
    return str(Said.from_json(kept_said)) if kept_said else english

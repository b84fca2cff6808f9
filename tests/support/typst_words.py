"""What a typst template shows by itself, for the check that every word of a
report comes translated from its data (tests/test_translations.py)."""

import re

# Quoted text a template may hold: fonts, layout words, option values,
# placeholders and the abbreviations every language keeps.
TYPST_OWN = re.compile(
    r"DejaVu Sans|WenQuanYi Micro Hei|Noto (Sans CJK \w+|Color Emoji)|a4|bold|italic|contain"
    r"|full|standard|%\(\w+\)s|(MDBI|MTBI)( 90 %)? ?"
)
IDENTIFIER = re.compile(r"[A-Za-z_][\w\-]*")


class TypstWords:
    """The words a typst template shows by itself: quoted strings with words, and
    the words of its markup, outside code and comments (enough of typst's syntax
    for FTT's templates: #expressions, #if/#for/#let/#set/#show, blocks)."""

    def __init__(self, source: str):
        self.s, self.found, self.markup = source + "\n", [], []
        end = self.parse_markup(0, closing=False)
        assert end >= len(source), end
        text = "".join(self.markup)
        self.found += re.findall(r"(?<![\w.\-])[A-Za-z]{3,}(?![\w.])", text)

    def comment(self, i: int) -> int:
        return self.s.index("\n", i) if self.s.startswith("//", i) else i

    def parse_markup(self, i: int, closing: bool) -> int:
        while i < len(self.s):
            if (j := self.comment(i)) != i:
                i = j
            elif self.s[i] == "]" and closing:
                return i + 1
            elif self.s[i] == "#":
                i = self.parse_hash(i + 1)
            else:
                self.markup.append(self.s[i])
                i += 1
        return i

    def parse_hash(self, i: int) -> int:
        name = IDENTIFIER.match(self.s, i)
        if name is None:
            return i
        i = name.end()
        if name.group() in {"if", "for", "while"}:
            i = self.parse_block(self.parse_code(i, stop="[{"))
            while more := re.compile(r"\s*else\s*(if\b)?").match(self.s, i):
                i = self.parse_code(more.end(), stop="[{") if more.group(1) else more.end()
                i = self.parse_block(i)
            return i
        if name.group() in {"let", "set", "show", "import"}:
            return self.parse_code(i, stop="\n")
        return self.parse_suffixes(i)

    def parse_suffixes(self, i: int) -> int:
        while True:
            if self.s[i] == "(":
                i = self.parse_code(i + 1, stop=")") + 1
            elif self.s[i] == "[":
                i = self.parse_markup(i + 1, closing=True)
            elif self.s[i] == "." and (name := IDENTIFIER.match(self.s, i + 1)):
                i = name.end()
            else:
                return i

    def parse_block(self, i: int) -> int:
        if self.s[i] == "[":
            return self.parse_markup(i + 1, closing=True)
        return self.parse_code(i + 1, stop="}") + 1

    def parse_code(self, i: int, stop: str) -> int:
        """Code up to (not past) the first character of ``stop`` outside brackets."""
        while self.s[i] not in stop:
            c = self.s[i]
            if (j := self.comment(i)) != i:
                i = j
            elif c == '"':
                end = re.compile(r'"(\\.|[^"\\])*"').match(self.s, i).end()
                text = self.s[i + 1 : end - 1]
                if re.search(r"[A-Za-z]{3,}", text) and not TYPST_OWN.fullmatch(text):
                    self.found.append(text)
                i = end
            elif c == "(":
                i = self.parse_code(i + 1, stop=")") + 1
            elif c == "{":
                i = self.parse_code(i + 1, stop="}") + 1
            elif c == "[":
                i = self.parse_markup(i + 1, closing=True)
            else:
                i += 1
        return i

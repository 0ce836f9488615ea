"""Notices: warnings of one line, each with a stable code and a pointer into the docs.

A :class:`Notice` says what is off about a case, with the numbers that matter, in at most
:data:`MAX_TEXT` characters; why it matters and what to do about it is in the docs section its
``docs`` names. A run keeps its notices in metrics.json's ``warnings`` as one string,
``[code] text (docs); [code] text (docs)`` (:func:`to_text`; :func:`from_text` reads it back),
and a batch shows each code once, for the first case that raised it, and counts the rest
(:class:`NoticeTally`).
"""

from __future__ import annotations

import re
import textwrap
from collections.abc import Callable, Iterable
from dataclasses import dataclass

__all__ = ["MAX_TEXT", "Notice", "NoticeTally", "from_text", "to_text"]

#: the longest text a notice may have [characters]
MAX_TEXT = 160

_CODE = re.compile(r"[a-z][a-z0-9-]*")
_DOCS = re.compile(r"docs/[A-Za-z0-9_./-]+\.md(#[a-z0-9-]+)?")
_ITEM = re.compile(r"\[([a-z][a-z0-9-]*)\] (.+) \((docs/[^\s;()]+)\)")
_SEPARATOR = "; "


@dataclass(frozen=True)
class Notice:
    """A warning about a case: ``code`` (stable, lowercase words joined by '-'), ``text`` (one
    line of at most :data:`MAX_TEXT` characters, no ';'), ``docs`` (a docs file and section,
    ``docs/models/interface.md#rear-meniscus-cells``)."""

    code: str
    text: str
    docs: str

    def __post_init__(self) -> None:
        if not _CODE.fullmatch(self.code):
            raise ValueError(f"notice code {self.code!r}: lowercase letters, digits and '-'")
        if len(self.text) > MAX_TEXT or "\n" in self.text or ";" in self.text:
            raise ValueError(f"notice {self.code}: its text must be one line of at most "
                             f"{MAX_TEXT} characters without ';' ({len(self.text)}: "
                             f"{self.text!r})")
        if not _DOCS.fullmatch(self.docs):
            raise ValueError(f"notice {self.code}: docs = {self.docs!r} is not a docs pointer "
                             "(docs/FILE.md or docs/FILE.md#section)")

    def __str__(self) -> str:
        return f"[{self.code}] {self.text} ({self.docs})"


def to_text(notices: Iterable[Notice]) -> str:
    """The notices as metrics.json keeps them: ``[code] text (docs)`` joined by '; ' ('' for
    none)."""
    return _SEPARATOR.join(str(n) for n in notices)


def from_text(text: str | None) -> list[Notice]:
    """The notices of a :func:`to_text` string (None or '' for none). Raises ValueError for
    text of another form (metrics.json written before warnings were notices)."""
    if not text:
        return []
    out = []
    for item in text.split(_SEPARATOR):
        m = _ITEM.fullmatch(item)
        if m is None:
            raise ValueError(f"not a notice: {item[:80]!r}")
        out.append(Notice(m[1], m[2], m[3]))
    return out


class NoticeTally:
    """A batch's notices: each code shown once, through ``emit``, for the first case that
    raised it; :meth:`summary` counts the cases per code."""

    def __init__(self, emit: Callable[[str], None]):
        self.emit = emit
        self.cases: dict[str, int] = {}

    def add(self, case: str, warnings: str | None) -> None:
        """The notices of ``case`` (its metrics.json ``warnings``): a line for each code not
        seen before in this batch."""
        try:
            found = [(n.code, str(n)) for n in from_text(warnings)]
        except ValueError:      # paragraph-long warnings of an older run: shortened
            found = [("unparsed", textwrap.shorten(warnings or "", MAX_TEXT))]
        for code, line in found:
            if code not in self.cases:
                self.emit(f"warning  {case}: {line}")
            self.cases[code] = self.cases.get(code, 0) + 1

    def summary(self) -> str | None:
        """One line: each code and how many cases raised it (None without notices)."""
        if not self.cases:
            return None
        counts = ", ".join(f"[{code}] {n} case{'s' if n > 1 else ''}"
                           for code, n in self.cases.items())
        return f"warnings {counts} (each case's metrics.json lists its own)"

"""A griffe extension for the API reference: a Markdown list that follows a line of text
directly (`**Arguments:**` then `- x: ...`, as fwid's docstrings write it) gets the blank
line before it that Python-Markdown needs to see a list. The docstrings are not changed."""

from __future__ import annotations

import re

import griffe

_ITEM = re.compile(r"^\s*(?:[-*+]|\d+\.)\s")


def blank_line_before_lists(text: str) -> str:
    """`text` with a blank line inserted where a list item follows a line that is neither
    blank nor a list item nor its continuation, outside code fences."""
    out: list[str] = []
    fenced = False
    in_list = False
    for line in text.split("\n"):
        if line.lstrip().startswith("```"):
            fenced = not fenced
        if not fenced and _ITEM.match(line):
            if out and out[-1].strip() and not in_list:
                out.append("")
            in_list = True
        elif not line.strip():
            in_list = False
        elif in_list and not line.startswith((" ", "\t")):
            in_list = False
        out.append(line)
    return "\n".join(out)


class BlankLineBeforeLists(griffe.Extension):
    """Apply `blank_line_before_lists` to every docstring griffe loads."""

    def on_object(self, *, obj, **kwargs) -> None:
        if obj.docstring is not None:
            obj.docstring.value = blank_line_before_lists(obj.docstring.value)

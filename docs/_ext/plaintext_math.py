"""Read the house's plain-text equations in docstrings as text, not as reStructuredText markup.

Our docstrings state their equations in plain text (DESIGN.md: "Every algorithm's docstring states its equations
in plain text"), and Sphinx reads a docstring as reStructuredText, where three habits of that text are errors under
``-W``: ``|x|`` (an absolute value, a determinant) is a substitution reference, ``y_+`` (a subscript) a hyperlink
reference, and ``Track``s (the plural of a literal) an unterminated literal. No docstring of sonartrack uses
substitutions or ``name_`` references, so before numpydoc reads a docstring this extension escapes ``|`` and a
word-ending ``_``, and joins a literal's plural "s" with an escaped space, outside inline literals, roles and
literal blocks. And it sets an indented block after a blank line (a block quote, where the text's equations and
aligned tables sit) as a literal block, so that their columns keep their alignment. Every other markup problem
is still an error.
"""

from __future__ import annotations

import re

# an inline literal, a role or an interpreted text: left as written
_CODE = re.compile(r"``.*?``|(:[\w:+-]+:)?`[^`]*`_{0,2}")
# a word character then "_" ending the word ("y_+", "beta_ "): a reference in RST, a subscript here
_REFERENCE_END = re.compile(r"(?<=[A-Za-z0-9])_(?![\w`])")
_DIRECTIVE = re.compile(r"^\s*\.\. [\w:-]+::")
# a border of a simple table ("=====  ====="): its rows are left as written (an escape would shift the columns)
_TABLE_BORDER = re.compile(r"^\s*=+( +=+)+\s*$")


def _escape_text(text: str) -> str:
    """Escape ``|`` and a word-ending ``_`` in text that holds no inline literal."""
    return _REFERENCE_END.sub(r"\\_", text.replace("|", r"\|"))


def escape_line(line: str) -> str:
    """One line of prose with its plain-text ``|`` and ``x_`` escaped (its literals and roles kept)."""
    stripped = line.lstrip()
    if stripped.startswith(("| ", "+-", "+=", ">>>")) or stripped == "|":  # a line block, a grid table, a doctest
        return line
    out, last = [], 0
    for match in _CODE.finditer(line):
        out.append(_escape_text(line[last:match.start()]))
        out.append(match.group(0))
        last = match.end()
        if line[last:last + 1].isalnum():  # ``Detection``s: the plural of a literal, joined by an escaped space
            out.append("\\ ")
    out.append(_escape_text(line[last:]))
    return "".join(out)


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


# the first line of a paragraph whose indented continuation is not an equation: a list item, a field, a
# directive, a comment, a numpydoc "name : type" line
_NOT_PROSE = re.compile(r"^\s*([-*+] |\d+[.)] |#\. |\(\w+\) |:\w|\.\. |[\w*, ]+ : )")


def _text_indent(line: str) -> int:
    """Where the text of a paragraph's first line starts (after a bullet or an enumerator)."""
    match = re.match(r"^\s*([-*+]|\d+[.)]|#\.)\s+", line)
    return match.end() if match else _indent(line)


def preformat_equations(lines: list[str]) -> None:
    """Turn each indented block after a blank line (a block quote in RST) into a literal block, in place.

    In our docstrings such a block is a plain-text equation or table whose columns line up: set in monospace
    it keeps them. The paragraph before it gains "::" (shown as ":" after a colon, else not shown)."""
    i, n = 0, len(lines)
    while i < n:
        first = i  # a paragraph: lines[first:i], then blank lines, then maybe a deeper block
        while i < n and lines[i].strip():
            i += 1
        last = i - 1
        while i < n and not lines[i].strip():
            i += 1
        if first > last or i >= n or i == last + 1:
            continue
        para = lines[first]
        if _indent(lines[i]) <= _text_indent(para) or _NOT_PROSE.match(para) or lines[last].rstrip().endswith("::"):
            continue
        end = lines[last].rstrip()
        lines[last] = end + (":" if end.endswith(":") else " ::")
        base = _text_indent(para)
        while i < n and (not lines[i].strip() or _indent(lines[i]) > base):
            i += 1


def escape_docstring(lines: list[str]) -> None:
    """Escape the plain-text equations of a docstring's lines in place, skipping literal blocks."""
    preformat_equations(lines)
    block_indent = None  # the indent of the paragraph that opened a literal block, while inside it
    opener = None  # the indent of a line ending with "::" (or a directive), waiting for its block
    in_table = after_border = False  # a simple table runs from a border to the blank line after a border
    for i, line in enumerate(lines):
        if _TABLE_BORDER.match(line):
            in_table = after_border = True
            continue
        if not line.strip():
            in_table = in_table and not after_border
            continue
        after_border = False
        if in_table:
            continue
        if block_indent is not None:
            if _indent(line) > block_indent:
                continue
            block_indent = None
        if opener is not None:
            if _indent(line) > opener:
                block_indent = opener
                opener = None
                continue
            opener = None
        if line.rstrip().endswith("::") or _DIRECTIVE.match(line):
            opener = _indent(line)
            if _DIRECTIVE.match(line):
                continue
        lines[i] = escape_line(line)


def _on_docstring(app, what, name, obj, options, lines) -> None:  # noqa: ARG001 (Sphinx's signature)
    escape_docstring(lines)


def setup(app):
    app.connect("autodoc-process-docstring", _on_docstring, priority=100)  # before numpydoc (500)
    return {"parallel_read_safe": True, "parallel_write_safe": True}

"""HTML building blocks of the evidence page: escaping, tables, values, inline PNGs and a markdown subset.

Everything here returns HTML text; nothing reads files except through the image resolver the caller
passes to :func:`markdown_html`.  Deterministic: values are formatted the same way on every run.
"""
from __future__ import annotations

import base64
import html
import json
import re
from collections.abc import Callable, Iterable, Mapping, Sequence

__all__ = ["esc", "value_text", "cell", "table", "png_data_uri", "figure", "flatten", "markdown_html", "BAD"]

#: CSS class of a value that needs attention (rendered red)
BAD = "bad"
#: longest compact-JSON text shown in one cell
_MAX_CELL_CHARS = 400
_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def esc(text: object) -> str:
    """``text`` escaped for HTML element content and attribute values."""
    return html.escape(str(text), quote=True)


def value_text(value: object) -> str:
    """A JSON value as plain text: floats to 6 significant digits, containers as compact JSON (shortened)."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, (int, str)):
        return str(value)
    if isinstance(value, Mapping) and value and all(isinstance(v, (int, float, str)) for v in value.values()):
        text = ", ".join(f"{k}: {value_text(value[k])}" for k in sorted(value))
        return text if len(text) <= _MAX_CELL_CHARS else text[:_MAX_CELL_CHARS - 3] + "..."
    text = json.dumps(value, sort_keys=True, separators=(", ", ": "))
    return text if len(text) <= _MAX_CELL_CHARS else text[:_MAX_CELL_CHARS - 3] + "..."


def cell(value: object, bad: bool = False, tag: str = "td") -> str:
    """One table cell holding ``value`` (escaped); ``bad``: marked red."""
    attr = f' class="{BAD}"' if bad else ""
    return f"<{tag}{attr}>{esc(value_text(value))}</{tag}>"


def table(header: Sequence[str], rows: Iterable[Sequence[str]]) -> str:
    """A table: ``header`` is plain text (escaped here), each row a sequence of cells from :func:`cell`."""
    head = "".join(f"<th>{esc(h)}</th>" for h in header)
    body = "\n".join(f"<tr>{''.join(r)}</tr>" for r in rows)
    return f"<table>\n<thead><tr>{head}</tr></thead>\n<tbody>\n{body}\n</tbody>\n</table>"


def png_data_uri(data: bytes) -> str | None:
    """``data:image/png;base64,...`` for PNG bytes; None when ``data`` is not a PNG."""
    if not data.startswith(_PNG_SIGNATURE):
        return None
    return "data:image/png;base64," + base64.b64encode(data).decode("ascii")


def figure(uri: str, alt: str, caption: str) -> str:
    """An inline image with its caption (both plain text)."""
    return (f'<figure><img src="{uri}" alt="{esc(alt)}">'
            f"<figcaption>{esc(caption)}</figcaption></figure>")


def flatten(data: Mapping[str, object], skip: Iterable[str] = (), prefix: str = "") -> list[tuple[str, object]]:
    """The leaves of nested dicts as (dotted key, value), keys sorted; lists stay whole; ``skip``: top keys."""
    left_out = set(skip)
    out: list[tuple[str, object]] = []
    for key in sorted(data):
        if key in left_out:
            continue
        value = data[key]
        name = f"{prefix}{key}"
        if isinstance(value, Mapping) and value:
            out.extend(flatten(value, prefix=f"{name}."))
        else:
            out.append((name, value))
    return out


# ---------------------------------------------------------------- markdown subset
#: an image on a line of its own
_IMAGE = re.compile(r"^!\[([^\]]*)\]\(([^)\s]+)\)$")
_HEADING = re.compile(r"^(#{1,6})\s+(.*)$")
_TABLE_RULE = re.compile(r"^\|?\s*:?-{3,}:?\s*(\|\s*:?-{3,}:?\s*)*\|?$")


def _inline(text: str) -> str:
    """Escaped text with ``code`` and **strong** spans."""
    parts = re.split(r"(`[^`]*`)", text)
    out = []
    for part in parts:
        if len(part) >= 2 and part.startswith("`") and part.endswith("`"):
            out.append(f"<code>{esc(part[1:-1])}</code>")
        else:
            out.append(re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", esc(part)))
    return "".join(out)


def _cells(line: str) -> list[str]:
    """The cells of a markdown table row (``\\|`` is a literal bar)."""
    body = line.strip()
    body = body[1:] if body.startswith("|") else body
    body = body[:-1] if body.endswith("|") and not body.endswith("\\|") else body
    return [c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", body)]


def _md_table(lines: list[str]) -> str:
    header = "".join(f"<th>{_inline(c)}</th>" for c in _cells(lines[0]))
    rows = "\n".join("<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in _cells(r)) + "</tr>" for r in lines[2:])
    return f"<table>\n<thead><tr>{header}</tr></thead>\n<tbody>\n{rows}\n</tbody>\n</table>"


def markdown_html(text: str, image: Callable[[str, str], str], heading_shift: int = 2) -> str:
    """HTML of the markdown subset the reports write: headings (shifted down ``heading_shift`` levels),
    paragraphs, ``-`` lists, pipe tables, fenced code and images on their own line (``image(src, alt)``
    returns the HTML for one)."""
    lines = text.splitlines()
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i].strip()
        if not line:
            i += 1
        elif line.startswith("```"):
            j = i + 1
            while j < len(lines) and not lines[j].strip().startswith("```"):
                j += 1
            out.append("<pre>" + esc("\n".join(lines[i + 1:j])) + "</pre>")
            i = j + 1
        elif m := _HEADING.match(line):
            level = min(len(m.group(1)) + heading_shift, 6)
            out.append(f"<h{level}>{_inline(m.group(2))}</h{level}>")
            i += 1
        elif m := _IMAGE.match(line):
            out.append(image(m.group(2), m.group(1)))
            i += 1
        elif line.startswith("|") and i + 1 < len(lines) and _TABLE_RULE.match(lines[i + 1].strip()):
            j = i + 2
            while j < len(lines) and lines[j].lstrip().startswith("|"):
                j += 1
            out.append(_md_table(lines[i:j]))
            i = j
        elif line.startswith(("- ", "* ")):
            items = []
            while i < len(lines) and lines[i].lstrip().startswith(("- ", "* ")):
                items.append(f"<li>{_inline(lines[i].lstrip()[2:])}</li>")
                i += 1
            out.append("<ul>\n" + "\n".join(items) + "\n</ul>")
        else:
            para = [line]  # the first line starts no other block (the branches above)
            i += 1
            while i < len(lines) and lines[i].strip() and not _starts_block(lines[i], lines, i):
                para.append(lines[i].strip())
                i += 1
            out.append(f"<p>{_inline(' '.join(para))}</p>")
    return "\n".join(out)


def _starts_block(line: str, lines: list[str], i: int) -> bool:
    """Whether ``line`` (at index ``i``) starts a block other than a paragraph."""
    stripped = line.strip()
    if stripped.startswith(("```", "- ", "* ")) or _HEADING.match(stripped) or _IMAGE.match(stripped):
        return True
    return stripped.startswith("|") and i + 1 < len(lines) and bool(_TABLE_RULE.match(lines[i + 1].strip()))

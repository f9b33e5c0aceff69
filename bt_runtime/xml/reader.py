"""Safe, lenient XML reading: what tinyxml2 (BT.CPP's parser) accepts, nothing dangerous.

* Safe: lxml with entity resolution, DTD loading and network access off; any DOCTYPE or
  ENTITY declaration is refused outright (no billion laughs), and so are files over
  ``MAX_XML_BYTES``.
* Lenient like tinyxml2: a raw ``<`` or an ``&`` that does not start an entity is accepted
  inside attribute values (``_skipIf="A<2"``, ``code="a && b"``), and literal newlines and
  tabs in attribute values are kept (a conforming parser would turn them into spaces). Only
  start tags are rewritten, and only when needed; line numbers in errors and on elements are
  mapped back to the original text.
"""

from __future__ import annotations

import bisect
import re
import stat
from dataclasses import dataclass, field
from pathlib import Path

from lxml import etree

from ..errors import XMLLoadError

MAX_XML_BYTES = 16 * 1024 * 1024

_START_TAG = re.compile(r"""<[A-Za-z_:][-\w:.]*(?:\s+[^\s=/>]+\s*=\s*(?:"[^"]*"|'[^']*'))*\s*/?>""")
_ATTR_VALUE = re.compile(r"""=(\s*)("[^"]*"|'[^']*')""")
_VALID_ENTITY = re.compile(r"&(?:amp|lt|gt|quot|apos|#[0-9]+|#x[0-9a-fA-F]+);")
# An attribute value holding a character tinyxml2 tolerates and libxml2 does not: '<', an '&' that
# starts no entity ('a && b'), or a newline/tab/CR (kept, where XML would turn it into a space).
# A value whose only '&'s start entities ('x &gt; 0', common in scripts) needs nothing. Possessive
# (no backtracking), so it also serves as the pre-check on the whole text.
_OK_ENTITY = r"&(?:amp|lt|gt|quot|apos|#[0-9]++|#x[0-9a-fA-F]++);"
_NEEDS_FIX = re.compile(rf"""=\s*+(?:"(?:[^"<&\n\t\r]++|{_OK_ENTITY})*+[<&\n\t\r]"""
                        rf"""|'(?:[^'<&\n\t\r]++|{_OK_ENTITY})*+[<&\n\t\r])""")
_MAY_NEED_FIX = _NEEDS_FIX
_DECLARATION = re.compile(r"^\ufeff?\s*<\?xml[^>]*\?>")
_DTD = re.compile(r"<!(DOCTYPE|ENTITY)", re.IGNORECASE)


@dataclass
class XMLDocument:
    """A parsed document: its root element, where it came from, and a line-number map."""

    root: etree._Element
    file: str | None
    text: str
    _line_starts: list[int] = field(default_factory=list)  # processed line numbers of fixed tags
    _line_removed: list[int] = field(default_factory=list)  # cumulative newlines removed by then

    _line_offsets: list[int] = field(default_factory=list, repr=False)  # start of each original line

    def line_of(self, element: etree._Element) -> int | None:
        """The line in the original text where the element's start tag begins."""
        return self.line_at(element.tag, element.sourceline)

    def line_at(self, tag: object, sourceline: int | None) -> int | None:
        """``line_of`` from an element's tag and lxml ``sourceline`` (what nodes keep)."""
        if sourceline is None:
            return None
        return self._tag_start_line(tag, self.original_line(sourceline))

    def _tag_start_line(self, tag: object, end_line: int) -> int:
        """libxml2 numbers an element by the line where its start tag *ends*; walk back to the
        line of its ``<tag`` (tinyxml2 and people count from there)."""
        if not isinstance(tag, str):
            return end_line
        offsets = self._line_offsets
        if not offsets:
            offsets.append(0)
            offsets.extend(m.end() for m in re.finditer("\n", self.text))
        if end_line > len(offsets):
            return end_line
        end = offsets[end_line] if end_line < len(offsets) else len(self.text)
        pos = self.text.rfind("<" + tag, 0, end)  # usually found on that very line
        while pos >= 0:
            after = self.text[pos + 1 + len(tag):pos + 2 + len(tag)]
            if after == "" or after.isspace() or after in "/>":
                return bisect.bisect_right(offsets, pos)
            pos = self.text.rfind("<" + tag, 0, pos)
        return end_line

    def original_line(self, processed_line: int) -> int:
        idx = bisect.bisect_left(self._line_starts, processed_line) - 1
        return processed_line + (self._line_removed[idx] if idx >= 0 else 0)

    @property
    def directory(self) -> Path:
        return Path(self.file).resolve().parent if self.file else Path.cwd()


def _fix_attribute_value(quoted: str) -> str:
    quote, body = quoted[0], quoted[1:-1]
    out = []
    pos = 0
    for m in re.finditer(r"[<&\r\n\t]", body):
        out.append(body[pos:m.start()])
        ch = m.group(0)
        if ch == "<":
            out.append("&lt;")
        elif ch == "&":
            out.append("&" if _VALID_ENTITY.match(body, m.start()) else "&amp;")
        elif ch == "\r":
            out.append("" if body[m.end():m.end() + 1] == "\n" else "&#10;")
        elif ch == "\n":
            out.append("&#10;")
        else:
            out.append("&#9;")
        pos = m.end()
    out.append(body[pos:])
    return quote + "".join(out) + quote


def _make_lenient(text: str) -> tuple[str, list[int], list[int]]:
    """Escape what tinyxml2 tolerates inside attribute values, tracking removed newlines."""
    starts: list[int] = []
    removed: list[int] = []
    state = {"removed": 0, "orig_line": 1, "orig_pos": 0}

    def fix_tag(m: re.Match[str]) -> str:
        tag = m.group(0)
        if not _NEEDS_FIX.search(tag):
            return tag
        state["orig_line"] += text.count("\n", state["orig_pos"], m.start())
        state["orig_pos"] = m.start()
        fixed = _ATTR_VALUE.sub(lambda a: "=" + a.group(1) + _fix_attribute_value(a.group(2)), tag)
        lost = tag.count("\n") - fixed.count("\n")
        if lost:
            state["removed"] += lost
            end_processed_line = (state["orig_line"] + tag.count("\n")) - state["removed"]
            starts.append(end_processed_line)
            removed.append(state["removed"])
        return fixed

    return _START_TAG.sub(fix_tag, text), starts, removed


def read_limited(path: str | Path, limit: int = MAX_XML_BYTES) -> bytes:
    """A regular file's bytes, at most ``limit`` of them: a FIFO, a device (``/dev/zero``) or a
    directory is refused before reading, and so is a file that turns out longer than ``limit``."""
    p = Path(path)
    try:
        info = p.stat()
        if not stat.S_ISREG(info.st_mode):
            raise XMLLoadError("Not a regular file (a FIFO, device or directory); refused", file=str(path))
        if info.st_size > limit:
            raise XMLLoadError(f"File too large ({info.st_size} bytes, limit {limit}); refused", file=str(path))
        with p.open("rb") as handle:
            raw = handle.read(limit + 1)
    except OSError as exc:
        raise XMLLoadError(f"Cannot read the file: {exc.strerror or exc}", file=str(path)) from None
    if len(raw) > limit:  # grew since stat
        raise XMLLoadError(f"File too large (over {limit} bytes); refused", file=str(path))
    return raw


def read_xml_file(path: str | Path) -> XMLDocument:
    raw = read_limited(path)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise XMLLoadError(f"The file is not valid UTF-8 ({exc.reason} at byte {exc.start})",
                           file=str(path)) from None
    return parse_xml_text(text, file=str(path))


def parse_xml_text(text: str | bytes, file: str | None = None) -> XMLDocument:
    """Parse BT.CPP tree XML safely and leniently. Raises XMLLoadError with file and line."""
    if isinstance(text, bytes):
        if len(text) > MAX_XML_BYTES:
            raise XMLLoadError(f"XML too large ({len(text)} bytes, limit {MAX_XML_BYTES}); refused", file=file)
        try:
            text = text.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise XMLLoadError(f"The XML is not valid UTF-8 ({exc.reason} at byte {exc.start})",
                               file=file) from None
    if len(text) > MAX_XML_BYTES:
        raise XMLLoadError(f"XML too large ({len(text)} characters, limit {MAX_XML_BYTES}); refused",
                           file=file)
    dtd = _DTD.search(text) if "<!" in text else None
    if dtd:
        line = text.count("\n", 0, dtd.start()) + 1
        raise XMLLoadError("DOCTYPE and ENTITY declarations are not allowed in tree files", file=file,
                           line=line)
    decl = _DECLARATION.match(text)
    if decl:
        text = "\n" * decl.group(0).count("\n") + text[decl.end():]
    if not text or text.isspace():  # (not text.strip(): no copy of the text)
        raise XMLLoadError("Error parsing the XML: empty document", file=file, line=1)
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False, dtd_validation=False,
                             huge_tree=False, remove_comments=True, remove_pis=True)
    if "\n" not in text and "\t" not in text and "\r" not in text:
        # One line: no attribute value holds a newline or tab, which a parser would quietly turn
        # into a space; a '<' or a bare '&' in one fails the parse. So parse first, and look
        # for values to escape only if it fails (the search costs ~0.1 us per attribute).
        try:
            return XMLDocument(etree.fromstring(text.encode("utf-8"), parser), file, text, [], [])
        except etree.XMLSyntaxError:
            pass
    if _MAY_NEED_FIX.search(text) is None:  # no attribute value anywhere needs escaping
        fixed, starts, removed = text, [], []
    else:
        fixed, starts, removed = _make_lenient(text)
    try:
        root = etree.fromstring(fixed.encode("utf-8"), parser)
    except etree.XMLSyntaxError as exc:
        doc = XMLDocument(etree.Element("root"), file, text, starts, removed)
        line = doc.original_line(exc.lineno) if exc.lineno else None
        raise XMLLoadError(f"Error parsing the XML: {exc.msg}", file=file, line=line) from None
    return XMLDocument(root, file, text, starts, removed)


def element_children(element: etree._Element) -> list[etree._Element]:
    """Child elements, ignoring comments and processing instructions."""
    children = element[:]  # one call: iterating the element costs a microsecond per child
    if not children:
        return children
    return [c for c in children if type(c) is ELEMENT or isinstance(c.tag, str)]


ELEMENT = etree._Element  # what a plain parsed element is (comments and PIs are subclasses)

"""Node models for Groot2's editor: the ``<TreeNodesModel>`` XML of registered node types.

* ``models_xml(factory)`` is BT.CPP's ``writeTreeNodesModelXML``: every node type the factory
  knows, sorted by ID, builtins only with ``include_builtin``.
* ``embed_models(path, factory)`` adds or refreshes the ``<TreeNodesModel>`` section of a tree
  file **in place**, splicing text: every byte outside that section (comments, order,
  formatting, quoting, line endings) is kept as it was.

What ``embed_models`` puts in the section:

* a freshly generated entry for every node type *used in the file's* ``<BehaviorTree>``
  elements that the factory knows and that is not a builtin (builtins too with
  ``include_builtin``); Groot2 already knows the builtins;
* every entry already in the section that is not regenerated, kept verbatim: ``<SubTree ID>``
  entries (BT.CPP reads their port declarations and defaults at load time, and they cannot be
  derived from the factory) and entries for node types the factory does not know (e.g. Nav2
  nodes implemented elsewhere). ``prune=True`` drops the kept entries whose ID is not used
  in the file (SubTree entries are dropped only when no ``<SubTree ID>`` of the file uses them).

Entries are sorted by ID. Node types used only in ``<include>``d files are not added: embed the
models into each included file. Running it twice changes nothing the second time.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from bt_runtime.xml.writer import model_element, render, write_tree_nodes_model_xml

if TYPE_CHECKING:
    from bt_runtime.factory import BehaviorTreeFactory

EXPLICIT_TAGS = ("Action", "Condition", "Control", "Decorator")


def models_xml(factory: BehaviorTreeFactory, include_builtin: bool = False) -> str:
    """``<root BTCPP_format="4"><TreeNodesModel>...`` for every registered node type."""
    return write_tree_nodes_model_xml(factory.manifests, include_builtin)


# ---------------------------------------------------------------------------------------------
# A lenient XML tokenizer that reports character offsets (for the text-level splice)
# ---------------------------------------------------------------------------------------------

_NAME_RE = re.compile(r"[^\s/>=]+")


@dataclass
class Tag:
    kind: str  # "start", "end" or "empty" (self-closing)
    name: str
    start: int  # offset of '<'
    end: int  # offset just after '>'
    attrs: dict[str, str] = field(default_factory=dict)


class XMLScanError(ValueError):
    pass


def scan_tags(text: str) -> list[Tag]:
    """Start/end/empty tags with their offsets; comments, CDATA, PIs and DOCTYPEs skipped.

    As lenient as tinyxml2 about ``<`` and ``&`` inside attribute values.
    """
    tags: list[Tag] = []
    i = 0
    n = len(text)
    while True:
        i = text.find("<", i)
        if i < 0:
            return tags
        if text.startswith("<!--", i):
            j = text.find("-->", i + 4)
            if j < 0:
                raise XMLScanError(f"unterminated comment at offset {i}")
            i = j + 3
            continue
        if text.startswith("<![CDATA[", i):
            j = text.find("]]>", i)
            if j < 0:
                raise XMLScanError(f"unterminated CDATA at offset {i}")
            i = j + 3
            continue
        if text.startswith("<?", i):
            j = text.find("?>", i + 2)
            if j < 0:
                raise XMLScanError(f"unterminated processing instruction at offset {i}")
            i = j + 2
            continue
        if text.startswith("<!", i):
            j = text.find(">", i)
            if j < 0:
                raise XMLScanError(f"unterminated declaration at offset {i}")
            i = j + 1
            continue
        if text.startswith("</", i):
            m = _NAME_RE.match(text, i + 2)
            j = text.find(">", i)
            if not m or j < 0:
                raise XMLScanError(f"malformed end tag at offset {i}")
            tags.append(Tag("end", m.group(0), i, j + 1))
            i = j + 1
            continue
        m = _NAME_RE.match(text, i + 1)
        if not m:
            raise XMLScanError(f"malformed tag at offset {i}")
        name = m.group(0)
        j = m.end()
        attrs: dict[str, str] = {}
        while True:
            while j < n and text[j].isspace():
                j += 1
            if j >= n:
                raise XMLScanError(f"unterminated tag <{name}> at offset {i}")
            if text.startswith("/>", j):
                tags.append(Tag("empty", name, i, j + 2, attrs))
                j += 2
                break
            if text[j] == ">":
                tags.append(Tag("start", name, i, j + 1, attrs))
                j += 1
                break
            am = _NAME_RE.match(text, j)
            if not am:
                raise XMLScanError(f"malformed attribute in <{name}> at offset {j}")
            j = am.end()
            while j < n and text[j].isspace():
                j += 1
            if j >= n or text[j] != "=":
                raise XMLScanError(f"attribute without value in <{name}> at offset {j}")
            j += 1
            while j < n and text[j].isspace():
                j += 1
            if j >= n or text[j] not in "\"'":
                raise XMLScanError(f"unquoted attribute value in <{name}> at offset {j}")
            quote = text[j]
            k = text.find(quote, j + 1)
            if k < 0:
                raise XMLScanError(f"unterminated attribute value in <{name}> at offset {j}")
            attrs[am.group(0)] = _unescape(text[j + 1:k])
            j = k + 1
        i = j


_ENTITY_RE = re.compile(r"&(amp|lt|gt|quot|apos|#[0-9]+|#x[0-9a-fA-F]+);")


def _unescape(value: str) -> str:
    def repl(m: re.Match) -> str:
        ent = m.group(1)
        if ent.startswith("#x"):
            return chr(int(ent[2:], 16))
        if ent.startswith("#"):
            return chr(int(ent[1:]))
        return {"amp": "&", "lt": "<", "gt": ">", "quot": '"', "apos": "'"}[ent]
    return _ENTITY_RE.sub(repl, value)


# ---------------------------------------------------------------------------------------------
# The structure of a tree file as far as the splice needs it
# ---------------------------------------------------------------------------------------------

@dataclass
class ModelEntry:
    model_id: str
    tag: str
    start: int
    end: int


@dataclass
class FileLayout:
    root_start: Tag
    root_end: Tag | None
    first_child: Tag | None = None  # first element directly inside <root>
    models_span: tuple[int, int] | None = None  # the whole <TreeNodesModel> element
    models_tag: Tag | None = None
    entries: list[ModelEntry] = field(default_factory=list)
    used_ids: list[str] = field(default_factory=list)  # node types in <BehaviorTree> elements
    used_subtrees: list[str] = field(default_factory=list)  # IDs of <SubTree> elements


def analyse(text: str) -> FileLayout:
    tags = scan_tags(text)
    stack: list[Tag] = []
    layout: FileLayout | None = None
    models_open: Tag | None = None
    entry_open: Tag | None = None
    used: dict[str, None] = {}
    subs: dict[str, None] = {}
    for tag in tags:
        depth = len(stack)  # depth of this tag's element (root = 0)
        if tag.kind == "end":
            if not stack or stack[-1].name != tag.name:
                raise XMLScanError(f"</{tag.name}> at offset {tag.start} does not close "
                                   f"<{stack[-1].name if stack else '?'}>")
            opened = stack.pop()
            if opened is models_open:
                layout.models_span = (opened.start, tag.end)
                models_open = None
            elif opened is entry_open:
                layout.entries.append(ModelEntry(opened.attrs.get("ID", ""), opened.name, opened.start, tag.end))
                entry_open = None
            elif depth == 1 and layout is not None:
                layout.root_end = tag
            continue
        if depth == 0:
            if layout is not None:
                raise XMLScanError("more than one document element")
            if tag.name != "root":
                raise XMLScanError(f"the document element is <{tag.name}>, expected <root>")
            layout = FileLayout(tag, None)
        elif depth == 1:
            if layout.first_child is None:
                layout.first_child = tag
            if tag.name == "TreeNodesModel":
                if layout.models_tag is not None:
                    raise XMLScanError("more than one <TreeNodesModel>")
                layout.models_tag = tag
                if tag.kind == "empty":
                    layout.models_span = (tag.start, tag.end)
                else:
                    models_open = tag
        elif depth == 2 and models_open is not None and stack[-1] is models_open:
            if tag.kind == "empty":
                layout.entries.append(ModelEntry(tag.attrs.get("ID", ""), tag.name, tag.start, tag.end))
            else:
                entry_open = tag
        elif depth >= 2 and stack[1].name == "BehaviorTree":
            if tag.name == "SubTree":
                if "ID" in tag.attrs:
                    subs[tag.attrs["ID"]] = None
            elif tag.name in EXPLICIT_TAGS:
                if "ID" in tag.attrs:
                    used[tag.attrs["ID"]] = None
            else:
                used[tag.name] = None
        if tag.kind == "start":
            stack.append(tag)
    if layout is None:
        raise XMLScanError("no document element")
    if stack:
        raise XMLScanError(f"<{stack[-1].name}> at offset {stack[-1].start} is never closed")
    if layout.root_start.kind == "empty":
        raise XMLScanError("<root/> is empty")
    layout.used_ids = list(used)
    layout.used_subtrees = list(subs)
    return layout


def _line_indent(text: str, offset: int) -> str | None:
    """The whitespace before ``offset`` on its line, or None if something else precedes it."""
    line_start = text.rfind("\n", 0, offset) + 1
    prefix = text[line_start:offset]
    return prefix if prefix.strip() == "" else None


# ---------------------------------------------------------------------------------------------
# Embedding
# ---------------------------------------------------------------------------------------------

@dataclass
class EmbedResult:
    path: str
    changed: bool
    text: str
    generated: list[str]  # IDs whose entry was (re)generated from the factory
    kept: list[str]  # IDs whose existing entry was kept verbatim
    missing: list[str]  # used node types with neither a registration nor an entry


def embed_models_text(text: str, factory: BehaviorTreeFactory, include_builtin: bool = False,
                      prune: bool = False, path: str = "<text>") -> EmbedResult:
    """Return ``text`` with its ``<TreeNodesModel>`` added or refreshed (see module doc)."""
    layout = analyse(text)
    manifests = factory.manifests
    newline = "\r\n" if "\r\n" in text else "\n"

    generated_ids = [rid for rid in layout.used_ids
                     if rid in manifests and (include_builtin or not manifests[rid].builtin)]
    generated = set(generated_ids)
    used = set(layout.used_ids)
    kept: list[ModelEntry] = []
    for entry in layout.entries:
        if entry.tag != "SubTree" and entry.model_id in generated:
            continue
        if prune:
            wanted = (entry.model_id in layout.used_subtrees if entry.tag == "SubTree"
                      else entry.model_id in used)
            if not wanted:
                continue
        kept.append(entry)
    known = generated | {e.model_id for e in kept if e.tag != "SubTree"}
    missing = [rid for rid in layout.used_ids
               if rid not in known and not (rid in manifests and manifests[rid].builtin)]

    # Indentation: the section's own line indent, else that of <root>'s first child.
    anchor = layout.models_tag or layout.first_child
    base = _line_indent(text, anchor.start) if anchor is not None else None
    if base is None:
        base = "    "
    unit = base if base else "    "
    # Entries keep the indentation the existing section already uses.
    entry_indent = base + unit
    if layout.entries:
        first = _line_indent(text, layout.entries[0].start)
        if first is not None and first.startswith(base) and len(first) > len(base):
            entry_indent = first
            unit = first[len(base):]

    pieces: list[tuple[bytes, str]] = []
    for rid in generated_ids:
        lines = render(model_element(manifests[rid])).rstrip("\n").split("\n")
        body = newline.join(entry_indent + _reindent(line, unit) for line in lines)
        pieces.append((rid.encode("utf-8"), body))
    for entry in kept:
        pieces.append((entry.model_id.encode("utf-8"), entry_indent + text[entry.start:entry.end]))
    pieces.sort(key=lambda p: p[0])

    if pieces:
        section = (f"<TreeNodesModel>{newline}" + newline.join(body for _, body in pieces)
                   + f"{newline}{base}</TreeNodesModel>")
    else:
        section = "<TreeNodesModel/>"

    if layout.models_span is not None:
        start, end = layout.models_span
        new_text = text[:start] + section + text[end:]
    else:
        close = layout.root_end
        insert_at = close.start
        close_indent = _line_indent(text, insert_at)
        if close_indent is not None:
            # "...\n</root>": put the section on its own line before the </root> line.
            line_start = insert_at - len(close_indent)
            new_text = text[:line_start] + base + section + newline + text[line_start:]
        else:
            new_text = text[:insert_at] + newline + base + section + newline + text[insert_at:]
    return EmbedResult(path, new_text != text, new_text, generated_ids,
                       [e.model_id for e in kept], missing)


def _reindent(line: str, unit: str) -> str:
    """Turn the writer's 4-space indentation into the file's indentation unit."""
    stripped = line.lstrip(" ")
    depth = (len(line) - len(stripped)) // 4
    return unit * depth + stripped


def embed_models(path: str | Path, factory: BehaviorTreeFactory, include_builtin: bool = False,
                 prune: bool = False, write: bool = True) -> EmbedResult:
    """Add or refresh the ``<TreeNodesModel>`` of the tree file at ``path``, in place.

    The file is only rewritten when its content changes, and only after the new text has been
    checked to be well-formed XML with the same ``<BehaviorTree>`` content.
    """
    p = Path(path)
    raw = p.read_bytes()
    text = raw.decode("utf-8")
    result = embed_models_text(text, factory, include_builtin, prune, path=str(p))
    if result.changed:
        _check_same_trees(text, result.text)
        if write:
            p.write_bytes(result.text.encode("utf-8"))
    return result


def _check_same_trees(before: str, after: str) -> None:
    """The new text must parse, and everything outside the models section must be unchanged."""
    from bt_runtime.xml.reader import parse_xml_text

    parse_xml_text(after)
    a, b = analyse(before), analyse(after)
    if a.used_ids != b.used_ids or a.used_subtrees != b.used_subtrees:
        raise XMLScanError("internal error: embedding the models changed the trees")

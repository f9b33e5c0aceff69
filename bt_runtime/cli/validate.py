"""``validate FILE... [--models MODELS.xml ...] [--json]``: load and instantiate every tree.

Each file gets a fresh factory (the builtins plus placeholder node types for every model of
the ``--models`` files), its document is registered (with its ``<include>``s) and every
``<BehaviorTree>`` the factory then knows is instantiated: node types, ports and literal
conversions, subtree references and remappings, scripts. Every problem is reported as
``file:line: <element>: message``; the exit code is 1 if there was any. Literals of enum-typed
ports (``else="DONE"``), which BT.CPP only converts when they are read, are checked too.

A load-time problem (unknown node, wrong child count, ...) stops BT.CPP at the first one in a
document. To report the problems of the *other* trees of the same file too, the tree holding
the problem is replaced by ``<AlwaysFailure/>`` (keeping its ID and every line number) and the
document is loaded again, until it loads.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import re
import sys
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass
from typing import Any

from ..errors import BehaviorTreeException, XMLLoadError
from ..factory import BehaviorTreeFactory
from ..ports import blackboard_key
from ..xml.reader import element_children, parse_xml_text, read_limited
from .registration import RegistrationError, add_registration_arguments, registrations


@dataclass(frozen=True)
class Problem:
    file: str
    line: int | None
    element: str | None
    message: str

    def __str__(self) -> str:
        where = self.file + (f":{self.line}" if self.line else "")
        elem = f" <{self.element}>:" if self.element else ""
        return f"{where}:{elem} " + self.message.replace("\n", "\n    ")


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    parser = subparsers.add_parser(
        "validate", help="load and check tree files (nodes, ports, subtrees, scripts)",
        description="Load every tree of each FILE and instantiate it; report every problem as "
                    "file:line: <element>: message. Exit status 1 if any problem was found.")
    parser.add_argument("files", nargs="*", metavar="FILE", help="BehaviorTree.CPP v4 (or v3) XML files")
    parser.add_argument("--models", action="append", default=[], metavar="MODELS.xml",
                        help="a <TreeNodesModel> file: its node types are registered as placeholders "
                             "(ports checked, not runnable). May be repeated.")
    parser.add_argument("--json", action="store_true",
                        help="print a JSON list of {file, line, element, message}")
    add_registration_arguments(parser)
    parser.set_defaults(func=run)
    return parser


def run(args: argparse.Namespace) -> int:
    problems: list[Problem] = []
    seen: set[Problem] = set()
    summaries: list[str] = []

    def report(problem: Problem) -> None:
        if problem not in seen:
            seen.add(problem)
            problems.append(problem)

    if not args.files:
        hint = (f" --models only adds node types from a <TreeNodesModel> file; to check "
                f"{args.models[-1]} itself: python -m bt_runtime validate {args.models[-1]}") if args.models else ""
        print(f"python -m bt_runtime validate: error: no FILE to check.{hint}", file=sys.stderr)
        raise SystemExit(2)  # a usage error, as argparse reports them
    try:
        node_registrations = registrations(args)
    except RegistrationError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    with _warnings_to_stderr():
        models = _read_models(args.models, report)
    if models is not None:
        for file in args.files:
            before = len(problems)
            with _warnings_to_stderr():
                checked = validate_file(file, models, report, node_registrations)
            found = len(problems) - before
            summaries.append(f"{file}: {checked} tree(s) checked, "
                             + ("OK" if not found else f"{found} problem(s)"))

    file_order = {f: i for i, f in enumerate(dict.fromkeys(p.file for p in problems))}
    problems.sort(key=lambda p: (file_order[p.file], p.line or 0))
    if args.json:
        print(json.dumps([asdict(p) for p in problems], indent=2))
    else:
        for problem in problems:
            print(problem)
        for line in summaries:
            print(line, file=sys.stderr)
    return 1 if problems else 0


@contextlib.contextmanager
def _warnings_to_stderr() -> Iterator[None]:
    """Print each distinct warning (e.g. a v3 file being translated) once, to stderr."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield
    for message in dict.fromkeys(str(w.message) for w in caught):
        print(f"warning: {message}", file=sys.stderr)


# -- checking one file -------------------------------------------------------------------------

def _problem(exc: BaseException, file: str) -> Problem:
    if isinstance(exc, XMLLoadError):
        return Problem(str(exc.file or file), exc.line, exc.element, exc.message)
    return Problem(file, None, None, f"{type(exc).__name__}: {exc}" if not isinstance(
        exc, BehaviorTreeException) else str(exc))


def _read_models(paths: list[str], report) -> list[tuple[str, str]] | None:
    """Read and check every models file once; None (after reporting) if one is unusable."""
    models = []
    for path in paths:
        try:
            try:
                raw = read_limited(path)
            except XMLLoadError as exc:
                report(Problem(path, None, None, f"cannot read the models file: {exc.message}"))
                return None
            text = raw.decode("utf-8-sig")
            misuse = _not_a_models_file(text, path)
            if misuse is not None:
                report(misuse)
                return None
            text = _models_only(text, path)
            BehaviorTreeFactory().register_models_from_text(text, file=path)
        except OSError as exc:
            report(Problem(path, None, None, f"cannot read the models file: {exc.strerror or exc}"))
            return None
        except (BehaviorTreeException, UnicodeDecodeError) as exc:
            report(_problem(exc, path))
            return None
        models.append((path, text))
    return models


def _models_only(text: str, path: str) -> str:
    """The file without its <BehaviorTree>s (blank lines keep line numbers): a tree file that
    also carries its models (``models --embed``) gives its models, not its trees' problems."""
    for _element, begin, tag_end, close in reversed(_tree_spans(text, path) or []):
        end = tag_end if close is None else text.index(">", close) + 1
        text = text[:begin] + _blank(text[begin:end]) + text[end:]
    return text


def _not_a_models_file(text: str, path: str) -> Problem | None:
    """A tree file given to --models (it holds trees but no <TreeNodesModel>) checks nothing."""
    try:
        doc = parse_xml_text(text, file=path)
    except BehaviorTreeException:
        return None  # reported by the models loader with its line
    if doc.root.find("TreeNodesModel") is not None or doc.root.tag == "TreeNodesModel":
        return None
    if doc.root.find("BehaviorTree") is None:
        return None
    return Problem(path, doc.root.sourceline, doc.root.tag,
                   "this is a tree file, not a models file: --models takes a file with a <TreeNodesModel> "
                   "(node types known only by their model, e.g. Nav2's); to check this tree: "
                   f"python -m bt_runtime validate {path}")


def _factory(models: list[tuple[str, str]], registrations: Sequence[Callable[[Any], Any]] = ()) -> BehaviorTreeFactory:
    factory = BehaviorTreeFactory()
    for registration in registrations:
        registration(factory)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # already reported by _read_models
        for path, text in models:
            factory.register_models_from_text(text, file=path)
    return factory


def validate_file(file: str, models: list[tuple[str, str]], report,
                  registrations: Sequence[Callable[[Any], Any]] = ()) -> int:
    """Check one file; report its problems; return how many trees were checked."""
    try:
        raw = read_limited(file)  # regular files only, at most the XML size limit
    except XMLLoadError as exc:
        report(Problem(file, None, None, exc.message[:1].lower() + exc.message[1:]))
        return 0
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        report(Problem(file, None, None, f"the file is not valid UTF-8 ({exc.reason} at byte {exc.start})"))
        return 0

    neutralized: set[str] = set()
    attempts = 0
    last_problem: Problem | None = None
    while True:
        factory = _factory(models, registrations)
        try:
            factory.registry.load_text(text, file=file)
            break
        except BehaviorTreeException as exc:
            problem = _problem(exc, file)
            report(problem)
            attempts += 1
            replaced = None
            if problem.file == file and problem.line and attempts <= 256:
                # the offending node alone first (the rest of its tree is still checked), then its tree
                node = _neutralize_node(text, problem) if problem != last_problem else None
                replaced = (node, set()) if node is not None else _neutralize(text, file, problem)
            last_problem = problem
            if replaced is None:
                return 0
            text, ids = replaced
            neutralized |= ids

    main_problem = _main_tree_problem(text, file, factory.registered_behavior_trees())
    if main_problem is not None:
        report(main_problem)
    checked = 0
    for tree_id in factory.registered_behavior_trees():
        if tree_id in neutralized:
            continue
        checked += 1
        try:
            tree = factory.create_tree(tree_id)
        except Exception as exc:  # noqa: BLE001 - every failure is a problem to report
            report(_problem(exc, file))
            continue
        for problem in _literal_problems(tree, file):
            report(problem)
    return checked


def _literal_problems(tree: Any, file: str) -> list[Problem]:
    """Literals of enum-typed ports (NodeStatus included): BT.CPP only converts them when the
    node reads them, so a bad one loads and fails at run time. Report them now."""
    problems = []
    for node in tree.nodes():
        manifest = node.config.manifest
        if manifest is None:
            continue
        for name, raw in node.config.input_ports.items():
            port = manifest.ports.get(name)
            if port is None or port.type.kind not in ("status", "enum") or not isinstance(raw, str):
                continue
            if blackboard_key(raw, name) is not None:
                continue
            try:
                port.type.from_string(raw, node.config.enums)
            except BehaviorTreeException:
                src_file, line = node.config.source
                problems.append(Problem(str(src_file or file), line, node.registration_name,
                                        f'The port with name "{name}" and value "{raw}" can not be converted '
                                        f"to {port.type.name}"))
    return problems


def _main_tree_problem(text: str, file: str, tree_ids: Sequence[str]) -> Problem | None:
    """``main_tree_to_execute`` must name a tree of the file (or of its includes)."""
    try:
        doc = parse_xml_text(text, file=file)
    except BehaviorTreeException:
        return None
    main = doc.root.get("main_tree_to_execute")
    if not main or main in tree_ids:
        return None
    import difflib

    close = difflib.get_close_matches(main, list(tree_ids), n=1)
    hint = f"; did you mean '{close[0]}'?" if close else ""
    return Problem(file, doc.root.sourceline, doc.root.tag,
                   f'main_tree_to_execute="{main}" names no tree of this file (trees: '
                   f'{", ".join(tree_ids) or "none"}){hint}')


# -- replacing a node or a tree that failed to load -----------------------------------------------

def _neutralize_node(text: str, problem: Problem) -> str | None:
    """Replace the element the problem names, on its line, by ``<AlwaysFailure/>`` (blank
    lines keep every line number), so the next load reports the tree's next problem."""
    if not problem.element or problem.element in ("BehaviorTree", "root", "include", "TreeNodesModel"):
        return None
    line_start = 0
    for _ in range((problem.line or 1) - 1):
        line_start = text.find("\n", line_start) + 1
        if line_start == 0:
            return None
    line_end = text.find("\n", line_start)
    line_end = len(text) if line_end < 0 else line_end
    m = re.compile(r"<" + re.escape(problem.element) + r"(?=[\s/>])").search(text, line_start, line_end)
    if m is None:
        return None
    tag_end = _start_tag_end(text, m.start())
    if tag_end is None:
        return None
    if text[tag_end - 2] == "/":
        end = tag_end
    else:
        end = _matching_close(text, problem.element, tag_end)
        if end is None:
            return None
    return text[:m.start()] + _PLACEHOLDER + _blank(text[m.start():end]) + text[end:]


def _matching_close(text: str, tag: str, pos: int) -> int | None:
    """Index just past the end tag closing the element of ``tag`` whose content starts at ``pos``."""
    pattern = re.compile(r"<(/?)" + re.escape(tag) + r"(?=[\s/>])")
    depth = 1
    for m in pattern.finditer(text, pos):
        if m.group(1):
            depth -= 1
            if depth == 0:
                return text.index(">", m.end()) + 1
            continue
        tag_end = _start_tag_end(text, m.start())
        if tag_end is not None and text[tag_end - 2] != "/":
            depth += 1
    return None



_BT_OPEN = re.compile(r"<BehaviorTree\b")
_BT_CLOSE = re.compile(r"</BehaviorTree\s*>")
_COMMENT = re.compile(r"<!--.*?-->", re.DOTALL)
_PLACEHOLDER = "<AlwaysFailure/>"


def _start_tag_end(text: str, pos: int) -> int | None:
    """Index just past the '>' closing the start tag that begins at ``pos`` (quotes respected)."""
    quote = None
    for i in range(pos, len(text)):
        ch = text[i]
        if quote:
            if ch == quote:
                quote = None
        elif ch in "\"'":
            quote = ch
        elif ch == ">":
            return i + 1
    return None


def _blank(fragment: str) -> str:
    return "\n" * fragment.count("\n")


def _tree_spans(text: str, file: str) -> list[tuple[Any, int, int, int | None]] | None:
    """(element, begin, start-tag end, end-tag start or None if self-closing) for each tree."""
    try:
        doc = parse_xml_text(text, file=file)
    except BehaviorTreeException:
        return None
    comments = [m.span() for m in _COMMENT.finditer(text)]
    opens = [m.start() for m in _BT_OPEN.finditer(text)
             if not any(a <= m.start() < b for a, b in comments)]
    elements = list(doc.root.iter("BehaviorTree"))
    if len(opens) != len(elements):
        return None
    top = set(element_children(doc.root))
    spans = []
    for element, begin in zip(elements, opens):
        tag_end = _start_tag_end(text, begin)
        if tag_end is None:
            return None
        if text[tag_end - 2] == "/":
            close = None
        else:
            m = _BT_CLOSE.search(text, tag_end)
            if m is None:
                return None
            close = m.start()
        if element in top:
            spans.append((element, begin, tag_end, close))
    return spans


def _neutralize(text: str, file: str, problem: Problem) -> tuple[str, set[str]] | None:
    """Replace the <BehaviorTree>(s) whose lines hold the problem: their content by a
    placeholder (the ID stays registered, so trees using it still build), or the whole element
    by blank lines when the element itself is wrong or already holds only the placeholder.
    Line numbers are kept. Returns the new text and the IDs replaced by a placeholder, or None
    when the problem is not inside a tree."""
    spans = _tree_spans(text, file)
    if not spans:
        return None
    edits = []
    for element, begin, tag_end, close in spans:
        end = tag_end if close is None else text.index(">", close) + 1
        first = text.count("\n", 0, begin) + 1
        last = first + text.count("\n", begin, end)
        if first <= (problem.line or 0) <= last:
            edits.append((element, begin, tag_end, close, end))
    if not edits:
        return None
    replaced: set[str] = set()
    for element, begin, tag_end, close, end in reversed(edits):
        already = close is not None and text[tag_end:close].strip() == _PLACEHOLDER
        if problem.element == "BehaviorTree" or already:
            text = text[:begin] + _blank(text[begin:end]) + text[end:]
            continue
        tree_id = element.get("ID")
        if tree_id:
            replaced.add(tree_id)
        if close is None:
            text = text[:begin] + text[begin:tag_end - 2] + ">" + _PLACEHOLDER + "</BehaviorTree>" + text[tag_end:]
        else:
            text = text[:tag_end] + _PLACEHOLDER + _blank(text[tag_end:close]) + text[close:]
    return text, replaced

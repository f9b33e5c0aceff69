"""Exception types. They mirror BT.CPP's hierarchy so callers can catch the same classes.

``LogicError`` is a programming/configuration error, ``BTRuntimeError`` a data or run-time
error; both derive from ``BehaviorTreeException``. Load-time problems raise an ``XMLLoadError``
carrying the file, line and element so a person can find them; each is also an instance of
the class BT.CPP 4.10 throws for that problem: ``XMLRuntimeError`` (a BTRuntimeError: bad XML,
unknown nodes or ports, duplicate paths, ...) or ``XMLLogicError`` (a LogicError: a literal
that does not convert, a node constructor's logic error). An exception raised from a node's
``tick()`` is wrapped once, at the node where it started, in ``NodeExecutionError`` (a
BTRuntimeError, as in BT.CPP 4.10), which keeps the node's full path.
"""

from __future__ import annotations


class BehaviorTreeException(Exception):
    """Base of every error raised by bt_runtime."""


class LogicError(BehaviorTreeException):
    """A programming or configuration error (bad tree, bad registration, misuse of the API)."""


class BTRuntimeError(BehaviorTreeException):
    """A data or run-time error (missing blackboard entry, failed conversion, ...)."""


class XMLLoadError(BehaviorTreeException):
    """A problem in a tree file, located by file, line and element. Raise one of the two
    subclasses below, the one matching the class BT.CPP throws; catch this one."""

    def __new__(cls, *args: object, **kwargs: object) -> XMLLoadError:
        # XMLLoadError(...) itself makes the common kind, BT.CPP's RuntimeError
        return super().__new__(XMLRuntimeError if cls is XMLLoadError else cls)

    def __init__(self, message: str, *, file: str | None = None, line: int | None = None,
                 element: str | None = None):
        self.message = message
        self.file = file
        self.line = line
        self.element = element
        super().__init__(self._format())

    def _format(self) -> str:
        """``file:line: <element>: message`` (``line N: ...`` for text input), as the CLI prints."""
        if self.file:
            where = f"{self.file}:{self.line}" if self.line else str(self.file)
        else:
            where = f"line {self.line}" if self.line else ""
        parts = [p for p in (where, f"<{self.element}>" if self.element else "") if p]
        return ": ".join([*parts, self.message])

    def to_dict(self) -> dict:
        return {"file": self.file, "line": self.line, "element": self.element, "message": self.message}


class XMLRuntimeError(XMLLoadError, BTRuntimeError):
    """A located load error that BT.CPP reports as ``BT::RuntimeError`` (most of them)."""


class XMLLogicError(XMLLoadError, LogicError):
    """A located load error that BT.CPP reports as ``BT::LogicError``."""


def located(exc: BehaviorTreeException, message: str, **where: object) -> XMLLoadError:
    """``message`` at ``where`` (file, line, element), keeping ``exc``'s BT.CPP class."""
    cls = XMLLogicError if isinstance(exc, LogicError) else XMLRuntimeError
    return cls(message, **where)


class NodeExecutionError(BTRuntimeError):
    """An exception raised inside a node's tick, wrapped once with the node's path and type."""

    def __init__(self, node_path: str, registration_id: str, original: BaseException,
                 node_name: str | None = None):
        self.node_path = node_path
        self.registration_id = registration_id
        self.original = original
        self.node_name = node_name if node_name is not None else node_path.rpartition("/")[2]
        super().__init__(f"Exception in node '{node_path}' [{registration_id}]: {original}")

    @property
    def original_message(self) -> str:
        """The wrapped exception's text (BT.CPP ``originalMessage()``)."""
        return str(self.original)

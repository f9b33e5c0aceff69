"""The three ways a script can fail, kept apart because BT.CPP treats them differently.

* ``ScriptError``: the text does not parse. Raised once, when the script is compiled.
* A ``BTRuntimeError`` raised while evaluating (BT.CPP's ``RuntimeError``) is re-raised by
  ``Script.run`` as ``ScriptRuntimeError('Error in script [<text>]\\n<message>')``.
* ``CastError``: a value-layer conversion failed (BT.CPP throws a plain ``std::runtime_error``
  from ``Any::cast``, which the script wrapper does not catch), so it propagates unwrapped,
  e.g. ``Any failed string to number conversion``.
"""

from __future__ import annotations

from ..errors import BTRuntimeError, LogicError


class ScriptError(LogicError):
    """A syntax error. ``message`` is the bare parser message, ``script`` the source text."""

    def __init__(self, script: str, message: str):
        self.script = script
        self.message = message
        super().__init__(f'Error in the script "{script}"\n{message}')


class ScriptRuntimeError(BTRuntimeError):
    """A run-time error wrapped with the script's text (``Error in script [...]``)."""


class CastError(BTRuntimeError):
    """A value conversion error; never wrapped with the script text."""

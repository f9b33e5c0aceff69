"""The BehaviorTree.CPP 4.10 script language (spec section 6), compiled to Python closures.

``compile_script(text)`` parses once (``ScriptError`` on a syntax error); ``Script.run(bb,
enums)`` evaluates against a blackboard and returns the last expression's value;
``to_bool``/``Script.run_bool`` give the condition value used by pre-conditions.
"""

from ..errors import BTRuntimeError
from .compiler import Script, compile_script
from .errors import CastError, ScriptError, ScriptRuntimeError
from .values import to_bool

__all__ = ["CastError", "Script", "ScriptError", "ScriptRuntimeError", "compile_node_script", "compile_script",
           "to_bool"]


def compile_node_script(text: str) -> Script:
    """Compile the script of a Script, ScriptCondition or Precondition node. Those nodes turn a
    syntax error into BT.CPP's ``RuntimeError`` (pre/post-condition attributes keep the
    ``LogicError`` that ``compile_script`` raises)."""
    try:
        return compile_script(text)
    except ScriptError as exc:
        raise BTRuntimeError(str(exc)) from None

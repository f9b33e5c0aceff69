"""Allocating many long-lived objects without the cyclic collector's help (trees, plans).

Loading only allocates: the collector's passes over a heap that grows by thousands of objects
made loading super-linear, and its young collections right after a load traverse the whole
new structure, costing as much as making it. So the collector is paused while a document is
read or a tree built, and what was made goes straight to the oldest generation
(``gc.freeze``/``unfreeze``, constant time). Such objects are freed by reference counting
(a tree breaks its own cycles when dropped), not by the collector. The move is skipped when
the application keeps objects frozen itself.
"""

from __future__ import annotations

import gc


class long_lived:
    """``with long_lived():`` pause the cyclic collector; on a normal exit, move everything
    made meanwhile (and anything else still young) to the oldest generation."""

    __slots__ = ("_was_enabled",)

    def __enter__(self) -> None:
        self._was_enabled = gc.isenabled()
        gc.disable()

    def __exit__(self, exc_type: object, *rest: object) -> None:
        try:
            if exc_type is None and gc.get_freeze_count() == 0:
                gc.freeze()
                gc.unfreeze()
        finally:
            if self._was_enabled:
                gc.enable()

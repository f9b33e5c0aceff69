"""Testing your own trees with pytest: the ``bt_runtime`` plugin (``bt_runtime.testing.plugin``).

Installed with the package and loaded by pytest automatically (a ``pytest11`` entry point). It
gives async tests a virtual-time event loop (``@pytest.mark.virtual_time``, or every async test
with ``bt_runtime_virtual_time = true`` in the pytest ini), fixtures for a simulated robot and
a runtime with a tree, and quiet logs in those tests. See docs/testing.md.
"""

from .plugin import loop_factories, quiet_logs, wants_virtual_time

__all__ = ["loop_factories", "quiet_logs", "wants_virtual_time"]

"""Where the repository and the steering folder's ``shared/`` are, for tests that read files.

``SHARED`` is ``../shared`` beside the checkout (as CI lays it out) or ``/work/shared``; tests
that need it skip when it is absent."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]



def _find_shared() -> Path:
    for base in (ROOT.parent, *ROOT.parents[1:3]):
        cand = base / "shared"
        if (cand / "reference").is_dir():
            return cand
    return Path("/work/shared")


SHARED = _find_shared()
REFERENCE = SHARED / "reference"

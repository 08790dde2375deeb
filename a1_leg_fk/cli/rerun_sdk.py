"""rerun-sdk for the commands that write or stream a Rerun recording (``view``, ``echo --rerun``):
imported with its own log lines off, or a one-line hint of how to install it; the viewer binary
that came with it.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from types import ModuleType

from a1_leg_fk.cli.common import PROG

RERUN_SDK = "rerun-sdk==0.41.0"
"""The version the ``view`` extra pins (setup.py)."""


def import_rerun(command: str) -> ModuleType | None:
    """The ``rerun`` module, its (Rust) log lines off unless ``RUST_LOG`` is set: what they would
    say (e.g. 7 lines for a description's meshes that do not resolve) our own output says once.
    None, after one line on stderr naming ``command`` and how to install rerun-sdk, without it.
    """
    os.environ.setdefault("RUST_LOG", "off")
    try:
        import rerun
    except ImportError:
        print(
            f"{PROG} {command} needs rerun-sdk: pip install 'a1_leg_fk[view]' (or pip install "
            f"{RERUN_SDK})",
            file=sys.stderr,
        )
        return None
    return rerun


def viewer_executable() -> str | None:
    """The viewer that came with rerun-sdk (its ``rerun_cli`` package), else None: ``rerun`` on
    the PATH (a virtualenv's bin folder is not on it when its python is run directly).
    """
    try:
        import rerun_cli  # type: ignore[import-untyped,unused-ignore]
    except ImportError:
        return None
    binary = Path(rerun_cli.__file__).with_name("rerun")
    return str(binary) if binary.is_file() else None

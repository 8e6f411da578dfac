"""Command line: ``fosmodel fit | predict | study | close-loop | allan | synth | demo``.

A thin layer over the library: :mod:`.parser` holds the grammar, :mod:`.commands` one
short function per command over public library functions, and :mod:`.exit_codes` the exit
codes: 0 success, 2 bad input or usage (one-line message on stderr), 1 internal error (with a
hint to report it; ``--verbose`` shows the traceback), 130 interrupted.

This module imports nothing heavy: :func:`main` imports the rest inside its guard, so that
Ctrl-C while numpy, pandas and scikit-learn load ends the command as it does later, in one
line and code 130, never with a traceback.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .parser import build_parser

__all__ = ["build_parser", "main"]


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    try:
        from .exit_codes import run

        return run(argv)
    except KeyboardInterrupt:  # while importing, or between the command and its exit code
        print("fosmodel: interrupted", file=sys.stderr)
        return 130


def __getattr__(name: str) -> object:
    """Import :func:`build_parser` on first use."""
    if name != "build_parser":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from .parser import build_parser

    return build_parser

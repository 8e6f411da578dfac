"""How a command ends: its exit code, its one-line error, its outputs all published or none.

0 success, 2 bad input or usage (one-line message on stderr), 1 internal error (with a hint
to report it; ``--verbose`` shows the traceback), 130 interrupted.  A command's outputs are
published together (:func:`fosmodel.io.journal.all_or_nothing`): when it fails, those it
already put in place are undone.  Ctrl-C has one behaviour whatever its moment: until the
command returns, its outputs are undone and the code is 130 (``fosmodel: interrupted``);
once it has returned they stand, and a Ctrl-C is ignored while it finishes (code 0).
"""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
import traceback
import warnings

from ..core.exceptions import InputError
from ..io.journal import all_or_nothing
from ..io.sensor_log import TopicError
from .flags import with_flags
from .parser import build_parser


def _one_line_warning(message: Warning | str, category: type[Warning], filename: str,
                      lineno: int, line: str | None = None) -> str:
    """Format a warning as the command line shows it: one line, like its notes and errors."""
    return f"fosmodel: warning: {' '.join(with_flags(str(message)).split())}\n"


def run(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    shown, warnings.formatwarning = warnings.formatwarning, _one_line_warning
    handler = signal.getsignal(signal.SIGINT) if _main_thread() else None
    try:
        return _run(args)
    finally:
        warnings.formatwarning = shown
        if handler is not None:  # a Ctrl-C after the outputs were committed was ignored
            signal.signal(signal.SIGINT, handler)


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _committed() -> None:
    """From here a command's outputs stand: a Ctrl-C no longer undoes them, it is ignored.

    So the exit code agrees with what is on disk whatever the moment of the Ctrl-C: before
    this, every output is taken back and the code is 130; after it, the command finishes
    (the files its outputs replaced are removed) and the code is 0.
    """
    if _main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def _run(args: argparse.Namespace) -> int:
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="fosmodel: %(message)s", stream=sys.stderr)
    try:
        with all_or_nothing():
            code = args.func(args)
            _committed()
        return code
    except InputError as exc:
        message = with_flags(exc.with_flag() if isinstance(exc, TopicError) else str(exc))
        print(f"fosmodel: error: {' '.join(message.split())}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("fosmodel: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # a bug: say so, briefly, and how to get details
        if args.verbose:
            traceback.print_exc()
        print(f"fosmodel: internal error: {type(exc).__name__}: {' '.join(str(exc).split())} "
              "(this is a bug; please report it with the command you ran; "
              "--verbose shows the traceback)", file=sys.stderr)
        return 1

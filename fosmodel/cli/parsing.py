"""How the command line is read, around :mod:`argparse`.

One-line usage errors, help that ends each option with its default, options a command refuses
with the reason, and argument types over the library's parsers.
"""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, NoReturn, TypeVar

from ..core.exceptions import InputError

T = TypeVar("T")


@dataclass(frozen=True)
class Command:
    """A command's function, named by its module of :mod:`fosmodel.cli` and imported when it runs.

    The parser of every command is built at each start (``fosmodel --version`` too); importing
    the commands' modules there would load pandas, SciPy and scikit-learn for nothing.
    """

    module: str
    name: str

    def __call__(self, args: argparse.Namespace) -> int:
        """Run the command on the parsed ``args``; return its exit code."""
        function = getattr(importlib.import_module(f"fosmodel.cli.{self.module}"), self.name)
        return int(function(args))


class CommandParser(argparse.ArgumentParser):
    """An argument parser whose usage errors take one line, like every other error.

    Its help, and its subcommands' (parsers of its class), shows each option's default
    (:class:`DefaultsFormatter`).
    """

    def error(self, message: str) -> NoReturn:
        """Exit with code 2 after one line: the message and where the usage is."""
        self.exit(2, f"fosmodel: error: {message} ({self.prog} --help shows the usage)\n")

    def _get_formatter(self) -> argparse.HelpFormatter:
        return DefaultsFormatter(prog=self.prog)


class DefaultsFormatter(argparse.HelpFormatter):
    """Ends the help of each option that takes a value with ``(default: ...)``.

    Only where it has a default and its help does not say it already: a flag or an option
    without default shows none (argparse's ArgumentDefaultsHelpFormatter would print
    ``(default: None)``).
    """

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if (action.option_strings and action.nargs != 0 and "(default" not in text
                and action.default not in (None, argparse.SUPPRESS) and action.default != []):
            text += " (default: %(default)s)"
        return text


class Refused(argparse.Action):
    """An option a command does not offer: refused with the reason ``why``.

    It is hidden from the command's help: a loader option that makes no sense for the command.
    """

    def __init__(self, option_strings: Sequence[str], dest: str, why: str) -> None:
        super().__init__(option_strings, dest, nargs=0, help=argparse.SUPPRESS)
        self.why = why

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: str | Sequence[Any] | None, option_string: str | None = None) -> NoReturn:
        """Refuse the option as a usage error that gives the reason."""
        parser.error(f"argument {option_string}: {self.why}")


def parsed(parse: Callable[[str], T]) -> Callable[[str], T]:
    """Make an argument type of a library parser (``SplitSpec.parse``).

    Its :class:`~fosmodel.core.exceptions.InputError` becomes a usage error of the option.
    """
    def read(text: str) -> T:
        try:
            return parse(text)
        except InputError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
    return read

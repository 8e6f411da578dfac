"""How the command line is read: one-line usage errors, help that shows each option's default,
options a command refuses with the reason, and argument types over the library's parsers."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any, NoReturn

from ..core.exceptions import InputError


class CommandParser(argparse.ArgumentParser):
    """An argument parser whose usage errors take one line, like every other error, and whose
    help ends each option with its default (its subcommands' too)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", DefaultsFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"fosmodel: error: {message} ({self.prog} --help shows the usage)\n")


class DefaultsFormatter(argparse.HelpFormatter):
    """Ends the help of each option that takes a value with ``(default: ...)``, where it has a
    default and its help does not say it already; a flag or an option without default shows
    none (argparse's ArgumentDefaultsHelpFormatter would print ``(default: None)``)."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if (action.option_strings and action.nargs != 0 and "(default" not in text
                and action.default not in (None, argparse.SUPPRESS) and action.default != []):
            text += " (default: %(default)s)"
        return text


class Refused(argparse.Action):
    """An option a command does not offer: refused with the reason ``why``, hidden from its
    help (a loader option that makes no sense for the command)."""

    def __init__(self, option_strings: list[str], dest: str, why: str, **kwargs: Any) -> None:
        super().__init__(option_strings, dest, nargs=0, help=argparse.SUPPRESS, **kwargs)
        self.why = why

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> NoReturn:
        parser.error(f"argument {option_string}: {self.why}")


def parsed(parse: Callable[[str], Any]) -> Callable[[str], Any]:
    """An argument type that reads with a library parser (``SplitSpec.parse``), its
    :class:`~fosmodel.core.exceptions.InputError` a usage error of the option."""
    def read(text: str) -> Any:
        try:
            return parse(text)
        except InputError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
    return read

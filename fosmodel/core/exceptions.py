"""Exceptions and warnings raised by fosmodel.

Every error that a user can cause (bad file, bad column, impossible fit) is an
:class:`InputError`; the command line turns it into a one-line message and exit
code 2.  Anything else reaching the command line is a bug (exit code 1).
"""

from __future__ import annotations

from collections.abc import Mapping


class FOSModelError(Exception):
    """Base class of all fosmodel errors."""


class InputError(FOSModelError, ValueError):
    """The input (data, column, option or file) cannot be used as given.

    The message names the problem precisely: the file, the column and the
    first offending sample where they apply.
    """


class OptionError(InputError):
    """An option given wrongly, named in the library's own terms.

    The message is written with ``{option}`` where the option is named: the library
    says its keyword (``max_lag``), :meth:`with_flag` the command line's flag for it.
    """

    def __init__(self, template: str, keyword: str) -> None:
        super().__init__(template.replace("{option}", keyword))
        self.template, self.keyword = template, keyword

    def with_flag(self, flags: Mapping[str, str] | None = None) -> str:
        """Return the message naming the option by its flag.

        The flag is ``flags[keyword]``, or ``--max-lag`` for ``max_lag``.
        """
        flag = (flags or {}).get(self.keyword, "--" + self.keyword.replace("_", "-"))
        return self.template.replace("{option}", flag)


def __getattr__(name: str) -> type:
    """Make :class:`NotFittedError` the first time it is asked for.

    It is also scikit-learn's ``NotFittedError``, and importing scikit-learn takes longer
    than everything a command needs to start: the class waits until a model is used.
    """
    if name != "NotFittedError":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from sklearn.exceptions import NotFittedError as SklearnNotFitted

    class NotFittedError(InputError, SklearnNotFitted):
        """A model was used before ``fit()``.

        scikit-learn's ``NotFittedError`` (so ``FOSModel``, ``FOSRegressor`` and the
        baselines all raise what scikit-learn users catch) and an :class:`InputError` (so
        the command line reports it in one line).
        """

    NotFittedError.__module__, NotFittedError.__qualname__ = __name__, "NotFittedError"
    globals()["NotFittedError"] = NotFittedError
    return NotFittedError


def error_line(exc: BaseException) -> str:
    """Return the first line of ``exc``'s message, or its type's name if it has none.

    That line is what a one-line :class:`InputError` quotes of a library's error.
    """
    return str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__


class UnstableModelWarning(UserWarning):
    """A fitted linear model has a characteristic root on or outside the unit circle."""


class FitWarning(UserWarning):
    """The fit finished but something about it deserves the user's attention."""

"""Model files: a fitted :class:`~fosmodel.models.model.FOSModel` as JSON, written and read back.

The file is ``FOSModel.to_dict`` with the record's facts in ``meta`` (source, column, rate).
:func:`loads` is the one place a model file is validated: it refuses, in one line naming the
file, anything that is not such a model down to its numbers (invalid JSON, a format this
version does not read, weights that are not finite, a source column that is not a name);
:func:`load_model` adds the reading of the file (unreadable or non-UTF-8 bytes).

Why here, in the models layer: a fitted model saves and loads itself (``FOSModel.save``,
``FOSModel.load``, which call these functions), and imports run one way (core -> models ->
io), so a model may not call into :mod:`fosmodel.io`.  The format and its checks therefore
live with the model, over the atomic writes and checked reads of :mod:`fosmodel.core.files`;
:mod:`fosmodel.io.model_file` gives the commands ``FOSModel.load`` and ``save`` under their
names.  This module takes the model's ``from_dict`` as an argument rather than importing
:mod:`fosmodel.models.model`, which imports it: no import cycle.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Mapping
from typing import Any, Protocol, TypeVar

import numpy as np

from ..core.exceptions import InputError
from ..core.files import read_text, write_text


class SavedModel(Protocol):
    """What a model file holds: a fitted model's weights, offsets, facts and its dict."""

    coef_: np.ndarray
    intercept_: float
    offsets_: dict[str, float]
    meta_: dict[str, Any]

    def to_dict(self, meta: Mapping[str, object] | None = None) -> dict:
        """Return the JSON-serialisable form of the model with ``meta``."""
        ...


_M = TypeVar("_M", bound=SavedModel)


def dumps(model: SavedModel, meta: Mapping[str, Any] | None = None) -> str:
    """Return the JSON text of a fitted ``model`` with ``meta`` (source, column, rate, ...)."""
    return json.dumps(model.to_dict(dict(meta or {})), indent=2) + "\n"


def loads(text: str, from_dict: Callable[[Any], _M],
          where: str | os.PathLike[str] = "the model") -> _M:
    """Return the model of a model file's ``text``, checked down to its numbers.

    Parameters
    ----------
    text : str
        The file's content.
    from_dict : callable
        The model class's ``from_dict`` (``FOSModel.from_dict``).
    where : path-like
        The file, which every message names.

    Raises
    ------
    InputError
        Not a model file, a format this version does not read, or a corrupted model.
    """
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{where}: not a model file (invalid JSON at line {exc.lineno})") \
            from None
    except (ValueError, RecursionError) as exc:  # a number of 4300+ digits, nesting too deep
        raise InputError(f"{where}: not a model file ({exc})") from None
    try:
        model = from_dict(data)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    except (AttributeError, TypeError, ValueError, OverflowError) as exc:  # e.g. terms of numbers
        raise InputError(f"{where}: corrupted model file: {type(exc).__name__}: {exc}") from None
    _check_numbers(model, where)
    return model


def load_model(path: str | os.PathLike[str], from_dict: Callable[[Any], _M]) -> _M:
    """Load the model saved in ``path``, checked down to its numbers and the column it names.

    ``from_dict`` is the model class's (``FOSModel.from_dict``).

    Raises
    ------
    InputError
        The file cannot be read or is not a model file (the message names it and why).
    """
    return loads(read_text(path, "model"), from_dict, path)


def save_model(path: str | os.PathLike[str], model: SavedModel,
               meta: Mapping[str, Any] | None = None) -> None:
    """Write ``model`` with ``meta`` (source, column, rate, ...) to ``path``, atomically."""
    write_text(path, dumps(model, meta))


def _check_numbers(model: SavedModel, where: str | os.PathLike[str]) -> None:
    """Refuse a model whose weights are not finite or whose source column is not a name."""
    numbers = [*model.coef_, model.intercept_, *model.offsets_.values()]
    if not np.isfinite(numbers).all():
        raise InputError(f"{where}: corrupted model file: a weight or offset is not a finite "
                         "number")
    column = model.meta_.get("column")
    if column is not None and not isinstance(column, str):
        raise InputError(f"{where}: corrupted model file: meta.column {column!r} is not a "
                         "column name")

"""Model files: a fitted :class:`~fosmodel.models.model.FOSModel` as JSON, written and read back.

The file is ``FOSModel.to_dict`` with the record's facts in ``meta`` (source, column, rate).
:func:`load_model` is the one reader of a model file, under both ``FOSModel.load`` and the
commands' :func:`fosmodel.io.model_file.read_model`: it refuses, in one line naming the file,
anything that is not such a model down to its numbers, and bounds what it reads before
parsing it:

* a path that is not a regular file (a FIFO, a device such as ``/dev/zero``, a directory) is
  refused from its metadata, never opened for reading to its end nor waited on
  (:func:`fosmodel.core.files.read_bounded`);
* at most :data:`MAX_BYTES` are read; the text must be UTF-8 JSON, nested at most
  :data:`MAX_DEPTH` deep, its integers at most :data:`MAX_DIGITS` digits long;
* its content must pass the schema of :mod:`fosmodel.models.model_schema` (each field's type
  and range, each term inside the model's own candidate set, weights against the training
  spread) before a model is built from it.

Why here, in the models layer: a fitted model saves and loads itself (``FOSModel.save``,
``FOSModel.load``, which call these functions), and imports run one way (core -> models ->
io), so a model may not call into :mod:`fosmodel.io`; a user loading a forged file in Python
must meet the same guards as the command line.  This module takes the model's ``from_dict``
as an argument rather than importing :mod:`fosmodel.models.model`, which imports it: no
import cycle.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Mapping
from typing import Any, Protocol, TypeVar

import numpy as np

from ..core.exceptions import InputError
from ..core.files import read_bounded, write_text
from .model_schema import check_model_dict

#: The largest model file read: a fit of ten thousand terms writes about 2 MB.
MAX_BYTES = 16 * 2**20
#: The deepest nesting of a model file's JSON (a model's own is three; ``meta`` may add some).
MAX_DEPTH = 16
#: The longest integer of a model file's JSON, in digits (a sample count has at most 16).
MAX_DIGITS = 20


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


def loads(raw: bytes, from_dict: Callable[[Any], _M],
          where: str | os.PathLike[str] = "the model") -> _M:
    """Return the model of a model file's bytes, checked down to its numbers.

    Parameters
    ----------
    raw : bytes
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
    data = _parse(raw, where)
    try:
        return from_dict(check_model_dict(data))
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    except (AttributeError, TypeError, ValueError, OverflowError) as exc:  # e.g. terms of numbers
        raise InputError(f"{where}: corrupted model file: {type(exc).__name__}: {exc}") from None


def load_model(path: str | os.PathLike[str], from_dict: Callable[[Any], _M]) -> _M:
    """Load the model saved in ``path``, checked down to its numbers and the column it names.

    ``from_dict`` is the model class's (``FOSModel.from_dict``).

    Raises
    ------
    InputError
        The file cannot be read or is not a model file (the message names it and why).
    """
    return loads(read_bounded(path, "model", MAX_BYTES), from_dict, path)


def save_model(path: str | os.PathLike[str], model: SavedModel,
               meta: Mapping[str, Any] | None = None) -> None:
    """Write ``model`` with ``meta`` (source, column, rate, ...) to ``path``, atomically."""
    write_text(path, dumps(model, meta))


def _parse(raw: bytes, where: str | os.PathLike[str]) -> object:
    """Parse the file's JSON within the limits on its nesting and its integers."""
    try:
        text = raw.decode("utf-8-sig")  # a byte-order mark, as a CSV's, is read past
    except UnicodeDecodeError:
        raise InputError(f"{where}: not a model file (not UTF-8 text)") from None
    try:
        data = json.loads(text, parse_int=_bounded_int)
    except json.JSONDecodeError as exc:
        raise InputError(f"{where}: not a model file (invalid JSON at line {exc.lineno})") \
            from None
    except RecursionError:
        raise InputError(f"{where}: not a model file (JSON nested more than {MAX_DEPTH} "
                         "deep)") from None
    except ValueError as exc:  # an integer too long
        raise InputError(f"{where}: not a model file ({exc})") from None
    if _depth(data) > MAX_DEPTH:
        raise InputError(f"{where}: not a model file (JSON nested more than {MAX_DEPTH} deep)")
    return data


def _bounded_int(text: str) -> int:
    digits = len(text.lstrip("-"))
    if digits > MAX_DIGITS:
        raise ValueError(f"an integer of {digits:,} digits")
    return int(text)


def _depth(value: object) -> int:
    """Return the nesting depth of a JSON value (a number or a string: 0), without recursion."""
    deepest, todo = 0, [(value, 0)]
    while todo:
        item, depth = todo.pop()
        if isinstance(item, (list, dict)):
            deepest = max(deepest, depth + 1)
            if deepest > MAX_DEPTH:
                return deepest
            todo.extend((v, depth + 1) for v in (item.values() if isinstance(item, dict)
                                                 else item))
    return deepest

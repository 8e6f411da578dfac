"""Model files: a fitted :class:`~fosmodel.models.model.FOSModel` as JSON, written and read back.

The file is :meth:`FOSModel.to_dict` with the record's facts in ``meta`` (source, column,
rate); :func:`read_model` refuses, in one line naming the file, anything that is not such a
model down to its numbers: unreadable or non-UTF-8 bytes, invalid JSON, a format this
version does not read, weights that are not finite, a source column that is not a name.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..core.exceptions import InputError
from ..models.compensation import check_compensation
from ..models.model import FOSModel
from .output import write_text


def write_model(path: str | os.PathLike[str], model: FOSModel,
                meta: Mapping[str, Any]) -> None:
    """Write ``model`` with ``meta`` (source, column, rate, ...) to ``path``, atomically."""
    write_text(path, json.dumps(model.to_dict(dict(meta)), indent=2) + "\n")


def read_model(path: str | os.PathLike[str]) -> FOSModel:
    """Load the model saved in ``path``, checked down to its numbers and the column it names.

    Raises
    ------
    InputError
        The file cannot be read or is not a model file (the message names it and why).
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise InputError(f"cannot read model {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a model file (not UTF-8 text)") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: not a model file (invalid JSON at line {exc.lineno})") from None
    except (ValueError, RecursionError) as exc:  # a number of 4300+ digits, nesting too deep
        raise InputError(f"{path}: not a model file ({exc})") from None
    try:
        model = FOSModel.from_dict(data)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    except (AttributeError, TypeError, ValueError, OverflowError) as exc:  # e.g. terms of numbers
        raise InputError(f"{path}: corrupted model file: {type(exc).__name__}: {exc}") from None
    _check_numbers(model, path)
    return model


def _check_numbers(model: FOSModel, path: str | os.PathLike[str]) -> None:
    """Refuse a model whose weights are not finite or whose source column is not a name."""
    try:
        check_compensation(model.compensation)
    except InputError as exc:
        raise InputError(f"{path}: corrupted model file: {exc}") from None
    numbers = [*model.coef_, model.intercept_, *model.offsets_.values()]
    if not np.isfinite(numbers).all():
        raise InputError(f"{path}: corrupted model file: a weight or offset is not a finite "
                         "number")
    column = model.meta_.get("column")
    if column is not None and not isinstance(column, str):
        raise InputError(f"{path}: corrupted model file: meta.column {column!r} is not a column "
                         "name")

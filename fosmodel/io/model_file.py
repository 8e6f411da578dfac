"""Model files for the commands: a fitted ``FOSModel`` as JSON, written and read back checked.

The file is :meth:`FOSModel.to_dict` with the record's facts in ``meta`` (source, column,
rate).  :func:`read_model` is the commands' read of a model file; it is ``FOSModel.load``
(:func:`fosmodel.models.model_file.load_model`), so that a file the command line refuses is
refused in Python too, in the same line: a path that is no regular file, a file too large,
JSON nested too deep or integers too long (the limits of :mod:`fosmodel.models.model_file`),
or content outside the schema of :mod:`fosmodel.models.model_schema`.  Writing goes
through :func:`fosmodel.io.output.write_text`, which joins the command's all-or-none publishing.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from ..models.model import FOSModel
from ..models.model_file import dumps
from .output import write_text


def write_model(path: str | os.PathLike[str], model: FOSModel,
                meta: Mapping[str, Any]) -> None:
    """Write ``model`` with ``meta`` (source, column, rate, ...) to ``path``, atomically.

    Through :func:`fosmodel.io.output.write_text`, so that the system's refusal to write is one
    line naming the path and the output joins the command's all-or-none publishing.
    """
    write_text(path, dumps(model, meta))


def read_model(path: str | os.PathLike[str]) -> FOSModel:
    """Load the model saved in ``path``, checked down to its numbers and the column it names.

    The same reader as :meth:`FOSModel.load`: bounded, then checked against the schema.

    Raises
    ------
    InputError
        The file cannot be read or is not a model file (the message names it and why).
    """
    return FOSModel.load(path)

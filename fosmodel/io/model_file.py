"""Model files for the commands: a fitted ``FOSModel`` as JSON, written and read back checked.

The format and its checks live with the model (:mod:`fosmodel.models.model_file`, the one
place that reads and validates a model file), so that :meth:`FOSModel.save` and
:meth:`FOSModel.load` need nothing above the models layer; the commands and the reports
write and read models through these names.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from ..models.model import FOSModel


def write_model(path: str | os.PathLike[str], model: FOSModel,
                meta: Mapping[str, Any]) -> None:
    """Write ``model`` with ``meta`` (source, column, rate, ...) to ``path``, atomically."""
    model.save(path, meta)


def read_model(path: str | os.PathLike[str]) -> FOSModel:
    """Load the model saved in ``path``, checked down to its numbers and the column it names.

    Raises
    ------
    InputError
        The file cannot be read or is not a model file (the message names it and why).
    """
    return FOSModel.load(path)

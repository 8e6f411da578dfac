"""Model files for the commands: a fitted ``FOSModel`` as JSON, written and read back checked.

The file is :meth:`FOSModel.to_dict` with the record's facts in ``meta`` (source, column,
rate).  :func:`read_model` is the commands' checked read of a model file: it refuses, in one
line naming the file, anything that is not such a model down to its numbers, and bounds what
it reads before parsing it:

* a path that is not a regular file (a FIFO, a device such as ``/dev/zero``, a directory) is
  refused from its metadata, never opened for reading to its end nor waited on;
* at most :data:`MAX_BYTES` are read; the text must be UTF-8 JSON, nested at most
  :data:`MAX_DEPTH` deep, its integers at most :data:`MAX_DIGITS` digits long;
* its content must pass the schema of :mod:`fosmodel.io.model_schema` (each field's type and
  range, each term inside the model's own candidate set) before a model is built from it.
"""

from __future__ import annotations

import json
import os
import stat
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..core.exceptions import InputError
from ..models.model import FOSModel
from ..models.model_file import dumps
from .model_schema import check_model_dict
from .output import write_text

#: The largest model file read: a fit of ten thousand terms writes about 2 MB.
MAX_BYTES = 16 * 2**20
#: The deepest nesting of a model file's JSON (a model's own is three; ``meta`` may add some).
MAX_DEPTH = 16
#: The longest integer of a model file's JSON, in digits (a sample count has at most 16).
MAX_DIGITS = 20


def write_model(path: str | os.PathLike[str], model: FOSModel,
                meta: Mapping[str, Any]) -> None:
    """Write ``model`` with ``meta`` (source, column, rate, ...) to ``path``, atomically.

    Through :func:`fosmodel.io.output.write_text`, so that the system's refusal to write is one
    line naming the path and the output joins the command's all-or-none publishing.
    """
    write_text(path, dumps(model, meta))


def read_model(path: str | os.PathLike[str]) -> FOSModel:
    """Load the model saved in ``path``, checked down to its numbers and the column it names.

    Raises
    ------
    InputError
        The file cannot be read or is not a model file (the message names it and why).
    """
    data = _parse(_read_bounded(Path(path)), path)
    try:
        model = FOSModel.from_dict(check_model_dict(data))
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    except (AttributeError, TypeError, ValueError, OverflowError) as exc:  # e.g. terms of numbers
        raise InputError(f"{path}: corrupted model file: {type(exc).__name__}: {exc}") from None
    return model


def _read_bounded(path: Path) -> bytes:
    """Return the bytes of a regular file of at most ``MAX_BYTES``, refusing anything else.

    What the path is comes from its metadata before it is opened, and again from the opened
    file (it may have been swapped between the two); the file is opened without blocking, so
    that a FIFO swapped in is refused rather than waited on.
    """
    try:
        _check_regular(path, os.stat(path))
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as exc:
        raise InputError(f"cannot read model {path}: {exc.strerror or exc}") from None
    try:
        info = os.fstat(fd)
        _check_regular(path, info)
        if info.st_size > MAX_BYTES:
            raise InputError(f"{path}: not a model file ({info.st_size:,} bytes; a model file "
                             f"holds at most {MAX_BYTES // 2**20} MiB)")
        chunks, size = [], 0
        while size <= MAX_BYTES:
            chunk = os.read(fd, min(2**20, MAX_BYTES + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as exc:
        raise InputError(f"cannot read model {path}: {exc.strerror or exc}") from None
    finally:
        os.close(fd)
    if size > MAX_BYTES:  # it grew while read
        raise InputError(f"{path}: not a model file (over {MAX_BYTES:,} bytes; a model file "
                         f"holds at most {MAX_BYTES // 2**20} MiB)")
    return b"".join(chunks)


def _check_regular(path: Path, info: os.stat_result) -> None:
    if stat.S_ISREG(info.st_mode):
        return
    kind = ("a directory" if stat.S_ISDIR(info.st_mode) else
            "a FIFO" if stat.S_ISFIFO(info.st_mode) else
            "a device" if stat.S_ISCHR(info.st_mode) or stat.S_ISBLK(info.st_mode) else
            "a socket" if stat.S_ISSOCK(info.st_mode) else "not a regular file")
    target = f" ({os.path.realpath(path)})" if path.is_symlink() else ""
    raise InputError(f"cannot read model {path}{target}: {kind}, not a model file")


def _parse(raw: bytes, path: str | os.PathLike[str]) -> object:
    """Parse the file's JSON within the limits on its nesting and its integers."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a model file (not UTF-8 text)") from None
    try:
        data = json.loads(text, parse_int=_bounded_int)
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: not a model file (invalid JSON at line {exc.lineno})") from None
    except RecursionError:
        raise InputError(f"{path}: not a model file (JSON nested more than {MAX_DEPTH} "
                         "deep)") from None
    except ValueError as exc:  # an integer too long
        raise InputError(f"{path}: not a model file ({exc})") from None
    if _depth(data) > MAX_DEPTH:
        raise InputError(f"{path}: not a model file (JSON nested more than {MAX_DEPTH} deep)")
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

